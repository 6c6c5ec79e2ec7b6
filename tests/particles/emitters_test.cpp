// Emitters and sinks: flow rate, recycling at a fixed budget.
#include <metariver/particles.h>
#include <metariver/pbf_solver.h>
#include <metariver/spring_solver.h>

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <set>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>
#include <vector>

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
    SpringSolver s(w.terrain, w.bvh, spawn, SpringDef{}, CollisionDef{.mode = CollisionMode::Robust},
                     IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1, SinkDef{});
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
    SpringSolver s(w.terrain, w.bvh, spawn, SpringDef{},
                     CollisionDef{.mode = CollisionMode::Robust, .damping = 0.0f, .offset = 0.01f},
                     IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1, SinkDef{.kind = SinkKind::Edges});
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

/// Springless particles sliding down the ramp from a box source near its top (x = 3) at
/// `rate` per second, 1/60 s frames of `substeps` steps.
SpringSolver sliding(const World& w, int count, float rate, SinkDef sink, int substeps = 1) {
    SpawnDef spawn{.count = count, .center = Vec3(3, 9, 8), .half_extent = Vec3(1, 0.2f, 1), .interval = 0};
    spawn.flow_rate = rate;
    return SpringSolver(w.terrain, w.bvh, spawn, SpringDef{},
                          CollisionDef{.mode = CollisionMode::Robust, .damping = 0.0f, .offset = 0.01f},
                          IntegratorDef{.fixed_dt = 1.0f / 60.0f, .substeps = substeps}, 1, sink);
}

TEST(Emitters, BoxSinkTakesParticlesOut) {
    World w = ramp_world();
    SpringSolver s =
        sliding(w, 50, 25.0f, SinkDef{.kind = SinkKind::Box, .min = Vec3(20, -10, 0), .max = Vec3(24, 20, 16)});
    for (int f = 0; f < 900; ++f) {
        s.step_frame(1.0f / 60.0f);
        ASSERT_TRUE(s.last_exits().empty()) << "a box sink takes particles over no edge: no exit positions";
    }
    EXPECT_GT(s.counters().sunk, 20u);
    for (size_t i = 0; i < s.particles().size(); ++i) {
        if (s.particles().active[i]) {
            EXPECT_LT(s.particles().position[i].x, 24.5f) << "none passes the sink";
        }
    }
}

