// Test support: topology and geometry checks for indexed triangle meshes.
//
// Header-only; works on anything with `positions` (Vec3) and `indices` (uint32_t, 3 per
// triangle), e.g. mr::SurfaceMesh. Edges are undirected vertex pairs; an edge's "uses"
// are the triangles that have it as a side, each in one direction.
#pragma once

#include <metariver/core.h>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <span>
#include <utility>
#include <vector>

namespace mr::test {

/// One undirected edge (a < b) and how the triangles use it.
struct EdgeUse {
    uint32_t a = 0, b = 0;
    int uses = 0;     ///< triangles with this edge as a side
    int forward = 0;  ///< of those, how many traverse it a -> b
};

/// Everything check_mesh measures.
struct MeshStats {
    size_t vertices = 0;              ///< positions
    size_t triangles = 0;             ///< index triples
    size_t bad_indices = 0;           ///< indices >= vertices (such triangles are skipped)
    size_t degenerate_triangles = 0;  ///< triangles with a repeated index (skipped)
    size_t used_vertices = 0;         ///< vertices referenced by a valid triangle
    size_t edges = 0;                 ///< undirected edges of valid triangles
    size_t boundary_edges = 0;        ///< edges in exactly one triangle
    size_t nonmanifold_edges = 0;     ///< edges in three or more triangles
    size_t misoriented_edges = 0;     ///< edges in two triangles that run it the same way
    size_t components = 0;            ///< connected components of the used vertices via triangles
    long long euler = 0;              ///< used vertices - edges + valid triangles
    double area = 0.0;                ///< sum of triangle areas
    double volume = 0.0;              ///< signed enclosed volume (divergence theorem); > 0 when
                                      ///< triangles wind counter-clockwise seen from outside

    size_t unused_vertices() const { return vertices - used_vertices; }
    /// Every edge in exactly two triangles, each direction once; no bad triangles.
    bool closed_oriented_manifold() const {
        return bad_indices == 0 && degenerate_triangles == 0 && boundary_edges == 0 &&
               nonmanifold_edges == 0 && misoriented_edges == 0;
    }
};

/// The undirected edges of the mesh's valid triangles, sorted by (a, b).
inline std::vector<EdgeUse> edge_uses(size_t vertex_count, std::span<const uint32_t> indices) {
    struct Directed {
        uint64_t key;
        bool forward;
    };
    std::vector<Directed> directed;
    directed.reserve(indices.size());
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        const uint32_t v[3] = {indices[t], indices[t + 1], indices[t + 2]};
        if (v[0] >= vertex_count || v[1] >= vertex_count || v[2] >= vertex_count) continue;
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) continue;
        for (int s = 0; s < 3; ++s) {
            const uint32_t p = v[s], q = v[(s + 1) % 3];
            const uint64_t lo = std::min(p, q), hi = std::max(p, q);
            directed.push_back({(lo << 32) | hi, p < q});
        }
    }
    std::sort(directed.begin(), directed.end(),
              [](const Directed& x, const Directed& y) { return x.key < y.key; });
    std::vector<EdgeUse> edges;
    for (size_t i = 0; i < directed.size();) {
        EdgeUse e;
        e.a = static_cast<uint32_t>(directed[i].key >> 32);
        e.b = static_cast<uint32_t>(directed[i].key & 0xffffffffu);
        size_t j = i;
        for (; j < directed.size() && directed[j].key == directed[i].key; ++j) {
            ++e.uses;
            e.forward += directed[j].forward ? 1 : 0;
        }
        edges.push_back(e);
        i = j;
    }
    return edges;
}

/// Edges used by exactly one triangle (the mesh's open boundary).
inline std::vector<EdgeUse> boundary_edges(size_t vertex_count, std::span<const uint32_t> indices) {
    std::vector<EdgeUse> out;
    for (const EdgeUse& e : edge_uses(vertex_count, indices)) {
        if (e.uses == 1) out.push_back(e);
    }
    return out;
}

