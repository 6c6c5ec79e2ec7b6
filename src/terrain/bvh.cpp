// The paper's AABB tree over the terrain triangles ("Real-time river simulation using
// metaballs", section 2.3.3): the triangle list is halved recursively down to leaves of
// at most leaf_triangles. The triangle list is in cell order (row-major, two triangles
// per cell), so halving it is halving the cell rectangle by rows while a range spans
// more than one row, then by columns; on 2^k+1 sides that is exactly the paper's list
// halving, on any other size it still gives leaf boxes that tile the terrain without
// overlapping in x/z. Every box spans the terrain's full height (bounds().min.y..max.y).
//
// Two queries: the paper's (descend to the leaf holding the particle's new position,
// Moller-Trumbore against that leaf's triangles only) and a robust one (every leaf the
// swept segment crosses, slab test, watertight triangle test).
#include <metariver/terrain.h>

#include "watertight_ray.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace mr {
namespace {

struct CellRange {
    int i0, i1;  // cell rows [i0, i1)
    int j0, j1;  // cell columns [j0, j1)
    size_t triangles() const { return 2u * static_cast<size_t>(i1 - i0) * static_cast<size_t>(j1 - j0); }
};

/// Slab test of the segment o + t*d, t in [0, tmax], against box grown by eps.
bool segment_hits_box(const Vec3& o, const Vec3& d, float tmax, const Aabb& box, float eps) {
    float t0 = 0.0f, t1 = tmax;
    for (int a = 0; a < 3; ++a) {
        const float lo = box.min[a] - eps, hi = box.max[a] + eps;
        if (d[a] == 0.0f) {
            if (o[a] < lo || o[a] > hi) return false;
            continue;
        }
        const float inv = 1.0f / d[a];
        float ta = (lo - o[a]) * inv, tb = (hi - o[a]) * inv;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (!(t0 <= t1)) return false;
    }
    return true;
}

RayHit make_hit(const Terrain& terrain, const Vec3& from, const Vec3& dir, float t, uint32_t tri) {
    RayHit hit;
    hit.t = t;
    hit.triangle = tri;
    hit.point = from + t * dir;
    hit.normal = terrain.triangle_normal(tri);
    return hit;
}

}  // namespace

Result<Bvh> Bvh::build(const Terrain& terrain, const BvhDef& def) {
    if (def.leaf_triangles < 2 || def.leaf_triangles > 4096) {
        return Error{fmt::format("collision.bvh_leaf_triangles: must be in [2, 4096] (got {})", def.leaf_triangles)};
    }
    if (terrain.columns() < 2 || terrain.rows() < 2 || terrain.triangle_count() == 0) {
        return Error{"terrain: empty mesh (build the terrain before its BVH)"};
    }
    const int W = terrain.columns(), H = terrain.rows();
    const float ymin = terrain.bounds().min.y, ymax = terrain.bounds().max.y;
    const size_t leaf_max = static_cast<size_t>(def.leaf_triangles);

    Bvh bvh;
    bvh.tri_ids_.reserve(terrain.triangle_count());
    // About 2 * triangles / (leaf_max / 2) nodes; reserve generously.
    bvh.nodes_.reserve(4 * terrain.triangle_count() / leaf_max + 8);

    // Depth-first, pre-order: a node's left subtree follows it directly.
    struct Frame {
        CellRange range;
        uint32_t node;
    };
    std::vector<Frame> stack;
    const auto verts = terrain.vertices();
    auto make_node = [&](const CellRange& r) {
        // x/z from the range's corner vertices (bit for bit the mesh's coordinates).
        const Vec3& lo = verts[static_cast<size_t>(r.i0) * W + r.j0];
        const Vec3& hi = verts[static_cast<size_t>(r.i1) * W + r.j1];
        BvhNode n;
        n.box.min = Vec3(lo.x, ymin, lo.z);
        n.box.max = Vec3(hi.x, ymax, hi.z);
        bvh.nodes_.push_back(n);
        return static_cast<uint32_t>(bvh.nodes_.size() - 1);
    };
    stack.push_back({CellRange{0, H - 1, 0, W - 1}, make_node(CellRange{0, H - 1, 0, W - 1})});
    while (!stack.empty()) {
        const Frame f = stack.back();
        stack.pop_back();
        const CellRange& r = f.range;
        if (r.triangles() <= leaf_max) {
            BvhNode& n = bvh.nodes_[f.node];
            n.first = static_cast<uint32_t>(bvh.tri_ids_.size());
            for (int i = r.i0; i < r.i1; ++i) {
                for (int j = r.j0; j < r.j1; ++j) {
                    const uint32_t cell = static_cast<uint32_t>(i) * static_cast<uint32_t>(W - 1) +
                                          static_cast<uint32_t>(j);
                    bvh.tri_ids_.push_back(2u * cell);
                    bvh.tri_ids_.push_back(2u * cell + 1u);
                }
            }
            n.count = static_cast<uint32_t>(bvh.tri_ids_.size()) - n.first;
            continue;
        }
        CellRange left = r, right = r;
        if (r.i1 - r.i0 > 1) {
            const int mid = r.i0 + (r.i1 - r.i0) / 2;
            left.i1 = mid;
            right.i0 = mid;
        } else {
            const int mid = r.j0 + (r.j1 - r.j0) / 2;
            left.j1 = mid;
            right.j0 = mid;
        }
        const uint32_t l = make_node(left);
        const uint32_t rn = make_node(right);
        bvh.nodes_[f.node].left = l;
        bvh.nodes_[f.node].right = rn;
        // Right pushed first so the left subtree is finished first.
        stack.push_back({right, rn});
        stack.push_back({left, l});
    }
    return bvh;
}

