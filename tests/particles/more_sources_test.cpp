// More than one source and more than one sink (issue 14): every source emits at its own
// rate into its own volume from the one budget, every sink box takes particles out, and
// only particles that left over an edge are recorded as outlet exits.
#include <metariver/particles.h>
#include <metariver/pbf_solver.h>
#include <metariver/spring_solver.h>

#include <gtest/gtest.h>

#include <cmath>
#include <utility>

namespace mr {
namespace {

struct World {
    Terrain terrain;
    Bvh bvh;
};

/// Flat ground at 0, 24 x 24 m.
World flat_world() {
    auto t = Terrain::build(flat_heightmap(25, 25), TerrainDef{.area_scale = 1.0f, .height_scale = 1.0f});
    auto b = Bvh::build(t.value(), BvhDef{});
    return World{std::move(t.value()), std::move(b.value())};
}

/// Active particles within 5 m (x, z) of `c` (the sources are 13 m apart).
size_t near(const Particles& p, Vec3 c) {
    size_t n = 0;
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i] && std::hypot(p.position[i].x - c.x, p.position[i].z - c.z) < 5.0f) ++n;
    return n;
}

SpawnDef three_sources(int count) {
    SpawnDef spawn{.count = count, .center = Vec3(5, 1.5f, 5), .half_extent = Vec3(1, 0.5f, 1), .interval = 0};
    spawn.flow_rate = 40.0f;
    spawn.sources = {SourceDef{.center = Vec3(18, 1.5f, 6), .half_extent = Vec3(1, 0.5f, 1), .flow_rate = 20.0f},
                     SourceDef{.center = Vec3(12, 1.5f, 18), .half_extent = Vec3(1, 0.5f, 1), .flow_rate = 0.0f}};
    return spawn;
}

TEST(MoreSources, EachSourceEmitsItsOwnRateIntoItsOwnVolume) {
    World w = flat_world();
    const SpawnDef spawn = three_sources(1000);
    ASSERT_FLOAT_EQ(spawn.total_particles_per_second(), 60.0f);
    const CollisionDef collision{.mode = CollisionMode::Robust, .radius = 0.1f};
    // The paper's particles (random points of each volume) and PBF (each source's lattice).
    SpringSolver springs(w.terrain, w.bvh, spawn, SpringDef{}, collision, IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1);
    PbfSolver pbf(w.terrain, w.bvh, spawn, PbfDef{}, collision, IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1);
    ASSERT_EQ(pbf.source_count(), 3u);
    for (size_t k = 0; k < 3; ++k) ASSERT_NE(pbf.lattice_source(k), nullptr) << k;
    EXPECT_EQ(pbf.lattice_source(3), nullptr);
    EXPECT_FLOAT_EQ(pbf.emit_rate(1), 20.0f);
    EXPECT_FLOAT_EQ(pbf.emit_rate(2), 0.0f);
    for (ParticleSolver* s : {static_cast<ParticleSolver*>(&springs), static_cast<ParticleSolver*>(&pbf)}) {
        for (int f = 0; f < 120; ++f) s->step_frame(1.0f / 60.0f);
        const Particles& p = s->particles();
        const size_t a = near(p, spawn.center), b = near(p, spawn.sources[0].center), c = near(p, spawn.sources[1].center);
        std::printf("2 s: %zu at the main source (40/s), %zu at the second (20/s), %zu at the third (0/s)\n", a, b, c);
        EXPECT_NEAR(double(a), 80.0, 2.0);
        EXPECT_NEAR(double(b), 40.0, 2.0);
        EXPECT_EQ(c, 0u) << "a source at rate 0 is off";
        EXPECT_EQ(a + b, p.active_count()) << "nothing born elsewhere";
        EXPECT_EQ(s->counters().emitted, uint64_t(a + b));
    }
}

TEST(MoreSources, AMoreSourceAloneEmitsAndTheBudgetIsShared) {
    // The main source off (rate 0) but a more source on: the scene emits by rate, not
    // all at once; a budget smaller than both rates need runs dry for both.
    World w = flat_world();
    SpawnDef spawn = three_sources(50);
    spawn.flow_rate = 0.0f;
    ASSERT_TRUE(spawn.has_rate());
    SpringSolver s(w.terrain, w.bvh, spawn, SpringDef{}, CollisionDef{.mode = CollisionMode::Robust},
                   IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1);
    for (int f = 0; f < 60; ++f) s.step_frame(1.0f / 60.0f);
    EXPECT_EQ(near(s.particles(), spawn.center), 0u);
    EXPECT_EQ(near(s.particles(), spawn.sources[0].center), 20u);
    for (int f = 0; f < 240; ++f) s.step_frame(1.0f / 60.0f);
    EXPECT_EQ(s.particles().active_count(), 50u) << "one budget";
}

TEST(MoreSinks, EveryBoxTakesParticlesAndOnlyEdgeExitsAreRecorded) {
    // A ramp falling along +x; the water of two sources slides into two box sinks, one
    // under each, besides the outlet edge: what a box takes is sunk, not an exit.
    Heightmap m = flat_heightmap(33, 17);
    for (int r = 0; r < 17; ++r)
        for (int c = 0; c < 33; ++c) m.samples[size_t(r) * 33 + c] = 1.0f - float(c) / 32.0f;
    auto t = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 8.0f});
    auto b = Bvh::build(t.value(), BvhDef{});
    SpawnDef spawn{.count = 400, .center = Vec3(3, 9, 4), .half_extent = Vec3(1, 0.2f, 1), .interval = 0};
    spawn.flow_rate = 30.0f;
    spawn.sources = {SourceDef{.center = Vec3(3, 9, 12), .half_extent = Vec3(1, 0.2f, 1), .flow_rate = 30.0f}};
    SinkDef sink{.kind = SinkKind::Edges};
    sink.boxes = {SinkBox{Vec3(14, -10, 0), Vec3(16, 20, 8)}, SinkBox{Vec3(20, -10, 8.5f), Vec3(22, 20, 16)}};
    SpringSolver s(t.value(), b.value(), spawn, SpringDef{},
                   CollisionDef{.mode = CollisionMode::Robust, .damping = 0.0f, .offset = 0.01f},
                   IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1, sink);
    size_t exits = 0;
    uint64_t sunk = 0, past_first = 0, past_second = 0;
    for (int f = 0; f < 900; ++f) {
        s.step_frame(1.0f / 60.0f);
        exits += s.last_exits().size();
        const Particles& p = s.particles();
        for (size_t i = 0; i < p.size(); ++i) {
            if (!p.active[i]) continue;
            past_first += p.position[i].z < 8.0f && p.position[i].x > 16.5f;
            past_second += p.position[i].z > 8.5f && p.position[i].x > 22.5f;
        }
    }
    sunk = s.counters().sunk;
    std::printf("sunk %llu, exits over the edge %zu\n", (unsigned long long)sunk, exits);
    EXPECT_GT(sunk, 300u) << "both boxes take the water";
    EXPECT_EQ(past_first, 0u) << "none passes the first box";
    EXPECT_EQ(past_second, 0u) << "none passes the second box";
    EXPECT_EQ(exits, 0u) << "every particle was taken by a box, none left over the edge";
    EXPECT_EQ(s.counters().respawned, 0u);
}

}  // namespace
}  // namespace mr
