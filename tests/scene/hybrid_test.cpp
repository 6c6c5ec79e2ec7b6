// The "hybrid" solver (include/metariver/hybrid_solver.h): the waterfall preset sheds grid
// water into particles and takes it back; total water and the momentum handed over are
// conserved in a closed waterfall; its [hybrid] keys are read and checked.
#include <metariver/hybrid_solver.h>
#include <metariver/pbf_solver.h>
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

namespace mr {
namespace {

constexpr float kFrame = 1.0f / 60.0f;

const HybridSolver& hybrid_of(const Simulation& s) { return dynamic_cast<const HybridSolver&>(s.solver()); }

/// The waterfall preset closed: the outlet channel's rows and a ring around the map raised to
/// 20 m (nothing leaves: the grid's open edges stay dry, spray falls back), no source, a
/// lake in the upper channel 1 m above the lip (from the lip up), dry below: the lake spills
/// over the cliff into the plunge pool until it is down to the lip, and no water leaves.
/// `pump` (m^3/s): the pump's rate from the plunge pool (above its sill) to the lake.
std::unique_ptr<Simulation> closed_waterfall(float pump = 0.0f) {
    SceneDef d = preset("waterfall").value();
    d.hybrid.pump_rate = pump;
    d.hybrid.pump_radius = 4.0f;
    d.hybrid.pump_from = Vec3(19.5f, 0.0f, 38.0f);
    d.hybrid.pump_to = Vec3(19.5f, 0.0f, 70.0f);
    d.swe.discharge = 0.0f;
    d.swe.initial_level = 0.62f * 20.0f + 1.0f;
    d.swe.dam_z = 0.7f * 79.0f;  // the lip's row
    d.surface = false;  // the water only (the test's time)
    Heightmap map = procedural_waterfall(d.source.width, d.source.height);
    for (int r = 0; r < map.height; ++r)
        for (int c = 0; c < map.width; ++c)
            if (r < 6 || r >= map.height - 2 || c < 2 || c >= map.width - 2)
                map.samples[static_cast<size_t>(r) * map.width + c] = 1.0f;  // walls 20 m high around it
    auto sim = Simulation::create(d, map);
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    return sim.ok() ? std::move(sim.value()) : nullptr;
}

TEST(Hybrid, TheWaterfallShedsParticlesAndTakesThemBack) {
    auto sim = Simulation::create(preset("waterfall").value());
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    EXPECT_EQ(s.solver_entry().kind, SolverKind::Hybrid);
    for (int f = 0; f < 600; ++f) s.step(kFrame);
    const HybridSolver& h = hybrid_of(s);
    const HybridStats& st = h.stats();
    std::printf("waterfall, 10 s: %.3f m^3 to particles, %.3f m^3 to the grid, %zu particles active, %.3f m^3 lost\n",
                st.to_particles, st.to_grid, s.particles().active_count(), st.lost);
    EXPECT_GT(st.to_particles, 0.5);  // 2 m^3/s reaches the cliff within seconds
    EXPECT_GT(st.to_grid, 0.1);
    EXPECT_GT(s.particles().active_count(), 10u);
    EXPECT_LT(st.lost, 1e-2 * st.to_particles);  // a few of spray thrown off the terrain
    // Both drawn: the particles' metaballs and the grid's heightfield in one mesh.
    ASSERT_NE(s.heightfield(), nullptr);
    EXPECT_GT(s.surface().triangle_count(), 0u);
    // The pool below the cliff holds grid water.
    const HeightfieldWater& w = *s.heightfield();
    const size_t pool = static_cast<size_t>(0.55f * 79.0f) * w.columns + w.columns / 2;
    EXPECT_GT(w.depth[pool], 0.05f);
}

TEST(Hybrid, AClosedWaterfallKeepsItsWaterAndTheMomentumHandedOver) {
    // CI runs 60 s of simulated time; HYBRID_SECONDS=600 runs the 10 minutes.
    const char* env = std::getenv("HYBRID_SECONDS");
    const int seconds = env ? std::max(1, std::atoi(env)) : 60;
    auto sim = closed_waterfall();
    ASSERT_NE(sim, nullptr);
    const HybridSolver& h = hybrid_of(*sim);
    const double initial = h.total_volume();
    ASSERT_GT(initial, 50.0);
    double worst = 0.0;
    for (int f = 0; f < 60 * seconds; ++f) {
        sim->step(kFrame);
        worst = std::max(worst, std::abs(h.total_volume() - initial) / initial);
    }
    const HybridStats& st = h.stats();
    const double end = std::abs(h.total_volume() - initial) / initial;
    std::printf("closed waterfall, %d s: %.3f m^3 of water, to particles %.3f m^3 (%llu), to the grid %.3f m^3 (%llu), "
                "now %zu particles; total drift %.2e at the end, %.2e at worst; momentum to particles x %.4e of %.4e "
                "z %.4e of %.4e, back x %.4e of %.4e z %.4e of %.4e\n",
                seconds, initial, st.to_particles, (unsigned long long)st.particles_made, st.to_grid,
                (unsigned long long)st.particles_absorbed, sim->particles().active_count(), end, worst,
                st.particle_momentum_in[0], st.cell_momentum_out[0], st.particle_momentum_in[1], st.cell_momentum_out[1],
                st.cell_momentum_in[0], st.particle_momentum_out[0], st.cell_momentum_in[1], st.particle_momentum_out[1]);
    EXPECT_GT(st.to_particles, 1.0);
    EXPECT_GT(st.to_grid, 1.0);
    EXPECT_EQ(st.lost, 0.0);
    EXPECT_EQ(h.grid_outflow(), 0.0);
    EXPECT_LT(worst, 1e-3);  // the 0.1 %
    // The grid's own balance counts the exchanged volume: round-off.
    EXPECT_LT(std::abs(h.grid_balance_error()), 1e-9 * initial);
    // Momentum: what the cells gave equals what the particles got, and back, within 0.1 %
    // of the momentum handed over.
    for (int a = 0; a < 2; ++a) {
        const double out = std::abs(st.cell_momentum_out[a]) + 1e-9, back = std::abs(st.particle_momentum_out[a]) + 1e-9;
        EXPECT_LE(std::abs(st.particle_momentum_in[a] - st.cell_momentum_out[a]), 1e-3 * out) << "axis " << a;
        EXPECT_LE(std::abs(st.cell_momentum_in[a] - st.particle_momentum_out[a]), 1e-3 * back) << "axis " << a;
    }
    // The flow over the cliff runs along -z (rows run along +z, the lip above the pool):
    // the momentum carried is mostly along it.
    EXPECT_LT(st.cell_momentum_out[1], 0.0);
    EXPECT_GT(std::abs(st.cell_momentum_out[1]), 10.0 * std::abs(st.cell_momentum_out[0]));
}

TEST(Hybrid, APumpedClosedWaterfallKeepsFallingAndKeepsItsWater) {
    // CI runs 90 s of simulated time in three windows; HYBRID_SECONDS=600 runs the issue's
    // 10 minutes in minutes. Without the pump the falls stop after about 60 s.
    const char* env = std::getenv("HYBRID_SECONDS");
    const int seconds = env ? std::max(3, std::atoi(env)) : 90;
    const int window = std::min(60, seconds / 3);
    auto sim = closed_waterfall(0.5f);
    ASSERT_NE(sim, nullptr);
    const HybridSolver& h = hybrid_of(*sim);
    const double initial = h.total_volume();
    double worst = 0.0, least = 1e30, before = 0.0;
    for (int f = 1; f <= 60 * seconds; ++f) {
        sim->step(kFrame);
        worst = std::max(worst, std::abs(h.total_volume() - initial) / initial);
        if (f % (60 * window) == 0) {
            least = std::min(least, h.stats().to_particles - before);
            before = h.stats().to_particles;
        }
    }
    const HybridStats& st = h.stats();
    std::printf("pumped closed waterfall, %d s: %.3f m^3 of water, pumped %.3f m^3, to particles %.3f m^3, to the grid "
                "%.3f m^3, least to particles in a %d s window %.3f m^3, total drift %.2e at worst, grid balance %.2e m^3\n",
                seconds, initial, st.pumped, st.to_particles, st.to_grid, window, least, worst, h.grid_balance_error());
    EXPECT_GT(st.pumped, 0.8 * 0.5 * seconds);  // the pool holds what the pump asks for
    EXPECT_GT(least, 0.1 * 0.5 * window);       // the falls run in every window
    EXPECT_EQ(st.lost, 0.0);
    EXPECT_EQ(h.grid_outflow(), 0.0);
    EXPECT_LT(worst, 1e-3);  // the 0.1 %
    EXPECT_LT(std::abs(h.grid_balance_error()), 1e-9 * initial);
}

TEST(Hybrid, ShedThenStepLeavesTheMomentumOfTheWater) {
    // One frame's hand-over moves horizontal momentum between the grid and the particles
    // without making any: grid + particles before and after shedding into particles that
    // have not moved yet agree to round-off (the frame's physics aside: compare the counters).
    auto sim = closed_waterfall();
    ASSERT_NE(sim, nullptr);
    const HybridSolver& h = hybrid_of(*sim);
    for (int f = 0; f < 240; ++f) sim->step(kFrame);
    const HybridStats& st = h.stats();
    ASSERT_GT(st.particles_made, 0u);
    const double made = st.cell_momentum_out[1];
    EXPECT_NEAR(st.particle_momentum_in[1], made, 1e-6 * std::abs(made) + 1e-9);
}

TEST(Hybrid, KeysAreReadAndChecked) {
    SceneDef d = preset("waterfall").value();
    d.hybrid.drop = -1.0f;
    auto v = validate(d);
    ASSERT_FALSE(v.ok());
    EXPECT_NE(v.error().message.find("hybrid.drop"), std::string::npos) << v.error().message;
    d = preset("waterfall").value();
    d.hybrid.max_particles = 0;
    v = validate(d);
    ASSERT_FALSE(v.ok());
    EXPECT_NE(v.error().message.find("hybrid.max_particles"), std::string::npos) << v.error().message;
    // [hybrid] in a PBF scene is refused, naming the section.
    auto pbf = parse_scene_toml("solver = \"pbf\"\n[hybrid]\ndrop = 2.0\n", "test.toml", default_scene());
    ASSERT_FALSE(pbf.ok());
    EXPECT_NE(pbf.error().message.find("hybrid"), std::string::npos) << pbf.error().message;
    // A particle source's keys are refused, naming the key and where the particles come from;
    // spawn_center is read (swe.source_center = "auto").
    for (const char* key : {"count = 300", "flow_rate = 5.0", "spawn_interval = 3", "initial_velocity = [0, 0, 1]"}) {
        auto r = parse_scene_toml(std::string("preset = \"waterfall\"\n[particles]\n") + key + "\n", "h.toml", default_scene());
        ASSERT_FALSE(r.ok()) << key;
        const std::string name = std::string("particles.") + std::string(key).substr(0, std::string(key).find(' '));
        EXPECT_NE(r.error().message.find(name), std::string::npos) << r.error().message;
        EXPECT_NE(r.error().message.find("come from the grid"), std::string::npos) << r.error().message;
    }
    EXPECT_TRUE(parse_scene_toml("preset = \"waterfall-alps\"\n[particles]\nspawn_center = \"auto\"\n", "h.toml", default_scene()).ok());
    // The preset's file reads back to the same scene.
    auto again = parse_scene_toml(scene_to_toml(preset("weir").value(), "weir"), "weir.toml", default_scene());
    ASSERT_TRUE(again.ok()) << again.error().message;
    EXPECT_EQ(again.value().solver, SolverKind::Hybrid);
    EXPECT_EQ(again.value().hybrid.drop, 0.5f);
    EXPECT_EQ(again.value().source.kind, TerrainSource::Weir);
}

TEST(Hybrid, TheWeirShedsAtItsCrest) {
    auto sim = Simulation::create(preset("weir").value());
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    for (int f = 0; f < 900; ++f) sim.value()->step(kFrame);
    const HybridStats& st = hybrid_of(*sim.value()).stats();
    std::printf("weir, 15 s: %.3f m^3 to particles, %.3f m^3 to the grid\n", st.to_particles, st.to_grid);
    EXPECT_GT(st.to_particles, 0.1);
    EXPECT_GT(st.to_grid, 0.05);
}

TEST(Hybrid, TheWaterfallMakesSprayFromItsParticlesAndFoamFromItsGrid) {
    SceneDef d = preset("waterfall").value();
    d.foam.enabled = true;
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    for (int f = 0; f < 300; ++f) s.step(kFrame);
    ASSERT_NE(s.foam(), nullptr);  // the particles' foam system
    const DiffuseParticles& spray = s.foam()->particles();
    // Spray at the foot of the fall: between the pool's middle (row 43) and the lip (row 55).
    size_t at_foot = 0;
    for (size_t i = 0; i < spray.size(); ++i)
        at_foot += spray.kind[i] == uint8_t(DiffuseKind::Spray) && spray.position[i].z > 40.0f && spray.position[i].z < 56.0f;
    // The grid's foam is drawn with it: the view holds more than the particles' own.
    const SceneView v = s.view();
    ASSERT_NE(v.foam, nullptr);
    std::printf("waterfall with foam, 5 s: %zu from the particles (%zu spray at the foot, %llu made), %zu from the grid\n",
                spray.size(), at_foot, static_cast<unsigned long long>(s.foam()->stats().generated_total),
                v.foam->size() - spray.size());
    EXPECT_GT(s.foam()->stats().generated_total, 0u);
    EXPECT_GT(at_foot, 0u);
    EXPECT_GT(v.foam->size(), spray.size());
}

TEST(Hybrid, SprayThatFallsIntoThePoolFloatsOnItAsTheGridsFoam) {
    // The particles' spray does not know the grid's water: it fell through the pool to its
    // bed (317 particle-frames under the pool's surface in 10 s). Now what is under the
    // surface of water 5 cm deep or more after a frame is the grid's foam, on the surface.
    SceneDef d = preset("waterfall").value();
    d.foam.enabled = true;
    d.surface = false;
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    size_t under = 0, handed = 0, on_pool = 0;
    for (int f = 0; f < 600; ++f) {
        s.step(kFrame);
        handed += s.foam()->stats().handed_over;
        const DiffuseParticles& spray = s.foam()->particles();
        const HeightfieldWater& w = *s.heightfield();
        const auto bed = s.terrain().vertices();
        for (size_t i = 0; i < spray.size(); ++i) {
            // The water's level there, bilinear between the four samples around.
            const Vec3 p = spray.position[i];
            const float u = (p.x - w.origin.x) / w.spacing, t = (p.z - w.origin.z) / w.spacing;
            if (!(u >= 0.0f && t >= 0.0f && u < float(w.columns - 1) && t < float(w.rows - 1))) continue;
            const size_t c = size_t(u), r = size_t(t), k = r * size_t(w.columns) + c;
            const float fu = u - float(c), ft = t - float(r);
            float level = 0.0f, shallowest = 1e9f;
            for (const auto& [n, wt] : {std::pair{k, (1 - fu) * (1 - ft)}, std::pair{k + 1, fu * (1 - ft)},
                                        std::pair{k + size_t(w.columns), (1 - fu) * ft}, std::pair{k + size_t(w.columns) + 1, fu * ft}}) {
                level += wt * (bed[n].y + w.depth[n]);
                shallowest = std::min(shallowest, w.depth[n]);
            }
            under += shallowest >= 0.05f && p.y < level - 0.01f;  // well in the water, 1 cm under
        }
    }
    // The grid's foam holds the spray that landed: on the water, in the pool below the lip.
    const SceneView v = s.view();
    for (size_t i = s.foam()->particles().size(); i < v.foam->size(); ++i)
        on_pool += v.foam->position[i].z > 30.0f && v.foam->position[i].z < 56.0f;
    std::printf("waterfall with foam, 10 s: %zu spray handed to the grid's foam, %zu particle-frames under the pool's "
                "surface, %zu of the grid's foam on the pool now\n", handed, under, on_pool);
    EXPECT_GT(handed, 10u);
    EXPECT_EQ(under, 0u);
    EXPECT_GT(on_pool, 0u);
}

TEST(Hybrid, TheAlpsPresetRunsOnItsBuiltInDem) {
    // terrain.source = "alps": the PNG built into the library, 108 x 61 samples at 5 m.
    SceneDef d = preset("waterfall-alps").value();
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    const HeightfieldWater& w0 = *sim.value()->heightfield();
    EXPECT_EQ(w0.columns, 108);
    EXPECT_EQ(w0.rows, 61);
    for (int f = 0; f < 600; ++f) sim.value()->step(kFrame);
    const HybridStats& st = hybrid_of(*sim.value()).stats();
    std::printf("waterfall-alps, 10 s: %.3f m^3 to particles, %.3f m^3 to the grid, %zu particles active\n", st.to_particles,
                st.to_grid, sim.value()->particles().active_count());
    EXPECT_GT(st.to_particles, 1.0);  // its valley heads drop more than hybrid.drop between cells
    EXPECT_GT(st.to_grid, 0.5);
    // Its file reads back to the same terrain, from any directory.
    auto again = parse_scene_toml(scene_to_toml(d, "waterfall-alps"), "alps.toml", default_scene());
    ASSERT_TRUE(again.ok()) << again.error().message;
    EXPECT_EQ(again.value().source.kind, TerrainSource::Alps);
}

}  // namespace
}  // namespace mr
