// Smoothing of the marching-cubes mesh (issue 11): still water comes out flat, a river
// keeps its shape (volume, watertightness, no self-intersections), drops are spared, open
// rims stay put, and the result does not depend on the thread count.
//
// The river frames are particle positions saved from real runs (tests/surface/data, the
// header of each file says which scene, frame and commit); the field is built with the
// default scene's [field] (poly6, radius 1 m, 3 samples per metre, bounds offset 1 m,
// threshold 0.4), the smoothing is SmoothingDef's defaults (the default scene's).
#include <metariver/surface.h>

#include "mesh_check.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

namespace mr {
namespace {

constexpr float kRadius = 1.0f, kResolution = 3.0f, kOffset = 1.0f, kThreshold = 0.4f;

SmoothingDef default_smoothing() { return SmoothingDef{.method = SmoothingMethod::Laplacian}; }

std::vector<Vec3> load_xyz(const std::string& name) {
    std::ifstream in(std::string(METARIVER_SOURCE_DIR) + "/tests/surface/data/" + name);
    std::vector<Vec3> out;
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream s(line);
        Vec3 p;
        s >> p.x >> p.y >> p.z;
        out.push_back(p);
    }
    return out;
}

struct Built {
    SparseField field;
    KernelDef kernel = poly6_kernel(kRadius, 1.0f);
    SurfaceMesh mesh;
    SmoothingField weights() const { return SmoothingField{.field = &field, .kernel = kernel, .threshold = kThreshold}; }
};

void build(const std::vector<Vec3>& balls, Built& b) {
    SparseFieldDef def;
    def.kernel = b.kernel;
    def.resolution = kResolution;
    def.bounds_offset = kOffset;
    ASSERT_TRUE(b.field.build(balls, def).ok());
    SurfaceWorkspace ws;
    extract_surface_sparse(b.field, kThreshold, b.mesh, ws);
}

/// Builds the mesh of `balls` into b, keeps it as extracted in `raw` and smooths b's.
void build_and_smooth(const std::vector<Vec3>& balls, Built& b, SurfaceMesh& raw, SmoothingWorkspace& ws,
                      const SmoothingDef& def = default_smoothing()) {
    build(balls, b);
    raw = b.mesh;
    const SmoothingField w = b.weights();
    smooth_surface(b.mesh, def, ws, &w);
}

/// issue 11's measure (scripts/surface_flatness.py): vertices whose normal is within 60
/// degrees of +y, in the inner 60 % of their x and z range; RMS of the normals' tilt
/// (degrees) and standard deviation of the heights (metres).
struct Flatness {
    size_t vertices = 0;
    double tilt_rms = 0.0, height_std = 0.0;
};
Flatness flatness(const SurfaceMesh& m) {
    std::vector<size_t> up;
    for (size_t i = 0; i < m.vertex_count(); ++i)
        if (m.normals[i].y > 0.5f) up.push_back(i);
    Flatness f;
    if (up.empty()) return f;
    float x0 = 1e30f, x1 = -1e30f, z0 = 1e30f, z1 = -1e30f;
    for (size_t i : up) {
        x0 = std::min(x0, m.positions[i].x), x1 = std::max(x1, m.positions[i].x);
        z0 = std::min(z0, m.positions[i].z), z1 = std::max(z1, m.positions[i].z);
    }
    const float mx = 0.2f * (x1 - x0), mz = 0.2f * (z1 - z0);
    double t2 = 0.0, y = 0.0, y2 = 0.0;
    for (size_t i : up) {
        const Vec3& p = m.positions[i];
        if (p.x < x0 + mx || p.x > x1 - mx || p.z < z0 + mz || p.z > z1 - mz) continue;
        const double tilt = std::acos(std::clamp(double(m.normals[i].y) / glm::length(m.normals[i]), -1.0, 1.0)) * 180.0 / M_PI;
        t2 += tilt * tilt, y += p.y, y2 += double(p.y) * p.y;
        ++f.vertices;
    }
    const double n = double(f.vertices);
    f.tilt_rms = std::sqrt(t2 / n);
    f.height_std = std::sqrt(std::max(0.0, y2 / n - (y / n) * (y / n)));
    return f;
}

/// Signed volume of each connected component (by shared vertices), largest first.
std::vector<double> component_volumes(const SurfaceMesh& m) {
    std::vector<uint32_t> parent(m.vertex_count());
    std::iota(parent.begin(), parent.end(), 0u);
    const auto find = [&](uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        parent[find(m.indices[3 * t + 1])] = find(m.indices[3 * t]);
        parent[find(m.indices[3 * t + 2])] = find(m.indices[3 * t]);
    }
    std::vector<double> vol(m.vertex_count(), 0.0);
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const glm::dvec3 a(m.positions[m.indices[3 * t]]), b(m.positions[m.indices[3 * t + 1]]),
            c(m.positions[m.indices[3 * t + 2]]);
        vol[find(m.indices[3 * t])] += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    std::vector<double> out;
    for (size_t v = 0; v < vol.size(); ++v)
        if (find(uint32_t(v)) == v && vol[v] != 0.0) out.push_back(vol[v]);
    std::sort(out.rbegin(), out.rend());
    return out;
}

/// Still water: particles on a 0.5 m lattice (PBF's rest spacing) filling a 12 x 2 x 12 m
/// box, each moved by up to +-0.15 m (water at rest is not a lattice), and `missing` of
/// the top layer left out (gaps that water still settling has and water at rest fills).
std::vector<Vec3> jittered_pool(float missing = 0.0f) {
    std::vector<Vec3> balls;
    uint32_t state = 12345u;
    const auto next = [&] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24) - 0.5f;
    };
    for (int k = 0; k < 24; ++k)
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 24; ++i) {
                const Vec3 p = Vec3(0.5f * i, 0.5f * j, 0.5f * k) + 0.3f * Vec3(next(), next(), next());
                if (j == 3 && next() < -0.5f + missing) continue;
                balls.push_back(p);
            }
    return balls;
}

