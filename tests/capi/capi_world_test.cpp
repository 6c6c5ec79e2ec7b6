// The C API (include/metariver/metariver.h) on a running world: NULL arguments and
// refusals that change nothing, the views equal to the copies and the counts to the C++
// Simulation's, the edits, the water queries against their brute-force twins, and
// determinism across thread counts.
#include "capi_support.h"

#include <metariver/metariver.h>
#include <metariver/scene.h>
#include <metariver/water_query.h>

#include "capi_internal.h"  // the world's arena (ThreadsBoundTheWorldsArena)

#include <tbb/info.h>
#include <tbb/task_scheduler_observer.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace capi_test;

// Every function given a NULL world or a NULL required pointer: MR_ERROR_NULL_ARGUMENT,
// never a crash, and a message naming the pointer where there is a world to hold it.
TEST(CApi, NullArguments) {
    float v3[3] = {1, 2, 3};
    size_t n = 0;
    mr_stats s{};
    mr_particles_view pv{};
    mr_surface_view sv{};
    mr_terrain_info ti{};
    mr_brush brush{};
    EXPECT_EQ(mr_world_step(nullptr, kDt), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_stats(nullptr, &s), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_particles(nullptr, &pv), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_copy_particles(nullptr, nullptr, nullptr, 0, &n), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_surface(nullptr, &sv), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_copy_surface(nullptr, nullptr, nullptr, 0, nullptr, 0, &n, &n), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_terrain(nullptr, &ti), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_copy_terrain_heights(nullptr, v3, 3), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_scene_toml(nullptr, nullptr, 0, &n), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_apply_toml(nullptr, "", nullptr), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_sculpt(nullptr, &brush), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_pour(nullptr, v3, 1), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_push(nullptr, v3, 1, v3, &n), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_move_source(nullptr, v3), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_set_sink_boxes(nullptr, nullptr, 0), MR_ERROR_NULL_ARGUMENT);
    mr_water_sample ws{};
    mr_ray_hit hit{};
    EXPECT_EQ(mr_world_sample_water(nullptr, v3, 1, &ws), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_water_velocity(nullptr, v3, 1, v3), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_raycast_water(nullptr, v3, v3, 1, 1.0f, &hit), MR_ERROR_NULL_ARGUMENT);
    EXPECT_STREQ(mr_world_last_error(nullptr), "world is NULL");
    mr_world_destroy(nullptr);

    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    mr_world* w = world.w;
    auto expect_null = [&](mr_status st, const char* name) {
        EXPECT_EQ(st, MR_ERROR_NULL_ARGUMENT) << name;
        EXPECT_TRUE(contains(world.last_error(), std::string(name) + " is NULL")) << world.last_error();
    };
    expect_null(mr_world_stats(w, nullptr), "out");
    expect_null(mr_world_particles(w, nullptr), "out");
    expect_null(mr_world_copy_particles(w, v3, nullptr, 1, nullptr), "count");
    expect_null(mr_world_surface(w, nullptr), "out");
    expect_null(mr_world_copy_surface(w, nullptr, nullptr, 0, nullptr, 0, nullptr, &n), "vertex_count");
    expect_null(mr_world_copy_surface(w, nullptr, nullptr, 0, nullptr, 0, &n, nullptr), "index_count");
    expect_null(mr_world_terrain(w, nullptr), "out");
    expect_null(mr_world_copy_terrain_heights(w, nullptr, 10), "heights");
    expect_null(mr_world_scene_toml(w, nullptr, 0, nullptr), "length");
    expect_null(mr_world_scene_toml(w, nullptr, 10, &n), "buffer");
    expect_null(mr_world_apply_toml(w, nullptr, nullptr), "toml");
    expect_null(mr_world_sculpt(w, nullptr), "brush");
    expect_null(mr_world_pour(w, nullptr, 1), "center");
    expect_null(mr_world_push(w, nullptr, 1, v3, &n), "center");
    expect_null(mr_world_push(w, v3, 1, nullptr, &n), "velocity");
    expect_null(mr_world_move_source(w, nullptr), "center");
    expect_null(mr_world_set_sink_boxes(w, nullptr, 1), "boxes");
    expect_null(mr_world_sample_water(w, nullptr, 1, &ws), "xz");
    expect_null(mr_world_sample_water(w, v3, 1, nullptr), "out");
    expect_null(mr_world_water_velocity(w, nullptr, 1, v3), "points");
    expect_null(mr_world_water_velocity(w, v3, 1, nullptr), "velocities");
    expect_null(mr_world_raycast_water(w, nullptr, v3, 1, 1.0f, &hit), "origins");
    expect_null(mr_world_raycast_water(w, v3, nullptr, 1, 1.0f, &hit), "directions");
    expect_null(mr_world_raycast_water(w, v3, v3, 1, 1.0f, nullptr), "out");
    EXPECT_EQ(world.stats().frame, 0u) << "nothing stepped";
}

