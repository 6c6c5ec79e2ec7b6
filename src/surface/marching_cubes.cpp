// metariver surface: marching cubes.
//
// Paul Bourke, "Polygonising a scalar field" (1994), http://paulbourke.net/geometry/polygonise/
// Every cell's 8 corners give a cube index (bit c set when corner c is inside, value >
// threshold); mc::kTriTable lists its triangles as triples of cell edges. Unlike Bourke's
// per-cell polygonise(), which emits three fresh vertices per triangle, the grid is
// walked slab by slab (z) and each crossed grid edge gets exactly one vertex, created
// when its layer is first reached and looked up through per-edge index caches: x and y
// edges for the slab's bottom and top layers, z edges for the slab itself. Vertices are
// therefore welded by grid edge, with no position hashing. Position: linear
// interpolation to the threshold along the edge. Normal: the negative field gradient
// (central differences at the samples, one-sided at the border) interpolated to the
// vertex and normalised, so it points outward, toward lower values.
#include <metariver/surface.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace mr {

namespace {

constexpr uint32_t kNoVertex = 0xffffffffu;

/// Where a cell edge's vertex lives in the caches: the grid axis the edge runs along
/// and the offset of its lower sample from the cell's corner 0.
struct EdgeSlot {
    int axis = 0;
    int dx = 0, dy = 0, dz = 0;
};

std::array<EdgeSlot, 12> make_edge_slots() {
    std::array<EdgeSlot, 12> slots{};
    for (int e = 0; e < 12; ++e) {
        const auto& a = mc::kCornerOffset[mc::kEdgeCorners[e][0]];
        const auto& b = mc::kCornerOffset[mc::kEdgeCorners[e][1]];
        EdgeSlot s;
        for (int d = 0; d < 3; ++d) {
            if (a[d] != b[d]) s.axis = d;
        }
        s.dx = std::min(a[0], b[0]);
        s.dy = std::min(a[1], b[1]);
        s.dz = std::min(a[2], b[2]);
        slots[e] = s;
    }
    return slots;
}

const std::array<EdgeSlot, 12> kEdgeSlots = make_edge_slots();

inline bool is_inside(float v, float threshold) { return v > threshold; }  // NaN: outside

/// The field's gradient at sample (i, j, k) in value per grid step: central differences,
/// one-sided on the border (every axis has at least 2 samples here).
Vec3 gradient_at(const ScalarGrid& g, int i, int j, int k) {
    const float* v = g.values.data();
    const size_t sx = 1;
    const size_t sy = static_cast<size_t>(g.nx);
    const size_t sz = static_cast<size_t>(g.nx) * static_cast<size_t>(g.ny);
    const size_t c = g.index(i, j, k);
    const auto diff = [&](int at, int n, size_t stride) {
        const int lo = at > 0 ? at - 1 : at;
        const int hi = at < n - 1 ? at + 1 : at;
        const float f_lo = v[c - static_cast<size_t>(at - lo) * stride];
        const float f_hi = v[c + static_cast<size_t>(hi - at) * stride];
        return (f_hi - f_lo) / static_cast<float>(hi - lo);
    };
    return Vec3(diff(i, g.nx, sx), diff(j, g.ny, sy), diff(k, g.nz, sz));
}

/// Adds the vertex of the crossed grid edge from sample (i, j, k) one step along `axis`.
uint32_t add_vertex(const ScalarGrid& g, float threshold, int i, int j, int k, int axis, SurfaceMesh& out) {
    const int i1 = i + (axis == 0);
    const int j1 = j + (axis == 1);
    const int k1 = k + (axis == 2);
    const float a = g.at(i, j, k);
    const float b = g.at(i1, j1, k1);
    float t = (threshold - a) / (b - a);
    if (!(t >= 0.0f && t <= 1.0f)) t = 0.5f;  // NaN or infinite sample: the edge's midpoint

    Vec3 p = g.position(i, j, k);
    p[axis] += t * g.spacing;

    Vec3 n = -((1.0f - t) * gradient_at(g, i, j, k) + t * gradient_at(g, i1, j1, k1));
    const float len2 = glm::dot(n, n);
    if (len2 > 0.0f && std::isfinite(len2)) {
        n /= std::sqrt(len2);
    } else {
        // No usable gradient (flat or non-finite field): the field falls from the inside
        // sample to the outside one, so point along the edge that way.
        n = Vec3(0.0f);
        n[axis] = is_inside(a, threshold) ? 1.0f : -1.0f;
    }

    const auto id = static_cast<uint32_t>(out.positions.size());
    out.positions.push_back(p);
    out.normals.push_back(n);
    return id;
}

}  // namespace

