// The C API on a shallow-water world (solver = "swe"): the grid read back as flat arrays
// (mr_world_heightfield, mr_world_copy_heightfield), equal to the C++ Simulation's, its
// errors, and the water queries answering from the heightfield's surface.
#include "capi_support.h"

#include <metariver/swe_solver.h>

#include <cmath>
#include <vector>

namespace capi_test {
namespace {

/// A still lake up to 13 m on the default valley.
mr_world_desc lake_desc() {
    mr_world_desc d = mr_world_desc_default();
    d.scene_toml = "solver = \"swe\"\n[swe]\ninitial_level = 13.0\nedges = \"open\"\n";  // at rest: the lake reaches the valley's edge
    return d;
}

TEST(CApiSwe, TheGridIsReadAsFlatArraysEqualToTheSimulations) {
    World world(lake_desc());
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(10);
    mr_heightfield_info info{};
    ASSERT_EQ(mr_world_heightfield(world.w, &info), MR_OK) << world.last_error();
    const mr_terrain_info t = terrain_info(world);
    EXPECT_EQ(info.columns, t.columns);
    EXPECT_EQ(info.rows, t.rows);
    EXPECT_EQ(info.spacing, t.area_scale);
    const size_t n = size_t(info.rows) * size_t(info.columns);
    std::vector<float> depth(n), velocity(2 * n), bed(n);
    ASSERT_EQ(mr_world_copy_heightfield(world.w, depth.data(), velocity.data(), bed.data(), n), MR_OK);
    EXPECT_EQ(bed, terrain_heights(world));
    // A lake at rest: wet where the bed is under 13 m, its surface there at 13 m.
    size_t wet = 0;
    for (size_t k = 0; k < n; ++k) {
        EXPECT_NEAR(depth[k], std::max(13.0f - bed[k], 0.0f), 1e-4f) << k;
        EXPECT_NEAR(velocity[2 * k], 0.0f, 1e-3f);
        wet += depth[k] > 0.0f;
    }
    EXPECT_GT(wet, 100u);
    // NULL buffers are skipped; a short capacity writes nothing.
    EXPECT_EQ(mr_world_copy_heightfield(world.w, nullptr, nullptr, nullptr, 0), MR_OK);
    std::vector<float> small(3, -1.0f);
    EXPECT_EQ(mr_world_copy_heightfield(world.w, small.data(), nullptr, nullptr, 3), MR_ERROR_BUFFER_TOO_SMALL);
    EXPECT_TRUE(contains(world.last_error(), "capacity: 3")) << world.last_error();
    EXPECT_EQ(small[0], -1.0f);
    EXPECT_EQ(mr_world_heightfield(world.w, nullptr), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_heightfield(nullptr, &info), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_copy_heightfield(nullptr, nullptr, nullptr, nullptr, 0), MR_ERROR_NULL_ARGUMENT);
}

TEST(CApiSwe, AParticleWorldHasNoGridAndSaysSo) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    mr_heightfield_info info{};
    EXPECT_EQ(mr_world_heightfield(world.w, &info), MR_ERROR_UNSUPPORTED);
    EXPECT_TRUE(contains(world.last_error(), "mr_world_heightfield: solver = \"pbf\" has no water grid"))
        << world.last_error();
    float d[1];
    EXPECT_EQ(mr_world_copy_heightfield(world.w, d, nullptr, nullptr, 1), MR_ERROR_UNSUPPORTED);
}

TEST(CApiSwe, WaterQueriesReadTheLakesSurface) {
    World world(lake_desc());
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(2);
    mr_heightfield_info info{};
    ASSERT_EQ(mr_world_heightfield(world.w, &info), MR_OK);
    const size_t n = size_t(info.rows) * size_t(info.columns);
    std::vector<float> depth(n);
    ASSERT_EQ(mr_world_copy_heightfield(world.w, depth.data(), nullptr, nullptr, n), MR_OK);
    size_t deepest = 0;
    for (size_t k = 0; k < n; ++k)
        if (depth[k] > depth[deepest]) deepest = k;
    const float xz[2] = {info.origin[0] + info.spacing * float(deepest % size_t(info.columns)),
                         info.origin[1] + info.spacing * float(deepest / size_t(info.columns))};
    mr_water_sample s{};
    ASSERT_EQ(mr_world_sample_water(world.w, xz, 1, &s), MR_OK) << world.last_error();
    EXPECT_EQ(s.wet, 1);
    EXPECT_NEAR(s.surface_y, 13.0f, 0.01f);
    EXPECT_NEAR(s.depth, depth[deepest], 0.01f);
}

}  // namespace
}  // namespace capi_test
