// The GPU field (gpu_field.h) against its twin, SparseField on the same fixed box: the
// same samples to float rounding, for both compact kernels, with balls outside the box,
// after the ball count grows and shrinks, and with no balls.
#include "gl_test_context.h"

#include <metariver/gpu_field.h>
#include <metariver/sparse_field.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace {

using namespace mr;

ScalarGrid cpu_field(std::span<const Vec3> balls, const KernelDef& k, const SampleGrid& g) {
    SparseField f;
    SparseFieldDef def{.kernel = k, .domain = DomainMode::FixedBox, .box = g};
    EXPECT_TRUE(f.build(balls, def).ok());
    ScalarGrid out;
    f.to_dense(out);
    return out;
}

// The largest difference over the samples, relative to the largest sample (at least 1).
float max_relative_difference(const ScalarGrid& a, const ScalarGrid& b) {
    EXPECT_EQ(a.values.size(), b.values.size());
    float diff = 0.0f, top = 1.0f;
    for (size_t i = 0; i < std::min(a.values.size(), b.values.size()); ++i) {
        diff = std::max(diff, std::abs(a.values[i] - b.values[i]));
        top = std::max(top, std::abs(b.values[i]));
    }
    return diff / top;
}

// Balls in and around a 6 x 4 x 5 m box, some out of it by up to the kernel radius and
// some far out (binned in the border cells, reaching nothing).
std::vector<Vec3> scattered_balls(int n, uint32_t seed) {
    Lcg rng(seed);
    std::vector<Vec3> b;
    for (int i = 0; i < n; ++i) {
        const float x = rng.uniform(-1.0f, 7.0f), y = rng.uniform(-1.0f, 5.0f), z = rng.uniform(-1.0f, 6.0f);
        b.emplace_back(x, y, z);
    }
    b.emplace_back(100.0f, 2.0f, 2.0f);
    b.emplace_back(3.0f, -50.0f, 2.0f);
    return b;
}

SampleGrid box_grid() { return SampleGrid{.origin = Vec3(0.0f), .spacing = 0.1f, .nx = 61, .ny = 41, .nz = 51}; }

TEST(GpuField, Poly6MatchesTheSparseFieldWithBallsInAndAroundTheBox) {
    REQUIRE_GL();
    const KernelDef k = poly6_kernel(0.45f, 1.0f);
    auto gpu = gpu::GpuField::create({.kernel = k, .grid = box_grid()});
    ASSERT_TRUE(gpu.ok()) << gpu.error().message;
    // Grow, shrink and grow again: the buffers grow to the largest frame; each build is
    // its own balls' field.
    for (int n : {300, 5000, 40, 12000}) {
        const std::vector<Vec3> balls = scattered_balls(n, uint32_t(n));
        ASSERT_TRUE(gpu.value()->build(balls).ok());
        ScalarGrid g;
        gpu.value()->to_dense(g);
        const ScalarGrid c = cpu_field(balls, k, box_grid());
        EXPECT_LT(max_relative_difference(g, c), 2e-6f) << n << " balls";
        EXPECT_GT(*std::max_element(c.values.begin(), c.values.end()), 1.0f) << "balls overlap: the test sums";
    }
}

TEST(GpuField, W1MatchesTheSparseFieldOnThePeersWorkload) {
    REQUIRE_GL();
    const int n = 400, res = 48;
    const std::vector<Vec3> balls = w1_balls(n);
    const KernelDef k = w1_kernel_for(n);
    auto gpu = gpu::GpuField::create({.kernel = k, .grid = w1_grid(res)});
    ASSERT_TRUE(gpu.ok()) << gpu.error().message;
    ASSERT_TRUE(gpu.value()->build(balls).ok());
    ScalarGrid g;
    gpu.value()->to_dense(g);
    const ScalarGrid c = cpu_field(balls, k, w1_grid(res));
    EXPECT_LT(max_relative_difference(g, c), 2e-6f);
    size_t above = 0;
    for (float v : c.values) above += v > kW1Iso;
    EXPECT_GT(above, 100u) << "the workload has a surface";
}

TEST(GpuField, NoBallsIsAnEmptyFieldAndTheLastBuildIsTimed) {
    REQUIRE_GL();
    auto gpu = gpu::GpuField::create({.kernel = poly6_kernel(0.45f, 1.0f), .grid = box_grid()});
    ASSERT_TRUE(gpu.ok());
    ASSERT_TRUE(gpu.value()->build(scattered_balls(100, 3)).ok());
    ASSERT_TRUE(gpu.value()->build({}).ok());
    gpu.value()->last_build_gpu_ms();
    ScalarGrid g;
    gpu.value()->to_dense(g);
    EXPECT_EQ(g.values.size(), box_grid().samples());
    EXPECT_EQ(*std::max_element(g.values.begin(), g.values.end()), 0.0f);
}

TEST(GpuField, RefusesWhatItCannotRunNamingTheField) {
    // Checked before any OpenGL call: no context needed.
    const auto refuses = [](gpu::GpuFieldDef def, const char* what) {
        auto g = gpu::GpuField::create(def);
        ASSERT_FALSE(g.ok());
        EXPECT_NE(g.error().message.find(what), std::string::npos) << g.error().message;
    };
    refuses({.kernel = poly6_kernel(0.0f, 1.0f), .grid = box_grid()}, "radius");
    refuses({.kernel = KernelDef{.type = FieldKernel::InverseSquare}, .grid = box_grid()}, "compact");
    SampleGrid g = box_grid();
    g.spacing = 0.0f;
    refuses({.kernel = poly6_kernel(0.45f, 1.0f), .grid = g}, "grid.spacing");
    g = box_grid();
    g.nx = 0;
    refuses({.kernel = poly6_kernel(0.45f, 1.0f), .grid = g}, "samples");
    g = box_grid();
    g.nx = g.ny = g.nz = 1 << 10;
    refuses({.kernel = poly6_kernel(0.45f, 1.0f), .grid = g}, "samples");
}

TEST(GpuField, ANonFiniteBallIsRefusedAndTheFieldKept) {
    REQUIRE_GL();
    auto gpu = gpu::GpuField::create({.kernel = poly6_kernel(0.45f, 1.0f), .grid = box_grid()});
    ASSERT_TRUE(gpu.ok());
    std::vector<Vec3> balls = scattered_balls(200, 5);
    ASSERT_TRUE(gpu.value()->build(balls).ok());
    ScalarGrid before, after;
    gpu.value()->to_dense(before);
    balls[7].z = std::numeric_limits<float>::infinity();
    const Status st = gpu.value()->build(balls);
    ASSERT_FALSE(st.ok());
    EXPECT_NE(st.error().message.find("ball 7"), std::string::npos) << st.error().message;
    gpu.value()->to_dense(after);
    EXPECT_EQ(before.values, after.values);
}

}  // namespace