TEST(CApi, RefusedCallsChangeNothing) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(20);
    const mr_stats before = world.stats();
    for (float dt : {0.0f, -kDt, 1.5f, std::numeric_limits<float>::quiet_NaN()}) {
        EXPECT_EQ(mr_world_step(world.w, dt), MR_ERROR_INVALID_ARGUMENT);
        EXPECT_TRUE(contains(world.last_error(), "frame_dt") && contains(world.last_error(), "(0, 1]"))
            << world.last_error();
    }
    EXPECT_EQ(world.stats().frame, before.frame);

    size_t count = 0;
    std::vector<float> small(3);
    EXPECT_EQ(mr_world_copy_particles(world.w, small.data(), nullptr, 1, &count), MR_ERROR_BUFFER_TOO_SMALL);
    EXPECT_EQ(count, before.active_particles) << "the count needed";
    EXPECT_TRUE(contains(world.last_error(), std::to_string(before.active_particles))) << world.last_error();
    size_t vertices = 0, indices = 0;
    EXPECT_EQ(mr_world_copy_surface(world.w, small.data(), nullptr, 1, nullptr, 0, &vertices, &indices),
              MR_ERROR_BUFFER_TOO_SMALL);
    EXPECT_EQ(vertices, before.surface_vertices);
    EXPECT_EQ(indices, 3 * before.surface_triangles);
    EXPECT_TRUE(contains(world.last_error(), "vertex_capacity")) << world.last_error();
    std::vector<uint32_t> idx(3);
    EXPECT_EQ(mr_world_copy_surface(world.w, nullptr, nullptr, 0, idx.data(), 3, &vertices, &indices),
              MR_ERROR_BUFFER_TOO_SMALL);
    EXPECT_TRUE(contains(world.last_error(), "index_capacity")) << world.last_error();
    EXPECT_EQ(mr_world_copy_terrain_heights(world.w, small.data(), 3), MR_ERROR_BUFFER_TOO_SMALL);
    const mr::TerrainSourceDef source = mr::default_scene().source;
    EXPECT_TRUE(contains(world.last_error(), std::to_string(source.width * source.height))) << world.last_error();
    char tiny[4] = "abc";
    size_t length = 0;
    EXPECT_EQ(mr_world_scene_toml(world.w, tiny, sizeof tiny, &length), MR_ERROR_BUFFER_TOO_SMALL);
    EXPECT_STREQ(tiny, "abc") << "nothing written";
    EXPECT_GT(length, 100u);

    std::vector<float> boxes(6 * 17);
    for (size_t i = 0; i < 17; ++i) {
        const float b[6] = {0, 0, float(i), 1, 1, float(i) + 0.5f};
        std::memcpy(&boxes[6 * i], b, sizeof b);
    }
    EXPECT_EQ(mr_world_set_sink_boxes(world.w, boxes.data(), 17), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "count") && contains(world.last_error(), "[0, 16]")) << world.last_error();
    const float nan3[3] = {std::numeric_limits<float>::quiet_NaN(), 0, 0};
    EXPECT_EQ(mr_world_pour(world.w, nan3, 10), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "center")) << world.last_error();
    const float c[3] = {30, 5, 30};
    EXPECT_EQ(mr_world_pour(world.w, c, 0), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "count")) << world.last_error();
    EXPECT_EQ(mr_world_push(world.w, c, -1.0f, c, nullptr), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "radius")) << world.last_error();
    const float far[3] = {-500, 0, -500};
    EXPECT_EQ(mr_world_move_source(world.w, far), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "spawn_center")) << world.last_error();
    mr_brush brush{.x = 30, .z = 30, .radius = -2, .strength = 1, .mode = MR_BRUSH_RAISE, .target = 0};
    EXPECT_EQ(mr_world_sculpt(world.w, &brush), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "radius")) << world.last_error();
    brush.radius = 3;
    const int bad_mode = 9;  // what a C caller may store (C++ may not form it as mr_brush_mode)
    std::memcpy(&brush.mode, &bad_mode, sizeof bad_mode);
    EXPECT_EQ(mr_world_sculpt(world.w, &brush), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "brush.mode")) << world.last_error();

    const mr_stats after = world.stats();
    EXPECT_EQ(after.frame, before.frame);
    EXPECT_EQ(after.active_particles, before.active_particles);
    EXPECT_EQ(after.surface_vertices, before.surface_vertices);
}

