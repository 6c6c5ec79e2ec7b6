// The GPU PBF step (gpu_pbf.h) against its twin, the CPU PbfSolver with the terrain's
// collision off: the same block, the same parameters, the same steps. On llvmpipe here;
// the same test runs on a real GPU wherever the headless context finds one.
#include "gl_test_context.h"

#include "pbf_probe.h"

#include <metariver/gpu_pbf.h>
#include <metariver/particles.h>
#include <metariver/pbf_solver.h>
#include <metariver/terrain.h>
#include <metariver/workloads.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace {

using namespace mr;

struct Frames {
    std::vector<Vec3> x, v;
};

// A W3 block of nx * nx * nx/2 particles squeezed to `squeeze` of the rest spacing
// about its lowest corner at (14, 1, 14), amid 32 x 32 m of flat ground: it springs
// apart (and falls, with gravity).
std::vector<Vec3> block(int nx, float squeeze) {
    const Vec3 o(14.0f, 1.0f, 14.0f);
    std::vector<Vec3> b = w3_block(nx, Vec3(0.0f));
    for (Vec3& p : b) p = o + squeeze * p;
    return b;
}

PbfDef w3_def() { return PbfDef{.spacing = kW3Spacing, .kernel_radius = 2.0f * kW3Spacing, .iterations = 3}; }

Frames cpu_run(const std::vector<Vec3>& start, const PbfDef& pbf, float gravity, int steps, float dt,
               bool slow = true) {
    auto terrain = Terrain::build(flat_heightmap(9, 9), TerrainDef{.area_scale = 4.0f, .height_scale = 1.0f});
    EXPECT_TRUE(terrain.ok());
    auto bvh = Bvh::build(terrain.value(), BvhDef{});
    EXPECT_TRUE(bvh.ok());
    SpawnDef spawn{.count = int(start.size()), .center = Vec3(16, 2, 16), .half_extent = Vec3(0.0f), .interval = 0};
    PbfSolver solver(terrain.value(), bvh.value(), spawn, pbf, CollisionDef{.mode = CollisionMode::None},
                     IntegratorDef{.gravity = gravity, .fixed_dt = dt, .substeps = 1}, 1u, SinkDef{});
    solver.place(start);
    if (slow) {  // the scalar 27-cell twin: the GPU's passes, summed one pair at a time
        PbfProbe::set_neighbor_lists(solver, false);
        PbfProbe::set_simd(solver, false);
    }
    for (int s = 0; s < steps; ++s) solver.step_frame(dt);
    const Particles& p = solver.particles();
    Frames r;
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i]) {
            r.x.push_back(p.position[i]);
            r.v.push_back(p.velocity[i]);
        }
    return r;
}

gpu::GpuPbfDef gpu_def(const PbfDef& pbf, float gravity) {
    // A box of 16 x 16 x 16 cells around the block: four scan work groups of 1024 cells.
    return gpu::GpuPbfDef{.pbf = pbf, .gravity = gravity, .domain_min = Vec3(13.2f, 0.0f, 13.2f),
                             .domain_max = Vec3(16.2f, 3.0f, 16.2f)};
}

Frames gpu_run(const std::vector<Vec3>& start, const PbfDef& pbf, float gravity, int steps, float dt,
            gpu::GpuPbfCounters* counters = nullptr) {
    auto g = gpu::GpuPbf::create(gpu_def(pbf, gravity), start);
    EXPECT_TRUE(g.ok()) << (g.ok() ? "" : g.error().message);
    if (!g) return {};
    for (int s = 0; s < steps; ++s) g.value()->step(dt);
    if (counters) *counters = g.value()->counters();
    return Frames{g.value()->positions(), g.value()->velocities()};
}

