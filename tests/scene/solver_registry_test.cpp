// The solver registry (include/metariver/solver_registry.h): a solver added here, in this
// file alone, runs through Simulation::create and step with no change to the library.
// Its water is a heightfield (a lake filling the terrain's lowest cells), so the surface
// must come from the heightfield, not from particles; with particles too, one mesh holds
// both surfaces.
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <gtest/gtest.h>
#include <build_options.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace mr {
namespace {

constexpr SolverKind kLake{"test-lake"};

/// A lake whose level rises from the terrain's lowest sample at `rise` metres per
/// second: depth = max(0, level - bed) on the terrain's grid. With `particles`, also a
/// still cluster of eight particles above the terrain's centre (water as both).
class RisingLake final : public Solver {
public:
    RisingLake(const Terrain& t, float rise, bool particles) : terrain_(t), rise_(rise), with_particles_(particles) {
        water_.rows = t.rows();
        water_.columns = t.columns();
        water_.origin = t.vertices().front();
        water_.spacing = t.area_scale();
        water_.depth.assign(water_.size(), 0.0f);
        water_.velocity.assign(water_.size(), Vec3(0.0f));
        level_ = t.mesh_bounds().min.y;
        if (particles) {
            const Vec3 c = t.mesh_bounds().center() + Vec3(0.0f, t.mesh_bounds().extent().y, 0.0f);
            particles_.resize(8);
            for (size_t i = 0; i < 8; ++i) {
                particles_.position[i] = c + Vec3(float(i & 1), float((i >> 1) & 1), float(i >> 2));
                particles_.active[i] = 1;
            }
        }
    }
    void step_frame(float frame_dt) override {
        ++frame_;
        level_ += rise_ * frame_dt;
        for (size_t k = 0; k < water_.size(); ++k) water_.depth[k] = std::max(0.0f, level_ - terrain_.vertices()[k].y);
    }
    const SolverCounters& counters() const override { return counters_; }
    uint64_t frame() const override { return frame_; }
    const HeightfieldWater* water_heightfield() const override { return &water_; }
    const Particles* water_particles() const override { return with_particles_ ? &particles_ : nullptr; }
    float level() const { return level_; }

private:
    const Terrain& terrain_;
    float rise_ = 0.0f, level_ = 0.0f;
    bool with_particles_ = false;
    HeightfieldWater water_;
    Particles particles_;
    SolverCounters counters_;
    uint64_t frame_ = 0;
};

/// The built-in solvers and the lake (rising `rise` m/s; with particles or not).
SolverRegistry with_lake(float rise, bool particles) {
    SolverRegistry r = SolverRegistry::builtin();
    const Status added = r.add({
        .kind = kLake,
        .help = "a lake filling the lowest cells (test)",
        .create = [rise, particles](const SceneDef&, const Terrain& t, const Bvh&) -> std::unique_ptr<Solver> {
            return std::make_unique<RisingLake>(t, rise, particles);
        },
        .no_push = "is still water; nothing to push",
        .no_sculpt = "reads the bed once; nothing to sculpt",
    });
    EXPECT_TRUE(added.ok()) << added.error().message;
    return r;
}

/// paper-full on its procedural twin (17 x 17 samples), no smoothing.
SceneDef lake_scene(SolverKind solver) {
    SceneDef d = preset("paper-full").value();
    d.source.kind = TerrainSource::Strict;
    d.source.width = d.source.height = 17;
    d.solver = solver;
    return d;
}

/// Cells whose four corners lie below `level`: the wet cells of the lake.
size_t cells_below(const Terrain& t, float level) {
    size_t n = 0;
    for (int i = 0; i + 1 < t.rows(); ++i)
        for (int j = 0; j + 1 < t.columns(); ++j)
            n += level > t.sample(i, j) && level > t.sample(i, j + 1) && level > t.sample(i + 1, j) &&
                 level > t.sample(i + 1, j + 1);
    return n;
}

TEST(SolverRegistry, AHeightfieldSolverAddedByATestMakesTheSurfaceFromItsHeightfield) {
    const SolverRegistry solvers = with_lake(3.0f, false);
    auto sim = Simulation::create(lake_scene(kLake), solvers);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    EXPECT_EQ(s.solver_entry().kind, kLake);
    for (int f = 0; f < 30; ++f) s.step(1.0f / 60.0f);
    EXPECT_EQ(s.frame(), 30u);
    const float level = s.terrain().mesh_bounds().min.y + 3.0f * 0.5f;  // 30 frames of 1/60 s at 3 m/s
    // The lake covers some cells, not all (else the count below would not test wetness).
    const size_t wet = cells_below(s.terrain(), level);
    const size_t cells = size_t(s.terrain().rows() - 1) * size_t(s.terrain().columns() - 1);
    ASSERT_GT(wet, 0u);
    ASSERT_LT(wet, cells);
    // The surface is the heightfield's: two triangles per wet cell and the shore's cells cut
    // where the level meets the ground (append_heightfield_surface), every vertex at
    // bed + depth = the level (0.1 mm: float sums of a few metres), normals up and unit.
    const SurfaceMesh& m = s.surface();
    EXPECT_GT(m.triangle_count(), 2 * wet);
    EXPECT_LT(m.triangle_count(), 2 * wet + 6 * (cells - wet));
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) {
        EXPECT_NEAR(m.positions[v].y, level, 1e-4f) << v;
        EXPECT_NEAR(glm::length(m.normals[v]), 1.0f, 1e-5f) << v;
        EXPECT_GT(m.normals[v].y, 0.99f) << v;  // a level lake: (0, 1, 0) up to rounding
    }
    // No particles; the particle stats are zero, and the hash follows the heightfield.
    EXPECT_EQ(s.particles().size(), 0u);
    ASSERT_NE(s.heightfield(), nullptr);
    (void)s.field_dims();  // no field was built: any dims, no crash
    EXPECT_EQ(s.spray_fraction(), 0.0f);
    EXPECT_EQ(s.wet_fraction(), 0.0f);
    // A heightfield solver's channel coverage is measured from its wet cells (the lake
    // covers part of the main channel, not all of it).
    EXPECT_GT(s.channel_coverage(), 0.0f);
    EXPECT_LT(s.channel_coverage(), 1.0f);
    EXPECT_TRUE(s.active_speeds().empty());
    EXPECT_TRUE(s.view().complete());
    EXPECT_EQ(s.view().particles->size(), 0u);
    const uint64_t h30 = s.state_hash();
    s.step(1.0f / 60.0f);
    EXPECT_NE(s.state_hash(), h30);  // the level rose
    auto again = Simulation::create(lake_scene(kLake), solvers);
    ASSERT_TRUE(again.ok());
    for (int f = 0; f < 31; ++f) again.value()->step(1.0f / 60.0f);
    EXPECT_EQ(again.value()->state_hash(), s.state_hash());
}

