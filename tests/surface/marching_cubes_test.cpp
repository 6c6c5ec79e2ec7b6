// Tests for extract_surface: closed 2-manifolds from a metaball, exact placement on a
// linear field, watertight and consistently oriented meshes from random fields, one
// vertex per crossed grid edge, capacity reuse, and degenerate input.
#include <metariver/surface.h>

#include "mesh_check.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>

namespace mr {
namespace {

using test::check_mesh;

void fill(ScalarGrid& g, const std::function<float(Vec3)>& f) {
    for (int k = 0; k < g.nz; ++k)
        for (int j = 0; j < g.ny; ++j)
            for (int i = 0; i < g.nx; ++i) g.values[g.index(i, j, k)] = f(g.position(i, j, k));
}

// One metaball, the paper's 1/r^2 falloff: inside (value > 1/R^2) is the ball of radius R.
ScalarGrid metaball_grid(int n, Vec3 origin, float spacing, Vec3 center) {
    ScalarGrid g;
    g.reset(n, n, n, origin, spacing);
    fill(g, [&](Vec3 p) {
        const Vec3 d = p - center;
        return 1.0f / std::max(glm::dot(d, d), 1e-6f);
    });
    return g;
}

ScalarGrid random_grid(int nx, int ny, int nz, uint32_t seed) {
    ScalarGrid g;
    g.reset(nx, ny, nz, Vec3(-1.0f, 2.0f, 0.5f), 0.75f);
    Lcg rng(seed);
    for (float& v : g.values) v = rng.uniform(0.0f, 1.0f);
    return g;
}

// Crossed grid edges, counted straight from the samples.
size_t crossed_edges(const ScalarGrid& g, float threshold) {
    size_t n = 0;
    for (int k = 0; k < g.nz; ++k)
        for (int j = 0; j < g.ny; ++j)
            for (int i = 0; i < g.nx; ++i) {
                const bool in = g.at(i, j, k) > threshold;
                if (i + 1 < g.nx && in != (g.at(i + 1, j, k) > threshold)) ++n;
                if (j + 1 < g.ny && in != (g.at(i, j + 1, k) > threshold)) ++n;
                if (k + 1 < g.nz && in != (g.at(i, j, k + 1) > threshold)) ++n;
            }
    return n;
}

// True when p lies on one of the grid's six boundary planes.
bool on_grid_boundary(const ScalarGrid& g, Vec3 p, int axis, int side) {
    const int n[3] = {g.nx, g.ny, g.nz};
    const float plane = g.origin[axis] + g.spacing * float(side ? n[axis] - 1 : 0);
    return p[axis] == plane;  // vertices on a boundary plane copy its coordinate exactly
}

bool edge_on_grid_boundary(const ScalarGrid& g, Vec3 a, Vec3 b) {
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side)
            if (on_grid_boundary(g, a, axis, side) && on_grid_boundary(g, b, axis, side)) return true;
    return false;
}

// The checker itself, on meshes whose answers are known.
TEST(MeshCheck, MeasuresAKnownTetrahedron) {
    const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    // Counter-clockwise seen from outside.
    std::vector<uint32_t> idx = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    test::MeshStats s = check_mesh(p, idx);
    EXPECT_TRUE(s.closed_oriented_manifold());
    EXPECT_EQ(s.edges, 6u);
    EXPECT_EQ(s.euler, 2);
    EXPECT_EQ(s.components, 1u);
    EXPECT_NEAR(s.volume, 1.0 / 6.0, 1e-12);  // double sums of exact small values
    EXPECT_NEAR(s.area, 1.5 + std::sqrt(3.0) / 2.0, 1e-6);  // float inputs, double sums

    std::swap(idx[1], idx[2]);  // flip one face
    s = check_mesh(p, idx);
    EXPECT_EQ(s.misoriented_edges, 3u);
    EXPECT_EQ(s.boundary_edges, 0u);

    idx.resize(9);  // drop a face: an open surface, a disc
    std::swap(idx[1], idx[2]);
    s = check_mesh(p, idx);
    EXPECT_EQ(s.boundary_edges, 3u);
    EXPECT_EQ(s.misoriented_edges, 0u);
    EXPECT_EQ(s.euler, 1);
    EXPECT_EQ(test::boundary_edges(p.size(), idx).size(), 3u);

    idx.insert(idx.end(), {0, 1, 3, 0, 0, 2, 7, 1, 2});  // a third use of 0-1 and 3-0, a repeat, a bad index
    s = check_mesh(p, idx);
    EXPECT_EQ(s.nonmanifold_edges, 2u);
    EXPECT_EQ(s.degenerate_triangles, 1u);
    EXPECT_EQ(s.bad_indices, 1u);

    const std::vector<Vec3> q = {{0, 0, 0}, {1, 2, 3}, {0, 0, 0}, {1, 2, 3}, {1, 2, 4}, {5, 5, 5}};
    EXPECT_EQ(test::count_duplicate_positions(q), 2u);
    const std::vector<uint32_t> two = {0, 1, 4, 2, 3, 5};  // no shared index: 2 components
    EXPECT_EQ(check_mesh(q, two).components, 2u);
    EXPECT_EQ(check_mesh(q, two).unused_vertices(), 0u);
}

TEST(MarchingCubes, MetaballIsAClosedSphere) {
    const Vec3 center(15.37f, 16.21f, 15.83f);  // off the grid points
    const float radius = 5.3f;                  // cells
    const ScalarGrid g = metaball_grid(32, Vec3(0.0f), 1.0f, center);
    SurfaceMesh mesh;
    extract_surface(g, 1.0f / (radius * radius), mesh);

    const test::MeshStats s = check_mesh(mesh);
    ASSERT_GT(s.triangles, 100u);
    EXPECT_TRUE(s.closed_oriented_manifold());
    EXPECT_EQ(s.boundary_edges, 0u);
    EXPECT_EQ(s.nonmanifold_edges, 0u);
    EXPECT_EQ(s.misoriented_edges, 0u);
    EXPECT_EQ(s.degenerate_triangles, 0u);
    EXPECT_EQ(s.euler, 2);
    EXPECT_EQ(s.components, 1u);
    EXPECT_EQ(s.unused_vertices(), 0u);
    EXPECT_EQ(mesh.vertex_count(), crossed_edges(g, 1.0f / (radius * radius)));

    const double pi = std::numbers::pi;
    const double volume = 4.0 / 3.0 * pi * radius * radius * radius;
    const double area = 4.0 * pi * radius * radius;
    // Facets are chords of the sphere: measured 0.5% low in volume and 0.06% high in
    // area at 5.3 cells per radius; 1.5% leaves room for other off-grid centres.
    EXPECT_NEAR(s.volume, volume, 0.015 * volume);
    EXPECT_NEAR(s.area, area, 0.015 * area);

    for (size_t i = 0; i < mesh.vertex_count(); ++i) {
        const Vec3 d = mesh.positions[i] - center;
        // Linear interpolation of 1/r^2 along an edge misplaces the crossing by at most
        // |f''/(2 f')| h^2 / 4 = 3 h^2 / (8 R) = 0.071 cell at R = 5.3 (leading order).
        EXPECT_NEAR(glm::length(d), radius, 0.08f) << "vertex " << i;
        EXPECT_NEAR(glm::length(mesh.normals[i]), 1.0f, 1e-5f);  // float normalisation
        // Central differences of 1/r^2 at ~5 cells: measured within 3 degrees of radial, 0.99 allows 8.
        EXPECT_GT(glm::dot(mesh.normals[i], glm::normalize(d)), 0.99f) << "vertex " << i;
    }
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
        const Vec3 a = mesh.positions[mesh.indices[3 * t]];
        const Vec3 b = mesh.positions[mesh.indices[3 * t + 1]];
        const Vec3 c = mesh.positions[mesh.indices[3 * t + 2]];
        const Vec3 n = glm::cross(b - a, c - a);
        // Outward = -gradient of 1/r^2 = away from the centre.
        EXPECT_GT(glm::dot(n, (a + b + c) / 3.0f - center), 0.0f) << "triangle " << t;
    }
}