TEST(Smoothing, MethodNoneLeavesTheMeshAsExtracted) {
    Built b;
    SurfaceMesh raw;
    SmoothingWorkspace ws;
    build_and_smooth(jittered_pool(), b, raw, ws, SmoothingDef{});  // method None
    EXPECT_EQ(b.mesh.positions, raw.positions);
    EXPECT_EQ(b.mesh.normals, raw.normals);
    EXPECT_EQ(b.mesh.indices, raw.indices);
}

TEST(Smoothing, StepSizesDampTheBandTheyAreMadeFor) {
    // The filter of N steps is prod(1 - s_i k) at mesh frequency k (an eigenvalue of the
    // uniform Laplacian, in [0, 2]).
    const auto filter = [](const std::vector<float>& s, double k, double* peak = nullptr) {
        double p = 1.0;
        for (float x : s) {
            p *= 1.0 - double(x) * k;
            if (peak) *peak = std::max(*peak, std::abs(p));
        }
        return p;
    };
    const SmoothingDef d = default_smoothing();  // 8 Chebyshev steps on [0.1, 2]
    const std::vector<float> cheb = smoothing_step_sizes(d);
    ASSERT_EQ(cheb.size(), 8u);
    double worst = 0.0, peak = 1.0;
    for (int i = 0; i <= 1000; ++i) {
        const double k = d.pass_band + (2.0 - d.pass_band) * i / 1000.0;
        worst = std::max(worst, std::abs(filter(cheb, k, &peak)));
    }
    EXPECT_LT(worst, 0.06) << "the whole band [0.1, 2] is damped to a twentieth";
    EXPECT_LT(peak, 5.0) << "the steps in between stay bounded";
    // Twice as many uniform steps of 1 leave the bottom of that band at 0.19.
    EXPECT_GT(std::abs(filter(std::vector<float>(16, 1.0f), d.pass_band)), 0.18);
    // Longer runs are cycles of at most 8 steps, so nothing in between grows large.
    SmoothingDef many = d;
    many.iterations = 40;
    peak = 1.0;
    for (int i = 0; i <= 1000; ++i) filter(smoothing_step_sizes(many), 2.0 * i / 1000.0, &peak);
    EXPECT_LT(peak, 20.0);
    // Uniform: lambda every step; Taubin: lambda, mu, ... with mu = 1 / (k_PB - 1 / lambda).
    SmoothingDef u = d;
    u.steps = SmoothingSteps::Uniform;
    EXPECT_EQ(smoothing_step_sizes(u), std::vector<float>(8, d.lambda));
    SmoothingDef t = d;
    t.method = SmoothingMethod::Taubin;
    t.iterations = 3;
    const float mu = 1.0f / (t.pass_band - 1.0f / t.lambda);
    EXPECT_EQ(smoothing_step_sizes(t), (std::vector<float>{t.lambda, mu, t.lambda}));
    EXPECT_LT(mu, -t.lambda);
}