// The views are the Simulation's arrays; the copies hold the active particles in index
// order and the whole surface; both describe the same frame.
TEST(CApi, ViewsEqualCopies) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const std::vector<float> at_start = copy_positions(world);
    world.step(45);
    const mr_stats s = world.stats();
    mr_particles_view pv{};
    ASSERT_EQ(mr_world_particles(world.w, &pv), MR_OK);
    EXPECT_EQ(pv.count, s.particle_slots);
    std::vector<float> pos(3 * s.active_particles), vel(3 * s.active_particles);
    size_t count = 0;
    ASSERT_EQ(mr_world_copy_particles(world.w, pos.data(), vel.data(), pos.size() / 3, &count), MR_OK);
    ASSERT_EQ(count, s.active_particles) << "exactly the active particles";
    size_t k = 0;
    for (size_t i = 0; i < pv.count; ++i) {
        if (!pv.active[i]) continue;
        ASSERT_LT(k, count);
        ASSERT_EQ(std::memcmp(&pos[3 * k], pv.positions + 3 * i, 3 * sizeof(float)), 0) << i;
        ASSERT_EQ(std::memcmp(&vel[3 * k], pv.velocities + 3 * i, 3 * sizeof(float)), 0) << i;
        ++k;
    }
    EXPECT_EQ(k, count);
    EXPECT_NE(copy_positions(world), at_start) << "stepping moved the water";

    mr_surface_view sv{};
    ASSERT_EQ(mr_world_surface(world.w, &sv), MR_OK);
    EXPECT_EQ(sv.vertex_count, s.surface_vertices);
    EXPECT_EQ(sv.index_count, 3 * s.surface_triangles);
    ASSERT_GT(sv.vertex_count, 0u);
    std::vector<float> sp(3 * sv.vertex_count), sn(3 * sv.vertex_count);
    std::vector<uint32_t> si(sv.index_count);
    size_t nv = 0, ni = 0;
    ASSERT_EQ(mr_world_copy_surface(world.w, sp.data(), sn.data(), sv.vertex_count, si.data(), si.size(), &nv, &ni),
              MR_OK);
    EXPECT_EQ(nv, sv.vertex_count);
    EXPECT_EQ(ni, sv.index_count);
    EXPECT_EQ(std::memcmp(sp.data(), sv.positions, sp.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(sn.data(), sv.normals, sn.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(si.data(), sv.indices, si.size() * sizeof(uint32_t)), 0);
    for (uint32_t i : si) ASSERT_LT(i, nv);
    const float* n0 = sv.normals;
    EXPECT_NEAR(std::sqrt(n0[0] * n0[0] + n0[1] * n0[1] + n0[2] * n0[2]), 1.0f, 1e-3f) << "unit normals";
}

// The C world and a C++ Simulation of the same scene, stepped alike, agree.
TEST(CApi, CountsEqualTheSimulations) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(40);
    const auto sim = twin(40);
    ASSERT_TRUE(sim);
    const mr_stats s = world.stats();
    EXPECT_EQ(s.active_particles, sim->particles().active_count());
    EXPECT_EQ(s.surface_vertices, sim->surface().vertex_count());
    EXPECT_EQ(s.surface_triangles, sim->surface().triangle_count());
}

TEST(CApi, SculptRaisesTheTerrain) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(5);
    const mr_terrain_info t = terrain_info(world);
    const std::vector<float> before = terrain_heights(world);
    const int row = 10, column = 50;  // off the river's channel
    const mr_brush brush{.x = column * t.area_scale, .z = row * t.area_scale, .radius = 4.0f * t.area_scale,
                         .strength = 2.0f, .mode = MR_BRUSH_RAISE, .target = 0.0f};
    ASSERT_EQ(mr_world_sculpt(world.w, &brush), MR_OK) << world.last_error();
    const std::vector<float> after = terrain_heights(world);
    const size_t centre = static_cast<size_t>(row) * t.columns + column;
    EXPECT_NEAR(after[centre] - before[centre], 2.0f, 1e-3f) << "the brush's strength at its centre";
    for (size_t i = 0; i < after.size(); ++i) ASSERT_GE(after[i], before[i] - 1e-6f) << i;
    world.step(2);
}