TEST(MarchingCubes, HonoursOriginAndSpacing) {
    // The same ball in metres: spacing 0.25 m, shifted origin.
    const Vec3 origin(-3.0f, 1.0f, 2.0f);
    const float h = 0.25f;
    const Vec3 center = origin + h * Vec3(12.4f, 11.7f, 12.9f);
    const float radius = 6.1f * h;
    const ScalarGrid g = metaball_grid(26, origin, h, center);
    SurfaceMesh mesh;
    extract_surface(g, 1.0f / (radius * radius), mesh);
    const test::MeshStats s = check_mesh(mesh);
    EXPECT_TRUE(s.closed_oriented_manifold());
    EXPECT_EQ(s.euler, 2);
    const double volume = 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
    EXPECT_NEAR(s.volume, volume, 0.015 * volume);  // chords: measured 0.4% low, as above
    // 3 h^2 / (8 R) = 0.061 cell at R = 6.1 cells (see above).
    for (const Vec3& p : mesh.positions) EXPECT_NEAR(glm::length(p - center), radius, 0.07f * h);
}

TEST(MarchingCubes, LinearFieldIsReproducedExactly) {
    // f(p) = a . p + b is linear along every edge, so interpolation is exact.
    const Vec3 a(0.3f, 1.0f, -0.45f);
    const float b = -4.0f;
    ScalarGrid g;
    g.reset(9, 10, 11, Vec3(0.5f, -1.0f, 2.0f), 0.8f);
    fill(g, [&](Vec3 p) { return glm::dot(a, p) + b; });
    const float iso = 0.37f;
    SurfaceMesh mesh;
    extract_surface(g, iso, mesh);

    const test::MeshStats s = check_mesh(mesh);
    ASSERT_GT(s.triangles, 0u);
    EXPECT_EQ(s.nonmanifold_edges, 0u);
    EXPECT_EQ(s.misoriented_edges, 0u);
    EXPECT_EQ(s.components, 1u);
    EXPECT_EQ(s.euler, 1);  // an open disc
    const Vec3 outward = -glm::normalize(a);
    for (size_t i = 0; i < mesh.vertex_count(); ++i) {
        const Vec3 p = mesh.positions[i];
        EXPECT_NEAR(glm::dot(a, p) + b, iso, 1e-5f);  // float rounding of positions ~8 m from 0
        // Central and one-sided differences of a linear field are exact up to float rounding.
        EXPECT_NEAR(glm::dot(mesh.normals[i], outward), 1.0f, 1e-5f);
    }
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
        const Vec3 p0 = mesh.positions[mesh.indices[3 * t]];
        const Vec3 p1 = mesh.positions[mesh.indices[3 * t + 1]];
        const Vec3 p2 = mesh.positions[mesh.indices[3 * t + 2]];
        const Vec3 n = glm::cross(p1 - p0, p2 - p0);
        EXPECT_GE(glm::dot(n, outward), 0.0f);  // zero-area slivers allowed; never backwards
    }
    for (const test::EdgeUse& e : test::boundary_edges(mesh.vertex_count(), mesh.indices)) {
        EXPECT_TRUE(edge_on_grid_boundary(g, mesh.positions[e.a], mesh.positions[e.b]));
    }
}

