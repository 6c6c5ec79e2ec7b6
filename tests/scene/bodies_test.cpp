// Bodies in still water (issue 44): a box floats at the draft Archimedes gives and is
// still; a dense one sinks and rests on the bed; the pool's level rises by the submerged
// volume; the water never ends a step inside a body, and the count can count; the same
// state at any thread count; errors name the key. Prints the numbers of the physics table.
#include <metariver/pbf_solver.h>
#include <metariver/scene.h>

#include "bodies_pool.h"
#include "body_cells.h"
#include "pbf_probe.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <cstdio>
#include <vector>

namespace mr {
namespace {

namespace fs = std::filesystem;

constexpr float kSpacing = 0.2f;
constexpr int kLayers = 8;  // 1.6 m of water
const Vec3 kBox(1.4f, 1.2f, 1.4f);

/// The level of the water farther than `clear` from (4, 4) horizontally: the mean height
/// of the highest particle per 2-spacing column, plus half a spacing.
float level_away(const Simulation& s, float clear) {
    const Particles& p = s.particles();
    const float cell = 2.0f * kSpacing;
    const int n = int(6.0f / cell) + 1;
    std::vector<float> top(size_t(n * n), -1e30f);
    for (size_t i = 0; i < p.size(); ++i) {
        if (!p.active[i]) continue;
        const Vec3 x = p.position[i];
        if (std::max(std::abs(x.x - 4.0f), std::abs(x.z - 4.0f)) < clear) continue;
        const int a = std::clamp(int((x.x - 1.0f) / cell), 0, n - 1), b = std::clamp(int((x.z - 1.0f) / cell), 0, n - 1);
        top[size_t(a * n + b)] = std::max(top[size_t(a * n + b)], x.y);
    }
    double sum = 0.0;
    int cnt = 0;
    for (float t : top)
        if (t > -1e29f) sum += t, ++cnt;
    return cnt ? float(sum / cnt) + 0.5f * kSpacing : 0.0f;
}

struct Float {
    float draft = 0.0f, level = 0.0f, speed = 0.0f, max_speed_late = 0.0f, y = 0.0f;
    uint64_t inside = 0;
};

/// A box of `density` let go with its bottom at the water's level in the pool, after
/// `seconds`: its draft under the level around it, its speed.
Float float_box(float density, float seconds, int threads = 0) {
    test::Pool pool = test::still_pool(kSpacing, kLayers);
    auto sim = Simulation::create(pool.def, pool.map);
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    Simulation& w = *sim.value();
    if (threads) {
        EXPECT_TRUE(w.set_threads(threads).ok());
    }
    for (int f = 0; f < 60; ++f) w.step(1.0f / 60.0f);
    Float r;
    if (density > 0.0f) {
        BodyDef b;
        b.size = kBox;
        b.density = density;
        b.position = Vec3(4.0f, level_away(w, 0.0f) + 0.5f * kBox.y, 4.0f);
        auto id = w.add_body(b);
        EXPECT_TRUE(id.ok()) << id.error().message;
    }
    const int frames = int(seconds * 60.0f);
    for (int f = 0; f < frames; ++f) {
        w.step(1.0f / 60.0f);
        if (density > 0.0f && f >= frames - 60) r.max_speed_late = std::max(r.max_speed_late, glm::length(w.bodies()[0].velocity));
    }
    r.level = level_away(w, 1.2f);
    if (density > 0.0f) {
        const BodyState& b = w.bodies()[0];
        r.y = b.position.y;
        r.draft = r.level - (b.position.y - 0.5f * kBox.y);
        r.speed = glm::length(b.velocity);
    }
    r.inside = w.counters().inside_bodies;
    return r;
}

TEST(Bodies, ABoxFloatsAtTheDraftArchimedesGivesAndTheLevelRises) {
    const Float still = float_box(0.0f, 10.0f);
    for (float rho : {250.0f, 500.0f, 750.0f}) {
        const Float r = float_box(rho, 10.0f);
        const float want = rho / 1000.0f * kBox.y;
        // The level rises by the submerged volume (the box's mass over water's density)
        // over the pool's area at the level.
        const float rise = r.level - still.level, want_rise = rho * kBox.x * kBox.y * kBox.z / 1000.0f / test::Pool::area(still.level);
        std::printf("box %.0f kg/m^3: draft %.3f m (Archimedes %.3f, error %+.1f %%), speed after 10 s %.4f m/s (max over the "
                    "last second %.4f), level rise %.3f m (expected %.3f, error %+.1f %%), particles inside bodies %llu\n",
                    rho, r.draft, want, 100.0f * (r.draft - want) / want, r.speed, r.max_speed_late, rise, want_rise,
                    100.0f * (rise - want_rise) / want_rise, (unsigned long long)r.inside);
        EXPECT_NEAR(r.draft, want, 0.1f * want) << rho;
        EXPECT_LT(r.speed, 0.02f) << rho << ": still after 10 s";
        EXPECT_LT(r.max_speed_late, 0.03f) << rho << ": jitter";
        EXPECT_NEAR(rise, want_rise, 0.1f * want_rise) << rho;
        EXPECT_EQ(r.inside, 0u);
    }
}

TEST(Bodies, ADenseBoxSinksAndRestsOnTheBed) {
    const Float r = float_box(2000.0f, 6.0f);
    std::printf("box 2000 kg/m^3: bottom %.3f m above the bed, speed %.4f m/s, inside %llu\n", r.y - 0.5f * kBox.y, r.speed,
                (unsigned long long)r.inside);
    // On the bed: what is left under it is less than half a spacing of water.
    EXPECT_NEAR(r.y - 0.5f * kBox.y, 0.0f, 0.5f * kSpacing) << "not on the bed";
    EXPECT_LT(r.max_speed_late, 0.02f);
    EXPECT_EQ(r.inside, 0u);
}

TEST(Bodies, TheSameStateAtOneAndTwoThreads) {
    uint64_t hash[2] = {0, 0};
    for (int t = 1; t <= 2; ++t) {
        test::Pool pool = test::still_pool(kSpacing, kLayers);
        pool.def.bodies.push_back(BodyDef{.size = Vec3(1.0f, 0.6f, 0.8f), .density = 600.0f, .position = Vec3(3.6f, 2.2f, 4.0f)});
        pool.def.bodies.push_back(BodyDef{.shape = BodyShape::Sphere, .size = Vec3(0.4f, 0.0f, 0.0f), .density = 800.0f,
                                          .position = Vec3(4.1f, 3.2f, 4.1f), .velocity = Vec3(0.0f, -2.0f, 0.0f)});
        auto sim = Simulation::create(pool.def, pool.map);
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        Simulation& w = *sim.value();
        ASSERT_TRUE(w.set_threads(t).ok());
        ASSERT_EQ(w.bodies().size(), 2u);
        for (int f = 0; f < 120; ++f) w.step(1.0f / 60.0f);
        hash[t - 1] = w.state_hash();
        // The sphere lands on the box: the water between them leaves both (pbf_bodies.cpp).
        std::printf("threads %d: state hash %016llx, particle-steps inside bodies %llu\n", t, (unsigned long long)hash[t - 1],
                    (unsigned long long)w.counters().inside_bodies);
        EXPECT_EQ(w.counters().inside_bodies, 0u);
    }
    EXPECT_EQ(hash[0], hash[1]);
}

// The count is honest: with the coupling off (the test probe) the water does not see a
// body falling through it, and the steps that end inside it are counted.
TEST(Bodies, TheInsideCountCounts) {
    test::Pool pool = test::still_pool(kSpacing, kLayers);
    auto sim = Simulation::create(pool.def, pool.map);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    const SceneDef& d = sim.value()->def();
    for (bool coupled : {true, false}) {
        PbfSolver s(sim.value()->terrain(), sim.value()->bvh(), d.spawn, d.pbf, d.collision, d.integrator, d.seed, d.sink);
        PbfProbe::set_body_coupling(s, coupled);
        for (int f = 0; f < 30; ++f) s.step_frame(1.0f / 60.0f);
        ASSERT_TRUE(s.add_body(BodyDef{.size = kBox, .density = 3000.0f, .position = Vec3(4.0f, 2.5f, 4.0f)}).ok());
        for (int f = 0; f < 60; ++f) s.step_frame(1.0f / 60.0f);
        std::printf("coupling %s: %llu particle-steps inside the body\n", coupled ? "on" : "off",
                    (unsigned long long)s.counters().inside_bodies);
        if (coupled) EXPECT_EQ(s.counters().inside_bodies, 0u);
        else EXPECT_GT(s.counters().inside_bodies, 100u);
    }
}

TEST(Bodies, ErrorsNameTheKey) {
    test::Pool pool = test::still_pool(kSpacing, 2);
    auto sim = Simulation::create(pool.def, pool.map);
    ASSERT_TRUE(sim.ok());
    Simulation& w = *sim.value();
    auto bad = w.add_body(BodyDef{.density = -1.0f});
    ASSERT_FALSE(bad.ok());
    EXPECT_EQ(bad.error().message, "bodies.density: must be in (0, 100000] (got -1)");
    EXPECT_NE(w.add_body(BodyDef{.size = Vec3(0.0f, 1.0f, 1.0f)}).error().message.find("bodies.size"), std::string::npos);
    EXPECT_NE(w.add_body(BodyDef{.friction = 3.0f}).error().message.find("bodies.friction"), std::string::npos);
    auto mesh = w.add_body(BodyDef{.shape = BodyShape::ConvexMesh, .size = Vec3(1.0f), .mesh = "/nonexistent/log.obj"});
    ASSERT_FALSE(mesh.ok());
    EXPECT_NE(mesh.error().message.find("bodies.mesh"), std::string::npos);
    EXPECT_NE(mesh.error().message.find("/nonexistent/log.obj"), std::string::npos);
    // Ids are stable and not reused; a removed id is an error naming it.
    const uint32_t a = w.add_body(BodyDef{.position = Vec3(4, 3, 4)}).value();
    const uint32_t b = w.add_body(BodyDef{.position = Vec3(4, 4, 4)}).value();
    ASSERT_TRUE(w.remove_body(a).ok());
    const uint32_t c = w.add_body(BodyDef{.position = Vec3(4, 5, 4)}).value();
    EXPECT_NE(c, a);
    EXPECT_EQ(w.bodies().size(), 2u);
    EXPECT_EQ(w.bodies()[0].id, b);
    EXPECT_NE(w.remove_body(a).error().message.find("id"), std::string::npos);
    EXPECT_FALSE(w.set_body_motion(b, Vec3(NAN), glm::quat(1, 0, 0, 0), Vec3(0), Vec3(0)).ok());
    EXPECT_EQ(w.view().bodies.size(), 2u);
    // Other solvers have no bodies: the error names `bodies` and the solver.
    SceneDef springs = pool.def;
    springs.solver = SolverKind::Springs;
    springs.bodies.push_back(BodyDef{});
    auto no = Simulation::create(springs, pool.map);
    ASSERT_FALSE(no.ok());
    const std::string& m = no.error().message;
    EXPECT_EQ(m.rfind("bodies: ", 0), 0u) << m;
    EXPECT_NE(m.find("solver = \"springs\""), std::string::npos) << m;
    EXPECT_NE(m.find("\"pbf\""), std::string::npos) << m;
}

// One definition of a body's ranges: validate_body (Simulation::add_body, the C API) says
// what the scene file's reader says about the same [[bodies]] entry, `bodies.` for
// `bodies[1].`, for every numeric key and the shape's needs.
TEST(Bodies, ValidateBodySaysWhatTheSceneReaderSays) {
    const BodyDef bad[] = {
        BodyDef{.density = -1.0f},
        BodyDef{.density = 2e5f},
        BodyDef{.size = Vec3(2000.0f, 1.0f, 1.0f)},
        BodyDef{.size = Vec3(0.0f, 1.0f, 1.0f)},
        BodyDef{.shape = BodyShape::ConvexMesh, .size = Vec3(1.0f)},
        BodyDef{.shape = BodyShape::Sphere, .size = Vec3(1.0f), .mesh = "a.obj"},
        BodyDef{.position = Vec3(0.0f, 2e6f, 0.0f)},
        BodyDef{.rotation = Vec3(400.0f, 0.0f, 0.0f)},
        BodyDef{.rotation = Vec3(0.0f, NAN, 0.0f)},
        BodyDef{.velocity = Vec3(0.0f, -200.0f, 0.0f)},
        BodyDef{.angular_velocity = Vec3(INFINITY, 0.0f, 0.0f)},
        BodyDef{.friction = 3.0f},
        BodyDef{.friction = -0.1f},
    };
    test::Pool pool = test::still_pool(kSpacing, 2);
    for (const BodyDef& b : bad) {
        const Status v = validate_body(b);
        ASSERT_FALSE(v.ok());
        SceneDef d = pool.def;
        d.bodies = {b};
        const Status scene = validate(d);
        ASSERT_FALSE(scene.ok()) << v.error().message;
        std::string want = scene.error().message;
        ASSERT_EQ(want.rfind("bodies[1].", 0), 0u) << want;
        want.replace(0, 10, "bodies.");
        EXPECT_EQ(v.error().message, want);
    }
    EXPECT_EQ(validate_body(BodyDef{.rotation = Vec3(400.0f, 0.0f, 0.0f)}).error().message,
              "bodies.rotation: every component must be in [-360, 360] (got [400, 0, 0])");
    EXPECT_TRUE(validate_body(BodyDef{.rotation = Vec3(-360.0f, 360.0f, 0.0f), .friction = 2.0f}).ok());
    EXPECT_TRUE(validate_body(BodyDef{.shape = BodyShape::Capsule, .size = Vec3(0.2f, 0.0f, 0.0f)}).ok());
}

// apply() with a changed [[bodies]] list keeps the bodies whose entry is unchanged (id,
// pose and motion go on) and those added live (add_body: the viewer's drops); only the
// changed entry's body is made again.
TEST(Bodies, ApplyKeepsTheBodiesItDoesNotChange) {
    test::Pool pool = test::still_pool(kSpacing, kLayers);
    pool.def.bodies = {BodyDef{.size = Vec3(0.8f, 0.4f, 0.6f), .density = 500.0f, .position = Vec3(3.0f, 2.5f, 3.0f)},
                       BodyDef{.size = Vec3(0.6f, 0.4f, 0.6f), .density = 600.0f, .position = Vec3(5.0f, 2.5f, 5.0f)}};
    auto sim = Simulation::create(pool.def, pool.map);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& w = *sim.value();
    const uint32_t dropped = w.add_body(BodyDef{.shape = BodyShape::Sphere, .size = Vec3(0.3f, 0.0f, 0.0f), .density = 400.0f,
                                                .position = Vec3(4.0f, 3.0f, 5.0f)})
                                 .value();
    for (int f = 0; f < 60; ++f) w.step(1.0f / 60.0f);
    ASSERT_EQ(w.bodies().size(), 3u);
    const BodyState a = w.bodies()[0], b = w.bodies()[1], c = w.bodies()[2];
    ASSERT_GT(std::abs(a.position.y - 2.5f), 0.05f) << "the first body should have fallen onto the water";
    SceneDef next = w.requested();
    next.bodies[1].density = 700.0f;  // the second entry changes
    auto r = w.apply(next);
    ASSERT_TRUE(r.ok()) << r.error().message;
    ASSERT_TRUE(r.value().rebuild_key.empty()) << r.value().rebuild_key;
    ASSERT_EQ(w.bodies().size(), 3u);
    const auto find = [&](uint32_t id) -> const BodyState* {
        for (const BodyState& s : w.bodies())
            if (s.id == id) return &s;
        return nullptr;
    };
    const BodyState* kept = find(a.id);
    ASSERT_NE(kept, nullptr) << "the unchanged entry's body was made again";
    EXPECT_EQ(kept->position, a.position);
    EXPECT_EQ(kept->velocity, a.velocity);
    const BodyState* drop = find(dropped);
    ASSERT_NE(drop, nullptr) << "the body added live was lost";
    EXPECT_EQ(drop->position, c.position);
    EXPECT_EQ(find(b.id), nullptr) << "the changed entry kept its old body";
    const BodyState& remade = w.bodies().back();
    EXPECT_NEAR(remade.mass, 700.0f * 0.6f * 0.4f * 0.6f, 1e-3f);
    EXPECT_EQ(remade.position, Vec3(5.0f, 2.5f, 5.0f));
    // The list emptied: its bodies go, the dropped one stays.
    next.bodies.clear();
    auto r2 = w.apply(next);
    ASSERT_TRUE(r2.ok() && r2.value().rebuild_key.empty());
    ASSERT_EQ(w.bodies().size(), 1u);
    EXPECT_EQ(w.bodies()[0].id, dropped);
}

// Sculpting keeps the bodies (ids and all) and they meet the new ground: a steel box resting
// on the pool's floor rides a mound raised under it, and goes down again when the stroke is
// undone; none of it ends under the ground.
TEST(Bodies, SculptingKeepsTheBodiesAndTheyRestOnTheNewGround) {
    test::Pool pool = test::still_pool(kSpacing, 2);
    auto sim = Simulation::create(pool.def, pool.map);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& w = *sim.value();
    const Vec3 size(0.6f, 0.6f, 0.6f);
    const uint32_t id = w.add_body(BodyDef{.size = size, .density = 7800.0f, .position = Vec3(4.0f, 0.6f, 4.0f)}).value();
    const auto settle = [&](int frames) {
        for (int f = 0; f < frames; ++f) w.step(1.0f / 60.0f);
        EXPECT_EQ(w.bodies().size(), 1u);
        EXPECT_EQ(w.bodies()[0].id, id) << "the body was made again";
        return w.bodies()[0];
    };
    // The lowest corner of the box over the ground under it (the terrain's mesh).
    const auto clearance = [&](const BodyState& b) {
        float lowest = 1e30f;
        for (int c = 0; c < 8; ++c) {
            const Vec3 local(c & 1 ? 0.5f : -0.5f, c & 2 ? 0.5f : -0.5f, c & 4 ? 0.5f : -0.5f);
            const Vec3 x = b.position + b.orientation * (local * size);
            lowest = std::min(lowest, x.y - w.terrain().height_mesh(x.x, x.z));
        }
        return lowest;
    };
    const BodyState floor = settle(120);
    EXPECT_LT(floor.position.y, 0.5f * size.y + 0.1f) << "the box should rest on the floor";
    auto edit = w.sculpt(Brush{.x = 4.0f, .z = 4.0f, .radius = 1.5f, .strength = 0.5f, .mode = BrushMode::Raise});
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    ASSERT_FALSE(edit.value().empty());
    const float mound = w.terrain().height_mesh(4.0f, 4.0f);
    ASSERT_GT(mound, 0.3f);
    const BodyState raised = settle(120);
    std::printf("sculpt: box centre %.3f m on the floor, %.3f m on the %.3f m mound; lowest corner %+.3f m over the ground\n",
                floor.position.y, raised.position.y, mound, clearance(raised));
    EXPECT_GT(raised.position.y, floor.position.y + 0.25f) << "the box did not ride the mound";
    EXPECT_GT(clearance(raised), -0.05f) << "the box ends under the new ground";
    w.restore(edit.value());
    const BodyState back = settle(120);
    EXPECT_LT(back.position.y, raised.position.y - 0.2f) << "the box stayed up after the mound was undone";
    EXPECT_GT(clearance(back), -0.05f);
    EXPECT_EQ(w.counters().inside_bodies, 0u);
}

// Shapes: the mass and volume of each primitive, and of an OBJ (a unit cube with a vertex
// inside it: the convex hull leaves it out; the triangle mesh needs the cube's faces).
TEST(Bodies, ShapesHaveTheirVolumeAndMass) {
    test::Pool pool = test::still_pool(kSpacing, 2);
    auto sim = Simulation::create(pool.def, pool.map);
    ASSERT_TRUE(sim.ok());
    Simulation& w = *sim.value();
    const fs::path obj = fs::temp_directory_path() / "metariver_bodies_cube.obj";
    {
        std::ofstream f(obj);
        f << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 0.5 0.5 0.5\n"
             "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    }
    struct Case {
        BodyDef def;
        float volume;
    };
    const float pi = 3.14159265f;
    const Case cases[] = {
        {BodyDef{.shape = BodyShape::Box, .size = Vec3(2.0f, 0.5f, 0.4f)}, 0.4f},
        {BodyDef{.shape = BodyShape::Sphere, .size = Vec3(0.5f, 0.0f, 0.0f)}, 4.0f / 3.0f * pi * 0.125f},
        {BodyDef{.shape = BodyShape::Capsule, .size = Vec3(0.2f, 1.0f, 0.0f)}, pi * 0.04f * 1.0f + 4.0f / 3.0f * pi * 0.008f},
        {BodyDef{.shape = BodyShape::ConvexMesh, .size = Vec3(2.0f), .mesh = obj.string()}, 8.0f},
        {BodyDef{.shape = BodyShape::TriangleMesh, .size = Vec3(1.0f), .mesh = obj.string()}, 1.0f},
    };
    for (const Case& c : cases) {
        Case k = c;
        k.def.position = Vec3(4.0f, 3.0f, 4.0f);
        auto id = w.add_body(k.def);
        ASSERT_TRUE(id.ok()) << id.error().message;
        const BodyState& b = w.bodies().back();
        EXPECT_NEAR(b.volume, c.volume, 1e-3f * c.volume) << to_string(c.def.shape);
        EXPECT_NEAR(b.mass, c.volume * k.def.density, 1e-3f * c.volume * k.def.density) << to_string(c.def.shape);
        ASSERT_TRUE(b.mesh);
        EXPECT_GE(b.mesh->indices.size(), 36u);
        EXPECT_EQ(b.mesh->positions.size(), b.mesh->normals.size());
    }
    fs::remove(obj);
}

}  // namespace
}  // namespace mr

namespace mr {
namespace {

// The broad phase's cells (body_cells.h) list, for any point, every body whose sphere holds
// it, in index order, so the coupling meets the same bodies as a loop over all of them:
// near sphere surfaces, with bodies far apart (wider cells), and with a non-finite sphere.
TEST(Bodies, CellsListEveryBodyWhoseSphereHoldsAPointInOrder) {
    std::vector<glm::vec4> spheres;
    uint32_t seed = 12345;
    const auto rnd = [&]() { return float((seed = seed * 1664525u + 1013904223u) >> 8) / float(1u << 24); };
    for (int b = 0; b < 40; ++b) {
        const float r = 0.2f + 2.0f * rnd();
        spheres.push_back(glm::vec4(100.0f * rnd(), 5.0f * rnd(), 100.0f * rnd(), r * r));
    }
    spheres.push_back(glm::vec4(5000.0f, 0.0f, -3000.0f, 1.0f));  // far away: the cells widen
    spheres.push_back(glm::vec4(NAN, 0.0f, 0.0f, 1.0f));           // never listed
    BodyCells cells;
    cells.build(spheres);
    int checked = 0, met = 0;
    for (int k = 0; k < 20000; ++k) {
        // Half the points just inside or outside a sphere's surface, the rest anywhere.
        const glm::vec4& s = spheres[size_t(k) % 41];
        const Vec3 dir = glm::normalize(Vec3(rnd() - 0.5f, rnd() - 0.5f, rnd() - 0.5f) + Vec3(1e-3f));
        const Vec3 x = k % 2 ? Vec3(s) + dir * std::sqrt(s.w) * (0.999f + 0.002f * rnd())
                             : Vec3(110.0f * rnd() - 5.0f, 5.0f * rnd(), 110.0f * rnd() - 5.0f);
        std::vector<size_t> want, got;
        for (size_t b = 0; b < spheres.size(); ++b) {
            const Vec3 d = x - Vec3(spheres[b]);
            if (glm::dot(d, d) <= spheres[b].w) want.push_back(b);
        }
        cells.visit(x, [&](size_t b) {
            const Vec3 d = x - Vec3(spheres[b]);
            if (glm::dot(d, d) <= spheres[b].w) got.push_back(b);
            return false;
        });
        ASSERT_EQ(want, got) << "point " << x.x << ", " << x.y << ", " << x.z;
        ++checked;
        met += !want.empty();
    }
    EXPECT_GT(met, checked / 5);  // the points do meet bodies (a quarter: half the surface points)
    // visit stops where f says so.
    int calls = 0;
    cells.visit(Vec3(spheres[0]), [&](size_t) { return ++calls, true; });
    EXPECT_EQ(calls, 1);
    // No spheres: no bodies anywhere.
    cells.build({});
    cells.visit(Vec3(0.0f), [&](size_t) { return ADD_FAILURE(), true; });
}

}  // namespace
}  // namespace mr