TEST(SolverRegistry, ParticlesAndAHeightfieldMakeOneMesh) {
    // The same scene with particles and a lake, and with each alone: the mesh holds the
    // particles' surface first, then the heightfield's, its indices offset past the first.
    auto mesh_of = [](float rise, bool particles) {
        auto sim = Simulation::create(lake_scene(kLake), with_lake(rise, particles));
        EXPECT_TRUE(sim.ok()) << sim.error().message;
        for (int f = 0; f < 30; ++f) sim.value()->step(1.0f / 60.0f);
        return sim.value()->surface();
    };
    const SurfaceMesh both = mesh_of(3.0f, true), lake = mesh_of(3.0f, false), drops = mesh_of(0.0f, true);
    ASSERT_GT(lake.triangle_count(), 0u);
    ASSERT_GT(drops.triangle_count(), 0u);  // the cluster's closed blob (a level-0 lake is dry)
    ASSERT_EQ(both.triangle_count(), drops.triangle_count() + lake.triangle_count());
    ASSERT_EQ(both.vertex_count(), drops.vertex_count() + lake.vertex_count());
    const auto offset = uint32_t(drops.vertex_count());
    for (size_t k = 0; k < drops.indices.size(); ++k) EXPECT_EQ(both.indices[k], drops.indices[k]);
    for (size_t k = 0; k < lake.indices.size(); ++k) EXPECT_EQ(both.indices[drops.indices.size() + k], lake.indices[k] + offset);
    for (size_t v = 0; v < lake.vertex_count(); ++v) EXPECT_EQ(both.positions[offset + v], lake.positions[v]);
}

TEST(SolverRegistry, BuiltinHasTheThreeSolversInTheSolverKeysOrder) {
    // All three; a build without Bullet (METARIVER_WITH_BULLET=OFF) the other two, in order.
    const SolverRegistry& r = SolverRegistry::builtin();
    std::vector<std::string_view> built;
    for (const std::string_view n : kBuiltinSolverNames)
        if (test::kWithBullet || n != SolverKind::Bullet.name) built.push_back(n);
    ASSERT_EQ(r.entries().size(), built.size());
    const SceneKey* key = find_scene_key("solver");
    ASSERT_NE(key, nullptr);
    ASSERT_EQ(key->choices.size(), std::size(kBuiltinSolverNames));  // scene files name all three
    for (size_t i = 0; i < r.entries().size(); ++i) {
        const SolverEntry& e = r.entries()[i];
        EXPECT_EQ(e.kind.name, built[i]);
        EXPECT_NE(std::find(key->choices.begin(), key->choices.end(), e.kind.name), key->choices.end());
        EXPECT_EQ(kBuiltinSolverNames[size_t(builtin_solver_index(e.kind))], e.kind.name);
        EXPECT_TRUE(e.create);
        EXPECT_FALSE(e.help.empty());
        ASSERT_TRUE(r.find(e.kind).ok());
        EXPECT_EQ(r.find(e.kind).value(), &e);
    }
    EXPECT_EQ(r.find(SolverKind::Pbf).value()->kind, SolverKind::Pbf);
    EXPECT_EQ(builtin_solver_index(kLake), -1);
}