TEST(Smoothing, StillWaterComesOutFlat) {
    const auto measure = [](float missing, Flatness& before, Flatness& after, SmoothingStats& stats) {
        Built b;
        SurfaceMesh raw;
        SmoothingWorkspace ws;
        build_and_smooth(jittered_pool(missing), b, raw, ws);
        before = flatness(raw);
        after = flatness(b.mesh);
        stats = ws.stats;
    };
    Flatness before, after;
    SmoothingStats stats;
    measure(0.0f, before, after, stats);
    std::printf("still water at rest: %zu vertices, tilt RMS %.2f -> %.2f deg, height std %.4f -> %.4f m\n",
                after.vertices, before.tilt_rms, after.tilt_rms, before.height_std, after.height_std);
    ASSERT_GT(after.vertices, 100u);
    // The extracted top is bumpy at the particles' scale; smoothed it meets issue 11's
    // targets for still water (tilt <= 2 degrees RMS, height std <= 0.02 m).
    EXPECT_GT(before.tilt_rms, 4.0);
    EXPECT_LE(after.tilt_rms, 2.0);
    EXPECT_LE(after.height_std, 0.02);
    EXPECT_GT(stats.mean_weight, 0.5) << "still water is bulk water: it moves";
    // Water still settling, one in six of the top layer missing (like the still pool of
    // issue 11 after 15 s: 6.9 degrees and 0.07 m on the same measure): the gaps are
    // wider than the smoothing reaches (it keeps shapes of a few metres), so the heights
    // stay above the target; the tilt still meets it.
    measure(1.0f / 6.0f, before, after, stats);
    std::printf("still water settling: tilt RMS %.2f -> %.2f deg, height std %.4f -> %.4f m\n", before.tilt_rms,
                after.tilt_rms, before.height_std, after.height_std);
    EXPECT_GT(before.tilt_rms, 8.0);
    EXPECT_LE(after.tilt_rms, 2.0);
    EXPECT_LT(after.height_std, 0.5 * before.height_std);
}

class RiverFrame : public ::testing::TestWithParam<const char*> {};

TEST_P(RiverFrame, KeepsItsVolumeAndStaysWatertight) {
    const std::vector<Vec3> balls = load_xyz(GetParam());
    ASSERT_GT(balls.size(), 500u) << GetParam();
    Built b;
    SurfaceMesh raw;
    SmoothingWorkspace ws;
    build_and_smooth(balls, b, raw, ws);
    ASSERT_GT(ws.stats.moving, 100u) << "the frame must have water that moves";

    const test::MeshStats s0 = test::check_mesh(raw), s1 = test::check_mesh(b.mesh);
    ASSERT_TRUE(s0.closed_oriented_manifold());
    // Watertight stays watertight (the connectivity is the marching cubes' own), and no
    // triangle collapses (a hole in all but name) or turns over.
    EXPECT_TRUE(s1.closed_oriented_manifold());
    EXPECT_EQ(s1.components, s0.components);
    size_t collapsed = 0, flipped = 0;
    for (size_t t = 0; t < raw.triangle_count(); ++t) {
        const auto normal = [&](const SurfaceMesh& m) {
            const Vec3 a = m.positions[m.indices[3 * t]], bb = m.positions[m.indices[3 * t + 1]],
                       c = m.positions[m.indices[3 * t + 2]];
            return glm::dvec3(glm::cross(bb - a, c - a));
        };
        const glm::dvec3 n0 = normal(raw), n1 = normal(b.mesh);
        if (glm::length(n1) < 1e-9 && glm::length(n0) >= 1e-9) ++collapsed;
        if (glm::dot(n0, n1) < 0.0) ++flipped;
    }
    std::printf("%s: %zu vertices (%zu move), volume %.2f -> %.2f m^3 (the steps took %.2f), %zu of %zu "
                "triangles turned over\n",
                GetParam(), raw.vertex_count(), ws.stats.moving, s0.volume, s1.volume, -ws.stats.volume_change, flipped,
                raw.triangle_count());
    EXPECT_EQ(collapsed, 0u);
    EXPECT_EQ(flipped, 0u) << "triangles turned over";
    // The volume stays within 5 % of the extracted mesh's (issue 11), and so does the
    // largest body of water's.
    EXPECT_NEAR(s1.volume / s0.volume, 1.0, 0.05) << s0.volume << " -> " << s1.volume;
    const std::vector<double> c0 = component_volumes(raw), c1 = component_volumes(b.mesh);
    ASSERT_EQ(c0.size(), c1.size());
    EXPECT_NEAR(c1[0] / c0[0], 1.0, 0.05);
    EXPECT_NEAR(ws.stats.volume_change / s0.volume, 0.0, 0.5) << "what the steps took, before it was given back";
}