TEST(CApi, PourPushAndMoveTheSource) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(60);
    const uint64_t before = world.stats().active_particles;
    mr_particles_view pv{};
    ASSERT_EQ(mr_world_particles(world.w, &pv), MR_OK);
    size_t first = 0;
    while (first < pv.count && !pv.active[first]) ++first;
    ASSERT_LT(first, pv.count);
    const float at[3] = {pv.positions[3 * first], pv.positions[3 * first + 1], pv.positions[3 * first + 2]};
    const float velocity[3] = {0.0f, 0.0f, 3.0f};
    size_t pushed = 0;
    ASSERT_EQ(mr_world_push(world.w, at, 2.0f, velocity, &pushed), MR_OK) << world.last_error();
    EXPECT_GT(pushed, 0u) << "water within 2 m of a particle";

    const mr_terrain_info t = terrain_info(world);
    const float centre[3] = {32.0f * t.area_scale, t.max_y + 1.0f, 32.0f * t.area_scale};
    ASSERT_EQ(mr_world_pour(world.w, centre, 200), MR_OK) << world.last_error();
    world.step(2);
    EXPECT_GT(world.stats().active_particles, before) << "poured particles join the water";
    ASSERT_EQ(mr_world_move_source(world.w, centre), MR_OK) << world.last_error();
    std::vector<char> text(1 << 20);
    size_t length = 0;
    ASSERT_EQ(mr_world_scene_toml(world.w, text.data(), text.size(), &length), MR_OK);
    EXPECT_TRUE(contains(text.data(), "spawn_center")) << "the moved source is in the scene";
}

TEST(CApi, ApplyTomlAndSinkBoxes) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(10);
    int32_t applied = -1;
    ASSERT_EQ(mr_world_apply_toml(world.w, "[pbf]\nxsph = 0.2\n", &applied), MR_OK) << world.last_error();
    EXPECT_EQ(applied, 1);
    std::vector<char> text(1 << 20);
    size_t length = 0;
    ASSERT_EQ(mr_world_scene_toml(world.w, text.data(), text.size(), &length), MR_OK);
    EXPECT_TRUE(contains(text.data(), "xsph = 0.2")) << "the edit is the world's scene";

    ASSERT_EQ(mr_world_apply_toml(world.w, "[terrain]\nheight_scale = 3.0\n", &applied), MR_OK);
    EXPECT_EQ(applied, 0) << "the terrain needs a new world";
    EXPECT_TRUE(contains(world.last_error(), "terrain.height_scale")) << world.last_error();
    EXPECT_EQ(mr_world_apply_toml(world.w, "[pbf]\nxsph = 3.0\n", &applied), MR_ERROR_SCENE);
    EXPECT_TRUE(contains(world.last_error(), "pbf.xsph")) << world.last_error();
    EXPECT_EQ(mr_world_apply_toml(world.w, "[pbf\nxsph = ", &applied), MR_ERROR_SCENE);
    ASSERT_EQ(mr_world_scene_toml(world.w, text.data(), text.size(), &length), MR_OK);
    EXPECT_TRUE(contains(text.data(), "xsph = 0.2")) << "the refused edits changed nothing";

    const float boxes[12] = {0, -10, 0, 5, 50, 5, 60, -10, 60, 64, 50, 64};
    ASSERT_EQ(mr_world_set_sink_boxes(world.w, boxes, 2), MR_OK) << world.last_error();
    ASSERT_EQ(mr_world_scene_toml(world.w, text.data(), text.size(), &length), MR_OK);
    EXPECT_TRUE(contains(text.data(), "\n[[sink.box]]")) << "an entry, not the list's comment";
    world.step(2);
    ASSERT_EQ(mr_world_set_sink_boxes(world.w, nullptr, 0), MR_OK) << world.last_error();
    ASSERT_EQ(mr_world_scene_toml(world.w, text.data(), text.size(), &length), MR_OK);
    EXPECT_FALSE(contains(text.data(), "\n[[sink.box]]")) << "count 0 removes them";
}

