// The C API's bodies (mr_world_add_body & co, include/metariver/metariver.h): the states
// read back as added and as the C++ Simulation holds them, a throw that moves the body,
// removal, and every refusal (NULL, a bad value naming its key, a missing mesh, an unknown
// id, a solver without bodies, a buffer too small) changing nothing.
#include "capi_support.h"

#include <metariver/metariver.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>
#include <string>

namespace {

using namespace capi_test;

/// A log above the middle of the terrain.
mr_body_desc log_above(const World& world) {
    const mr_terrain_info t = terrain_info(world);
    mr_body_desc d = mr_body_desc_default();
    d.position[0] = 0.5f * float(t.columns - 1) * t.area_scale;
    d.position[1] = t.max_y + 3.0f;
    d.position[2] = 0.5f * float(t.rows - 1) * t.area_scale;
    return d;
}

size_t body_count(const World& world) {
    size_t n = 99;
    EXPECT_EQ(mr_world_bodies(world.w, nullptr, 0, &n), MR_OK);
    return n;
}

TEST(CApiBodies, NullArguments) {
    const mr_body_desc d = mr_body_desc_default();
    const float v3[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1};
    uint32_t id = 0;
    size_t n = 0;
    EXPECT_EQ(mr_world_add_body(nullptr, &d, &id), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_remove_body(nullptr, 1), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_set_body_motion(nullptr, 1, v3, q, v3, v3), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_bodies(nullptr, nullptr, 0, &n), MR_ERROR_NULL_ARGUMENT);
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    EXPECT_EQ(mr_world_add_body(world.w, nullptr, &id), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(world.last_error(), "mr_world_add_body: desc is NULL");
    EXPECT_EQ(mr_world_add_body(world.w, &d, nullptr), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(world.last_error(), "mr_world_add_body: out_id is NULL");
    EXPECT_EQ(mr_world_set_body_motion(world.w, 1, v3, nullptr, v3, v3), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(world.last_error(), "mr_world_set_body_motion: orientation is NULL");
    EXPECT_EQ(mr_world_bodies(world.w, nullptr, 0, nullptr), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(body_count(world), 0u);
}

TEST(CApiBodies, AddReadThrowAndRemove) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(2);
    const mr_body_desc d = log_above(world);
    uint32_t a = 0, b = 0;
    ASSERT_EQ(mr_world_add_body(world.w, &d, &a), MR_OK) << world.last_error();
    mr_body_desc ball = d;
    ball.shape = MR_BODY_SPHERE;
    ball.size[0] = 0.4f;
    ball.position[0] += 5.0f;
    ball.density = 800.0f;
    ASSERT_EQ(mr_world_add_body(world.w, &ball, &b), MR_OK) << world.last_error();
    EXPECT_NE(a, b);
    mr_body_state s[2]{};
    size_t n = 0;
    ASSERT_EQ(mr_world_bodies(world.w, s, 2, &n), MR_OK);
    ASSERT_EQ(n, 2u);
    EXPECT_EQ(s[0].id, a);
    EXPECT_EQ(s[0].shape, MR_BODY_BOX);
    EXPECT_EQ(s[1].shape, MR_BODY_SPHERE);
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(s[0].position[c], d.position[c]);
    EXPECT_FLOAT_EQ(s[0].orientation[3], 1.0f) << "x, y, z, w: no rotation is w = 1";
    EXPECT_NEAR(s[0].mass, 500.0f * 2.0f * 0.5f * 0.5f, 1e-2f) << "density x volume";
    EXPECT_NEAR(s[1].mass, 800.0f * 4.0f / 3.0f * 3.14159265f * 0.4f * 0.4f * 0.4f, 1.0f);
    EXPECT_FLOAT_EQ(s[0].submerged_fraction, 0.0f) << "in the air";

    // A throw: the body goes where it is put, then moves with its new velocity (and falls).
    const float to[3] = {d.position[0] - 2.0f, d.position[1] + 1.0f, d.position[2]};
    const float q[4] = {0.0f, 0.0f, 0.0f, 2.0f};  // normalised by the call
    const float v[3] = {3.0f, 0.0f, 0.0f}, w[3] = {0.0f, 0.0f, 0.0f};
    ASSERT_EQ(mr_world_set_body_motion(world.w, a, to, q, v, w), MR_OK) << world.last_error();
    ASSERT_EQ(mr_world_bodies(world.w, s, 2, &n), MR_OK);
    EXPECT_FLOAT_EQ(s[0].position[0], to[0]);
    EXPECT_FLOAT_EQ(s[0].velocity[0], 3.0f);
    world.step(6);
    ASSERT_EQ(mr_world_bodies(world.w, s, 2, &n), MR_OK);
    EXPECT_GT(s[0].position[0], to[0] + 0.2f) << "thrown along +x";
    EXPECT_LT(s[0].position[1], to[1]) << "falling";

    // Removal: gone, the other stays; its id is refused afterwards and is never reused.
    ASSERT_EQ(mr_world_remove_body(world.w, a), MR_OK);
    ASSERT_EQ(mr_world_bodies(world.w, s, 2, &n), MR_OK);
    ASSERT_EQ(n, 1u);
    EXPECT_EQ(s[0].id, b);
    EXPECT_EQ(mr_world_remove_body(world.w, a), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "id")) << world.last_error();
    uint32_t c = 0;
    ASSERT_EQ(mr_world_add_body(world.w, &d, &c), MR_OK);
    EXPECT_NE(c, a);
}

TEST(CApiBodies, RefusalsNameTheFieldAndChangeNothing) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    uint32_t id = 77;
    auto refused = [&](mr_body_desc d, mr_status code, const std::string& part) {
        EXPECT_EQ(mr_world_add_body(world.w, &d, &id), code) << part;
        EXPECT_TRUE(contains(world.last_error(), part)) << world.last_error();
    };
    mr_body_desc d = log_above(world);
    d.density = -1.0f;
    refused(d, MR_ERROR_INVALID_ARGUMENT, "bodies.density");
    d = log_above(world);
    d.shape = 9;
    refused(d, MR_ERROR_INVALID_ARGUMENT, "shape");
    d = log_above(world);
    d.size[1] = 0.0f;
    refused(d, MR_ERROR_INVALID_ARGUMENT, "bodies.size");
    d = log_above(world);
    d.position[2] = NAN;
    refused(d, MR_ERROR_INVALID_ARGUMENT, "bodies.position");
    d = log_above(world);
    d.shape = MR_BODY_CONVEX_MESH;
    d.mesh = "/nonexistent/rock.obj";
    d.size[0] = 1.0f;
    refused(d, MR_ERROR_IO, "/nonexistent/rock.obj");
    EXPECT_EQ(id, 77u) << "out_id untouched";
    EXPECT_EQ(body_count(world), 0u);

    d = log_above(world);
    ASSERT_EQ(mr_world_add_body(world.w, &d, &id), MR_OK);
    const float p[3] = {1, 2, 3}, zero4[4] = {0, 0, 0, 0}, v[3] = {0, 0, 0}, bad[3] = {0, INFINITY, 0};
    const float q[4] = {0, 0, 0, 1};
    EXPECT_EQ(mr_world_set_body_motion(world.w, id, p, zero4, v, v), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "orientation")) << world.last_error();
    EXPECT_EQ(mr_world_set_body_motion(world.w, id, p, q, bad, v), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "velocity")) << world.last_error();
    EXPECT_EQ(mr_world_set_body_motion(world.w, id + 100, p, q, v, v), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "id")) << world.last_error();
    mr_body_state s{};
    size_t n = 0;
    ASSERT_EQ(mr_world_bodies(world.w, &s, 1, &n), MR_OK);
    EXPECT_FLOAT_EQ(s.position[1], d.position[1]) << "a refused motion moved nothing";
    ASSERT_EQ(mr_world_add_body(world.w, &d, &id), MR_OK);
    EXPECT_EQ(mr_world_bodies(world.w, &s, 1, &n), MR_ERROR_BUFFER_TOO_SMALL);
    EXPECT_EQ(n, 2u) << "the count says how many";
    EXPECT_TRUE(contains(world.last_error(), "capacity")) << world.last_error();
}