TEST_P(RiverFrame, IntroducesNoSelfIntersections) {
    Built b;
    SurfaceMesh raw;
    SmoothingWorkspace ws;
    build_and_smooth(load_xyz(GetParam()), b, raw, ws);
    const size_t before = test::count_self_intersections(raw.positions, raw.indices);
    EXPECT_EQ(before, 0u) << "marching cubes' own mesh";
    EXPECT_EQ(test::count_self_intersections(b.mesh.positions, b.mesh.indices), before);
}

INSTANTIATE_TEST_SUITE_P(Frames, RiverFrame, ::testing::Values("default_river_f1800.xyz", "dense_river_f600.xyz"));

TEST(Smoothing, SelfIntersectionCountSeesAMeshThroughItself) {
    // Two triangles that share no vertex, one through the other; and apart.
    const std::vector<Vec3> p = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5f, 0.5f, -1}, {0.5f, 0.5f, 1}, {1.5f, 1.5f, 0.5f}};
    EXPECT_EQ(test::count_self_intersections(p, std::vector<uint32_t>{0, 1, 2, 3, 4, 5}), 1u);
    std::vector<Vec3> q = p;
    for (size_t i = 3; i < 6; ++i) q[i].x += 5.0f;
    EXPECT_EQ(test::count_self_intersections(q, std::vector<uint32_t>{0, 1, 2, 3, 4, 5}), 0u);
}

TEST(Smoothing, LoneDropsKeepTheirShapeWhileTheWaterBesideThemIsSmoothed) {
    std::vector<Vec3> balls = jittered_pool();
    const size_t pool = balls.size();
    balls.push_back(Vec3(3.0f, 5.0f, 3.0f));         // a drop 3 m above the pool
    balls.push_back(Vec3(8.0f, 5.0f, 8.0f));         // a pair of touching drops
    balls.push_back(Vec3(8.45f, 5.1f, 8.0f));
    Built b;
    SurfaceMesh raw;
    SmoothingWorkspace ws;
    build_and_smooth(balls, b, raw, ws);
    const SmoothingField w = b.weights();
    size_t drop_vertices = 0, pool_moved = 0, pool_vertices = 0;
    for (size_t i = 0; i < raw.vertex_count(); ++i) {
        if (raw.positions[i].y > 4.0f) {
            ++drop_vertices;
            EXPECT_EQ(b.mesh.positions[i], raw.positions[i]) << "drop vertex " << i;
            EXPECT_EQ(b.mesh.normals[i], raw.normals[i]) << "drop vertex " << i;
        } else {
            ++pool_vertices;
            pool_moved += b.mesh.positions[i] != raw.positions[i];
        }
    }
    EXPECT_GT(drop_vertices, 20u);
    EXPECT_GT(pool_moved, pool_vertices / 2) << pool;
    // Without feature weights the drops shrink.
    SurfaceMesh m = raw;
    SmoothingDef all = default_smoothing();
    all.feature_count = 0.0f;
    all.keep_volume = false;
    smooth_surface(m, all, ws, &w);
    const std::vector<double> c0 = component_volumes(raw), c1 = component_volumes(m);
    ASSERT_EQ(c0.size(), 3u);
    EXPECT_LT(c1[2] / c0[2], 0.8) << "a lone drop smoothed with everything else";
}