/// Counts the threads that work in one arena.
class ArenaThreads : public tbb::task_scheduler_observer {
public:
    explicit ArenaThreads(tbb::task_arena& a) : tbb::task_scheduler_observer(a) { observe(true); }
    ~ArenaThreads() override { observe(false); }
    void on_scheduler_entry(bool) override {
        std::lock_guard<std::mutex> lock(mutex_);
        ids_.insert(std::this_thread::get_id());
    }
    size_t count() {
        std::lock_guard<std::mutex> lock(mutex_);
        return ids_.size();
    }

private:
    std::mutex mutex_;
    std::set<std::thread::id> ids_;
};

// desc.threads bounds the threads a world's work runs on (its arena, seen from inside the
// library: src/capi/capi_internal.h); 0 takes every core.
TEST(CApi, ThreadsBoundTheWorldsArena) {
    for (int threads : {1, 2, 0}) {
        mr_world_desc d = mr_world_desc_default();
        d.threads = threads;
        World world(d);
        ASSERT_EQ(world.status, MR_OK) << world.error.message;
        const int expected = threads > 0 ? threads : tbb::info::default_concurrency();
        EXPECT_EQ(world.w->arena.max_concurrency(), expected) << "threads " << threads;
        // The Simulation's own arena, where its steps run (SimulationThreads.* bound it), has
        // the same count: the world's arena alone does not reach into it.
        EXPECT_EQ(world.w->sim->threads(), threads) << "threads " << threads;
        ArenaThreads seen(world.w->arena);
        world.step(20);
        EXPECT_LE(seen.count(), static_cast<size_t>(expected)) << "threads " << threads;
        EXPECT_GE(seen.count(), 1u) << "the caller works in the arena";
    }
}

// The world's own arena: 1 thread and 2 threads step the same particles, bit for bit.
TEST(CApi, ThreadCountsGiveTheSameState) {
    std::vector<std::vector<float>> states;
    for (int threads : {1, 2}) {
        mr_world_desc d = mr_world_desc_default();
        d.threads = threads;
        World world(d);
        ASSERT_EQ(world.status, MR_OK) << world.error.message;
        world.step(60);
        mr_particles_view pv{};
        ASSERT_EQ(mr_world_particles(world.w, &pv), MR_OK);
        std::vector<float> all(pv.positions, pv.positions + 3 * pv.count);
        all.insert(all.end(), pv.velocities, pv.velocities + 3 * pv.count);
        states.push_back(std::move(all));
    }
    ASSERT_EQ(states[0].size(), states[1].size());
    EXPECT_EQ(std::memcmp(states[0].data(), states[1].data(), states[0].size() * sizeof(float)), 0);
}

/// A NaN or infinite point in a batch is answered as WaterQuery answers it (dry, zero
/// velocity, no hit) and the call succeeds with every other point's answer unchanged
/// (`samples`, `velocities`, `hits`: the answers to the finite inputs). The points made
/// bad are two that were wet, moving and hit, so "dry" and "no hit" can be told apart.
void expect_bad_points_answered_alone(mr_world* w, std::vector<float> xz, std::vector<float> points,
                                      std::vector<float> origins, std::vector<float> directions,
                                      const std::vector<mr_water_sample>& samples,
                                      const std::vector<float>& velocities, const std::vector<mr_ray_hit>& hits) {
    const size_t n = xz.size() / 2;
    std::vector<size_t> bad;
    for (size_t i = 0; i < n && bad.size() < 2; ++i)
        if (samples[i].wet && hits[i].hit && velocities[3 * i] != 0.0f) bad.push_back(i);
    ASSERT_EQ(bad.size(), 2u) << "two wet points whose rays hit";
    constexpr float kInf = std::numeric_limits<float>::infinity();
    xz[2 * bad[0]] = std::numeric_limits<float>::quiet_NaN();
    xz[2 * bad[1] + 1] = -kInf;
    points[3 * bad[0] + 1] = kInf;
    points[3 * bad[1] + 2] = std::numeric_limits<float>::quiet_NaN();
    origins[3 * bad[0]] = std::numeric_limits<float>::quiet_NaN();
    directions[3 * bad[1] + 1] = kInf;
    std::vector<mr_water_sample> s(n);
    std::vector<float> v(3 * n, 7.0f);
    std::vector<mr_ray_hit> h(n);
    ASSERT_EQ(mr_world_sample_water(w, xz.data(), n, s.data()), MR_OK) << mr_world_last_error(w);
    ASSERT_EQ(mr_world_water_velocity(w, points.data(), n, v.data()), MR_OK) << mr_world_last_error(w);
    ASSERT_EQ(mr_world_raycast_water(w, origins.data(), directions.data(), n, 100.0f, h.data()), MR_OK)
        << mr_world_last_error(w);
    for (size_t i = 0; i < n; ++i) {
        const bool is_bad = i == bad[0] || i == bad[1];
        EXPECT_EQ(s[i].wet, is_bad ? 0 : samples[i].wet) << i;
        EXPECT_EQ(s[i].surface_y, is_bad ? 0.0f : samples[i].surface_y) << i;
        EXPECT_EQ(s[i].depth, is_bad ? 0.0f : samples[i].depth) << i;
        for (int c = 0; c < 3; ++c) EXPECT_EQ(v[3 * i + c], is_bad ? 0.0f : velocities[3 * i + c]) << i;
        EXPECT_EQ(h[i].hit, is_bad ? 0 : hits[i].hit) << i;
        EXPECT_EQ(h[i].t, is_bad ? 0.0f : hits[i].t) << i;
    }
}

