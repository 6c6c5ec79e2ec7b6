// The surface of water given as depths over a heightfield (a solver's HeightfieldWater):
// a triangle grid over the wet cells at bed + depth, split as the terrain's mesh is, with
// area-weighted vertex normals.
#include <metariver/surface.h>

#include <glm/geometric.hpp>

#include <cstdint>
#include <limits>

namespace mr {

void append_heightfield_surface(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns,
                                SurfaceMesh& out, std::vector<uint32_t>* scratch) {
    if (rows < 2 || columns < 2) return;
    const size_t n = size_t(rows) * size_t(columns);
    if (bed.size() != n || depth.size() != n) return;
    constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
    const auto wet = [&](int i, int j) {
        const size_t c = size_t(i) * size_t(columns) + size_t(j);
        return depth[c] > 0.0f && depth[c + 1] > 0.0f && depth[c + size_t(columns)] > 0.0f &&
               depth[c + size_t(columns) + 1] > 0.0f;
    };
    // One vertex per sample of a wet cell, numbered in sample order after what `out` holds.
    const size_t first = out.positions.size();
    std::vector<uint32_t> own;
    std::vector<uint32_t>& vertex = scratch ? *scratch : own;  // sample -> its vertex, kNone: none
    vertex.assign(n, kNone);
    for (int i = 0; i + 1 < rows; ++i)
        for (int j = 0; j + 1 < columns; ++j) {
            if (!wet(i, j)) continue;
            const size_t c = size_t(i) * size_t(columns) + size_t(j);
            for (const size_t s : {c, c + 1, c + size_t(columns), c + size_t(columns) + 1}) vertex[s] = 0;
        }
    for (size_t s = 0; s < n; ++s) {
        if (vertex[s] == kNone) continue;
        vertex[s] = uint32_t(out.positions.size());
        out.positions.push_back(bed[s] + Vec3(0.0f, depth[s], 0.0f));
    }
    out.normals.resize(out.positions.size(), Vec3(0.0f));
    // Two triangles per wet cell, (c, c + w, c + 1) and (c + 1, c + w, c + w + 1) as the
    // terrain's; each adds its area-weighted normal (the cross product) to its corners.
    const auto triangle = [&](size_t a, size_t b, size_t c) {
        const uint32_t ia = vertex[a], ib = vertex[b], ic = vertex[c];
        out.indices.insert(out.indices.end(), {ia, ib, ic});
        const Vec3 nrm = glm::cross(out.positions[ib] - out.positions[ia], out.positions[ic] - out.positions[ia]);
        for (const uint32_t v : {ia, ib, ic}) out.normals[v] += nrm;
    };
    for (int i = 0; i + 1 < rows; ++i)
        for (int j = 0; j + 1 < columns; ++j) {
            if (!wet(i, j)) continue;
            const size_t c = size_t(i) * size_t(columns) + size_t(j), w = size_t(columns);
            triangle(c, c + w, c + 1);
            triangle(c + 1, c + w, c + w + 1);
        }
    for (size_t v = first; v < out.normals.size(); ++v) {
        const float len = glm::length(out.normals[v]);
        out.normals[v] = len > 0.0f ? out.normals[v] / len : Vec3(0.0f, 1.0f, 0.0f);
    }
}

}  // namespace mr
