// LatticeSource: emission on a lattice at the rest spacing, never on top of water
// (see emitters.h). The free test bins the active particles near the source into a
// dense grid of cells one spacing wide over the source's box, so each slot checks the
// 27 cells around it: O(active + slots) per call.
#include <metariver/emitters.h>

#include <algorithm>
#include <cmath>
#include <limits>
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
        const Vec3 he = source_half_size(def.shape, def.half_extent);
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
    auto footprint_ground = [&](const Vec3& q) {
        float ground = terrain.height_mesh(q.x, q.z);
        for (const Vec3 o : {Vec3(-hd, 0, -hd), Vec3(hd, 0, -hd), Vec3(-hd, 0, hd), Vec3(hd, 0, hd)})
            if (terrain.contains_xz(q.x + o.x, q.z + o.z)) ground = std::max(ground, terrain.height_mesh(q.x + o.x, q.z + o.z));
        return ground;
    };
    // follow_ground: each column is lowered until its lowest slot sits the clearance and a
    // quarter spacing above the ground under it (never raised): water is born on the
    // ground instead of falling from a flat disc metres above a slope.
    float bottom = std::numeric_limits<float>::infinity();  // the lowest layer as drawn
    for (const Vec3& q : cand) bottom = std::min(bottom, q.y);
    struct Kept {
        Vec3 at;     // where the slot is
        float drop;  // how far follow_ground lowered it
        Vec3 drawn() const { return at + Vec3(0.0f, drop, 0.0f); }
    };
    std::vector<Kept> kept;
    for (const Vec3& q : cand) {
        if (!terrain.contains_xz(q.x, q.z)) continue;
        const float ground = footprint_ground(q);
        const float drop = def.follow_ground ? std::max(bottom - (ground + def.clearance + 0.25f * d), 0.0f) : 0.0f;
        if (q.y - drop >= ground + def.clearance) kept.push_back({q - Vec3(0.0f, drop, 0.0f), drop});
    }
    // Downstream first: along the inflow direction (down when there is none); ties by
    // position so the order is fixed. Ordered and measured as drawn (before any
    // lowering): each column still leaves one layer per spacing / speed.
    const float vin = glm::length(def.inflow);
    const Vec3 u = vin > 0.0f ? def.inflow / vin : Vec3(0.0f, -1.0f, 0.0f);
    auto along = [&](const Kept& k) { return glm::dot(k.drawn(), u); };
    std::stable_sort(kept.begin(), kept.end(), [&](const Kept& a, const Kept& b) { return along(a) > along(b); });
    for (size_t k = 0; k < kept.size(); ++k) {
        s.slots_.push_back(kept[k].at);
        if (k == 0 || along(kept[k - 1]) - along(kept[k]) > 1e-3f * d) s.layer_start_.push_back(uint32_t(k));
    }
    s.layer_start_.push_back(uint32_t(s.slots_.size()));
    s.next_.assign(s.layer_start_.size() - 1, 0);
    if (!s.slots_.empty()) {
        const float lo = along(kept.back()), hi = along(kept.front());
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
    auto is_free = [&](const Vec3& slot) {
        int cx, cy, cz;
        cell_of(slot, cx, cy, cz);
        for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, nz - 1); ++z)
            for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, ny - 1); ++y)
                for (int x = std::max(cx - 1, 0); x <= std::min(cx + 1, nx - 1); ++x) {
                    const size_t c = index(x, y, z);
                    for (uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
                        const Vec3 dd = binned_[k] - slot;
                        if (glm::dot(dd, dd) < free2) return false;
                    }
                }
        return true;
    };
    // Layer by layer, downstream first; within a layer from where its last emission
    // stopped, so the layer fills evenly (from one side only, the source's far side
    // stayed dry: strict17.png's channel head).
    for (size_t l = 0; l + 1 < layer_start_.size() && out.size() < want; ++l) {
        const uint32_t b = layer_start_[l], n = layer_start_[l + 1] - b, from = next_[l];
        for (uint32_t t = 0; t < n && out.size() < want; ++t) {
            const uint32_t k = b + (from + t) % n;
            if (!is_free(slots_[k])) continue;
            out.push_back(slots_[k]);  // distinct slots are a spacing apart: no clash among them
            next_[l] = (k - b + 1) % n;
        }
    }
}

}  // namespace mr