TEST(SolverRegistry, RefusesAnUnknownSolverNamingTheKnownOnes) {
    const auto r = SolverRegistry::builtin().find(SolverKind{"lava"});
    ASSERT_FALSE(r.ok());
    const std::string& m = r.error().message;
    EXPECT_EQ(m.rfind("solver: ", 0), 0u) << m;
    for (const std::string_view n : {"lava", "springs", "bullet", "pbf"}) {
        if (test::kWithBullet || n != "bullet") {
            EXPECT_NE(m.find(n), std::string::npos) << m;
        }
    }
    // The Simulation refuses a solver its registry does not hold, with the same message.
    auto sim = Simulation::create(lake_scene(kLake));
    ASSERT_FALSE(sim.ok());
    EXPECT_EQ(sim.error().message.rfind("solver: ", 0), 0u) << sim.error().message;
    EXPECT_NE(sim.error().message.find("test-lake"), std::string::npos) << sim.error().message;
    EXPECT_NE(sim.error().message.find("\"pbf\""), std::string::npos) << sim.error().message;
}

TEST(SolverRegistry, RefusesANamelessOrRepeatedSolver) {
    SolverRegistry r = SolverRegistry::builtin();
    const auto factory = [](const SceneDef&, const Terrain& t, const Bvh&) -> std::unique_ptr<Solver> {
        return std::make_unique<RisingLake>(t, 0.0f, false);
    };
    const Status nameless = r.add({.kind = SolverKind{""}, .create = factory});
    ASSERT_FALSE(nameless.ok());
    EXPECT_EQ(nameless.error().message.rfind("solver: ", 0), 0u);
    const Status repeated = r.add({.kind = SolverKind::Pbf, .create = factory});
    ASSERT_FALSE(repeated.ok());
    EXPECT_NE(repeated.error().message.find("\"pbf\" is registered already"), std::string::npos);
    const Status no_factory = r.add({.kind = kLake});
    ASSERT_FALSE(no_factory.ok());
    EXPECT_NE(no_factory.error().message.find("no factory"), std::string::npos);
    EXPECT_EQ(r.entries().size(), SolverRegistry::builtin().entries().size());  // nothing added
}

TEST(SolverRegistry, TheBulletScenesRunExactlyWhereTheBuildHasBullet) {
    SceneDef d = preset("paper-engine").value();
    d.source.kind = TerrainSource::Strict;  // its procedural twin: no PNG needed
    auto sim = Simulation::create(d);
    if (test::kWithBullet) {
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        EXPECT_EQ((*sim)->solver_entry().kind, SolverKind::Bullet);
        return;
    }
    // METARIVER_WITH_BULLET=OFF: refused, naming the solver, the ones there are and the option.
    ASSERT_FALSE(sim.ok());
    const std::string& m = sim.error().message;
    for (const std::string_view s : {"solver: ", "'bullet'", "\"springs\", \"pbf\"", "METARIVER_WITH_BULLET=OFF"})
        EXPECT_NE(m.find(s), std::string::npos) << m;
}

TEST(SolverRegistry, AnEntrysRefusalsNameItsSolver) {
    auto sim = Simulation::create(lake_scene(kLake), with_lake(1.0f, false));
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    const auto pushed = s.push(Vec3(8.0f, 3.0f, 8.0f), 2.0f, Vec3(1.0f, 0.0f, 0.0f));
    ASSERT_FALSE(pushed.ok());
    EXPECT_EQ(pushed.error().message, "push: solver = \"test-lake\" is still water; nothing to push");
    const auto sculpted = s.sculpt({.x = 8.0f, .z = 8.0f, .radius = 2.0f, .strength = 1.0f});
    ASSERT_FALSE(sculpted.ok());
    EXPECT_EQ(sculpted.error().message, "sculpt: solver = \"test-lake\" reads the bed once; nothing to sculpt");
}

}  // namespace
}  // namespace mr