TEST(CApiBodies, ASolverWithoutBodiesRefusesThem) {
    mr_world_desc desc = mr_world_desc_default();
    desc.preset = "paper-bowl";
    World world(desc);
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const mr_body_desc d = log_above(world);
    uint32_t id = 0;
    EXPECT_EQ(mr_world_add_body(world.w, &d, &id), MR_ERROR_UNSUPPORTED);
    EXPECT_TRUE(contains(world.last_error(), "solver = \"springs\" has no bodies")) << world.last_error();
    EXPECT_EQ(body_count(world), 0u);
}

TEST(CApiBodies, ABoxFloatsOnAGridsLake) {
    // solver = "swe": the grid's water floats the body (docs/bodies.md, "On the grid's water").
    mr_world_desc desc = mr_world_desc_default();
    desc.scene_toml = "solver = \"swe\"\n[swe]\ninitial_level = 13.0\nedges = \"open\"\n";
    World world(desc);
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(1);
    mr_heightfield_info info{};
    ASSERT_EQ(mr_world_heightfield(world.w, &info), MR_OK) << world.last_error();
    const size_t n = size_t(info.rows) * size_t(info.columns);
    std::vector<float> depth(n);
    ASSERT_EQ(mr_world_copy_heightfield(world.w, depth.data(), nullptr, nullptr, n), MR_OK);
    size_t deepest = 0;  // away from the map's edges
    for (size_t k = 0; k < n; ++k) {
        const int32_t row = int32_t(k / size_t(info.columns)), column = int32_t(k % size_t(info.columns));
        if (row >= 5 && row < info.rows - 5 && column >= 5 && column < info.columns - 5 && depth[k] > depth[deepest]) deepest = k;
    }
    ASSERT_GT(depth[deepest], 2.0f);
    mr_body_desc d = mr_body_desc_default();
    d.size[0] = d.size[1] = d.size[2] = 1.0f;
    d.density = 500.0f;
    d.position[0] = info.origin[0] + float(deepest % size_t(info.columns)) * info.spacing;
    d.position[1] = 13.5f;
    d.position[2] = info.origin[1] + float(deepest / size_t(info.columns)) * info.spacing;
    uint32_t id = 0;
    ASSERT_EQ(mr_world_add_body(world.w, &d, &id), MR_OK) << world.last_error();
    world.step(300);
    mr_body_state s{};
    size_t count = 0;
    ASSERT_EQ(mr_world_bodies(world.w, &s, 1, &count), MR_OK);
    ASSERT_EQ(count, 1u);
    EXPECT_NEAR(s.submerged_fraction, 0.5f, 0.02f);
    EXPECT_NEAR(s.position[1], 13.0f, 0.02f) << "half of it under the level";
    EXPECT_LT(std::hypot(s.velocity[0], s.velocity[1], s.velocity[2]), 0.05f);
    EXPECT_EQ(mr_world_remove_body(world.w, id), MR_OK);
    EXPECT_EQ(body_count(world), 0u);
}

}  // namespace