// Each GPU particle's nearest CPU particle (the two keep their arrays in different
// orders): the largest distance and the largest velocity difference over the pairs;
// the pairing must be one to one.
struct Match {
    float dx = 0.0f, dv = 0.0f;
    bool one_to_one = true;
};
Match match(const Frames& gpu, const Frames& cpu) {
    Match m;
    std::vector<int> used(cpu.x.size(), 0);
    for (size_t i = 0; i < gpu.x.size(); ++i) {
        size_t best = 0;
        float bd = std::numeric_limits<float>::max();
        for (size_t j = 0; j < cpu.x.size(); ++j) {
            const float d = glm::length(gpu.x[i] - cpu.x[j]);
            if (d < bd) bd = d, best = j;
        }
        if (used[best]++) m.one_to_one = false;
        m.dx = std::max(m.dx, bd);
        m.dv = std::max(m.dv, glm::length(gpu.v[i] - cpu.v[best]));
    }
    return m;
}

TEST(GpuPbf, MatchesTheCpuStepOnASqueezedFallingBlock) {
    REQUIRE_GL();
    const std::vector<Vec3> start = block(10, 0.9f);  // 500 particles at 0.09 m: C about 0.37
    const float dt = 1.0f / 120.0f;
    const int steps = 20;
    const Frames cpu = cpu_run(start, w3_def(), 9.82f, steps, dt);
    const Frames gpu = gpu_run(start, w3_def(), 9.82f, steps, dt);
    ASSERT_EQ(gpu.x.size(), start.size());
    ASSERT_EQ(cpu.x.size(), start.size());
    const Match m = match(gpu, cpu);
    EXPECT_TRUE(m.one_to_one);
    // Measured on llvmpipe: 4.3e-5 m and 4.7e-4 m/s after 20 steps (the sums' order
    // differs; the CPU's AVX2 path, fixed-point gradients, is 7.5e-4 m off its own
    // scalar twin by then).
    EXPECT_LT(m.dx, 1e-4f) << "max distance to the CPU twin's particle";
    EXPECT_LT(m.dv, 2e-3f) << "max velocity difference, m/s";
    // One step: within a few float steps of the positions (about 1e-6 m at 15 m).
    const Match one = match(gpu_run(start, w3_def(), 9.82f, 1, dt), cpu_run(start, w3_def(), 9.82f, 1, dt));
    EXPECT_LT(one.dx, 4e-6f);
    // The block did move: it fell (0.136 m in 1/6 s) and spread.
    double mean_y0 = 0.0, mean_y = 0.0;
    for (size_t i = 0; i < start.size(); ++i) mean_y0 += start[i].y, mean_y += gpu.x[i].y;
    EXPECT_NEAR((mean_y0 - mean_y) / double(start.size()), 0.5 * 9.82 * (steps * dt) * (steps * dt), 0.01);
    const auto width = [](const std::vector<Vec3>& x) {
        float lo = x[0].x, hi = x[0].x;
        for (const Vec3& p : x) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
        return hi - lo;
    };
    EXPECT_GT(width(gpu.x), width(start) + 0.02f) << "the squeezed block springs apart";
}

TEST(GpuPbf, MatchesTheCpuStepOnTheW3BlockAsItFallsAsleep) {
    REQUIRE_GL();
    // W3 itself (rest spacing, 1 % jitter, no gravity): the jitter relaxes, the block
    // slows under the sleeping threshold and falls asleep after kSleepAfterSeconds.
    const std::vector<Vec3> start = block(10, 1.0f);
    const float dt = 1.0f / 120.0f;
    const int steps = 30;
    gpu::GpuPbfCounters c;
    const Frames cpu = cpu_run(start, w3_def(), 0.0f, steps, dt);
    const Frames gpu = gpu_run(start, w3_def(), 0.0f, steps, dt, &c);
    const Match m = match(gpu, cpu);
    EXPECT_TRUE(m.one_to_one);
    EXPECT_LT(m.dx, 1e-4f);
    EXPECT_LT(m.dv, 2e-3f);
    EXPECT_GT(c.asleep, 0u) << "the asleep counter can go non-zero";
}

