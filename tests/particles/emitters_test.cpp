// Emitters and sinks: flow rate, recycling at a fixed budget, the drainage network.
#include <metariver/particles.h>

#include <gtest/gtest.h>

namespace mr {
namespace {

struct World {
    Terrain terrain;
    Bvh bvh;
};

World ramp_world() {
    // Heights fall along +x: image column c has 1 - c / (w - 1); 33 x 17 samples.
    Heightmap m = flat_heightmap(33, 17);
    for (int r = 0; r < 17; ++r)
        for (int c = 0; c < 33; ++c) m.samples[size_t(r) * 33 + c] = 1.0f - float(c) / 32.0f;
    auto t = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 8.0f});
    auto b = Bvh::build(t.value(), BvhDef{});
    return World{std::move(t.value()), std::move(b.value())};
}

TEST(Emitters, FlowRateEmitsThatManyParticlesPerSecondUntilTheBudgetIsOut) {
    World w = ramp_world();
    SpawnDef spawn{.count = 100, .center = Vec3(3, 9, 8), .half_extent = Vec3(1, 0.2f, 1), .interval = 0};
    spawn.flow_rate = 30.0f;
    ParticleSolver s(w.terrain, w.bvh, spawn, SpringDef{}, CollisionDef{.mode = CollisionMode::Robust},
                     IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1, std::nullopt, SinkDef{});
    for (int f = 0; f < 60; ++f) s.step_frame(1.0f / 60.0f);
    EXPECT_EQ(s.counters().emitted, 30u);
    EXPECT_EQ(s.particles().active_count(), 30u);
    for (int f = 0; f < 240; ++f) s.step_frame(1.0f / 60.0f);
    EXPECT_EQ(s.particles().active_count(), 100u) << "the budget caps the flow";
}

TEST(Emitters, LitresPerSecondConvertWithTheParticleVolume) {
    SpawnDef spawn;
    spawn.flow_rate = 250.0f;           // litres per second
    spawn.litres_per_particle = 125.0f;  // a 0.5 m cube of water
    EXPECT_FLOAT_EQ(spawn.particles_per_second(), 2.0f);
}

TEST(Emitters, OutletEdgesRecycleParticlesToTheSourceAtAFixedBudget) {
    World w = ramp_world();
    SpawnDef spawn{.count = 200, .center = Vec3(3, 9, 8), .half_extent = Vec3(1, 0.2f, 1), .interval = 0};
    spawn.flow_rate = 40.0f;
    spawn.shape = SourceShape::Disc;
    ParticleSolver s(w.terrain, w.bvh, spawn, SpringDef{},
                     CollisionDef{.mode = CollisionMode::Robust, .damping = 0.0f, .offset = 0.01f},
                     IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1, std::nullopt, SinkDef{.kind = SinkKind::Edges});
    for (int f = 0; f < 1200; ++f) {
        s.step_frame(1.0f / 60.0f);
        ASSERT_LE(s.particles().active_count(), 200u);
        // Active particles stay a prefix.
        const auto& a = s.particles().active;
        for (size_t i = 1; i < a.size(); ++i) ASSERT_LE(a[i], a[i - 1]);
    }
    EXPECT_GT(s.counters().sunk, 100u) << "the water runs off the low edge and comes back";
    EXPECT_EQ(s.counters().respawned, 0u) << "outlets recycle, nothing is lost";
    EXPECT_EQ(s.counters().tunneled, 0u);
    // Every particle id still exists exactly once.
    std::vector<int> seen(200, 0);
    for (uint32_t id : s.particles().id) ++seen[id];
    for (int c : seen) EXPECT_EQ(c, 1);
}

TEST(Emitters, BoxSinkTakesParticlesOut) {
    World w = ramp_world();
    SpawnDef spawn{.count = 50, .center = Vec3(3, 9, 8), .half_extent = Vec3(1, 0.2f, 1), .interval = 0};
    spawn.flow_rate = 25.0f;
    ParticleSolver s(w.terrain, w.bvh, spawn, SpringDef{},
                     CollisionDef{.mode = CollisionMode::Robust, .damping = 0.0f, .offset = 0.01f},
                     IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1, std::nullopt,
                     SinkDef{.kind = SinkKind::Box, .min = Vec3(20, -10, 0), .max = Vec3(24, 20, 16)});
    for (int f = 0; f < 900; ++f) s.step_frame(1.0f / 60.0f);
    EXPECT_GT(s.counters().sunk, 20u);
    for (size_t i = 0; i < s.particles().size(); ++i) {
        if (s.particles().active[i]) {
            EXPECT_LT(s.particles().position[i].x, 24.5f) << "none passes the sink";
        }
    }
}

TEST(ChannelMap, ValleyChannelHeadIsAtTheUpstreamEndAndRampDrainsDownhill) {
    auto t = Terrain::build(procedural_valley(65, 97, 7), TerrainDef{.area_scale = 1.0f, .height_scale = 24.0f});
    const ChannelMap m = ChannelMap::build(t.value());
    const auto [i, j] = m.main_head();
    EXPECT_GT(i, int(0.8 * 96)) << "the valley runs from high z (its head) to low z";
    EXPECT_TRUE(m.is_channel(i, j));
    World w = ramp_world();
    const ChannelMap r = ChannelMap::build(w.terrain);
    EXPECT_GT(r.flow_direction(8, 10).x, 0.9f) << "downhill is +x";
}

TEST(FlowMeter, SteadyRateIsSteadyAndABurstIsNot) {
    FlowMeter steady, burst;
    for (int f = 1; f <= 600; ++f) {
        steady.record(f / 60.0, uint64_t(f / 2));
        burst.record(f / 60.0, f < 500 ? 0u : uint64_t(f - 500));
    }
    EXPECT_TRUE(steady.summary().steady);
    EXPECT_NEAR(steady.summary().rate, 30.0, 0.5);
    EXPECT_FALSE(burst.summary().steady);
}

}  // namespace
}  // namespace mr
