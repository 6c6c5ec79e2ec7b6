// The "swe" solver at scene level: made by the registry from a scene, its water a
// heightfield the Simulation meshes, its [swe] keys read and checked, its mass balance on a
// real terrain, a lake at rest on a terrain staying at rest.
#include <metariver/scene.h>
#include <metariver/scene_keys.h>
#include <metariver/swe_solver.h>

#include "shallow_water.h"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace mr {
namespace {

SceneDef swe_scene(float discharge) {
    SceneDef d = default_scene();
    d.solver = SolverKind::Swe;
    d.swe.discharge = discharge;
    return d;
}

TEST(SweSolver, ASourceOnTheValleyFillsCellsTheSimulationMeshes) {
    auto sim = Simulation::create(swe_scene(2.0f));
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    EXPECT_EQ(s.solver_entry().kind, SolverKind::Swe);
    for (int f = 0; f < 120; ++f) s.step(1.0f / 60.0f);
    const HeightfieldWater* w = s.heightfield();
    ASSERT_NE(w, nullptr);
    const size_t wet = static_cast<size_t>(std::count_if(w->depth.begin(), w->depth.end(), [](float h) { return h > 1e-3f; }));
    EXPECT_GT(wet, 10u);
    EXPECT_LT(wet, w->size());
    EXPECT_GT(s.surface().triangle_count(), 0u);
    EXPECT_GE(s.counters().substeps, 120u);  // at least one step a frame
    EXPECT_GT(s.counters().cell_updates, 0u);
    EXPECT_EQ(s.particles().size(), 0u);
}

TEST(SweSolver, ItsViewIsTheCoresStateWithEachRowsWetColumnsThroughWettingAndDrying) {
    // A dam break on the valley, a pour and a push: the published view (written over the
    // rows' wet spans, old and new, only) holds the core's depth and velocity in every
    // sample, zeros outside its rows' wet columns, and the fastest speed among them.
    SceneDef d = swe_scene(0.0f);
    d.swe.initial_level = 13.0f;
    d.swe.dam_z = 50.0f;
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    const auto& solver = dynamic_cast<const SweSolver&>(s.solver());
    const swe::ShallowWater& core = solver.core();
    const HeightfieldWater& w = *s.heightfield();
    ASSERT_EQ(w.wet_first.size(), size_t(w.rows));
    ASSERT_EQ(w.wet_last.size(), size_t(w.rows));
    int dried = 0;
    for (int f = 0; f < 240; ++f) {
        if (f == 60) s.pour(Vec3(w.origin.x + 20.0f, 0.0f, w.origin.z + 20.0f), 40);
        if (f == 90) {
            ASSERT_TRUE(s.push(Vec3(w.origin.x + 20.0f, 0.0f, w.origin.z + 20.0f), 4.0f, Vec3(2.0f, 0.0f, 0.0f)).ok());
        }
        s.step(1.0f / 60.0f);
        float fastest = 0.0f;
        for (int i = 0; i < w.rows; ++i) {
            const auto [first, last] = w.wet_columns(i);
            for (int j = 0; j < w.columns; ++j) {
                const size_t k = size_t(i) * size_t(w.columns) + size_t(j);
                const double h = core.depth(j, i);
                const bool moving = h > core.def().dry_depth;
                const Vec3 u = moving ? Vec3(float(core.discharge_x(j, i) / h), 0.0f, float(core.discharge_y(j, i) / h)) : Vec3(0.0f);
                ASSERT_EQ(w.depth[k], float(h)) << f << ": " << i << ", " << j;
                ASSERT_EQ(w.velocity[k], u) << f << ": " << i << ", " << j;
                if (j < first || j > last) {
                    ASSERT_EQ(w.depth[k], 0.0f) << f << ": " << i << ", " << j;
                }
                fastest = std::max(fastest, glm::length(u));
                dried += h == 0.0 && j >= first && j <= last;  // dry inside a span: written as zeros
            }
        }
        ASSERT_EQ(solver.counters().max_speed, fastest) << f;
    }
    EXPECT_GT(dried, 0);  // spans with dry samples in them (the view wrote their zeros)
}

TEST(SweSolver, DischargeAndRainAreLiveEditsTheInitialLakeARebuild) {
    auto sim = Simulation::create(swe_scene(1.0f));
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    for (int f = 0; f < 30; ++f) s.step(1.0f / 60.0f);
    SceneDef next = swe_scene(1.0f);  // the scene as written (def() holds the resolved values)
    next.swe.discharge = 4.0f;
    next.swe.rain = 10.0f;
    auto r = s.apply(next);
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_TRUE(r.value().applied);
    EXPECT_EQ(r.value().keys, (std::vector<std::string>{"swe.discharge", "swe.rain"}));
    s.step(1.0f / 60.0f);  // runs on with the edited source
    next.swe.initial_level = 3.0f;
    r = s.apply(next);
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_FALSE(r.value().applied);
    EXPECT_EQ(r.value().rebuild_key, "swe.initial_level");
}

TEST(SweSolver, MassBalanceOnTheValleyWithRain) {
    auto sim = Simulation::create(swe_scene(0.0f));
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    SweDef def;
    def.discharge = 5.0f;
    def.rain = 100.0f;
    SweSolver solver(sim.value()->terrain(), def, sim.value()->def().spawn.center);
    for (int f = 0; f < 600; ++f) solver.step_frame(1.0f / 60.0f);
    const SweBalance b = solver.balance();
    EXPECT_NEAR(b.inflow, 5.0 * 600.0 * double(1.0f / 60.0f), 1e-9);  // 600 frames of 5 m^3/s
    EXPECT_GT(b.rain, 0.0);
    EXPECT_GT(b.stored, 0.0);
    // inflow + rain - outflow - stored, relative to what came in: the 1e-5 per
    // minute, here to round-off of doubles.
    EXPECT_LT(std::abs(b.error()), 1e-9 * (b.inflow + b.rain));
}

TEST(SweSolver, ALakeAtRestOnTheBowlStaysAtRest) {
    SceneDef d = preset("paper-bowl").value();
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    const Terrain& t = sim.value()->terrain();
    const float lo = t.mesh_bounds().min.y, hi = t.mesh_bounds().max.y;
    SweDef def;
    def.initial_level = lo + 0.3f * (hi - lo);
    SweSolver solver(t, def, Vec3(0.0f));
    const std::vector<float> before = solver.water_heightfield()->depth;
    ASSERT_GT(std::count_if(before.begin(), before.end(), [](float h) { return h > 0.0f; }), 0);
    for (int f = 0; f < 120; ++f) solver.step_frame(1.0f / 60.0f);
    const HeightfieldWater& w = *solver.water_heightfield();
    float dev = 0.0f, speed = 0.0f;
    for (size_t k = 0; k < w.size(); ++k) {
        dev = std::max(dev, std::abs(w.depth[k] - before[k]));
        speed = std::max(speed, glm::length(w.velocity[k]));
    }
    // Well balanced: the lake's depth is the float of a double unchanged to round-off.
    EXPECT_LT(dev, 1e-5f);
    EXPECT_LT(speed, 1e-6f);
    EXPECT_LT(std::abs(solver.balance().error()), 1e-9 * solver.balance().initial);
}

// swe.dam_z: the lake only upstream of the dam line (z >= dam_z) at the start; released, the
// water crosses the line (a dam break) and the volume balances.
TEST(SweSolver, DamZHoldsTheLakeUpstreamAndTheDamBreaks) {
    auto d = parse_scene_toml("solver = \"swe\"\n[swe]\ninitial_level = 13.0\ndam_z = 50.0\n", "dam.toml", default_scene());
    ASSERT_TRUE(d.ok()) << d.error().message;
    EXPECT_FLOAT_EQ(d.value().swe.dam_z, 50.0f);
    auto sim = Simulation::create(d.value());
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    const auto wet_below_dam = [&] {
        const HeightfieldWater& w = *s.heightfield();
        size_t n = 0, wet = 0;
        for (int r = 0; r < w.rows; ++r)
            for (int c = 0; c < w.columns; ++c) {
                const float h = w.depth[static_cast<size_t>(r) * w.columns + c];
                wet += h > 1e-3f;
                n += h > 1e-3f && w.origin.z + static_cast<float>(r) * w.spacing < 50.0f;
            }
        return std::pair{n, wet};
    };
    const auto [below0, wet0] = wet_below_dam();
    EXPECT_EQ(below0, 0u);
    EXPECT_GT(wet0, 100u);
    for (int f = 0; f < 180; ++f) s.step(1.0f / 60.0f);
    EXPECT_GT(wet_below_dam().first, 100u);  // 3 s later the flood is past the line
    const auto* swe = dynamic_cast<const SweSolver*>(&s.solver());
    ASSERT_NE(swe, nullptr);
    EXPECT_LT(std::abs(swe->balance().error()), 1e-9 * swe->balance().initial);
    auto none = parse_scene_toml("solver = \"swe\"\n[swe]\ndam_z = \"none\"\n", "n.toml", default_scene());
    ASSERT_TRUE(none.ok()) << none.error().message;
    EXPECT_TRUE(std::isnan(none.value().swe.dam_z));
}

TEST(SweSolver, SweKeysAreReadByTheSweSolverOnlyAndRangeChecked) {
    const std::string ok = "solver = \"swe\"\n[swe]\nmanning = 0.05\ndischarge = 3.5\nrain = 20\ninitial_level = \"none\"\n";
    auto d = parse_scene_toml(ok, "ok.toml", default_scene());
    ASSERT_TRUE(d.ok()) << d.error().message;
    EXPECT_FLOAT_EQ(d.value().swe.manning, 0.05f);
    EXPECT_FLOAT_EQ(d.value().swe.discharge, 3.5f);
    EXPECT_TRUE(std::isnan(d.value().swe.initial_level));
    EXPECT_TRUE(d.value().swe.auto_source);

    auto pbf = parse_scene_toml("[swe]\nmanning = 0.05\n", "pbf.toml", default_scene());
    ASSERT_FALSE(pbf.ok());
    EXPECT_NE(pbf.error().message.find("swe"), std::string::npos) << pbf.error().message;

    auto bad = parse_scene_toml("solver = \"swe\"\n[swe]\ncfl = 0.9\n", "bad.toml", default_scene());
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("swe.cfl"), std::string::npos) << bad.error().message;
    EXPECT_NE(bad.error().message.find("0.5"), std::string::npos) << bad.error().message;

    auto placed = parse_scene_toml("solver = \"swe\"\n[swe]\nsource_center = [3, 0, 4]\ninitial_level = 2.5\n", "p.toml", default_scene());
    ASSERT_TRUE(placed.ok()) << placed.error().message;
    EXPECT_FALSE(placed.value().swe.auto_source);
    EXPECT_FLOAT_EQ(placed.value().swe.initial_level, 2.5f);
}

}  // namespace
}  // namespace mr