TEST(GpuPbf, IsDeterministicAndItsCountersMove) {
    REQUIRE_GL();
    const std::vector<Vec3> start = block(12, 0.9f);
    const Frames a = gpu_run(start, w3_def(), 9.82f, 10, 1.0f / 120.0f);
    const Frames b = gpu_run(start, w3_def(), 9.82f, 10, 1.0f / 120.0f);
    ASSERT_EQ(a.x.size(), b.x.size());
    for (size_t i = 0; i < a.x.size(); ++i) {
        ASSERT_EQ(a.x[i], b.x[i]) << "particle " << i;
        ASSERT_EQ(a.v[i], b.v[i]) << "particle " << i;
    }
    gpu::GpuPbfCounters c;
    gpu_run(start, w3_def(), 9.82f, 1, 1.0f / 120.0f, &c);
    EXPECT_GT(c.density_error_max, 0.05f) << "a squeezed block is over-dense";
    EXPECT_GT(c.max_speed, 0.5f);
    EXPECT_EQ(c.asleep, 0u) << "a falling block never sleeps";
}

TEST(GpuPbf, ParticlesOutsideTheGridAreStillNeighbours) {
    REQUIRE_GL();
    // The same squeezed block with a grid box that ends inside it: the particles beyond
    // are binned in the border cells and still find each other (the twin agrees).
    const std::vector<Vec3> start = block(8, 0.8f);
    gpu::GpuPbfDef def = gpu_def(w3_def(), 0.0f);
    def.domain_max = Vec3(14.3f, 1.1f, 14.3f);
    auto g = gpu::GpuPbf::create(def, start);
    ASSERT_TRUE(g.ok()) << g.error().message;
    for (int s = 0; s < 5; ++s) g.value()->step(1.0f / 120.0f);
    const Frames gpu{g.value()->positions(), g.value()->velocities()};
    const Frames cpu = cpu_run(start, w3_def(), 0.0f, 5, 1.0f / 120.0f);
    const Match m = match(gpu, cpu);
    EXPECT_TRUE(m.one_to_one);
    EXPECT_LT(m.dx, 1e-4f);
}

TEST(GpuPbf, RefusesWhatItCannotRunNamingTheField) {
    // Checked before any OpenGL call: no context needed.
    const std::vector<Vec3> start = block(4, 1.0f);
    const auto refuses = [&](gpu::GpuPbfDef def, const char* field) {
        auto g = gpu::GpuPbf::create(def, start);
        ASSERT_FALSE(g.ok());
        EXPECT_NE(g.error().message.find(field), std::string::npos) << g.error().message;
    };
    gpu::GpuPbfDef d = gpu_def(w3_def(), 9.82f);
    d.pbf.vorticity = 0.1f;
    refuses(d, "pbf.vorticity");
    d = gpu_def(w3_def(), 9.82f);
    d.pbf.wall_density = 1.0f;
    refuses(d, "pbf.wall_density");
    d = gpu_def(w3_def(), 9.82f);
    d.pbf.iterations = 0;
    refuses(d, "pbf.iterations");
    d = gpu_def(w3_def(), 9.82f);
    d.domain_max = Vec3(1e4f);
    refuses(d, "cells");
    d = gpu_def(w3_def(), 9.82f);
    d.domain_max = Vec3(0.0f);
    refuses(d, "domain_max");
    d = gpu_def(w3_def(), -1.0f);
    refuses(d, "gravity");
    std::vector<Vec3> bad = start;
    bad[3].y = std::numeric_limits<float>::quiet_NaN();
    auto g = gpu::GpuPbf::create(gpu_def(w3_def(), 9.82f), bad);
    ASSERT_FALSE(g.ok());
    EXPECT_NE(g.error().message.find("not finite"), std::string::npos);
}

}  // namespace
