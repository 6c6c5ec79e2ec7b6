// Live edits (issue 14): Simulation::apply changes a running simulation's parameters in
// place, the particles kept, and asks for a new Simulation only where the terrain, the
// tree, the budget or an automatic value was built from the edited key.
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <gtest/gtest.h>
#include <build_options.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

namespace mr {
namespace {

std::unique_ptr<Simulation> make(const SceneDef& d, int frames) {
    auto sim = Simulation::create(d);
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    if (!sim.ok()) return nullptr;
    for (int f = 0; f < frames; ++f) sim.value()->step(1.0f / 60.0f);
    return std::move(sim.value());
}

bool has(const std::vector<std::string>& v, const std::string& s) { return std::find(v.begin(), v.end(), s) != v.end(); }

// SceneView (issue 14): the plain views a renderer reads point at the Simulation's own
// data of the latest frame, and the frame they name advances with it.
TEST(View, TheViewIsTheLatestFrame) {
    auto sim = Simulation::create(default_scene());
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    for (int i = 0; i < 30; ++i) s.step(1.0f / 60.0f);
    const SceneView v = s.view();
    ASSERT_TRUE(v.complete());
    EXPECT_EQ(v.terrain, &s.terrain());
    EXPECT_EQ(v.bvh, &s.bvh());
    EXPECT_EQ(v.particles, &s.particles());
    EXPECT_EQ(v.surface, &s.surface());
    ASSERT_NE(s.foam(), nullptr);
    EXPECT_EQ(v.foam, &s.foam()->particles());
    EXPECT_EQ(v.owner, &s);
    EXPECT_EQ(v.frame, s.frame());
    EXPECT_GT(v.surface->triangle_count(), 0u);
    EXPECT_EQ(v.flow_radius, s.def().field.radius) << "poly6: the field's support";
    s.step(1.0f / 60.0f);
    EXPECT_EQ(s.view().frame, v.frame + 1);
}

TEST(Apply, AnEditKeepsTheWaterFlowing) {
    auto sim = make(default_scene(), 90);
    ASSERT_TRUE(sim);
    const uint64_t hash = sim->state_hash(), frame = sim->frame();
    const size_t active = sim->particles().active_count();
    ASSERT_GT(active, 100u);
    SceneDef next = sim->requested();
    next.pbf.xsph = 0.1f;
    next.collision.damping = 0.004f;
    next.integrator.gravity = 5.0f;
    next.field.threshold = 0.5f;
    next.smoothing.iterations = 4;
    next.foam.max_particles = 500;
    auto r = sim->apply(next);
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_TRUE(r->applied) << r->rebuild_key;
    for (const char* k : {"pbf.xsph", "collision.damping", "forces.gravity", "field.threshold", "surface.iterations",
                          "foam.max_particles"})
        EXPECT_TRUE(has(r->keys, k)) << k;
    EXPECT_EQ(r->keys.size(), 6u);
    // The particles are untouched by the edit; the new values are what runs.
    EXPECT_EQ(sim->state_hash(), hash);
    EXPECT_EQ(sim->frame(), frame);
    EXPECT_FLOAT_EQ(sim->def().pbf.xsph, 0.1f);
    EXPECT_FLOAT_EQ(sim->def().integrator.gravity, 5.0f);
    EXPECT_EQ(sim->def().smoothing.iterations, 4);
    EXPECT_FLOAT_EQ(sim->requested().field.threshold, 0.5f);
    // Resolved values stay resolved (the river's budget, its source on the channel).
    EXPECT_NE(sim->def().spawn.count, kAutoCount);
    EXPECT_FALSE(sim->def().spawn.auto_center);
    for (int f = 0; f < 30; ++f) sim->step(1.0f / 60.0f);
    EXPECT_EQ(sim->frame(), frame + 30);
    EXPECT_GE(sim->particles().active_count(), active);  // the source keeps emitting
    EXPECT_EQ(sim->counters().tunneled, 0u);
    ASSERT_TRUE(sim->foam());
    EXPECT_EQ(sim->foam()->def().max_particles, 500);
    EXPECT_LE(sim->foam()->particles().size(), 500u);
}

// The same scene stepped twice, one copy edited after 20 frames: a key the solver reads
// changes the particles' path within a few frames; a field or surface key the mesh.
TEST(Apply, EachEditTakesEffect) {
    const SceneDef base = default_scene();
    struct Edit {
        const char* key;
        void (*set)(SceneDef&);
        bool surface_only;
    };
    const Edit edits[] = {
        {"forces.gravity", [](SceneDef& d) { d.integrator.gravity = 20.0f; }, false},
        {"pbf.xsph", [](SceneDef& d) { d.pbf.xsph = 0.5f; }, false},
        {"pbf.iterations", [](SceneDef& d) { d.pbf.iterations = 1; }, false},
        {"pbf.kernel_radius", [](SceneDef& d) { d.pbf.kernel_radius = 1.3f; }, false},
        {"pbf.vorticity", [](SceneDef& d) { d.pbf.vorticity = 2.0f; }, false},
        {"collision.damping", [](SceneDef& d) { d.collision.damping = 0.2f; }, false},
        {"collision.friction_speed", [](SceneDef& d) { d.collision.friction_speed = 0.5f; }, false},
        {"integrator.substeps", [](SceneDef& d) { d.integrator.substeps = 4; }, false},
        {"particles.initial_velocity", [](SceneDef& d) { d.spawn.initial_velocity = Vec3(0.0f, -8.0f, 0.0f); }, false},
        {"field.threshold", [](SceneDef& d) { d.field.threshold = 0.6f; }, true},
        {"field.radius", [](SceneDef& d) { d.field.radius = 1.4f; }, true},
        {"surface.iterations", [](SceneDef& d) { d.smoothing.iterations = 1; }, true},
        {"surface.smooth_hidden", [](SceneDef& d) { d.smoothing.smooth_hidden = true; }, true},
    };
    for (const Edit& e : edits) {
        SCOPED_TRACE(e.key);
        auto a = make(base, 20), b = make(base, 20);
        ASSERT_TRUE(a && b);
        SceneDef next = b->requested();
        e.set(next);
        auto r = b->apply(next);
        ASSERT_TRUE(r.ok()) << r.error().message;
        ASSERT_TRUE(r->applied) << r->rebuild_key;
        ASSERT_EQ(r->keys, std::vector<std::string>{e.key});
        for (int f = 0; f < 5; ++f) {
            a->step(1.0f / 60.0f);
            b->step(1.0f / 60.0f);
        }
        if (e.surface_only) {
            EXPECT_EQ(a->state_hash(), b->state_hash());  // the water is the same
            const auto& pa = a->surface().positions;
            const auto& pb = b->surface().positions;
            EXPECT_TRUE(pa.size() != pb.size() || !std::equal(pa.begin(), pa.end(), pb.begin()));
        } else {
            EXPECT_NE(a->state_hash(), b->state_hash());
        }
    }
}

// Every key the default scene reads, changed alone: applied in place (and then what
// runs), or a rebuild asked for with nothing changed.
TEST(Apply, EveryKeyIsAppliedOrAsksForARebuild) {
    auto sim = make(default_scene(), 10);
    ASSERT_TRUE(sim);
    int applied = 0, rebuilds = 0;
    for (const SceneKey& k : scene_keys()) {
        if (!k.readers(sim->requested()) || k.type != KeyType::Float) continue;
        if (k.words.current && k.words.current(sim->requested()) >= 0) continue;  // "auto": rebuild, below
        SceneDef next = sim->requested();
        float* v = std::get<float*>(k.field(next));
        *v = *v > 0.0f ? *v * 1.1f : 0.01f;
        if (!validate(next)) continue;  // out of its range or another key's
        SCOPED_TRACE(std::string(k.name));
        const SceneDef before = sim->def();
        const uint64_t hash = sim->state_hash();
        auto r = sim->apply(next);
        ASSERT_TRUE(r.ok()) << r.error().message;
        ASSERT_EQ(r->keys, std::vector<std::string>{std::string(k.name)});
        EXPECT_EQ(sim->state_hash(), hash);
        EXPECT_EQ(r->applied, k.edit != KeyEdit::Rebuild) << "the table's edit rule (SceneKey::edit)";
        if (r->applied) {
            ++applied;
            EXPECT_EQ(key_value_toml(k, sim->def()), key_value_toml(k, next));
            sim->step(1.0f / 60.0f);
        } else {
            ++rebuilds;
            EXPECT_EQ(r->rebuild_key, k.name);
            EXPECT_EQ(key_value_toml(k, sim->def()), key_value_toml(k, before));
        }
    }
    EXPECT_GT(applied, 30);
    EXPECT_GE(rebuilds, 1);  // terrain.height_scale at least
}

// The edit rules of the key table (SceneKey::edit) in a Bullet scene: its world is built
// once from its defs, so what the solver reads needs a new Simulation; the field, the
// surface and the renderer take an edit in place.
TEST(Apply, ABulletSceneRebuildsForWhatItsSolverReads) {
    if (!test::kWithBullet) GTEST_SKIP() << "this build leaves out Bullet (METARIVER_WITH_BULLET=OFF)";
    SceneDef d = preset("paper-engine").value();
    d.source.kind = TerrainSource::Strict;  // its procedural twin: no PNG needed
    auto sim = make(d, 10);
    ASSERT_TRUE(sim);
    int live = 0, rebuilds = 0;
    for (const SceneKey& k : scene_keys()) {
        if (!k.readers(d) || k.type != KeyType::Float || k.words.apply) continue;
        SceneDef next = sim->requested();
        float* v = std::get<float*>(k.field(next));
        *v = *v > 0.0f ? *v * 1.1f : 0.01f;
        if (!validate(next)) continue;
        SCOPED_TRACE(std::string(k.name));
        auto r = sim->apply(next);
        ASSERT_TRUE(r.ok()) << r.error().message;
        EXPECT_EQ(r->applied, k.edit == KeyEdit::Live);
        if (r->applied) {
            ++live;
        } else {
            ++rebuilds;
            EXPECT_EQ(r->rebuild_key, k.name);
        }
    }
    EXPECT_GE(live, 3);      // field.threshold, radius, bounds_offset, resolution
    EXPECT_GE(rebuilds, 5);  // bullet.*, forces.gravity, particles.*
    const KeyEdit gravity = find_scene_key("forces.gravity")->edit, threshold = find_scene_key("field.threshold")->edit;
    EXPECT_EQ(gravity, KeyEdit::Solver);  // live in the default river, a rebuild here
    EXPECT_EQ(threshold, KeyEdit::Live);
}

TEST(Apply, TerrainBudgetAndAutoValuesAskForANewSimulation) {
    auto sim = make(default_scene(), 10);
    ASSERT_TRUE(sim);
    const uint64_t hash = sim->state_hash();
    const auto expect_rebuild = [&](void (*set)(SceneDef&), const char* key) {
        SCOPED_TRACE(key);
        SceneDef next = sim->requested();
        set(next);
        auto r = sim->apply(next);
        ASSERT_TRUE(r.ok()) << r.error().message;
        EXPECT_FALSE(r->applied);
        EXPECT_EQ(r->rebuild_key, key);
        EXPECT_EQ(sim->state_hash(), hash);
    };
    expect_rebuild([](SceneDef& d) { d.terrain.height_scale = 30.0f; }, "terrain.height_scale");
    expect_rebuild([](SceneDef& d) { d.spawn.count = 5000; }, "particles.count");  // was "auto"
    expect_rebuild([](SceneDef& d) { d.spawn.flow_rate = 40.0f; }, "particles.flow_rate");
    expect_rebuild([](SceneDef& d) { d.solver = SolverKind::Springs; }, "solver");
    expect_rebuild([](SceneDef& d) { d.seed = 9; }, "seed");
    // An invalid scene is an error that changes nothing.
    SceneDef bad = sim->requested();
    bad.pbf.xsph = 7.0f;
    auto r = sim->apply(bad);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("pbf.xsph"), std::string::npos) << r.error().message;
    EXPECT_FLOAT_EQ(sim->def().pbf.xsph, default_scene().pbf.xsph);
}

// Sculpting under running water (issue 14): a stroke that raises the river's bed lifts
// the water it rose over onto the new ground (counted), nothing goes through it after,
// and undo gives the terrain back.
TEST(Sculpt, RaisingTheBedUnderTheRiverLiftsTheWaterAndNothingTunnels) {
    auto sim = make(default_scene(), 120);
    ASSERT_TRUE(sim);
    const auto path = sim->main_channel();
    ASSERT_GT(path.size(), 10u);
    const auto [ci, cj] = path[path.size() / 3];
    const float s = sim->terrain().area_scale();
    const Vec3 o = sim->terrain().vertices().front();
    const std::vector<Vec3> before(sim->terrain().vertices().begin(), sim->terrain().vertices().end());
    auto e = sim->sculpt({.x = o.x + float(cj) * s, .z = o.z + float(ci) * s, .radius = 4.0f, .strength = 2.5f});
    ASSERT_TRUE(e.ok()) << e.error().message;
    ASSERT_FALSE(e->empty());
    EXPECT_GT(sim->terrain_lifts(), 0u);  // water sat on the bed that rose
    const auto above_ground = [&] {
        const Particles& p = sim->particles();
        size_t below = 0;
        for (size_t i = 0; i < p.size(); ++i)
            if (p.active[i] && sim->terrain().contains_xz(p.position[i].x, p.position[i].z) &&
                p.position[i].y < sim->terrain().height_mesh(p.position[i].x, p.position[i].z) - 1e-4f)
                ++below;
        return below;
    };
    EXPECT_EQ(above_ground(), 0u);
    for (int f = 0; f < 120; ++f) sim->step(1.0f / 60.0f);
    EXPECT_EQ(sim->counters().tunneled, 0u);
    EXPECT_EQ(above_ground(), 0u);
    sim->restore(e.value());
    for (size_t k = 0; k < before.size(); ++k) ASSERT_EQ(sim->terrain().vertices()[k].y, before[k].y) << k;
    for (int f = 0; f < 60; ++f) sim->step(1.0f / 60.0f);
    EXPECT_EQ(sim->counters().tunneled, 0u);
    // A bad brush is an error that changes nothing.
    EXPECT_FALSE(sim->sculpt({.radius = -1.0f}).ok());
    for (size_t k = 0; k < before.size(); ++k) ASSERT_EQ(sim->terrain().vertices()[k].y, before[k].y) << k;
}

// The drainage network after strokes: a drag of strokes leaves it stale and it is built
// once when read, then it is the network of the sculpted terrain (the same as one built
// from scratch: accumulation everywhere, the main head, the path from the source).
TEST(Sculpt, TheChannelReadAfterStrokesIsTheSculptedTerrains) {
    auto sim = make(default_scene(), 60);
    ASSERT_TRUE(sim);
    const std::vector<std::pair<int, int>> path(sim->main_channel().begin(), sim->main_channel().end());
    const auto [ci, cj] = path[path.size() / 2];
    const float s = sim->terrain().area_scale();
    const Vec3 o = sim->terrain().vertices().front();
    for (int k = 0; k < 5; ++k)  // a dam across the channel
        ASSERT_TRUE(sim->sculpt({.x = o.x + float(cj + k - 2) * s, .z = o.z + float(ci) * s, .radius = 4.0f, .strength = 1.0f}).ok());
    const ChannelMap fresh = ChannelMap::build(sim->terrain());
    const ChannelMap& m = sim->channel();
    ASSERT_EQ(m.rows(), fresh.rows());
    for (int i = 0; i < m.rows(); ++i)
        for (int j = 0; j < m.columns(); ++j) ASSERT_EQ(m.accumulation(i, j), fresh.accumulation(i, j)) << i << " " << j;
    EXPECT_EQ(m.main_head(), fresh.main_head());
    const auto after = sim->main_channel();
    ASSERT_FALSE(after.empty());
    using Path = std::vector<std::pair<int, int>>;
    const Path now(after.begin(), after.end());
    EXPECT_EQ(now, fresh.path_from(after.front().first, after.front().second));
    EXPECT_NE(now, path) << "the dam changed the main channel";
}

// Pushing water (issue 14): a pool at rest moves where it is pushed, in the push's
// direction, and nowhere else.
TEST(Push, APoolAtRestMovesWhereItIsPushed) {
    auto d = parse_scene_toml(R"(solver = "pbf"
[terrain]
source = "bowl"
width = 33
height = 33
height_scale = 7.0
[particles]
count = 700
spawn_center = [16.0, 4.0, 16.0]
spawn_half_extent = [3.0, 1.0, 3.0]
spawn_interval = 0
flow_rate = 0.0
source_shape = "box"
[sink]
kind = "none"
)",
                              "pool.toml", default_scene());
    ASSERT_TRUE(d.ok()) << d.error().message;
    auto sim = make(d.value(), 420);  // 7 s: at rest
    ASSERT_TRUE(sim);
    auto speeds0 = sim->active_speeds();
    std::sort(speeds0.begin(), speeds0.end());
    ASSERT_LT(speeds0[speeds0.size() * 95 / 100], 0.1) << "the pool must be at rest first";
    // Push the water near the pool's middle along +x at 3 m/s.
    const Particles& p = sim->particles();
    Vec3 c(0.0f);
    size_t n = 0;
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i]) c += p.position[i], ++n;
    c /= float(n);
    auto pushed = sim->push(c, 2.0f, Vec3(3.0f, 0.0f, 0.0f));
    ASSERT_TRUE(pushed.ok()) << pushed.error().message;
    EXPECT_GT(pushed.value(), 10u);
    EXPECT_LT(pushed.value(), n);
    for (int f = 0; f < 3; ++f) sim->step(1.0f / 60.0f);
    double near_vx = 0.0, far_speed = 0.0;
    size_t near = 0, far = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        if (!p.active[i]) continue;
        const float dist = glm::length(p.position[i] - c);
        if (dist < 1.0f) near_vx += p.velocity[i].x, ++near;
        if (dist > 5.0f) far_speed = std::max(far_speed, double(glm::length(p.velocity[i]))), ++far;
    }
    ASSERT_GT(near, 0u);
    EXPECT_GT(near_vx / double(near), 0.3);  // moving along the push
    ASSERT_GT(far, 0u);
    EXPECT_LT(far_speed, 0.5);  // the far side of the pool has not felt it yet
    EXPECT_FALSE(sim->push(c, 0.0f, Vec3(1.0f)).ok());
    EXPECT_FALSE(sim->push(c, 1.0f, Vec3(NAN)).ok());
}