// The three queries through the C API answer what the C++ queries' brute-force twins
// answer on a Simulation stepped alike (the same scene, deterministic).
TEST(CApi, WaterQueriesAnswerLikeTheTwins) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(60);
    const auto sim = twin(60);
    ASSERT_TRUE(sim);
    const mr::Simulation& s = *sim;
    mr_surface_view sv{};
    ASSERT_EQ(mr_world_surface(world.w, &sv), MR_OK);
    ASSERT_GT(sv.vertex_count, 10u);
    std::vector<float> xz, points, origins, directions;
    for (size_t i = 0; i < sv.vertex_count; i += sv.vertex_count / 10) {
        const float* v = sv.positions + 3 * i;
        xz.insert(xz.end(), {v[0], v[2]});
        points.insert(points.end(), {v[0], v[1] - 0.1f, v[2]});
        origins.insert(origins.end(), {v[0] + 0.01f, v[1] + 20.0f, v[2] + 0.01f});
        directions.insert(directions.end(), {0.0f, -1.0f, 0.0f});
    }
    const size_t n = xz.size() / 2;
    std::vector<mr_water_sample> samples(n);
    ASSERT_EQ(mr_world_sample_water(world.w, xz.data(), n, samples.data()), MR_OK) << world.last_error();
    std::vector<float> velocities(3 * n);
    ASSERT_EQ(mr_world_water_velocity(world.w, points.data(), n, velocities.data()), MR_OK) << world.last_error();
    std::vector<mr_ray_hit> hits(n);
    ASSERT_EQ(mr_world_raycast_water(world.w, origins.data(), directions.data(), n, 100.0f, hits.data()), MR_OK)
        << world.last_error();
    size_t wet = 0;
    for (size_t i = 0; i < n; ++i) {
        const mr::WaterSample b = mr::sample_water_brute(s, xz[2 * i], xz[2 * i + 1]);
        EXPECT_EQ(samples[i].wet, b.wet ? 1 : 0) << i;
        EXPECT_NEAR(samples[i].surface_y, b.surface_y, 1e-4f) << i;
        EXPECT_NEAR(samples[i].depth, b.depth, 1e-4f) << i;
        wet += samples[i].wet;
        const mr::Vec3 p{points[3 * i], points[3 * i + 1], points[3 * i + 2]};
        const mr::Vec3 vb = mr::water_velocity_brute(s, p);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(velocities[3 * i + c], vb[c], 1e-3f) << i;
        const mr::Vec3 o{origins[3 * i], origins[3 * i + 1], origins[3 * i + 2]};
        const mr::WaterRayHit hb = mr::raycast_water_brute(s, o, mr::Vec3(0, -1, 0), 100.0f);
        EXPECT_EQ(hits[i].hit, hb.hit ? 1 : 0) << i;
        EXPECT_NEAR(hits[i].t, hb.t, 1e-3f) << i;
    }
    EXPECT_GT(wet, n / 2) << "points under the surface's own vertices";
    expect_bad_points_answered_alone(world.w, xz, points, origins, directions, samples, velocities, hits);
    EXPECT_EQ(mr_world_raycast_water(world.w, origins.data(), directions.data(), n, -1.0f, hits.data()),
              MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), "max_distance")) << world.last_error();
}

}  // namespace