TEST(MarchingCubes, RandomFieldsGiveManifoldOrientedMeshes) {
    for (uint32_t seed = 1; seed <= 6; ++seed) {
        for (float threshold : {0.2f, 0.5f, 0.8f}) {
            const ScalarGrid g = random_grid(7, 9, 11, seed);
            SurfaceMesh mesh;
            extract_surface(g, threshold, mesh);
            SCOPED_TRACE(testing::Message() << "seed " << seed << " threshold " << threshold);
            const test::MeshStats s = check_mesh(mesh);
            ASSERT_GT(s.triangles, 0u);
            EXPECT_EQ(s.bad_indices, 0u);
            EXPECT_EQ(s.degenerate_triangles, 0u);
            EXPECT_EQ(s.nonmanifold_edges, 0u);
            EXPECT_EQ(s.misoriented_edges, 0u);
            EXPECT_EQ(s.unused_vertices(), 0u);
            EXPECT_EQ(test::count_duplicate_positions(mesh.positions), 0u);
            EXPECT_EQ(mesh.vertex_count(), crossed_edges(g, threshold));
            EXPECT_EQ(mesh.normals.size(), mesh.vertex_count());
            // Watertight inside the grid: the only open edges run along its boundary.
            for (const test::EdgeUse& e : test::boundary_edges(mesh.vertex_count(), mesh.indices)) {
                EXPECT_TRUE(edge_on_grid_boundary(g, mesh.positions[e.a], mesh.positions[e.b]));
            }
            for (const Vec3& n : mesh.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);  // float normalisation
        }
    }
}