/// Topology (edge use, orientation, Euler characteristic, components) and geometry
/// (area, signed volume) of an indexed triangle mesh.
inline MeshStats check_mesh(std::span<const Vec3> positions, std::span<const uint32_t> indices) {
    MeshStats s;
    s.vertices = positions.size();
    s.triangles = indices.size() / 3;

    std::vector<uint32_t> parent(positions.size());
    std::iota(parent.begin(), parent.end(), 0u);
    const auto find = [&parent](uint32_t x) {
        while (parent[x] != x) {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        return x;
    };
    std::vector<char> used(positions.size(), 0);
    size_t valid = 0;
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        const uint32_t v[3] = {indices[t], indices[t + 1], indices[t + 2]};
        if (v[0] >= s.vertices || v[1] >= s.vertices || v[2] >= s.vertices) {
            ++s.bad_indices;
            continue;
        }
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
            ++s.degenerate_triangles;
            continue;
        }
        ++valid;
        for (uint32_t x : v) used[x] = 1;
        parent[find(v[1])] = find(v[0]);
        parent[find(v[2])] = find(v[0]);

        const glm::dvec3 a(positions[v[0]]), b(positions[v[1]]), c(positions[v[2]]);
        s.area += 0.5 * glm::length(glm::cross(b - a, c - a));
        s.volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    for (size_t i = 0; i < positions.size(); ++i) {
        if (!used[i]) continue;
        ++s.used_vertices;
        if (find(static_cast<uint32_t>(i)) == i) ++s.components;
    }

    const std::vector<EdgeUse> edges = edge_uses(s.vertices, indices);
    s.edges = edges.size();
    for (const EdgeUse& e : edges) {
        if (e.uses == 1) ++s.boundary_edges;
        if (e.uses > 2) ++s.nonmanifold_edges;
        if (e.uses == 2 && e.forward != 1) ++s.misoriented_edges;
    }
    s.euler = static_cast<long long>(s.used_vertices) - static_cast<long long>(s.edges) +
              static_cast<long long>(valid);
    return s;
}

template <class Mesh>
inline MeshStats check_mesh(const Mesh& mesh) {
    return check_mesh(std::span<const Vec3>(mesh.positions), std::span<const uint32_t>(mesh.indices));
}

/// Number of positions equal (bit for bit, as floats) to an earlier one.
inline size_t count_duplicate_positions(std::span<const Vec3> positions) {
    std::vector<Vec3> sorted(positions.begin(), positions.end());
    const auto less = [](const Vec3& p, const Vec3& q) {
        if (p.x != q.x) return p.x < q.x;
        if (p.y != q.y) return p.y < q.y;
        return p.z < q.z;
    };
    std::sort(sorted.begin(), sorted.end(), less);
    size_t dup = 0;
    for (size_t i = 1; i < sorted.size(); ++i) {
        if (sorted[i] == sorted[i - 1]) ++dup;
    }
    return dup;
}

/// Whether segment p-q crosses the interior of triangle a, b, c (Moller-Trumbore in
/// double; touching an edge or a corner, or lying in its plane, does not count).
inline bool segment_crosses_triangle(const glm::dvec3& p, const glm::dvec3& q, const glm::dvec3& a,
                                     const glm::dvec3& b, const glm::dvec3& c) {
    const glm::dvec3 d = q - p, e1 = b - a, e2 = c - a;
    const glm::dvec3 h = glm::cross(d, e2);
    const double det = glm::dot(e1, h);
    if (std::abs(det) < 1e-18) return false;
    const double inv = 1.0 / det;
    const glm::dvec3 s = p - a;
    const double u = glm::dot(s, h) * inv;
    if (u <= 0.0 || u >= 1.0) return false;
    const glm::dvec3 qv = glm::cross(s, e1);
    const double v = glm::dot(d, qv) * inv;
    if (v <= 0.0 || u + v >= 1.0) return false;
    const double t = glm::dot(e2, qv) * inv;
    return t > 0.0 && t < 1.0;
}

