// The solver parts (solver_parts.h) are shared, not copied: the springs, PBF and Bullet
// solvers draw their particles through the one Emitters part (the same points for the
// same seed), and the terrain collider works alone, on any particle set: its robust
// policies never let a particle through where the paper's leaf query does.
#include <metariver/bullet_solver.h>
#include <metariver/pbf_solver.h>
#include <metariver/solver_parts.h>
#include <metariver/spring_solver.h>

#include <gtest/gtest.h>

#include <vector>

namespace mr {
namespace {

struct World {
    Terrain terrain;
    Bvh bvh;
};

World flat_world(int size) {
    auto t = Terrain::build(flat_heightmap(size, size), TerrainDef{.area_scale = 1.0f, .height_scale = 10.0f});
    EXPECT_TRUE(t.ok());
    auto b = Bvh::build(t.value(), BvhDef{});
    EXPECT_TRUE(b.ok());
    return World{std::move(t.value()), std::move(b.value())};
}

std::vector<Vec3> first(const Particles& p, size_t n) { return {p.position.begin(), p.position.begin() + long(n)}; }

TEST(SolverParts, SpringsPbfAndBulletSpawnTheSamePointsThroughTheOneEmitters) {
    const World w = flat_world(33);
    constexpr int kCount = 24;
    constexpr uint32_t kSeed = 7;
    // Well above the ground (y = 0): no solver raises a point onto it.
    const SpawnDef spawn{.count = kCount, .center = Vec3(16.0f, 8.0f, 16.0f), .half_extent = Vec3(3.0f, 1.0f, 2.0f), .interval = 0};

    // The part alone: interval 0 activates the whole budget in the first frame.
    ParticlePool pool(kCount, spawn.center);
    Emitters emitters(w.terrain, EmitterDef{.spawn = spawn}, kSeed);
    emitters.activate_due(pool);
    ASSERT_EQ(pool.next_to_activate, size_t(kCount));
    const std::vector<Vec3> drawn = first(pool.particles, kCount);
    for (size_t i = 1; i < drawn.size(); ++i) EXPECT_NE(drawn[i], drawn[0]) << i << ": random points, not one";
    for (const Vec3& x : drawn) {
        EXPECT_LE(glm::abs(x.x - spawn.center.x), spawn.half_extent.x);
        EXPECT_LE(glm::abs(x.y - spawn.center.y), spawn.half_extent.y);
        EXPECT_LE(glm::abs(x.z - spawn.center.z), spawn.half_extent.z);
    }

    // A frame of 0 s runs each solver's frame loop (activation, step) without moving anything.
    SpringSolver springs(w.terrain, w.bvh, spawn, SpringDef{}, CollisionDef{.mode = CollisionMode::None},
                         IntegratorDef{}, kSeed);
    springs.step_frame(0.0f);
    EXPECT_EQ(first(springs.particles(), kCount), drawn) << "springs";

    BulletSolver bullet(w.terrain, spawn, SpringDef{}, IntegratorDef{}, BulletDef{}, kSeed);
    bullet.step_frame(0.0f);
    EXPECT_EQ(first(bullet.particles(), kCount), drawn) << "Bullet";

    // PBF emits through its lattice; its random spawn is the same part's.
    PbfSolver pbf(w.terrain, w.bvh, spawn, PbfDef{}, CollisionDef{.mode = CollisionMode::None}, IntegratorDef{}, kSeed);
    for (size_t i = 0; i < size_t(kCount); ++i) pbf.spawn(i);
    EXPECT_EQ(first(pbf.particles(), kCount), drawn) << "PBF";
}

/// One particle that moved from above the flat ground (y = 0) at (10, 1, 10) to below
/// it at (40, -1, 40) in one step: it crossed the ground at (25, 0, 25), far from where
/// it ended.
Particles crossing(float dt) {
    Particles p;
    p.resize(1);
    p.active[0] = 1;
    p.last_position[0] = Vec3(10.0f, 1.0f, 10.0f);
    p.position[0] = Vec3(40.0f, -1.0f, 40.0f);
    p.velocity[0] = (p.position[0] - p.last_position[0]) / dt;
    return p;
}

TEST(SolverParts, TheColliderAloneStopsWhatThePapersLeafQueryLetsThrough) {
    const World w = flat_world(65);
    constexpr float dt = 1.0f / 60.0f;

    // The paper's query searches the tree leaf that holds the new position; the crossing
    // is in another leaf: the particle ends under the ground, counted as tunneled.
    Particles paper_p = crossing(dt);
    const TerrainCollider paper(w.terrain, w.bvh, CollisionDef{.mode = CollisionMode::Paper}, false);
    ASSERT_EQ(paper.response(), ContactResponse::Paper);
    const ContactCounts pc = paper.collide_active(paper_p, dt);
    EXPECT_EQ(pc.steps, 1u);
    EXPECT_EQ(pc.tunneled, 1u);
    EXPECT_LT(paper_p.position[0].y, 0.0f);

    // The robust query sweeps the whole segment: the bounce (springs) and the slide (the
    // fluid) both stop it at the crossing, and neither needs the guard.
    for (const bool fluid : {false, true}) {
        Particles p = crossing(dt);
        const TerrainCollider robust(w.terrain, w.bvh, CollisionDef{.mode = CollisionMode::Robust}, fluid);
        EXPECT_EQ(robust.response(), fluid ? ContactResponse::Slide : ContactResponse::Bounce);
        const ContactCounts c = robust.collide_active(p, dt);
        EXPECT_EQ(c.steps, 1u);
        EXPECT_GE(c.collisions, 1u) << fluid;
        EXPECT_EQ(c.tunneled, 0u) << fluid;
        EXPECT_EQ(c.guarded, 0u) << fluid;
        EXPECT_GE(p.position[0].y, 0.0f) << fluid;
        EXPECT_GE(p.velocity[0].y, 0.0f) << fluid << ": nothing left of its way into the ground";
    }
}

}  // namespace
}  // namespace mr