TEST(MarchingCubes, RandomFieldsWithOutsideBorderAreClosed) {
    // Outside on the grid border closes every component: a closed oriented surface,
    // each component a sphere with handles, so V - E + F is even; positive volume.
    for (uint32_t seed = 11; seed <= 16; ++seed) {
        ScalarGrid g = random_grid(10, 8, 9, seed);
        for (int k = 0; k < g.nz; ++k)
            for (int j = 0; j < g.ny; ++j)
                for (int i = 0; i < g.nx; ++i)
                    if (i == 0 || j == 0 || k == 0 || i == g.nx - 1 || j == g.ny - 1 || k == g.nz - 1)
                        g.values[g.index(i, j, k)] = 0.0f;
        SurfaceMesh mesh;
        extract_surface(g, 0.45f, mesh);
        SCOPED_TRACE(testing::Message() << "seed " << seed);
        const test::MeshStats s = check_mesh(mesh);
        ASSERT_GT(s.triangles, 0u);
        EXPECT_TRUE(s.closed_oriented_manifold());
        EXPECT_EQ(s.euler % 2, 0);
        EXPECT_LE(s.euler, 2 * static_cast<long long>(s.components));
        EXPECT_GT(s.volume, 0.0);
        EXPECT_EQ(mesh.vertex_count(), crossed_edges(g, 0.45f));
    }
}

TEST(MarchingCubes, OneVertexPerCrossedEdgeOnTheEdge) {
    const ScalarGrid g = random_grid(6, 5, 7, 99u);
    const float threshold = 0.5f;
    SurfaceMesh mesh;
    extract_surface(g, threshold, mesh);
    ASSERT_EQ(mesh.vertex_count(), crossed_edges(g, threshold));
    // Every vertex sits strictly inside a crossed grid edge, where the edge's linear
    // interpolant equals the threshold.
    for (const Vec3& p : mesh.positions) {
        const Vec3 q = (p - g.origin) / g.spacing;
        int fractional = -1, count = 0;
        for (int axis = 0; axis < 3; ++axis) {
            if (std::abs(q[axis] - std::round(q[axis])) > 1e-5f) {  // grid coordinates are exact up to float rounding
                fractional = axis;
                ++count;
            }
        }
        ASSERT_EQ(count, 1) << "vertex not on a grid edge";
        int c[3] = {int(std::round(q.x)), int(std::round(q.y)), int(std::round(q.z))};
        c[fractional] = int(std::floor(q[fractional]));
        int d[3] = {c[0], c[1], c[2]};
        ++d[fractional];
        const float fa = g.at(c[0], c[1], c[2]), fb = g.at(d[0], d[1], d[2]);
        EXPECT_NE(fa > threshold, fb > threshold);
        const float t = q[fractional] - float(c[fractional]);
        EXPECT_NEAR(fa + t * (fb - fa), threshold, 1e-5f);  // float rounding of t
    }
}

TEST(MarchingCubes, ReusesCapacityAndIsDeterministic) {
    const ScalarGrid big = metaball_grid(24, Vec3(0.0f), 1.0f, Vec3(11.3f, 12.1f, 10.7f));
    const ScalarGrid small = random_grid(5, 6, 7, 3u);
    SurfaceMesh first, mesh;
    extract_surface(big, 0.02f, first);
    extract_surface(big, 0.02f, mesh);
    EXPECT_EQ(mesh.positions, first.positions);
    EXPECT_EQ(mesh.normals, first.normals);
    EXPECT_EQ(mesh.indices, first.indices);

    const Vec3* positions = mesh.positions.data();
    const Vec3* normals = mesh.normals.data();
    const uint32_t* indices = mesh.indices.data();
    extract_surface(big, 0.02f, mesh);
    extract_surface(small, 0.5f, mesh);
    ASSERT_LT(mesh.indices.size(), first.indices.size());
    EXPECT_EQ(mesh.positions.data(), positions);  // refilled in place, no reallocation
    EXPECT_EQ(mesh.normals.data(), normals);
    EXPECT_EQ(mesh.indices.data(), indices);
    SurfaceMesh fresh;
    extract_surface(small, 0.5f, fresh);
    EXPECT_EQ(mesh.positions, fresh.positions);
    EXPECT_EQ(mesh.indices, fresh.indices);
}