/// Pairs of triangles that share no vertex and intersect (an edge of one crosses the
/// other's interior): a mesh that passes through itself. Broad phase: a uniform grid of
/// cells twice the mean edge length over the triangles' boxes.
inline size_t count_self_intersections(std::span<const Vec3> positions, std::span<const uint32_t> indices) {
    const size_t nt = indices.size() / 3;
    if (nt < 2) return 0;
    double edge = 0.0;
    glm::dvec3 lo(1e300), hi(-1e300);
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const glm::dvec3 a(positions[indices[3 * t + k]]), b(positions[indices[3 * t + (k + 1) % 3]]);
            edge += glm::length(b - a);
            lo = glm::min(lo, a);
            hi = glm::max(hi, a);
        }
    const double cell = std::max(2.0 * edge / double(3 * nt), 1e-6);
    const glm::ivec3 n = glm::max(glm::ivec3(glm::floor((hi - lo) / cell)) + 1, glm::ivec3(1));
    const auto key = [&](int i, int j, int k) { return (size_t(k) * size_t(n.y) + size_t(j)) * size_t(n.x) + size_t(i); };
    std::vector<std::vector<uint32_t>> cells(size_t(n.x) * n.y * n.z);
    const auto box = [&](size_t t, glm::ivec3& a, glm::ivec3& b) {
        glm::dvec3 mn(1e300), mx(-1e300);
        for (int k = 0; k < 3; ++k) {
            mn = glm::min(mn, glm::dvec3(positions[indices[3 * t + k]]));
            mx = glm::max(mx, glm::dvec3(positions[indices[3 * t + k]]));
        }
        a = glm::clamp(glm::ivec3(glm::floor((mn - lo) / cell)), glm::ivec3(0), n - 1);
        b = glm::clamp(glm::ivec3(glm::floor((mx - lo) / cell)), glm::ivec3(0), n - 1);
    };
    for (size_t t = 0; t < nt; ++t) {
        glm::ivec3 a, b;
        box(t, a, b);
        for (int k = a.z; k <= b.z; ++k)
            for (int j = a.y; j <= b.y; ++j)
                for (int i = a.x; i <= b.x; ++i) cells[key(i, j, k)].push_back(static_cast<uint32_t>(t));
    }
    std::vector<size_t> seen(nt, SIZE_MAX);
    size_t count = 0;
    for (size_t t = 0; t < nt; ++t) {
        glm::ivec3 a, b;
        box(t, a, b);
        const uint32_t* ti = &indices[3 * t];
        const glm::dvec3 p[3] = {glm::dvec3(positions[ti[0]]), glm::dvec3(positions[ti[1]]), glm::dvec3(positions[ti[2]])};
        for (int k = a.z; k <= b.z; ++k)
            for (int j = a.y; j <= b.y; ++j)
                for (int i = a.x; i <= b.x; ++i)
                    for (const uint32_t u : cells[key(i, j, k)]) {
                        if (u <= t || seen[u] == t) continue;
                        seen[u] = t;
                        const uint32_t* ui = &indices[3 * size_t(u)];
                        bool shared = false;
                        for (int x = 0; x < 3; ++x)
                            for (int y = 0; y < 3; ++y) shared |= ti[x] == ui[y];
                        if (shared) continue;
                        const glm::dvec3 r[3] = {glm::dvec3(positions[ui[0]]), glm::dvec3(positions[ui[1]]),
                                                 glm::dvec3(positions[ui[2]])};
                        bool hit = false;
                        for (int e = 0; e < 3 && !hit; ++e) {
                            hit = segment_crosses_triangle(p[e], p[(e + 1) % 3], r[0], r[1], r[2]) ||
                                  segment_crosses_triangle(r[e], r[(e + 1) % 3], p[0], p[1], p[2]);
                        }
                        count += hit ? 1 : 0;
                    }
    }
    return count;
}

}  // namespace mr::test
