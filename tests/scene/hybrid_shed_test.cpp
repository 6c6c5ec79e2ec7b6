// Where the hybrid solver's grid sheds particles (include/metariver/hybrid_solver.h,
// docs/waterfalls.md): the rule scales with the cell. On km cells a gentle reach drops
// hundreds of metres between neighbours yet sheds nothing, while a cliff does; the
// waterfall-alps keys at the Alps' real scale shed nothing; the keys are checked.
#include <metariver/hybrid_solver.h>
#include <metariver/pbf_solver.h>
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace mr {
namespace {

constexpr float kFrame = 1.0f / 60.0f;
constexpr float kCell = 1000.0f;  // metres per sample: km cells
constexpr float kHeight = 8000.0f;

const HybridSolver& hybrid_of(const Simulation& s) { return dynamic_cast<const HybridSolver&>(s.solver()); }

/// A 9-column map `rows` long: `bed(row)` in the channel (columns 2-6), `bank` metres
/// higher on either side, heights over `height_scale` metres.
template <class Bed>
Heightmap channel(int rows, float height_scale, float bank, Bed bed) {
    Heightmap m;
    m.width = 9;
    m.height = rows;
    m.bit_depth = 32;
    m.samples.resize(static_cast<size_t>(m.width) * m.height);
    for (int r = 0; r < m.height; ++r)
        for (int c = 0; c < m.width; ++c)
            m.samples[static_cast<size_t>(r) * m.width + c] = (bed(r) + (c < 2 || c > 6 ? bank : 0.0f)) / height_scale;
    return m;
}

/// A river on km cells, flowing to -z: rows 10-29 a 24 % reach (240 m a cell), a 1500 m
/// cliff from row 10 to row 9 (grade 1.5), a flat pool in rows 0-9 that leaves the map
/// (outfall edges). The channel is columns 2-6, between banks 500 m higher.
Heightmap km_river() {
    return channel(30, kHeight, 500.0f, [](int r) { return r <= 9 ? 100.0f : 1600.0f + 0.24f * kCell * float(r - 10); });
}

/// The waterfall preset's keys on km_river(): 1000 m^3/s at the head (row 27), the river
/// spun up before frame 0; `old_rule`: any drop over hybrid.drop sheds (min_grade and
/// launch 0, the rule before the grade).
std::unique_ptr<Simulation> km_sim(bool old_rule) {
    SceneDef d = preset("waterfall").value();
    d.terrain.area_scale = kCell;
    d.terrain.height_scale = kHeight;
    d.swe.discharge = 1000.0f;
    d.swe.source_center = Vec3(4.0f * kCell, 0.0f, 27.0f * kCell);
    d.spawn.center = d.swe.source_center;
    d.swe.initial_level = std::nanf("");
    d.swe.dam_z = std::nanf("");
    d.swe.init = SweInit::Steady;
    d.pbf = PbfDef{.spacing = 0.5f, .kernel_radius = 1.0f};
    d.pbf.auto_spacing = false;
    d.hybrid.drop = 3.0f;
    if (old_rule) d.hybrid.min_grade = d.hybrid.launch = 0.0f;
    d.surface = false;
    auto sim = Simulation::create(d, km_river());
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    return sim.ok() ? std::move(sim.value()) : nullptr;
}

/// The active particles' z extent after `frames` frames.
struct Made {
    double volume = 0.0;
    float z_min = 1e30f, z_max = -1e30f;
    size_t active = 0;
};
Made run(Simulation& s, int frames) {
    for (int f = 0; f < frames; ++f) s.step(kFrame);
    Made m;
    m.volume = hybrid_of(s).stats().to_particles;
    const Particles& p = s.particles();
    for (size_t k = 0; k < p.size(); ++k)
        if (p.active[k]) {
            m.z_min = std::min(m.z_min, p.position[k].z);
            m.z_max = std::max(m.z_max, p.position[k].z);
            ++m.active;
        }
    return m;
}

TEST(HybridShed, OnKmCellsAGentleReachDoesNotShedButACliffDoes) {
    auto now = km_sim(false), before = km_sim(true);
    ASSERT_NE(now, nullptr);
    ASSERT_NE(before, nullptr);
    const HybridSolver& h = hybrid_of(*now);
    // The cliff's row (row 10 -> 9, its 9 columns, banks included) is all the cliffs; the
    // reach's convex faces (its top, the banks' sides) are launch faces, and none of them
    // launches at a few m/s over 1 km.
    EXPECT_EQ(h.cliff_faces(), 9u);
    const Made m = run(*now, 5), b = run(*before, 5);
    std::printf("km cells, 5 frames: %.1f m^3 to particles (%zu active, z %.0f to %.0f m); %zu launch faces; the old rule "
                "%.1f m^3 (%zu active, z %.0f to %.0f m)\n",
                m.volume, m.active, m.z_min, m.z_max, h.launch_faces(), b.volume, b.active, b.z_min, b.z_max);
    EXPECT_GT(m.volume, 1.0);
    ASSERT_GT(m.active, 0u);
    // Every particle left over the cliff: between the pool's top row and the lip's.
    EXPECT_GT(m.z_min, 9.0f * kCell);
    EXPECT_LT(m.z_max, 10.0f * kCell);
    // The old rule sheds all down the 24 % reach too.
    EXPECT_GT(b.z_max, 12.0f * kCell);
}

TEST(HybridShed, TheAlpsAtTheirRealScaleShedNothingWithTheWaterfallAlpsKeys) {
    // ETOPO5: 7890.5 m between samples, 6429 m from the lowest to the highest.
    SceneDef d = preset("waterfall-alps").value();
    d.terrain.area_scale = 7890.5f;
    d.terrain.height_scale = 6429.0f;
    d.surface = false;
    const auto sheds = [&](float min_grade, float launch) {
        d.hybrid.min_grade = min_grade;
        d.hybrid.launch = launch;
        auto sim = Simulation::create(d);
        EXPECT_TRUE(sim.ok()) << sim.error().message;
        if (!sim.ok()) return -1.0;
        for (int f = 0; f < 60; ++f) sim.value()->step(kFrame);
        return hybrid_of(*sim.value()).stats().to_particles;
    };
    const double now = sheds(0.2f, 1.0f), before = sheds(0.0f, 0.0f);
    std::printf("the Alps at 7.9 km a cell, 1 s: %.1f m^3 to particles, %.1f m^3 with the old rule\n", now, before);
    EXPECT_EQ(now, 0.0);
    EXPECT_GT(before, 10.0);  // its 0.1 % fill slope drops 7.9 m a cell, more than hybrid.drop
}

/// 1 m cells, flowing to -z: a head reach at 2 % (rows 20-39), then a 60 % ramp (rows 10-19:
/// 0.6 m a cell, under the 45 degrees of a cliff) into a pool (rows 0-9). The ramp's top row
/// is its only convex row: it bends by 0.6 - 0.02 = 0.58 (banks 0.4 m high).
Heightmap ramp() {
    return channel(40, 20.0f, 0.4f, [](int r) {
        return r >= 20 ? 10.0f + 0.02f * float(r - 20) : r >= 9 ? 10.0f - 0.6f * float(20 - r) : 3.4f;
    });
}

TEST(HybridShed, AGentlerConvexFaceShedsWhereTheFlowIsFastEnoughToLaunch) {
    // The ramp's top sheds where 2 u^2 0.58 >= launch x 9.81 x 1 m: u >= 2.9 m/s at launch 1,
    // u >= 0.65 m/s at launch 0.05. The river down the head reach runs between the two.
    SceneDef d = preset("waterfall").value();
    d.swe.discharge = 2.0f;
    d.swe.source_center = Vec3(4.0f, 0.0f, 36.0f);
    d.spawn.center = d.swe.source_center;
    d.swe.initial_level = std::nanf("");
    d.swe.dam_z = std::nanf("");
    d.swe.init = SweInit::Steady;
    d.hybrid.drop = 0.5f;  // the ramp's faces drop 0.6 m
    d.surface = false;
    const auto sheds = [&](float launch, float* lip_speed) {
        d.hybrid.launch = launch;
        auto sim = Simulation::create(d, ramp());
        EXPECT_TRUE(sim.ok()) << sim.error().message;
        if (!sim.ok()) return -1.0;
        const HybridSolver& h = hybrid_of(*sim.value());
        EXPECT_EQ(h.cliff_faces(), 0u);
        EXPECT_EQ(h.launch_faces(), launch > 0.0f ? 9u : 0u);  // the ramp's top row, banks included
        for (int f = 0; f < 60; ++f) sim.value()->step(kFrame);
        const HeightfieldWater& w = *sim.value()->heightfield();
        if (lip_speed) *lip_speed = -w.velocity[static_cast<size_t>(20) * w.columns + 4].z;
        return h.stats().to_particles;
    };
    float u = 0.0f;
    const double at_1 = sheds(1.0f, &u), at_005 = sheds(0.05f, nullptr), off = sheds(0.0f, nullptr);
    std::printf("a 0.58 bend on 1 m cells, flow %.2f m/s at its top: %.3f m^3 to particles at launch 1, %.3f at 0.05, %.3f "
                "at 0\n", u, at_1, at_005, off);
    ASSERT_GT(u, 0.65f);
    ASSERT_LT(u, 2.9f);
    EXPECT_EQ(at_1, 0.0);
    EXPECT_GT(at_005, 0.1);
    EXPECT_EQ(off, 0.0);
}

TEST(HybridShed, TheGradeAndLaunchKeysAreChecked) {
    for (const char* key : {"min_grade = -0.5", "launch = -1.0", "min_grade = 1e5", "launch = 2000.0"}) {
        auto r = parse_scene_toml(std::string("preset = \"waterfall\"\n[hybrid]\n") + key + "\n", "h.toml", default_scene());
        ASSERT_FALSE(r.ok()) << key;
        const std::string name = std::string("hybrid.") + std::string(key).substr(0, std::string(key).find(' '));
        EXPECT_NE(r.error().message.find(name), std::string::npos) << r.error().message;
        EXPECT_NE(r.error().message.find("[0, 1000]"), std::string::npos) << r.error().message;
    }
    auto ok = parse_scene_toml("preset = \"waterfall\"\n[hybrid]\nmin_grade = 0.5\nlaunch = 0\n", "h.toml", default_scene());
    ASSERT_TRUE(ok.ok()) << ok.error().message;
    EXPECT_EQ(ok.value().hybrid.min_grade, 0.5f);
    EXPECT_EQ(ok.value().hybrid.launch, 0.0f);
    // The presets' files read back with their grade.
    auto alps = parse_scene_toml(scene_to_toml(preset("waterfall-alps").value(), "waterfall-alps"), "a.toml", default_scene());
    ASSERT_TRUE(alps.ok()) << alps.error().message;
    EXPECT_EQ(alps.value().hybrid.min_grade, 0.2f);
}

}  // namespace
}  // namespace mr
