// SceneDef{} is the default scene (issue 43): a scene made in code with no value set is
// the river `metariver run` runs, not the paper's springs.
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <gtest/gtest.h>

namespace mr {
namespace {

TEST(SceneDefDefaults, ASceneDefMadeInCodeIsTheDefaultScene) {
    const SceneDef made{};
    const SceneDef preset_default = default_scene();
    // The scene file each writes, whole, and key by key (a difference names its key).
    EXPECT_EQ(scene_to_toml(made), scene_to_toml(preset_default));
    for (const SceneKey& k : scene_keys())
        EXPECT_EQ(key_value_toml(k, made), key_value_toml(k, preset_default)) << k.name;
    for (const SceneList& l : scene_lists()) EXPECT_EQ(list_toml(l, made), list_toml(l, preset_default)) << l.name;
    // The members that are not scene-file keys.
    EXPECT_EQ(made.name, preset_default.name);
    EXPECT_EQ(made.carve_spacing, preset_default.carve_spacing);
    EXPECT_EQ(made.render.flow_detail, preset_default.render.flow_detail);
    // It is the river: PBF, sized, carved, prefilled, recycled at the edges, foam on.
    EXPECT_EQ(made.solver, SolverKind::Pbf);
    EXPECT_EQ(made.spawn.count, kAutoCount);
    EXPECT_TRUE(made.spawn.auto_rate());
    EXPECT_TRUE(made.spawn.prefill);
    EXPECT_EQ(made.sink.kind, SinkKind::Edges);
    EXPECT_TRUE(made.foam.enabled);
    EXPECT_TRUE(is_river(made));
    EXPECT_EQ(resolved_condition(made), TerrainCondition::Carve);
}

TEST(SceneDefDefaults, TheSpringsPresetsSayTheirSolverAndTables) {
    // Built on their own base (every table at its type's defaults), not on SceneDef{}.
    for (const char* name : {"springs-valley", "paper-full", "paper-nile", "paper-bowl"}) {
        auto p = preset(name);
        ASSERT_TRUE(p.ok()) << p.error().message;
        EXPECT_EQ(p->solver, SolverKind::Springs) << name;
        EXPECT_EQ(p->sink.kind, SinkKind::None) << name;
        EXPECT_FALSE(p->foam.enabled) << name;
        EXPECT_EQ(p->smoothing.method, SmoothingMethod::None) << name;
        EXPECT_FALSE(p->spawn.prefill) << name;
        EXPECT_FALSE(is_river(*p)) << name;
    }
}

TEST(SceneDefDefaults, ASimulationOfSceneDefIsTheDefaultRiver) {
    auto a = Simulation::create(SceneDef{});
    auto b = Simulation::create(default_scene());
    ASSERT_TRUE(a.ok()) << a.error().message;
    ASSERT_TRUE(b.ok()) << b.error().message;
    for (int f = 0; f < 10; ++f) {
        a.value()->step(1.0f / 60.0f);
        b.value()->step(1.0f / 60.0f);
    }
    EXPECT_GT(a.value()->particles().active_count(), 0u);
    EXPECT_EQ(a.value()->state_hash(), b.value()->state_hash());
}

}  // namespace
}  // namespace mr