TEST(Smoothing, AnOpenRimStaysWhereItIs) {
    // A slab of water cut by the field's box (a fixed box that ends inside the water):
    // the mesh is open there, and its rim must not move.
    std::vector<Vec3> balls = jittered_pool();
    SparseFieldDef def;
    def.kernel = poly6_kernel(kRadius, 1.0f);
    def.domain = DomainMode::FixedBox;
    def.box = SampleGrid{.origin = Vec3(-1.0f, -1.0f, -1.0f), .spacing = 1.0f / kResolution, .nx = 25, .ny = 13, .nz = 40};
    SparseField field;
    ASSERT_TRUE(field.build(balls, def).ok());
    SurfaceMesh mesh;
    SurfaceWorkspace sws;
    extract_surface_sparse(field, kThreshold, mesh, sws);
    const std::vector<test::EdgeUse> rim = test::boundary_edges(mesh.vertex_count(), mesh.indices);
    ASSERT_GT(rim.size(), 10u);
    const SurfaceMesh raw = mesh;
    SmoothingWorkspace ws;
    const SmoothingField w{.field = &field, .kernel = def.kernel, .threshold = kThreshold};
    smooth_surface(mesh, default_smoothing(), ws, &w);
    for (const test::EdgeUse& e : rim) {
        EXPECT_EQ(mesh.positions[e.a], raw.positions[e.a]);
        EXPECT_EQ(mesh.positions[e.b], raw.positions[e.b]);
    }
    EXPECT_GT(ws.stats.pinned, 0u);
    EXPECT_GT(ws.stats.moving, mesh.vertex_count() / 2);
}

// The ground hides the water's bed (about half of a river's mesh): those vertices stay
// exactly as extracted and cost nothing past the ground test; the rest is smoothed as
// without a ground. smooth_hidden = true smooths everything, as with no ground.
TEST(Smoothing, VerticesBelowTheGroundStayWhereMarchingCubesPutThem) {
    constexpr float kGround = 0.6f;  // the pool's balls span y 0 to 1.65, its mesh about -0.5 to 2.1
    const std::vector<Vec3> corners = {{0, kGround, 0}, {100, kGround, 0}, {0, kGround, 100}, {100, kGround, 100}};
    const SmoothingGround ground{.vertices = corners.data(), .columns = 2, .rows = 2, .spacing = 100.0f};
    Built b;
    build(jittered_pool(), b);
    const SurfaceMesh raw = b.mesh;
    const SmoothingField w = b.weights();
    SmoothingWorkspace ws;
    SurfaceMesh all = raw, kept = raw, forced = raw;
    smooth_surface(all, default_smoothing(), ws, &w);
    const size_t moving_all = ws.stats.moving;
    EXPECT_EQ(ws.stats.hidden, 0u) << "no ground, nothing hidden";
    smooth_surface(kept, default_smoothing(), ws, &w, &ground);
    const SmoothingStats st = ws.stats;
    size_t below = 0, moved_below = 0, moved_above = 0;
    for (size_t v = 0; v < raw.vertex_count(); ++v) {
        if (raw.positions[v].y < kGround) {
            ++below;
            moved_below += kept.positions[v] != raw.positions[v] || kept.normals[v] != raw.normals[v];
        } else {
            moved_above += kept.positions[v] != raw.positions[v];
        }
    }
    std::printf("pool over a ground at y = %.1f: %zu of %zu vertices hidden, %zu move (%zu without the ground)\n",
                kGround, st.hidden, raw.vertex_count(), st.moving, moving_all);
    EXPECT_EQ(st.hidden, below);
    EXPECT_GT(below, raw.vertex_count() / 4);
    EXPECT_EQ(moved_below, 0u);
    EXPECT_GT(moved_above, raw.vertex_count() / 4);
    EXPECT_LT(st.moving, moving_all - below / 2);
    // The visible top is as flat as without the ground, and the body keeps its volume.
    const Flatness f = flatness(kept);
    EXPECT_LE(f.tilt_rms, 2.0);
    EXPECT_LE(f.height_std, 0.02);
    EXPECT_NEAR(test::check_mesh(kept).volume / test::check_mesh(raw).volume, 1.0, 0.05);
    EXPECT_TRUE(test::check_mesh(kept).closed_oriented_manifold());
    // smooth_hidden: the ground is not read.
    SmoothingDef def = default_smoothing();
    def.smooth_hidden = true;
    smooth_surface(forced, def, ws, &w, &ground);
    EXPECT_EQ(ws.stats.hidden, 0u);
    EXPECT_EQ(forced.positions, all.positions);
}