void extract_surface(const ScalarGrid& grid, float threshold, SurfaceMesh& out) {
    out.clear();
    const int nx = grid.nx, ny = grid.ny, nz = grid.nz;
    if (nx < 2 || ny < 2 || nz < 2 || grid.values.size() < grid.size()) return;

    const size_t nxe = static_cast<size_t>(nx - 1) * ny;  // x edges per layer
    const size_t nye = static_cast<size_t>(nx) * (ny - 1);  // y edges per layer
    const size_t nze = static_cast<size_t>(nx) * ny;        // z edges per slab
    std::vector<uint32_t> x_edges[2] = {std::vector<uint32_t>(nxe), std::vector<uint32_t>(nxe)};
    std::vector<uint32_t> y_edges[2] = {std::vector<uint32_t>(nye), std::vector<uint32_t>(nye)};
    std::vector<uint32_t> z_edges(nze);
    uint32_t* xl[2] = {x_edges[0].data(), x_edges[1].data()};  // [0] bottom layer, [1] top
    uint32_t* yl[2] = {y_edges[0].data(), y_edges[1].data()};
    uint32_t* zl = z_edges.data();

    const float* v = grid.values.data();
    const auto layer_edges = [&](int k, uint32_t* xs, uint32_t* ys) {
        for (int j = 0; j < ny; ++j) {
            const float* row = v + grid.index(0, j, k);
            uint32_t* xrow = xs + static_cast<size_t>(nx - 1) * j;
            for (int i = 0; i + 1 < nx; ++i) {
                xrow[i] = is_inside(row[i], threshold) != is_inside(row[i + 1], threshold)
                              ? add_vertex(grid, threshold, i, j, k, 0, out)
                              : kNoVertex;
            }
            if (j + 1 == ny) continue;
            const float* up = row + nx;
            uint32_t* yrow = ys + static_cast<size_t>(nx) * j;
            for (int i = 0; i < nx; ++i) {
                yrow[i] = is_inside(row[i], threshold) != is_inside(up[i], threshold)
                              ? add_vertex(grid, threshold, i, j, k, 1, out)
                              : kNoVertex;
            }
        }
    };

    // Offsets of the 8 corners from corner 0 in the value array.
    std::array<size_t, 8> corner_offset{};
    for (int c = 0; c < 8; ++c) {
        const auto& o = mc::kCornerOffset[c];
        corner_offset[c] = static_cast<size_t>(o[0]) +
                           static_cast<size_t>(nx) * (o[1] + static_cast<size_t>(ny) * o[2]);
    }

    layer_edges(0, xl[0], yl[0]);
    for (int k = 0; k + 1 < nz; ++k) {
        layer_edges(k + 1, xl[1], yl[1]);
        const float* lo = v + grid.index(0, 0, k);
        const float* hi = v + grid.index(0, 0, k + 1);
        for (size_t s = 0; s < nze; ++s) {
            zl[s] = is_inside(lo[s], threshold) != is_inside(hi[s], threshold)
                        ? add_vertex(grid, threshold, static_cast<int>(s % nx), static_cast<int>(s / nx), k, 2, out)
                        : kNoVertex;
        }

        for (int j = 0; j + 1 < ny; ++j) {
            for (int i = 0; i + 1 < nx; ++i) {
                const float* base = v + grid.index(i, j, k);
                unsigned cube = 0;
                for (int c = 0; c < 8; ++c) {
                    cube |= static_cast<unsigned>(is_inside(base[corner_offset[c]], threshold)) << c;
                }
                if (cube == 0 || cube == 255) continue;
                const auto& tris = mc::kTriTable[cube];
                for (int t = 0; t < 16 && tris[t] >= 0; ++t) {
                    const EdgeSlot& s = kEdgeSlots[static_cast<size_t>(tris[t])];
                    const int ei = i + s.dx;
                    const int ej = j + s.dy;
                    uint32_t id;
                    if (s.axis == 0) {
                        id = xl[s.dz][static_cast<size_t>(nx - 1) * ej + ei];
                    } else if (s.axis == 1) {
                        id = yl[s.dz][static_cast<size_t>(nx) * ej + ei];
                    } else {
                        id = zl[static_cast<size_t>(nx) * ej + ei];
                    }
                    out.indices.push_back(id);
                }
            }
        }
        std::swap(xl[0], xl[1]);
        std::swap(yl[0], yl[1]);
    }
}

}  // namespace mr