BvhStats Bvh::stats() const {
    BvhStats st;
    st.nodes = nodes_.size();
    if (nodes_.empty()) return st;
    std::vector<std::pair<uint32_t, int>> stack{{0u, 1}};
    while (!stack.empty()) {
        const auto [id, level] = stack.back();
        stack.pop_back();
        const BvhNode& n = nodes_[id];
        st.depth = std::max(st.depth, level);
        if (n.count > 0) {
            ++st.leaves;
            st.max_leaf_triangles = std::max<size_t>(st.max_leaf_triangles, n.count);
        } else {
            stack.push_back({n.left, level + 1});
            stack.push_back({n.right, level + 1});
        }
    }
    return st;
}

int Bvh::leaf_containing(const Vec3& p) const {
    if (nodes_.empty() || !nodes_[0].box.contains(p)) return -1;
    uint32_t id = 0;
    while (nodes_[id].count == 0) {
        const BvhNode& n = nodes_[id];
        if (nodes_[n.left].box.contains(p)) {
            id = n.left;
        } else if (nodes_[n.right].box.contains(p)) {
            id = n.right;
        } else {
            return -1;
        }
    }
    return static_cast<int>(id);
}

std::span<const uint32_t> Bvh::leaf_triangles(int leaf) const {
    if (leaf < 0 || static_cast<size_t>(leaf) >= nodes_.size()) return {};
    const BvhNode& n = nodes_[static_cast<size_t>(leaf)];
    return std::span<const uint32_t>(tri_ids_).subspan(n.first, n.count);
}

std::optional<RayHit> Bvh::intersect_paper(const Terrain& terrain, const Vec3& from, const Vec3& to) const {
    const int leaf = leaf_containing(to);
    if (leaf < 0) return std::nullopt;
    const Vec3 dir = to - from;
    const auto verts = terrain.vertices();
    const auto idx = terrain.indices();
    std::optional<RayHit> best;
    for (const uint32_t tri : leaf_triangles(leaf)) {
        const size_t k = 3 * size_t{tri};
        const auto t = ray_triangle_paper(from, dir, verts[idx[k]], verts[idx[k + 1]], verts[idx[k + 2]]);
        if (t && (!best || *t < best->t)) best = make_hit(terrain, from, dir, *t, tri);
    }
    return best;
}

std::optional<RayHit> Bvh::intersect_segment(const Terrain& terrain, const Vec3& from, const Vec3& to) const {
    if (nodes_.empty()) return std::nullopt;
    const Vec3 dir = to - from;
    const watertight::Ray ray = watertight::prepare(from, dir);
    const auto verts = terrain.vertices();
    const auto idx = terrain.indices();
    const Aabb& root = nodes_[0].box;
    // Boxes are grown by a hair so float rounding in the slab test never drops a leaf
    // whose triangle the (exact-signed) watertight test would hit.
    const float eps = 1e-5f * (1.0f + std::max({std::abs(root.min.x), std::abs(root.max.x), std::abs(root.min.y),
                                                std::abs(root.max.y), std::abs(root.min.z), std::abs(root.max.z)}));
    float best_t = 1.0f;
    uint32_t best_tri = 0;
    bool found = false;
    uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const BvhNode& n = nodes_[stack[--top]];
        if (!segment_hits_box(from, dir, best_t, n.box, eps)) continue;
        if (n.count > 0) {
            for (uint32_t k = n.first; k < n.first + n.count; ++k) {
                const uint32_t tri = tri_ids_[k];
                const size_t v = 3 * size_t{tri};
                const auto t = watertight::hit(ray, verts[idx[v]], verts[idx[v + 1]], verts[idx[v + 2]]);
                if (t && (!found || *t < best_t || (*t == best_t && tri < best_tri))) {
                    best_t = *t;
                    best_tri = tri;
                    found = true;
                }
            }
            continue;
        }
        // Visit the nearer child first (pushed last) so best_t prunes the other.
        uint32_t first = n.left, second = n.right;
        const Vec3 dl = nodes_[n.left].box.center() - from, dr = nodes_[n.right].box.center() - from;
        if (glm::dot(dr, dir) < glm::dot(dl, dir)) std::swap(first, second);
        if (top + 2 > 128) return std::nullopt;  // unreachable: depth <= ~26 for 4097^2
        stack[top++] = second;
        stack[top++] = first;
    }
    if (!found) return std::nullopt;
    return make_hit(terrain, from, dir, best_t, best_tri);
}

void Bvh::refit_heights(const Terrain& terrain) {
    for (BvhNode& n : nodes_) {
        n.box.min.y = terrain.bounds().min.y;
        n.box.max.y = terrain.bounds().max.y;
    }
}

}  // namespace mr