TEST(Smoothing, SameResultForAnyThreadCount) {
    Built b;
    build(load_xyz("dense_river_f600.xyz"), b);
    ASSERT_GT(b.mesh.vertex_count(), 20000u) << "large enough to be split between threads";
    const SmoothingField w = b.weights();
    SurfaceMesh one = b.mesh, two = b.mesh;
    SmoothingWorkspace ws;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        smooth_surface(one, default_smoothing(), ws, &w);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
        smooth_surface(two, default_smoothing(), ws, &w);
    }
    EXPECT_EQ(one.positions, two.positions);
    EXPECT_EQ(one.normals, two.normals);
}

// The feature weights' eight-wide pass (AVX2) and its scalar twin give the same weights
// bit for bit, and so the same mesh: on river frames, with and without a bumpy ground
// (about half the vertices hidden), with a field of half the balls (probes outside its
// grid and in blocks it does not store) and without a field (weight 1).
TEST(Smoothing, SimdWeightsEqualTheScalarTwin) {
    for (const char* name : {"default_river_f1800.xyz", "dense_river_f600.xyz"}) {
        const std::vector<Vec3> balls = load_xyz(name);
        Built b;
        build(balls, b);
        ASSERT_GT(b.mesh.vertex_count(), 10000u) << name;
        // Half the balls (every other one in x order): a smaller grid, holes in it.
        std::vector<Vec3> half_balls = balls;
        std::sort(half_balls.begin(), half_balls.end(), [](const Vec3& a, const Vec3& c) { return a.x < c.x; });
        half_balls.resize(half_balls.size() / 2);
        Built h;
        build(half_balls, h);
        // A ground through the water: the mesh's median height, +-0.8 m of bumps, on a
        // 0.37 m grid from the origin over only part of the mesh (the rest reads its
        // clamped edge).
        float lo = 1e30f, hi = -1e30f, x0 = 1e30f, z0 = 1e30f, x1 = -1e30f, z1 = -1e30f;
        for (const Vec3& p : b.mesh.positions) {
            lo = std::min(lo, p.y), hi = std::max(hi, p.y);
            x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), z0 = std::min(z0, p.z), z1 = std::max(z1, p.z);
        }
        const float spacing = 0.37f;
        const int columns = int((x0 + 0.8f * (x1 - x0)) / spacing) + 2, rows = int((z0 + 0.9f * (z1 - z0)) / spacing) + 2;
        std::vector<Vec3> g;
        uint32_t state = 7u;
        for (int i = 0; i < rows; ++i)
            for (int j = 0; j < columns; ++j) {
                state = state * 1664525u + 1013904223u;
                const float bump = 1.6f * (float(state >> 8) / float(1u << 24) - 0.5f);
                g.push_back(Vec3(spacing * j, 0.5f * (lo + hi) + bump, spacing * i));
            }
        const SmoothingGround ground{.vertices = g.data(), .columns = columns, .rows = rows, .spacing = spacing};
        const SmoothingField own = b.weights(), halved = h.weights();
        struct Case {
            const SmoothingField* field;
            const SmoothingGround* ground;
            float feature_count;
        };
        const Case cases[] = {{&own, nullptr, 3.0f}, {&own, &ground, 3.0f}, {&halved, &ground, 3.0f},
                              {&own, &ground, 0.0f}, {&own, nullptr, 2.0f}};
        for (const Case& c : cases) {
            SmoothingDef def = default_smoothing();
            def.feature_count = c.feature_count;
            SurfaceMesh fast = b.mesh, slow = b.mesh;
            SmoothingWorkspace wf, wsl;
            wsl.scalar = true;
            smooth_surface(fast, def, wf, c.field, c.ground);
            smooth_surface(slow, def, wsl, c.field, c.ground);
            const std::string what = std::string(name) + (c.field == &halved ? ", half the balls' field" : "") +
                                     (c.ground ? ", ground" : "") + ", feature_count " + std::to_string(int(c.feature_count));
            EXPECT_FALSE(wsl.stats.simd_weights);
            if (mr::avx2_enabled()) {
                EXPECT_TRUE(wf.stats.simd_weights) << what;
            }
            size_t differ = 0, zero = 0, one = 0, between = 0;
            for (size_t v = 0; v < wf.weight.size(); ++v) {
                differ += std::memcmp(&wf.weight[v], &wsl.weight[v], sizeof(float)) != 0;
                const float w = wsl.weight[v];
                zero += w == 0.0f, one += w == 1.0f, between += w > 0.0f && w < 1.0f;
            }
            std::printf("%s: %zu vertices, %zu hidden; weights 0: %zu, 1: %zu, between: %zu; %zu differ\n",
                        what.c_str(), wf.weight.size(), wsl.stats.hidden, zero, one, between, differ);
            ASSERT_EQ(wf.weight.size(), wsl.weight.size());
            EXPECT_EQ(differ, 0u) << what;
            EXPECT_EQ(wf.stats.hidden, wsl.stats.hidden) << what;
            EXPECT_EQ(wf.stats.moving, wsl.stats.moving) << what;
            EXPECT_EQ(fast.positions, slow.positions) << what;
            EXPECT_EQ(fast.normals, slow.normals) << what;
            // Each case reaches the branches it is for.
            if (c.ground) {
                EXPECT_GT(wsl.stats.hidden, wf.weight.size() / 10) << what;
            }
            if (c.feature_count > 0.0f) {
                EXPECT_GT(between, 100u) << what;
            }
        }
    }
}

