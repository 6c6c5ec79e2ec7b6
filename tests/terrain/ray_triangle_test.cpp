// Ray/triangle tests: Moller-Trumbore (the paper's eq. 4) and the watertight test of
// Woop, Benthin and Wald (JCGT 2013).
#include <metariver/terrain.h>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

namespace mr {
namespace {

using Fn = std::optional<float> (*)(const Vec3&, const Vec3&, const Vec3&, const Vec3&, const Vec3&);

class BothTests : public ::testing::TestWithParam<Fn> {};

TEST_P(BothTests, SimpleHitBothFaces) {
    const Fn f = GetParam();
    const Vec3 a(0, 0, 0), b(0, 0, 1), c(1, 0, 0);  // up-facing, paper winding
    const auto down = f(Vec3(0.25f, 1.0f, 0.25f), Vec3(0, -2.0f, 0), a, b, c);
    ASSERT_TRUE(down.has_value());
    EXPECT_FLOAT_EQ(*down, 0.5f);  // 4 ulps: t comes out of float arithmetic
    const auto up = f(Vec3(0.25f, -1.0f, 0.25f), Vec3(0, 4.0f, 0), a, b, c);  // from below: back face
    ASSERT_TRUE(up.has_value());
    EXPECT_FLOAT_EQ(*up, 0.25f);  // same reason
    // Slanted.
    const auto slant = f(Vec3(0.0f, 1.0f, 0.0f), Vec3(0.5f, -2.0f, 0.5f), a, b, c);
    ASSERT_TRUE(slant.has_value());
    EXPECT_FLOAT_EQ(*slant, 0.5f);  // same reason
}

TEST_P(BothTests, SegmentLimitsAndMisses) {
    const Fn f = GetParam();
    const Vec3 a(0, 0, 0), b(0, 0, 1), c(1, 0, 0);
    EXPECT_FALSE(f(Vec3(0.25f, 1.0f, 0.25f), Vec3(0, -0.9f, 0), a, b, c));  // stops short
    EXPECT_FALSE(f(Vec3(0.25f, 1.0f, 0.25f), Vec3(0, 2.0f, 0), a, b, c));   // points away
    EXPECT_FALSE(f(Vec3(0.75f, 1.0f, 0.75f), Vec3(0, -2.0f, 0), a, b, c));  // outside the hypotenuse
    EXPECT_FALSE(f(Vec3(-0.1f, 1.0f, 0.5f), Vec3(0, -2.0f, 0), a, b, c));   // outside an edge
    EXPECT_FALSE(f(Vec3(0.2f, 1.0f, 0.2f), Vec3(1.0f, 0.0f, 0.0f), a, b, c));  // parallel
    EXPECT_FALSE(f(Vec3(0.2f, 1.0f, 0.2f), Vec3(0.0f), a, b, c));              // zero length
    EXPECT_FALSE(f(Vec3(0.2f, 1.0f, 0.2f), Vec3(0, -2, 0), a, a, c));          // degenerate
    EXPECT_FALSE(f(Vec3(NAN, 1.0f, 0.2f), Vec3(0, -2, 0), a, b, c));
    EXPECT_FALSE(f(Vec3(0.2f, 1.0f, 0.2f), Vec3(0, -INFINITY, 0), a, b, c));
    // End points touching the plane count (t = 0 and t = 1).
    const auto t1 = f(Vec3(0.25f, 1.0f, 0.25f), Vec3(0, -1.0f, 0), a, b, c);
    ASSERT_TRUE(t1.has_value());
    EXPECT_EQ(*t1, 1.0f);
    const auto t0 = f(Vec3(0.25f, 0.0f, 0.25f), Vec3(0, -1.0f, 0), a, b, c);
    ASSERT_TRUE(t0.has_value());
    EXPECT_EQ(*t0, 0.0f);
}

INSTANTIATE_TEST_SUITE_P(RayTriangle, BothTests, ::testing::Values(&ray_triangle_paper, &ray_triangle_watertight));

/// Barycentrics and t of the ray/plane hit in double precision (reference).
struct Reference {
    bool parallel;
    double t, u, v;
};
Reference reference(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c) {
    const glm::dvec3 O(o), D(d), A(a), B(b), C(c);
    const glm::dvec3 e1 = B - A, e2 = C - A, p = glm::cross(D, e2);
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-9) return {true, 0, 0, 0};
    const glm::dvec3 s = O - A, q = glm::cross(s, e1);
    return {false, glm::dot(e2, q) / det, glm::dot(s, p) / det, glm::dot(D, q) / det};
}

TEST(RayTriangle, PaperAndWatertightAgreeOnRandomRays) {
    Lcg rng(42);
    int hits = 0, misses = 0;
    for (int k = 0; k < 20000; ++k) {
        auto rv = [&](float lo, float hi) { return Vec3(rng.uniform(lo, hi), rng.uniform(lo, hi), rng.uniform(lo, hi)); };
        const Vec3 a = rv(-1, 1), b = rv(-1, 1), c = rv(-1, 1);
        const Vec3 o = rv(-3, 3);
        Vec3 d = rv(-4, 4);
        if (k % 2 == 0) {
            // Aim at a random point of the triangle's plane near it; reach it at t in (0.3, 1.2).
            const float u = rng.uniform(-0.3f, 1.0f), v = rng.uniform(-0.3f, 1.0f);
            d = (a + u * (b - a) + v * (c - a) - o) * rng.uniform(0.8f, 3.3f);
        }
        const Reference r = reference(o, d, a, b, c);
        if (r.parallel) continue;
        const auto p = ray_triangle_paper(o, d, a, b, c);
        const auto w = ray_triangle_watertight(o, d, a, b, c);
        // Only clear cases: barycentrics and t at least 1e-3 away from every boundary
        // (float rounding may decide either way closer to an edge).
        const double m = 1e-3;
        const double w0 = 1.0 - r.u - r.v;
        const bool clearly_in = r.u > m && r.v > m && w0 > m && r.t > m && r.t < 1 - m;
        const bool clearly_out = r.u < -m || r.v < -m || w0 < -m || r.t < -m || r.t > 1 + m;
        if (clearly_in) {
            ++hits;
            ASSERT_TRUE(p.has_value()) << k;
            ASSERT_TRUE(w.has_value()) << k;
            EXPECT_NEAR(*p, r.t, 1e-3 * (1 + std::abs(r.t)));  // float vs double, random (ill-conditioned) triangles
            EXPECT_NEAR(*w, r.t, 1e-3 * (1 + std::abs(r.t)));  // same reason
            EXPECT_NEAR(*p, *w, 1e-3f);                        // same reason
        } else if (clearly_out) {
            ++misses;
            EXPECT_FALSE(p.has_value()) << k;
            EXPECT_FALSE(w.has_value()) << k;
        }
    }
    EXPECT_GT(hits, 1000);
    EXPECT_GT(misses, 1000);
}

/// Random terrain whose slopes stay below 1 so steep rays cross it exactly once.
Terrain gentle_terrain(int w, int h, float s, uint32_t seed) {
    Heightmap m;
    m.width = w;
    m.height = h;
    Lcg rng(seed);
    m.samples.resize(static_cast<size_t>(w) * h);
    for (float& v : m.samples) v = static_cast<float>(rng.next());
    auto t = Terrain::build(m, TerrainDef{s, 0.5f * s, true});
    EXPECT_TRUE(t.ok());
    return std::move(t).value();
}

template <class F>
bool hits_any(const Terrain& t, const Vec3& o, const Vec3& d, F f) {
    const auto v = t.vertices();
    const auto idx = t.indices();
    for (size_t tri = 0; tri < t.triangle_count(); ++tri) {
        if (f(o, d, v[idx[3 * tri]], v[idx[3 * tri + 1]], v[idx[3 * tri + 2]])) return true;
    }
    return false;
}

TEST(RayTriangle, WatertightNeverMissesSharedEdgesAndVertices) {
    // Rays aimed exactly at interior grid vertices, at points on cell diagonals and on
    // grid edges of a random terrain (odd area scale, so coordinates are inexact).
    // Vertical rays and steep slanted rays (horizontal/vertical <= 1, steeper than any
    // triangle: each ray crosses the surface exactly once, near the aimed point).
    const Terrain t = gentle_terrain(12, 10, 0.37f, 2024);
    const auto v = t.vertices();
    const int W = t.columns(), H = t.rows();
    Lcg rng(77);
    long rays = 0, watertight_misses = 0, paper_misses = 0;
    for (int i = 1; i + 1 < H; ++i) {
        for (int j = 1; j + 1 < W; ++j) {
            const Vec3 p00 = v[static_cast<size_t>(i) * W + j];
            const Vec3 p10 = v[static_cast<size_t>(i + 1) * W + j];
            const Vec3 p01 = v[static_cast<size_t>(i) * W + j + 1];
            for (int k = 0; k < 12; ++k) {
                Vec3 target;
                if (k < 4) {
                    target = p00;  // a vertex shared by six triangles
                } else if (k < 8) {
                    target = p10 + rng.uniform(0.0f, 1.0f) * (p01 - p10);  // the cell diagonal
                } else {
                    target = p00 + rng.uniform(0.0f, 1.0f) * (p01 - p00);  // a grid edge along x
                }
                Vec3 d(0.0f, -2.0f, 0.0f);
                if (k % 4 != 0) d = Vec3(rng.uniform(-1.0f, 1.0f), -2.0f, rng.uniform(-1.0f, 1.0f));
                const Vec3 o = target - 0.5f * d;  // the segment passes the target at t = 0.5
                ++rays;
                if (!hits_any(t, o, d, ray_triangle_watertight)) ++watertight_misses;
                if (!hits_any(t, o, d, ray_triangle_paper)) ++paper_misses;
            }
        }
    }
    EXPECT_EQ(watertight_misses, 0) << "of " << rays << " rays";
    std::cout << "[ info ] edge/vertex rays: " << rays << ", paper (Moller-Trumbore) misses: " << paper_misses
              << ", watertight misses: " << watertight_misses << "\n";
    ::testing::Test::RecordProperty("paper_misses", static_cast<int>(paper_misses));
}

TEST(RayTriangle, WatertightNeverMissesOnRandomVerticalRays) {
    // Also on the paper's unit grid with exact vertex and diagonal coordinates.
    const Terrain t = gentle_terrain(9, 9, 1.0f, 7);
    long misses = 0, paper_misses = 0, rays = 0;
    for (int i = 1; i < 16; ++i) {
        for (int j = 1; j < 16; ++j) {
            // Interior half-sample lattice: vertices, edge midpoints and cell centres
            // (which lie on the cell diagonals), all exact in float.
            const float x = 0.5f * static_cast<float>(j), z = 0.5f * static_cast<float>(i);
            const Vec3 o(x, 10.0f, z), d(0.0f, -20.0f, 0.0f);
            ++rays;
            if (!hits_any(t, o, d, ray_triangle_watertight)) ++misses;
            if (!hits_any(t, o, d, ray_triangle_paper)) ++paper_misses;
        }
    }
    EXPECT_EQ(misses, 0) << "of " << rays;
    std::cout << "[ info ] lattice vertical rays: " << rays << ", paper misses: " << paper_misses << "\n";
}

}  // namespace
}  // namespace mr
