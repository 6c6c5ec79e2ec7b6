// The carved main channel filled with water at the start (particles.prefill): a river
// that runs from the first frame instead of a front that needs the channel's transit
// time to reach the outlet (a 95 m channel at 1 m/s: 95 s, most of a 120 s run).
#include <metariver/scene.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

namespace mr {

ChannelFill fill_channel(const Terrain& t, std::span<const std::pair<int, int>> path, const ChannelFillDef& def) {
    ChannelFill out;
    const float s = def.spacing;
    if (path.size() < 2 || !(s > 0.0f) || def.most == 0 || !(def.share > 0.0f)) return out;
    const float a = t.area_scale();
    // The path's cell centres in metres (x = column, z = row), and its arc length.
    std::vector<Vec3> pts;
    pts.reserve(path.size());
    for (const auto& [i, j] : path) pts.emplace_back(float(j) * a, 0.0f, float(i) * a);
    std::vector<float> arc(pts.size(), 0.0f);
    for (size_t k = 1; k < pts.size(); ++k) arc[k] = arc[k - 1] + glm::length(pts[k] - pts[k - 1]);
    const float length = arc.back();
    // Particles across the bed (clear of its walls by half a spacing) and layers deep.
    const int across = std::max(1, int(std::floor(def.floor_m / s)) - 1);
    const int layers = std::max(1, int(std::lround(def.depth_m / s)));
    // A hash of occupied cells of side s: a bend's inner side is shorter than the
    // centreline, so stations there would overlap; a position nearer than 0.9 s to one
    // already placed is skipped (PBF would push such a pair apart as a burst).
    auto key = [&](const Vec3& p) {
        const auto c = [&](float v) { return int64_t(std::floor(v / s)) & 0x1FFFFF; };
        return (c(p.x) << 42) | (c(p.y) << 21) | c(p.z);
    };
    std::unordered_map<int64_t, std::vector<Vec3>> cells;
    auto free_at = [&](const Vec3& p) {
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto it = cells.find(key(p + s * Vec3(float(dx), float(dy), float(dz))));
                    if (it == cells.end()) continue;
                    for (const Vec3& q : it->second)
                        if (glm::dot(q - p, q - p) < 0.81f * s * s) return false;
                }
        return true;
    };
    uint64_t candidates = 0;
    size_t seg = 0;
    for (float u = 0.5f * s; u < length && out.position.size() < def.most; u += s) {
        while (seg + 2 < arc.size() && arc[seg + 1] < u) ++seg;
        const float w = (u - arc[seg]) / std::max(arc[seg + 1] - arc[seg], 1e-6f);
        const Vec3 c = glm::mix(pts[seg], pts[seg + 1], std::clamp(w, 0.0f, 1.0f));
        // The tangent over about two samples either side: a diagonal step's zigzag
        // would otherwise turn every other station's cross-section.
        const size_t lo = seg >= 2 ? seg - 2 : 0, hi = std::min(seg + 3, pts.size() - 1);
        Vec3 tangent = pts[hi] - pts[lo];
        tangent.y = 0.0f;
        if (glm::dot(tangent, tangent) < 1e-12f) continue;
        tangent = glm::normalize(tangent);
        const Vec3 side(-tangent.z, 0.0f, tangent.x);
        if (def.skip_radius_m > 0.0f) {
            const Vec3 d(c.x - def.skip_center.x, 0.0f, c.z - def.skip_center.z);
            if (glm::dot(d, d) < def.skip_radius_m * def.skip_radius_m) continue;
        }
        for (int k = 0; k < across && out.position.size() < def.most; ++k) {
            const Vec3 q = c + (float(k) - 0.5f * float(across - 1)) * s * side;
            if (!t.contains_xz(q.x, q.z)) continue;
            const float ground = t.height_mesh(q.x, q.z);
            for (int l = 0; l < layers && out.position.size() < def.most; ++l) {
                const Vec3 p(q.x, ground + def.clearance_m + (0.5f + float(l)) * s, q.z);
                if (!free_at(p)) continue;
                // Keep candidate k when floor((k + 1) share) passes an integer: evenly
                // spread, exactly round(candidates x share) of them.
                const double k = double(candidates++);
                if (std::floor((k + 1.0) * double(def.share)) == std::floor(k * double(def.share))) continue;
                cells[key(p)].push_back(p);
                out.position.push_back(p);
                out.velocity.push_back(def.speed * tangent);
            }
        }
    }
    return out;
}

}  // namespace mr
