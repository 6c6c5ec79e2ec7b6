// How the shallow water looks (issue 45, "seen like the particle river"): foam seeded from
// the grid's velocity (src/scene/heightfield_foam.h), the velocity at the water mesh's
// vertices (the flow detail's), both through the Simulation.
#include <metariver/scene.h>
#include <metariver/swe_solver.h>

#include "heightfield_foam.h"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <memory>
#include <utility>
#include <vector>

namespace mr {
namespace {

/// A flat 20 x 20 bed at 1 m spacing, 0.5 m of water at rest.
struct Flat {
    HeightfieldWater w;
    std::vector<Vec3> bed;
    Flat() {
        w.rows = w.columns = 20;
        w.spacing = 1.0f;
        w.depth.assign(w.size(), 0.5f);
        w.velocity.assign(w.size(), Vec3(0.0f));
        for (int i = 0; i < w.rows; ++i)
            for (int j = 0; j < w.columns; ++j) bed.emplace_back(float(j), 0.0f, float(i));
    }
};

TEST(HeightfieldFoam, StillWaterMakesNoneAJumpMakesFoamThatRidesAndDiesWhereTheWaterEnds) {
    FoamDef def;
    def.enabled = true;
    Flat still;
    HeightfieldFoam none(def);
    for (int f = 0; f < 60; ++f) none.step(still.w, still.bed, 1.0f / 60.0f, uint64_t(f));
    EXPECT_EQ(none.generated_total(), 0u);

    // A jump: 5 m/s downstream (+x) in the first half, 0.5 m/s after it.
    Flat jump;
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 20; ++j) jump.w.velocity[size_t(i) * 20 + size_t(j)] = Vec3(j < 10 ? 5.0f : 0.5f, 0.0f, 0.0f);
    HeightfieldFoam foam(def);
    EXPECT_GT(foam.emission_rate(jump.w, jump.bed, 5, 9), 0.0f);   // at the jump
    EXPECT_EQ(foam.emission_rate(jump.w, jump.bed, 5, 14), 0.0f);  // slow and uniform after it
    EXPECT_EQ(foam.emission_rate(jump.w, jump.bed, 5, 4), 0.0f);   // fast but uniform: no shear, flat
    for (int f = 0; f < 30; ++f) foam.step(jump.w, jump.bed, 1.0f / 60.0f, uint64_t(f));
    const DiffuseParticles& p = foam.particles();
    ASSERT_GT(p.size(), 0u);
    for (size_t k = 0; k < p.size(); ++k) {
        EXPECT_EQ(p.kind[k], uint8_t(DiffuseKind::Foam));
        EXPECT_NEAR(p.position[k].y, 0.5f, 0.05f) << k;  // on the surface
        EXPECT_GE(p.position[k].x, 8.0f) << k;            // from the jump's cells, carried downstream
    }
    // The same steps give the same foam (counter-based draws).
    HeightfieldFoam again(def);
    for (int f = 0; f < 30; ++f) again.step(jump.w, jump.bed, 1.0f / 60.0f, uint64_t(f));
    ASSERT_EQ(again.particles().size(), p.size());
    for (size_t k = 0; k < p.size(); ++k) EXPECT_EQ(again.particles().position[k], p.position[k]);
    // The water gone: every foam particle goes with it.
    Flat dry = jump;
    std::fill(dry.w.depth.begin(), dry.w.depth.end(), 0.0f);
    foam.step(dry.w, dry.bed, 1.0f / 60.0f, 30);
    EXPECT_EQ(foam.particles().size(), 0u);
}

TEST(SweLook, ADamBreakHasFoamAndItsMeshCarriesTheWatersVelocity) {
    SceneDef d = default_scene();
    d.solver = SolverKind::Swe;
    d.swe.initial_level = 13.0f;
    d.swe.dam_z = 50.0f;
    d.foam.enabled = true;
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    for (int f = 0; f < 180; ++f) s.step(1.0f / 60.0f);
    const SceneView v = s.view();
    ASSERT_NE(v.foam, nullptr);
    EXPECT_GT(v.foam->size(), 0u);
    // One velocity per vertex of the heightfield's mesh (all of it: no particles), moving.
    ASSERT_EQ(v.surface_velocity.size(), v.surface->vertex_count());
    float fastest = 0.0f;
    for (const Vec3& u : v.surface_velocity) fastest = std::max(fastest, glm::length(u));
    EXPECT_GT(fastest, 2.0f);
    EXPECT_LE(fastest, s.solver().counters().max_speed + 1e-4f);
}


/// The default valley under swe with a still lake up to 13 m over its lower part.
std::unique_ptr<Simulation> lake() {
    SceneDef d = default_scene();
    d.solver = SolverKind::Swe;
    d.swe.initial_level = 13.0f;
    auto sim = Simulation::create(d);
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    return sim.ok() ? std::move(sim.value()) : nullptr;
}

const SweSolver& swe(const Simulation& s) { return dynamic_cast<const SweSolver&>(s.solver()); }

/// The wet sample nearest the lake's middle: (row, column) and its position.
std::pair<size_t, Vec3> a_wet_sample(const Simulation& s) {
    const HeightfieldWater& w = *s.heightfield();
    size_t best = 0;
    for (size_t k = 0; k < w.size(); ++k)
        if (w.depth[k] > w.depth[best]) best = k;
    return {best, s.terrain().vertices()[best]};
}

TEST(SweLook, PourAddsWaterCountedAsInflowPushMovesItSculptingMovesTheBed) {
    auto sim = lake();
    ASSERT_TRUE(sim);
    Simulation& s = *sim;
    const auto [k, at] = a_wet_sample(s);
    const double before = swe(s).balance().stored;
    s.pour(at, 40);  // 40 x 0.125 m^3
    EXPECT_NEAR(swe(s).balance().stored - before, 40 * SweSolver::kPourVolume, 1e-9);
    EXPECT_NEAR(swe(s).balance().inflow, 40 * SweSolver::kPourVolume, 1e-12);
    for (int f = 0; f < 60; ++f) s.step(1.0f / 60.0f);
    EXPECT_LT(std::abs(swe(s).balance().error()), 1e-9 * swe(s).balance().stored);

    // Push: the cells within the radius move the way they were pushed.
    auto still = lake();
    ASSERT_TRUE(still);
    auto pushed = s.push(at, 3.0f, Vec3(2.0f, 0.0f, 0.0f));
    ASSERT_TRUE(pushed.ok()) << pushed.error().message;
    EXPECT_GT(pushed.value(), 5u);
    EXPECT_GT(s.heightfield()->velocity[k].x, 1.0f);

    // Sculpt: a mound raised under the lake raises the water with it (the core's bed),
    // and the lake flows off it.
    auto edit = still->sculpt(Brush{.x = at.x, .z = at.z, .radius = 3.0f, .strength = 1.0f, .mode = BrushMode::Raise});
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    const float bed_now = still->terrain().vertices()[k].y;
    EXPECT_GT(bed_now, at.y);
    for (int f = 0; f < 30; ++f) still->step(1.0f / 60.0f);
    EXPECT_GT(still->solver().counters().max_speed, 0.05f);  // was at rest
    EXPECT_LT(std::abs(swe(*still).balance().error()), 1e-9 * swe(*still).balance().stored);
}

}  // namespace
}  // namespace mr
