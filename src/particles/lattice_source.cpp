// LatticeSource: emission on a lattice at the rest spacing, never on top of water
// (see emitters.h). The free test bins the active particles near the source into a
// dense grid of cells one spacing wide over the source's box, so each slot checks the
// 27 cells around it: O(active + slots) per call.
#include <metariver/emitters.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace mr {

LatticeSource LatticeSource::build(const Def& def, const Terrain& terrain) {
    LatticeSource s;
    s.def_ = def;
    const float d = def.spacing;
    // Lattice points along one axis through the source's centre: k d for |k| <= he / d
    // (so the centre is always a slot, even in a source smaller than a spacing).
    auto axis = [d](float he) {
        const int k = static_cast<int>(std::floor(std::max(he, 0.0f) / d + 1e-4f));
        return std::pair<int, float>(2 * k + 1, -float(k) * d);
    };
    std::vector<Vec3> cand;
    if (def.shape == SourceShape::Point) {
        cand.push_back(def.center);
    } else {
        const Vec3 he = def.shape == SourceShape::Disc ? Vec3(def.half_extent.x, def.half_extent.y, def.half_extent.x)
                                                       : def.half_extent;
        const auto [nx, ox] = axis(he.x);
        const auto [ny, oy] = axis(he.y);
        const auto [nz, oz] = axis(he.z);
        const float r2 = def.half_extent.x * def.half_extent.x * (1.0f + 1e-4f);
        for (int b = 0; b < ny; ++b)
            for (int c = 0; c < nz; ++c)
                for (int a = 0; a < nx; ++a) {
                    const Vec3 o(ox + float(a) * d, oy + float(b) * d, oz + float(c) * d);
                    if (def.shape == SourceShape::Disc && o.x * o.x + o.z * o.z > r2) continue;
                    cand.push_back(def.center + o);
                }
    }
    // Above the terrain: the slot's centre and the corners of its cell footprint keep
    // the clearance (a slot beside a steep wall must not start inside it).
    const float hd = 0.5f * d;
    for (const Vec3& q : cand) {
        if (!terrain.contains_xz(q.x, q.z)) continue;
        float ground = terrain.height_mesh(q.x, q.z);
        for (const Vec3 o : {Vec3(-hd, 0, -hd), Vec3(hd, 0, -hd), Vec3(-hd, 0, hd), Vec3(hd, 0, hd)})
            if (terrain.contains_xz(q.x + o.x, q.z + o.z)) ground = std::max(ground, terrain.height_mesh(q.x + o.x, q.z + o.z));
        if (q.y >= ground + def.clearance) s.slots_.push_back(q);
    }
    // Downstream first: along the inflow direction (down when there is none); ties by
    // position so the order is fixed.
    const float vin = glm::length(def.inflow);
    const Vec3 u = vin > 0.0f ? def.inflow / vin : Vec3(0.0f, -1.0f, 0.0f);
    std::stable_sort(s.slots_.begin(), s.slots_.end(),
                     [&](const Vec3& a, const Vec3& b) { return glm::dot(a, u) > glm::dot(b, u); });
    if (!s.slots_.empty()) {
        float lo = glm::dot(s.slots_.back(), u), hi = glm::dot(s.slots_.front(), u);
        const float speed = std::max(vin, std::sqrt(std::max(def.gravity, 0.0f) * d * 0.5f));
        // Slots per layer across u = slots * d / (extent along u + d); each layer leaves
        // once per d / speed seconds.
        s.max_rate_ = float(s.slots_.size()) * speed / ((hi - lo) + d);
        for (const Vec3& q : s.slots_) s.box_.grow(q);
        s.box_.min -= Vec3(d);
        s.box_.max += Vec3(d);
    }
    return s;
}

void LatticeSource::emit(std::span<const Vec3> positions, size_t active, size_t want, std::vector<Vec3>& out) {
    out.clear();
    if (want == 0 || slots_.empty()) return;
    const float d = def_.spacing;
    const float free2 = (kFreeFraction * d) * (kFreeFraction * d);
    // Bin the active particles inside the box (cells of one spacing).
    const Vec3 ext = box_.max - box_.min;
    const int nx = std::max(1, int(std::ceil(ext.x / d))), ny = std::max(1, int(std::ceil(ext.y / d))),
              nz = std::max(1, int(std::ceil(ext.z / d)));
    auto cell_of = [&](const Vec3& q, int& cx, int& cy, int& cz) {
        cx = std::clamp(int((q.x - box_.min.x) / d), 0, nx - 1);
        cy = std::clamp(int((q.y - box_.min.y) / d), 0, ny - 1);
        cz = std::clamp(int((q.z - box_.min.z) / d), 0, nz - 1);
    };
    const size_t ncell = size_t(nx) * size_t(ny) * size_t(nz);
    start_.assign(ncell + 1, 0);
    near_.clear();
    for (size_t i = 0; i < active; ++i) {
        const Vec3& q = positions[i];
        if (q.x >= box_.min.x && q.y >= box_.min.y && q.z >= box_.min.z && q.x <= box_.max.x && q.y <= box_.max.y &&
            q.z <= box_.max.z)
            near_.push_back(q);
    }
    auto index = [&](int cx, int cy, int cz) { return (size_t(cy) * size_t(nz) + size_t(cz)) * size_t(nx) + size_t(cx); };
    for (const Vec3& q : near_) {
        int cx, cy, cz;
        cell_of(q, cx, cy, cz);
        ++start_[index(cx, cy, cz) + 1];
    }
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    binned_.resize(near_.size());
    fill_ = start_;
    for (const Vec3& q : near_) {
        int cx, cy, cz;
        cell_of(q, cx, cy, cz);
        binned_[fill_[index(cx, cy, cz)]++] = q;
    }
    for (const Vec3& slot : slots_) {
        int cx, cy, cz;
        cell_of(slot, cx, cy, cz);
        bool free = true;
        for (int z = std::max(cz - 1, 0); free && z <= std::min(cz + 1, nz - 1); ++z)
            for (int y = std::max(cy - 1, 0); free && y <= std::min(cy + 1, ny - 1); ++y)
                for (int x = std::max(cx - 1, 0); free && x <= std::min(cx + 1, nx - 1); ++x) {
                    const size_t c = index(x, y, z);
                    for (uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
                        const Vec3 dd = binned_[k] - slot;
                        if (glm::dot(dd, dd) < free2) {
                            free = false;
                            break;
                        }
                    }
                }
        if (!free) continue;
        out.push_back(slot);  // distinct lattice slots are a spacing apart: no clash among them
        if (out.size() == want) break;
    }
}

}  // namespace mr