TEST(MarchingCubes, DegenerateGridsGiveEmptyMeshes) {
    SurfaceMesh mesh;
    mesh.positions.push_back(Vec3(1.0f));  // stale content must be cleared
    mesh.indices.push_back(0);
    for (auto [nx, ny, nz] : {std::array{0, 0, 0}, std::array{1, 1, 1}, std::array{2, 1, 5}, std::array{5, 5, 1}}) {
        ScalarGrid g;
        g.reset(nx, ny, nz, Vec3(0.0f), 1.0f, 1.0f);
        extract_surface(g, 0.5f, mesh);
        EXPECT_EQ(mesh.vertex_count(), 0u);
        EXPECT_EQ(mesh.triangle_count(), 0u);
        EXPECT_TRUE(mesh.normals.empty());
    }
    ScalarGrid g;
    g.reset(6, 7, 8, Vec3(0.0f), 1.0f, 2.0f);
    extract_surface(g, 0.5f, mesh);  // all inside
    EXPECT_EQ(mesh.triangle_count(), 0u);
    extract_surface(g, 2.0f, mesh);  // equal to the threshold is outside: all outside
    EXPECT_EQ(mesh.triangle_count(), 0u);
    for (size_t i = 0; i < g.values.size(); i += 2) g.values[i] = 1.0f;  // below, next to equal
    extract_surface(g, 2.0f, mesh);
    EXPECT_EQ(mesh.triangle_count(), 0u);
    g.values.clear();  // dimensions claim more samples than there are: refused, no read
    extract_surface(g, 0.5f, mesh);
    EXPECT_EQ(mesh.triangle_count(), 0u);
}

TEST(MarchingCubes, NonFiniteSamplesAreOutside) {
    ScalarGrid g = random_grid(8, 8, 8, 5u);
    Lcg rng(77u);
    const float specials[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                              -std::numeric_limits<float>::infinity()};
    for (int n = 0; n < 40; ++n) g.values[rng.next_u32() % g.values.size()] = specials[n % 3];
    SurfaceMesh mesh;
    extract_surface(g, 0.5f, mesh);
    const test::MeshStats s = check_mesh(mesh);
    ASSERT_GT(s.triangles, 0u);
    EXPECT_EQ(s.nonmanifold_edges, 0u);
    EXPECT_EQ(s.misoriented_edges, 0u);
    EXPECT_EQ(s.degenerate_triangles, 0u);
    EXPECT_EQ(mesh.vertex_count(), crossed_edges(g, 0.5f));  // NaN compares as outside here too
    for (size_t i = 0; i < mesh.vertex_count(); ++i) {
        EXPECT_TRUE(std::isfinite(mesh.positions[i].x) && std::isfinite(mesh.positions[i].y) &&
                    std::isfinite(mesh.positions[i].z));
        EXPECT_NEAR(glm::length(mesh.normals[i]), 1.0f, 1e-5f);  // float normalisation
    }
    for (const test::EdgeUse& e : test::boundary_edges(mesh.vertex_count(), mesh.indices)) {
        EXPECT_TRUE(edge_on_grid_boundary(g, mesh.positions[e.a], mesh.positions[e.b]));
    }
}

TEST(MarchingCubes, ThroughputOnALargeField) {
    // Not a pass/fail timing; prints cells per second and checks the big mesh is sound.
    const int n = 128;
    ScalarGrid g;
    g.reset(n, n, n, Vec3(0.0f), 1.0f);
    const Vec3 balls[] = {{40.2f, 50.3f, 60.1f}, {80.7f, 70.2f, 60.9f}, {60.1f, 90.4f, 50.3f}};
    fill(g, [&](Vec3 p) {
        float f = 0.0f;
        for (const Vec3& b : balls) f += 1.0f / std::max(glm::dot(p - b, p - b), 1e-6f);
        return f;
    });
    SurfaceMesh mesh;
    extract_surface(g, 1.0f / 400.0f, mesh);  // warm-up, sizes the buffers
    const auto t0 = std::chrono::steady_clock::now();
    extract_surface(g, 1.0f / 400.0f, mesh);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("[ info ] %d^3 grid: %zu triangles in %.2f ms (%.1f Mcells/s)\n", n, mesh.triangle_count(), ms,
                double(n - 1) * (n - 1) * (n - 1) / ms / 1e3);
    const test::MeshStats s = check_mesh(mesh);
    EXPECT_TRUE(s.closed_oriented_manifold());
    EXPECT_EQ(s.euler % 2, 0);
}

}  // namespace
}  // namespace mr
