// The terrain mesh of the paper's figure 2 ("Real-time river simulation using
// metaballs", section 2.2): one vertex per heightmap sample, vertex c = i*W + j at
// (j*s, h*height_scale, i*s), and per grid cell the triangles (c, c+W, c+1) and
// (c+1, c+W, c+W+1). With x = j*s and z = i*s, (b-a) x (c-a) of both triangles has a
// positive y component (s^2), so the paper's order already winds them up (+y).
// Each cell's diagonal runs from vertex (i+1, j) to vertex (i, j+1).
#include <metariver/terrain.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace mr {

float resolved_area_scale(const TerrainDef& def, int columns, int rows) {
    if (!def.auto_area_scale || !(def.area_scale > 0.0f)) return def.area_scale;
    const int shorter = std::max(1, std::min(columns, rows) - 1);
    return std::max(def.area_scale, kAutoMinSide / static_cast<float>(shorter));
}

void Terrain::recompute_bounds() {
    static std::atomic<uint64_t> revisions{0};  // process-wide: revisions of different terrains never meet
    revision_ = revisions.fetch_add(1, std::memory_order_relaxed) + 1;
    // The paper's terrain box: the mesh's bounds grown by 1 m up and down.
    Aabb b;
    for (const Vec3& v : vertices_) b.grow(v);
    mesh_bounds_ = b;
    b.min.y -= 1.0f;
    b.max.y += 1.0f;
    bounds_ = b;
}

Result<Terrain> Terrain::build(const Heightmap& map, const TerrainDef& def) {
    if (map.width < 2 || map.height < 2) {
        return Error{fmt::format("heightmap: must be at least 2 x 2 samples (got {} x {})", map.width, map.height)};
    }
    if (map.width > kMaxHeightmapSide || map.height > kMaxHeightmapSide) {
        return Error{fmt::format("heightmap: must be at most {} x {} samples (got {} x {})", kMaxHeightmapSide,
                                 kMaxHeightmapSide, map.width, map.height)};
    }
    const size_t n = static_cast<size_t>(map.width) * static_cast<size_t>(map.height);
    if (map.samples.size() != n) {
        return Error{fmt::format("heightmap: has {} samples, expected width x height = {} x {} = {}",
                                 map.samples.size(), map.width, map.height, n)};
    }
    const float as = resolved_area_scale(def, map.width, map.height);
    if (!std::isfinite(as) || !(as > 0.0f)) {
        return Error{fmt::format("terrain.area_scale: must be finite and > 0 (got {})", def.area_scale)};
    }
    if (!std::isfinite(def.height_scale) || !(def.height_scale > 0.0f)) {
        return Error{fmt::format("terrain.height_scale: must be finite and > 0 (got {})", def.height_scale)};
    }
    const float extent_x = static_cast<float>(map.width - 1) * as;
    const float extent_z = static_cast<float>(map.height - 1) * as;
    if (!std::isfinite(extent_x) || !std::isfinite(extent_z)) {
        return Error{fmt::format("terrain.area_scale: too large, the terrain extent overflows (got {})",
                                 as)};
    }
    for (size_t k = 0; k < n; ++k) {
        const float y = map.samples[k] * def.height_scale;
        if (!std::isfinite(map.samples[k]) || !std::isfinite(y)) {
            return Error{fmt::format("heightmap: sample at row {}, column {} is not finite after scaling (value {})",
                                     k / map.width, k % map.width, map.samples[k])};
        }
    }

    Terrain t;
    t.columns_ = map.width;
    t.rows_ = map.height;
    t.area_scale_ = as;
    const int W = map.width, H = map.height;
    t.vertices_.resize(n);
    for (int i = 0; i < H; ++i) {
        const int r = def.paper_row_orientation ? H - 1 - i : i;
        for (int j = 0; j < W; ++j) {
            const Vec3 p(static_cast<float>(j) * as, map.at(r, j) * def.height_scale,
                         static_cast<float>(i) * as);
            t.vertices_[static_cast<size_t>(i) * W + j] = p;
        }
    }
    if (def.condition == TerrainCondition::Fill || def.condition == TerrainCondition::Breach ||
        def.condition == TerrainCondition::Carve) {
        // Carve breaches here; the scene carves its channel afterwards (carve_channel).
        std::vector<float> h(n);
        for (size_t k = 0; k < n; ++k) h[k] = t.vertices_[k].y;
        t.given_heights_ = h;
        const TerrainCondition mode = def.condition == TerrainCondition::Carve ? TerrainCondition::Breach : def.condition;
        t.condition_ = condition_heights(h, W, H, as, mode);
        t.condition_.mode = def.condition;
        for (size_t k = 0; k < n; ++k) t.vertices_[k].y = h[k];
    }
    t.indices_.reserve(static_cast<size_t>(W - 1) * (H - 1) * 6);
    for (int i = 0; i + 1 < H; ++i) {
        for (int j = 0; j + 1 < W; ++j) {
            const uint32_t c = static_cast<uint32_t>(i) * static_cast<uint32_t>(W) + static_cast<uint32_t>(j);
            const uint32_t w = static_cast<uint32_t>(W);
            t.indices_.insert(t.indices_.end(), {c, c + w, c + 1, c + 1, c + w, c + w + 1});
        }
    }
    t.recompute_bounds();
    return t;
}

Vec3 Terrain::triangle_normal(uint32_t tri) const {
    const glm::dvec3 a(vertices_[indices_[3 * size_t{tri}]]);
    const glm::dvec3 b(vertices_[indices_[3 * size_t{tri} + 1]]);
    const glm::dvec3 c(vertices_[indices_[3 * size_t{tri} + 2]]);
    glm::dvec3 nrm = glm::cross(b - a, c - a);
    if (nrm.y < 0.0) nrm = -nrm;  // never for a mesh built here; kept so the contract holds
    const double len = glm::length(nrm);
    if (!(len > 0.0)) return Vec3(0.0f, 1.0f, 0.0f);
    return Vec3(nrm / len);
}

float Terrain::height_bilinear(float x, float z) const {
    if (vertices_.empty()) return 0.0f;
    const auto [h00, h01, h10, h11, u, v] = cell_corners(x, z);
    return (h00 * (1.0f - u) + h01 * u) * (1.0f - v) + (h10 * (1.0f - u) + h11 * u) * v;
}

Vec3 Terrain::normal_bilinear(float x, float z) const {
    if (vertices_.empty()) return Vec3(0.0f, 1.0f, 0.0f);
    const auto [h00, h01, h10, h11, u, v] = cell_corners(x, z);
    const float dhdx = ((h01 - h00) * (1.0f - v) + (h11 - h10) * v) / area_scale_;
    const float dhdz = ((h10 - h00) * (1.0f - u) + (h11 - h01) * u) / area_scale_;
    return glm::normalize(Vec3(-dhdx, 1.0f, -dhdz));
}

Vec3 Terrain::normal_mesh(float x, float z) const {
    if (indices_.empty()) return Vec3(0.0f, 1.0f, 0.0f);
    return triangle_normal(triangle_at(x, z));
}

}  // namespace mr