// Moving the source by hand (issue 14): new water is born at the new place, the scene
// it reports says so, and a centre off the terrain is refused.
TEST(MoveSource, NewWaterIsBornWhereTheSourceWasMoved) {
    auto sim = make(default_scene(), 60);
    ASSERT_TRUE(sim);
    const Vec3 old = sim->def().spawn.center;
    const Vec3 c = sim->terrain().bounds().center();
    const Vec3 to(c.x, sim->terrain().height_mesh(c.x, c.z) + 2.0f, c.z);
    ASSERT_GT(glm::length(to - old), 10.0f);
    const uint64_t moved_at = sim->frame();
    ASSERT_TRUE(sim->move_source(to).ok());
    EXPECT_EQ(sim->def().spawn.center, to);
    EXPECT_EQ(sim->requested().spawn.center, to);
    EXPECT_FALSE(sim->requested().spawn.auto_center);
    for (int f = 0; f < 4; ++f) sim->step(1.0f / 60.0f);
    const Particles& p = sim->particles();
    size_t born = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        if (!p.active[i] || p.birth_frame[i] <= moved_at) continue;
        ++born;
        EXPECT_LT(glm::length(Vec3(p.position[i].x - to.x, 0.0f, p.position[i].z - to.z)),
                  sim->def().spawn.half_extent.x + 1.0f);
    }
    EXPECT_GT(born, 0u);
    // The scene it reports is the one it runs: applying it changes nothing.
    auto same = sim->apply(sim->requested());
    ASSERT_TRUE(same.ok());
    EXPECT_TRUE(same->applied);
    EXPECT_TRUE(same->keys.empty());
    // Off the terrain: an error naming the key, the source where it was.
    auto off = sim->move_source(Vec3(-500.0f, 0.0f, 0.0f));
    ASSERT_FALSE(off.ok());
    EXPECT_NE(off.error().message.find("particles.spawn_center"), std::string::npos) << off.error().message;
    EXPECT_EQ(sim->def().spawn.center, to);
}

}  // namespace
}  // namespace mr
