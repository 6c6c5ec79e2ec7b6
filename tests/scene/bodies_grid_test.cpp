// Bodies on the grid's water (solver = "swe", "hybrid"; src/particles/rigid_bodies_grid.h):
// a box floats in a still lake at the draft Archimedes gives and is still, a tilted flat box
// rights itself, a dense one sinks and rests on the bed, a body in a uniform stream reaches
// the water's speed, the same state at any thread count, and the grid's water (depth,
// velocity, mass balance) is the same with and without bodies (one way). Prints the numbers.
#include <metariver/scene.h>
#include <metariver/swe_solver.h>

#include "bodies_pool.h"
#include "rigid_bodies_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace mr {
namespace {

constexpr float kLevel = 1.6f;  // the lake's level over the pool's floor at y = 0
const Vec3 kBox(1.4f, 1.2f, 1.4f);

/// The bodies' pool (bodies_pool.h) as a still lake on the grid, 1.6 m deep.
SceneDef lake() {
    SceneDef d = test::still_pool(0.2f, 8).def;
    d.name = "bodies lake";
    d.solver = SolverKind::Swe;
    d.swe.initial_level = kLevel;
    d.swe.discharge = 0.0f;
    return d;
}

std::unique_ptr<Simulation> make(const SceneDef& d, int threads = 0) {
    auto sim = Simulation::create(d, test::still_pool(0.2f, 8).map);
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    if (!sim.ok()) return nullptr;
    if (threads) {
        EXPECT_TRUE(sim.value()->set_threads(threads).ok());
    }
    return std::move(sim.value());
}

BodyDef box(float density, Vec3 size = kBox, Vec3 rotation = Vec3(0.0f)) {
    BodyDef b;
    b.shape = BodyShape::Box;
    b.size = size;
    b.density = density;
    b.position = Vec3(4.0f, kLevel + 0.5f * size.y, 4.0f);  // let go with its bottom at the level
    b.rotation = rotation;
    return b;
}

/// Steps `seconds`; the fastest speed over the last second.
float run(Simulation& s, float seconds) {
    const int frames = int(seconds * 60.0f);
    float late = 0.0f;
    for (int f = 0; f < frames; ++f) {
        s.step(1.0f / 60.0f);
        if (f >= frames - 60)
            for (const BodyState& b : s.bodies()) late = std::max(late, glm::length(b.velocity));
    }
    return late;
}

TEST(BodiesOnGrid, ABoxFloatsAtArchimedesDraftAndIsStill) {
    for (const float density : {250.0f, 500.0f, 750.0f}) {
        auto s = make(lake());
        ASSERT_TRUE(s);
        auto id = s->add_body(box(density));
        ASSERT_TRUE(id.ok()) << id.error().message;
        const float late = run(*s, 10.0f);
        const BodyState& b = s->bodies()[0];
        const float draft = kLevel - (b.position.y - 0.5f * kBox.y);
        const float want = density / 1000.0f * kBox.y;
        std::printf("grid lake: density %4.0f draft %.4f m (Archimedes %.4f, error %+.2f %%) submerged %.3f, speed in the "
                    "last second <= %.4f m/s\n",
                    density, draft, want, 100.0f * (draft - want) / want, b.submerged_fraction, late);
        EXPECT_NEAR(draft, want, 0.02f * want) << density;
        EXPECT_NEAR(b.submerged_fraction, density / 1000.0f, 0.02f) << density;
        EXPECT_LT(late, 0.02f) << density;
        EXPECT_NEAR(std::abs(b.orientation.w), 1.0f, 1e-3f) << "it stays level";
    }
}

TEST(BodiesOnGrid, ATiltedFlatBoxRightsItself) {
    auto s = make(lake());
    ASSERT_TRUE(s);
    // 2 x 0.5 x 2 m at 500 kg/m^3 (metacentric height 1.2 m: stable), let go tilted 20 degrees.
    ASSERT_TRUE(s->add_body(box(500.0f, Vec3(2.0f, 0.5f, 2.0f), Vec3(0.0f, 0.0f, 20.0f))).ok());
    const float late = run(*s, 10.0f);
    const BodyState& b = s->bodies()[0];
    const Vec3 up = b.orientation * Vec3(0.0f, 1.0f, 0.0f);
    const float tilt = glm::degrees(std::acos(std::clamp(up.y, -1.0f, 1.0f)));
    std::printf("grid lake: a flat box let go at 20 degrees: %.3f degrees after 10 s, speed %.4f m/s\n", tilt, late);
    EXPECT_LT(tilt, 1.0f);
    EXPECT_LT(late, 0.02f);
}

TEST(BodiesOnGrid, ADenseBodySinksAndRestsOnTheBed) {
    auto s = make(lake());
    ASSERT_TRUE(s);
    ASSERT_TRUE(s->add_body(box(2000.0f)).ok());
    const float late = run(*s, 10.0f);
    const BodyState& b = s->bodies()[0];
    std::printf("grid lake: density 2000 rests at y %.4f (bed + half its height: %.4f), speed %.4f m/s\n", b.position.y,
                0.5f * kBox.y, late);
    EXPECT_NEAR(b.position.y, 0.5f * kBox.y, 0.03f);
    EXPECT_NEAR(b.submerged_fraction, 1.0f, 1e-3f);
    EXPECT_LT(late, 0.02f);
}

TEST(BodiesOnGrid, ABodyInAUniformStreamReachesTheWatersSpeed) {
    // A flat map under 1 m of water flowing at 1.5 m/s along x everywhere: the steady uniform
    // channel flow, given to the bodies directly.
    SceneDef d = lake();
    d.source.width = d.source.height = 64;
    auto sim = Simulation::create(d, flat_heightmap(64, 64));
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    const Terrain& t = sim.value()->terrain();
    HeightfieldWater w;
    w.rows = t.rows(), w.columns = t.columns(), w.spacing = t.area_scale();
    w.depth.assign(w.size(), 1.0f);
    w.velocity.assign(w.size(), Vec3(1.5f, 0.0f, 0.0f));
    for (const BodyShape shape : {BodyShape::Box, BodyShape::Sphere, BodyShape::Capsule}) {
        GridBodies bodies;
        BodyDef log;
        log.shape = shape;
        log.size = shape == BodyShape::Box ? Vec3(2.0f, 0.5f, 0.5f) : Vec3(0.3f, 1.5f, 0.0f);
        log.density = 600.0f;
        log.position = Vec3(5.0f, 1.0f, 32.0f);
        ASSERT_TRUE(bodies.add(log).ok());
        float at2 = 0.0f;
        for (int f = 0; f < 600; ++f) {
            bodies.step(w, t, 1.0f / 60.0f, 9.81f);
            if (f == 119) at2 = bodies.states()[0].velocity.x;
        }
        const BodyState& b = bodies.states()[0];
        std::printf("grid stream 1.5 m/s: %s speed %.4f m/s after 2 s, %.4f after 10 s (%.2f %% of the water's), drifted "
                    "%.1f m, across %.4f m\n",
                    std::string(to_string(shape)).c_str(), at2, b.velocity.x, 100.0f * b.velocity.x / 1.5f,
                    b.position.x - 5.0f, b.position.z - 32.0f);
        EXPECT_NEAR(b.velocity.x, 1.5f, 0.01f * 1.5f) << to_string(shape);
        EXPECT_GT(at2, 0.8f * 1.5f) << "within two seconds";
        EXPECT_GT(b.position.x - 5.0f, 12.0f);
        EXPECT_NEAR(b.position.z, 32.0f, 1e-3f) << "straight down the stream";
        EXPECT_NEAR(b.submerged_fraction, 0.6f, 0.05f) << "it floats";
    }
}

TEST(BodiesOnGrid, TheGridsWaterIsTheSameWithAndWithoutBodies) {
    // One way: the bodies read the grid, never write it (a pour and a push make it move).
    SceneDef d = lake();
    d.swe.discharge = 0.5f;
    d.swe.auto_source = false;
    d.swe.source_center = Vec3(3.0f, 0.0f, 3.0f);
    auto with = make(d), without = make(d);
    ASSERT_TRUE(with && without);
    ASSERT_TRUE(with->add_body(box(500.0f)).ok());
    ASSERT_TRUE(with->add_body(box(2000.0f, Vec3(0.5f), Vec3(10.0f, 20.0f, 30.0f))).ok());
    for (int f = 0; f < 240; ++f) {
        for (Simulation* s : {with.get(), without.get()}) {
            if (f == 30) {
                EXPECT_TRUE(s->push(Vec3(4.0f, 0.0f, 4.0f), 2.0f, Vec3(1.0f, 0.0f, 0.0f)).ok());
            }
            s->step(1.0f / 60.0f);
        }
    }
    EXPECT_EQ(with->heightfield()->depth, without->heightfield()->depth);
    EXPECT_EQ(with->heightfield()->velocity, without->heightfield()->velocity);
    const SweBalance a = dynamic_cast<const SweSolver&>(with->solver()).balance();
    const SweBalance b = dynamic_cast<const SweSolver&>(without->solver()).balance();
    EXPECT_EQ(a.stored, b.stored);
    EXPECT_EQ(a.inflow, b.inflow);
    EXPECT_EQ(a.outflow, b.outflow);
    EXPECT_LT(std::abs(a.error()), 1e-9 * (a.initial + a.inflow));
    EXPECT_GT(glm::length(with->bodies()[0].velocity) + glm::length(with->bodies()[1].velocity), 0.0f);
}

TEST(BodiesOnGrid, TheSameStateAtAnyThreadCount) {
    SceneDef d = lake();
    d.swe.discharge = 0.5f;
    d.swe.auto_source = false;
    d.swe.source_center = Vec3(3.0f, 0.0f, 3.0f);
    uint64_t hash[2] = {0, 0};
    for (const int threads : {1, 2}) {
        auto s = make(d, threads);
        ASSERT_TRUE(s);
        // Three bodies that touch: the contacts between them too.
        ASSERT_TRUE(s->add_body(box(500.0f, Vec3(1.0f, 0.5f, 1.0f))).ok());
        BodyDef b = box(300.0f, Vec3(0.8f, 0.4f, 0.8f), Vec3(0.0f, 30.0f, 10.0f));
        b.position += Vec3(0.7f, 0.3f, 0.2f);
        ASSERT_TRUE(s->add_body(b).ok());
        b.shape = BodyShape::Sphere;
        b.size = Vec3(0.3f);
        b.position = Vec3(3.5f, kLevel + 1.0f, 3.6f);
        ASSERT_TRUE(s->add_body(b).ok());
        run(*s, 4.0f);
        hash[threads - 1] = s->state_hash();
    }
    EXPECT_EQ(hash[0], hash[1]);
}

TEST(BodiesOnGrid, SceneBodiesLoadOnSweAndHybridAndLiveEditsKeepThem) {
    SceneDef d = lake();
    d.bodies = {box(500.0f), box(2000.0f, Vec3(0.4f))};
    auto s = make(d);
    ASSERT_TRUE(s);
    ASSERT_EQ(s->bodies().size(), 2u);
    run(*s, 0.5f);
    const Vec3 was = s->bodies()[0].position;
    SceneDef next = d;
    next.bodies.pop_back();
    auto r = s->apply(next);
    ASSERT_TRUE(r.ok()) << r.error().message;
    ASSERT_EQ(s->bodies().size(), 1u);
    EXPECT_EQ(s->bodies()[0].position, was) << "the unchanged entry keeps its body";
    EXPECT_TRUE(s->remove_body(s->bodies()[0].id).ok());
    EXPECT_TRUE(s->bodies().empty());
    EXPECT_FALSE(s->remove_body(99).ok());
    // A bad body names its key; a solver without water to float them on refuses them.
    BodyDef bad = box(-1.0f);
    auto e = s->add_body(bad);
    ASSERT_FALSE(e.ok());
    EXPECT_EQ(e.error().message.rfind("bodies.density", 0), 0u) << e.error().message;
    SceneDef springs = d;
    springs.solver = SolverKind::Springs;
    EXPECT_FALSE(Simulation::create(springs, test::still_pool(0.2f, 8).map).ok());
    SceneDef hybrid = preset("waterfall").value();
    hybrid.bodies = {box(500.0f)};
    hybrid.bodies[0].position = Vec3(0.0f);  // placed below: it falls to the ground
    auto h = Simulation::create(hybrid);
    ASSERT_TRUE(h.ok()) << h.error().message;
    EXPECT_EQ(h.value()->bodies().size(), 1u);
    h.value()->step(1.0f / 60.0f);
    EXPECT_TRUE(std::isfinite(h.value()->bodies()[0].position.y));
}

}  // namespace
}  // namespace mr

