// The renderer's terrain mesh and tree boxes on the CPU (terrain_geometry.h).
#include "terrain_geometry.h"

#include <glm/geometric.hpp>

#include <algorithm>

namespace mr::render {

namespace {

/// Upward face normal (not normalised) of triangle k: cross(b - a, c - a), flipped up.
Vec3 face_normal(std::span<const Vec3> verts, std::span<const uint32_t> idx, size_t k) {
    const Vec3 &a = verts[idx[3 * k]], &b = verts[idx[3 * k + 1]], &c = verts[idx[3 * k + 2]];
    Vec3 n = glm::cross(b - a, c - a);
    if (n.y < 0.0f) n = -n;
    return n;
}

Vec3 normalised_or_up(const Vec3& n) {
    const float len = glm::length(n);
    return len > 0.0f ? n / len : Vec3(0.0f, 1.0f, 0.0f);
}

/// Replaces the skirts (everything after the grid vertices) from the current border
/// heights; with `indices`, appends their triangles too (a full build).
void build_skirts(std::span<const Vec3> verts, TerrainGeometry& g, std::vector<uint32_t>* indices) {
    const int W = g.columns, H = g.rows;
    g.vertices.resize(g.grid_vertices());
    auto wall = [&](int i0, int j0, int i1, int j1, Vec3 outward) {
        const Vec3 a = verts[static_cast<size_t>(i0) * W + j0], b = verts[static_cast<size_t>(i1) * W + j1];
        const auto base = static_cast<uint32_t>(g.vertices.size());
        g.vertices.push_back({a, outward, 1.0f});
        g.vertices.push_back({b, outward, 1.0f});
        g.vertices.push_back({Vec3(a.x, g.skirt_bottom, a.z), outward, 1.0f});
        g.vertices.push_back({Vec3(b.x, g.skirt_bottom, b.z), outward, 1.0f});
        if (indices) indices->insert(indices->end(), {base, base + 2, base + 1, base + 1, base + 2, base + 3});
    };
    for (int j = 0; j + 1 < W; ++j) {
        wall(0, j, 0, j + 1, Vec3(0, 0, -1));
        wall(H - 1, j, H - 1, j + 1, Vec3(0, 0, 1));
    }
    for (int i = 0; i + 1 < H; ++i) {
        wall(i, 0, i + 1, 0, Vec3(-1, 0, 0));
        wall(i, W - 1, i + 1, W - 1, Vec3(1, 0, 0));
    }
}

}  // namespace

void build_terrain_geometry(const Terrain& t, bool paper_rows, TerrainGeometry& g) {
    const auto verts = t.vertices();
    const auto idx = t.indices();
    g.columns = t.columns();
    g.rows = t.rows();
    g.vertices.assign(verts.size(), TerrainVertex{});
    for (size_t i = 0; i < verts.size(); ++i) g.vertices[i] = {verts[i], Vec3(0.0f), 0.0f};
    for (size_t k = 0; 3 * k + 2 < idx.size(); ++k) {
        const Vec3 n = face_normal(verts, idx, k);
        for (int c = 0; c < 3; ++c) g.vertices[idx[3 * k + c]].normal += n;
    }
    for (size_t i = 0; i < verts.size(); ++i) g.vertices[i].normal = normalised_or_up(g.vertices[i].normal);
    g.indices.assign(idx.begin(), idx.end());
    g.skirt_bottom = t.bounds().min.y;
    build_skirts(verts, g, &g.indices);
    g.bounds = t.mesh_bounds();
    // Texture row 0 is the heightmap's row 0: at the far end (high z) in the paper's
    // orientation, at z = 0 otherwise.
    const float xmax = float(g.columns - 1) * t.area_scale(), zmax = float(g.rows - 1) * t.area_scale();
    g.rect = paper_rows ? glm::vec4(0.0f, zmax, xmax, 0.0f) : glm::vec4(0.0f, 0.0f, xmax, zmax);
}

bool touches_border(const TerrainGeometry& g, const TerrainEdit& r) {
    return r.i0 <= 0 || r.j0 <= 0 || r.i1 >= g.rows - 1 || r.j1 >= g.columns - 1;
}

bool update_terrain_geometry(const Terrain& t, const TerrainEdit& changed, TerrainGeometry& g, TerrainEdit& rows_out) {
    const int W = t.columns(), H = t.rows();
    if (W != g.columns || H != g.rows || g.vertices.size() < g.grid_vertices() || t.bounds().min.y != g.skirt_bottom)
        return false;
    rows_out = TerrainEdit{};
    if (changed.empty()) return true;
    const auto verts = t.vertices();
    const auto idx = t.indices();
    // A sample's normal sums the triangles of the (up to) four cells around it, so the
    // samples one around the changed ones are rewritten too.
    const int i0 = std::max(changed.i0 - 1, 0), i1 = std::min(changed.i1 + 1, H - 1);
    const int j0 = std::max(changed.j0 - 1, 0), j1 = std::min(changed.j1 + 1, W - 1);
    for (int i = i0; i <= i1; ++i)
        for (int j = j0; j <= j1; ++j) {
            // Its triangles in increasing index, as the whole build adds them: cell
            // (i-1, j-1) triangle 1, (i-1, j) 0 and 1, (i, j-1) 0 and 1, (i, j) 0.
            Vec3 n(0.0f);
            const auto cell = [&](int ci, int cj, int first, int last) {
                if (ci < 0 || cj < 0 || ci >= H - 1 || cj >= W - 1) return;
                const size_t base = 2 * (size_t(ci) * size_t(W - 1) + size_t(cj));
                for (int k = first; k <= last; ++k) n += face_normal(verts, idx, base + size_t(k));
            };
            cell(i - 1, j - 1, 1, 1);
            cell(i - 1, j, 0, 1);
            cell(i, j - 1, 0, 1);
            cell(i, j, 0, 0);
            const size_t v = size_t(i) * size_t(W) + size_t(j);
            g.vertices[v] = {verts[v], normalised_or_up(n), 0.0f};
        }
    rows_out = TerrainEdit{.i0 = i0, .j0 = j0, .i1 = i1, .j1 = j1, .before = {}};
    if (touches_border(g, rows_out)) build_skirts(verts, g, nullptr);
    g.bounds = t.mesh_bounds();
    return true;
}

void build_tree_boxes(const Bvh& bvh, TreeBoxes& out) {
    const auto nodes = bvh.nodes();
    std::vector<int> depth(nodes.size(), 0);
    // Parents usually come before children; settle depths by repeated passes anyway.
    for (bool changed = true; changed;) {
        changed = false;
        for (size_t n = 0; n < nodes.size(); ++n) {
            if (nodes[n].count != 0) continue;
            for (uint32_t c : {nodes[n].left, nodes[n].right}) {
                if (depth[c] != depth[n] + 1) {
                    depth[c] = depth[n] + 1;
                    changed = true;
                }
            }
        }
    }
    out.depth = 0;
    for (int d : depth) out.depth = std::max(out.depth, d);
    out.nodes = nodes.size();
    out.boxes.clear();
    out.node.clear();
    out.boxes.reserve(nodes.size() * 2);
    out.node.reserve(nodes.size() * 2);
    const auto add = [&](size_t n, int d) {
        out.boxes.push_back({nodes[n].box.min, nodes[n].box.max, float(d)});
        out.node.push_back(uint32_t(n));
    };
    out.level_first.assign(size_t(out.depth) + 1, 0);
    out.level_count.assign(size_t(out.depth) + 1, 0);
    for (int d = 0; d <= out.depth; ++d) {
        out.level_first[size_t(d)] = uint32_t(out.boxes.size());
        for (size_t n = 0; n < nodes.size(); ++n)
            if (depth[n] == d) add(n, d);
        out.level_count[size_t(d)] = uint32_t(out.boxes.size()) - out.level_first[size_t(d)];
    }
    out.leaves_first = uint32_t(out.boxes.size());
    for (size_t n = 0; n < nodes.size(); ++n)
        if (nodes[n].count > 0) add(n, depth[n]);
    out.leaves_count = uint32_t(out.boxes.size()) - out.leaves_first;
}

bool refit_tree_boxes(const Bvh& bvh, TreeBoxes& t, std::vector<std::pair<uint32_t, uint32_t>>& spans) {
    const auto nodes = bvh.nodes();
    spans.clear();
    if (t.boxes.empty() || nodes.size() != t.nodes) return false;
    std::vector<uint32_t> starts = t.level_first;
    starts.push_back(t.leaves_first);
    starts.push_back(uint32_t(t.boxes.size()));
    for (size_t s = 0; s + 1 < starts.size(); ++s) {
        uint32_t lo = starts[s + 1], hi = starts[s];  // first and end of the moved boxes
        for (uint32_t k = starts[s]; k < starts[s + 1]; ++k) {
            const Aabb& b = nodes[t.node[k]].box;
            if (t.boxes[k].min == b.min && t.boxes[k].max == b.max) continue;
            t.boxes[k].min = b.min;
            t.boxes[k].max = b.max;
            lo = std::min(lo, k);
            hi = k + 1;
        }
        if (lo < hi) spans.emplace_back(lo, hi);
    }
    return true;
}

}  // namespace mr::render