TEST(Emitters, OutletEdgeExitsAreRecordedWhereTheParticlesLeftEachFrame) {
    World w = ramp_world();
    SpringSolver s = sliding(w, 150, 40.0f, SinkDef{.kind = SinkKind::Edges}, 2);
    uint64_t exits = 0;
    for (int f = 0; f < 900; ++f) {
        const uint64_t before = s.counters().sunk;
        s.step_frame(1.0f / 60.0f);
        ASSERT_EQ(s.last_exits().size(), s.counters().sunk - before) << "frame " << f;
        for (const Vec3& p : s.last_exits()) {
            EXPECT_GT(p.x, 32.0f) << "past the low edge";
            EXPECT_GE(p.z, 0.0f);
            EXPECT_LE(p.z, 16.0f);
        }
        exits += s.last_exits().size();
    }
    EXPECT_GT(exits, 100u);
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

namespace mr {
namespace {

World bowlish_world() {
    // A V-shaped trough along x: heights rise with |z - 8|; 17 x 17 samples.
    Heightmap m = flat_heightmap(17, 17);
    for (int r = 0; r < 17; ++r)
        for (int c = 0; c < 17; ++c) m.samples[size_t(r) * 17 + c] = std::abs(float(r) - 8.0f) / 8.0f;
    auto t = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 8.0f});
    auto b = Bvh::build(t.value(), BvhDef{});
    return World{std::move(t.value()), std::move(b.value())};
}

TEST(LatticeSource, SlotsAreALatticeAtTheSpacingAboveTheTerrainDownstreamFirst) {
    World w = bowlish_world();
    const LatticeSource::Def def{.shape = SourceShape::Box, .center = Vec3(8, 3, 8), .half_extent = Vec3(2, 2, 4),
                                 .inflow = Vec3(0, -2, 0), .spacing = 0.5f, .clearance = 0.1f};
    const LatticeSource src = LatticeSource::build(def, w.terrain);
    const auto slots = src.slots();
    ASSERT_FALSE(slots.empty());
    EXPECT_LT(slots.size(), size_t(9 * 9 * 17)) << "slots inside the trough's walls are dropped";
    for (size_t i = 0; i < slots.size(); ++i) {
        const Vec3 q = slots[i];
        const Vec3 o = (q - def.center) / def.spacing;
        EXPECT_NEAR(o.x, std::round(o.x), 1e-4f);
        EXPECT_NEAR(o.y, std::round(o.y), 1e-4f);
        EXPECT_NEAR(o.z, std::round(o.z), 1e-4f);
        EXPECT_GE(q.y, w.terrain.height_mesh(q.x, q.z) + def.clearance) << "slot under the ground";
        if (i > 0) {
            EXPECT_GE(q.y, slots[i - 1].y) << "downstream (the bottom, for an inflow going down) first";
        }
    }
    // Rate: slots * speed / (extent along the inflow + d).
    const float extent = slots.back().y - slots.front().y;
    EXPECT_NEAR(src.max_rate(), float(slots.size()) * 2.0f / (extent + 0.5f), 1e-3f);
}

TEST(LatticeSource, NeverEmitsOntoWaterOrTwiceIntoOneSlot) {
    World w = bowlish_world();
    LatticeSource src = LatticeSource::build(
        LatticeSource::Def{.shape = SourceShape::Disc, .center = Vec3(8, 6, 8), .half_extent = Vec3(1.5f, 0.5f, 0),
                           .spacing = 0.5f},
        w.terrain);
    // Water already sits in part of the source: random points in its lower half.
    std::vector<Vec3> water;
    Lcg rng(4);
    for (int k = 0; k < 40; ++k) water.emplace_back(rng.uniform(6.5f, 9.5f), rng.uniform(5.4f, 6.0f), rng.uniform(6.5f, 9.5f));
    std::vector<Vec3> out;
    src.emit(water, water.size(), 1000, out);
    ASSERT_FALSE(out.empty());
    EXPECT_LT(out.size(), src.slots().size()) << "occupied slots were skipped";
    const float free = LatticeSource::kFreeFraction * 0.5f;
    for (size_t a = 0; a < out.size(); ++a) {
        for (const Vec3& q : water) EXPECT_GE(glm::length(out[a] - q), free) << "emitted onto water";
        for (size_t b = a + 1; b < out.size(); ++b) EXPECT_GE(glm::length(out[a] - out[b]), 0.5f - 1e-4f);
    }
    // The same particles plus the emitted ones: nothing is free any more.
    std::vector<Vec3> all = water;
    all.insert(all.end(), out.begin(), out.end());
    std::vector<Vec3> again;
    src.emit(all, all.size(), 1000, again);
    EXPECT_TRUE(again.empty());
    // Inactive particles (past `active`) do not block.
    src.emit(all, 0, 1000, again);
    EXPECT_EQ(again.size(), src.slots().size());
}

TEST(LatticeSource, FollowGroundLowersEachColumnToJustAboveItsGroundAndKeepsTheRate) {
    // A disc over the ramp (8 m over 32 m along x: the ground under the disc falls 1.25 m).
    World w = ramp_world();
    LatticeSource::Def def{.shape = SourceShape::Disc, .center = Vec3(12, 8, 8), .half_extent = Vec3(2.5f, 0.5f, 0),
                           .inflow = Vec3(0, -3, 0), .spacing = 0.5f, .clearance = 0.1f};
    const LatticeSource flat = LatticeSource::build(def, w.terrain);
    def.follow_ground = true;
    const LatticeSource draped = LatticeSource::build(def, w.terrain);
    ASSERT_EQ(flat.slots().size(), draped.slots().size()) << "the same columns and layers";
    // Each column's lowest slot: clearance + d / 4 above the highest ground of its cell footprint.
    std::map<std::pair<int, int>, float> lowest;
    for (const Vec3& q : draped.slots()) {
        const auto key = std::make_pair(int(std::lround(q.x * 2.0f)), int(std::lround(q.z * 2.0f)));
        auto [it, fresh] = lowest.emplace(key, q.y);
        if (!fresh) it->second = std::min(it->second, q.y);
        EXPECT_GE(q.y, w.terrain.height_mesh(q.x, q.z) + def.clearance) << "slot under the ground";
    }
    float most_over = 0.0f;
    for (const auto& [key, y] : lowest) {
        const float x = 0.5f * float(key.first), z = 0.5f * float(key.second);
        float ground = -1e9f;
        for (float dx : {-0.25f, 0.25f})
            for (float dz : {-0.25f, 0.25f}) ground = std::max(ground, w.terrain.height_mesh(x + dx, z + dz));
        EXPECT_NEAR(y, ground + def.clearance + 0.125f, 1e-3f) << "column at x " << x << ", z " << z;
        most_over = std::max(most_over, y - w.terrain.height_mesh(x, z));
    }
    float flat_over = 0.0f;
    for (const Vec3& q : flat.slots()) flat_over = std::max(flat_over, q.y - 0.5f - w.terrain.height_mesh(q.x, q.z));
    EXPECT_GT(flat_over, 2.0f) << "the flat disc's downhill side starts metres above its ground";
    EXPECT_LT(most_over, 0.5f);
    EXPECT_FLOAT_EQ(draped.max_rate(), flat.max_rate()) << "each column still leaves a layer per spacing / speed";
}

TEST(LatticeSource, ALayerFillsRoundRobinNotAlwaysFromOneSide) {
    // One particle per call with nothing near the source: consecutive calls walk the
    // whole bottom layer before any slot repeats (before, every call took its first slot).
    World w = bowlish_world();
    LatticeSource src = LatticeSource::build(
        LatticeSource::Def{.shape = SourceShape::Disc, .center = Vec3(8, 6, 8), .half_extent = Vec3(1.5f, 0.5f, 0),
                           .inflow = Vec3(0, -3, 0), .spacing = 0.5f},
        w.terrain);
    const float bottom = src.slots().front().y;
    size_t layer = 0;
    for (const Vec3& q : src.slots()) layer += std::abs(q.y - bottom) < 1e-4f;
    ASSERT_GT(layer, 4u);
    std::set<std::pair<float, float>> seen;
    std::vector<Vec3> out;
    for (size_t k = 0; k < layer; ++k) {
        src.emit({}, 0, 1, out);
        ASSERT_EQ(out.size(), 1u);
        EXPECT_NEAR(out[0].y, bottom, 1e-4f) << "the bottom layer first";
        EXPECT_TRUE(seen.emplace(out[0].x, out[0].z).second) << "slot repeated after " << k << " calls";
    }
}

TEST(LatticeSource, AFlowRateTheSourceCannotDeliverIsAWarningAndCapped) {
    World w = ramp_world();
    SpawnDef spawn{.count = 4000, .center = Vec3(4, 9, 8), .half_extent = Vec3(1, 0.25f, 1), .interval = 0,
                   .initial_velocity = Vec3(0, -1, 0)};
    spawn.shape = SourceShape::Disc;
    spawn.flow_rate = 2000.0f;
    PbfSolver s(w.terrain, w.bvh, spawn, PbfDef{}, CollisionDef{.mode = CollisionMode::Robust, .radius = 0.1f},
                     IntegratorDef{.fixed_dt = 1.0f / 120.0f}, 1, SinkDef{});
    ASSERT_NE(s.lattice_source(), nullptr);
    const float cap = s.lattice_source()->max_rate();
    EXPECT_LT(cap, 2000.0f);
    EXPECT_FLOAT_EQ(s.emit_rate(), cap);
    const auto warn = s.warnings();
    ASSERT_EQ(warn.size(), 1u);
    EXPECT_NE(warn[0].find("particles.flow_rate"), std::string::npos) << warn[0];
    char capped[32];
    std::snprintf(capped, sizeof capped, "capped to %.1f", cap);
    EXPECT_NE(warn[0].find(capped), std::string::npos) << warn[0];
    for (int f = 0; f < 240; ++f) s.step_frame(1.0f / 120.0f);
    EXPECT_LE(double(s.counters().emitted), 2.0 * cap + 60.0) << "at most the cap (plus the first fill)";
    EXPECT_GT(double(s.counters().emitted), 0.5 * 2.0 * cap);
}

}  // namespace
}  // namespace mr