TEST(Smoothing, AFrameNoLargerThanOneBeforeAllocatesNothing) {
    Built b;
    build(load_xyz("default_river_f1800.xyz"), b);
    const SurfaceMesh raw = b.mesh;
    const SmoothingField w = b.weights();
    SmoothingWorkspace ws;
    SurfaceMesh m = raw;
    smooth_surface(m, default_smoothing(), ws, &w);
    const size_t bytes = ws.capacity_bytes();
    m = raw;
    smooth_surface(m, default_smoothing(), ws, &w);
    EXPECT_EQ(ws.capacity_bytes(), bytes);
}

TEST(Smoothing, AMalformedMeshIsLeftAsItIs) {
    Built b;
    build(jittered_pool(), b);
    b.mesh.indices.back() = static_cast<uint32_t>(b.mesh.vertex_count());  // out of range
    const SurfaceMesh raw = b.mesh;
    SmoothingWorkspace ws;
    smooth_surface(b.mesh, default_smoothing(), ws);
    EXPECT_EQ(b.mesh.positions, raw.positions);
    EXPECT_EQ(b.mesh.normals, raw.normals);
}

TEST(Smoothing, AMeshWithoutNormalsGetsThem) {
    Built b;
    build(jittered_pool(), b);
    b.mesh.normals.clear();
    SmoothingWorkspace ws;
    const SmoothingField w = b.weights();
    smooth_surface(b.mesh, default_smoothing(), ws, &w);
    ASSERT_EQ(b.mesh.normals.size(), b.mesh.vertex_count());
    EXPECT_EQ(ws.stats.moving, b.mesh.vertex_count()) << "no normals, no feature weights: everything moves";
    for (const Vec3& n : b.mesh.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-4f);
}

TEST(Smoothing, LoneBallIsoDistanceIsWhereOneBallReachesTheThreshold) {
    const KernelDef k = poly6_kernel(1.0f, 1.0f);
    const float r = lone_ball_iso_distance(k, 0.4f);
    EXPECT_NEAR(kernel_value(k, r * r), 0.4f, 1e-4f);
    EXPECT_NEAR(r, std::sqrt(1.0f - std::cbrt(0.4f)), 1e-4f);
    EXPECT_EQ(lone_ball_iso_distance(k, 2.0f), 0.0f) << "one ball never reaches 2";
}

}  // namespace
}  // namespace mr
