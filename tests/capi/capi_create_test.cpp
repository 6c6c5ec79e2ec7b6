// The C API (include/metariver/metariver.h), creating worlds: every source of the scene
// and of the terrain (a file, TOML text, a preset, a PNG, the caller's heights and their
// order), the overrides, and each refusal with its code and a message naming the culprit.
#include "capi_support.h"
#include "build_options.h"

#include <metariver/metariver.h>
#include <metariver/scene.h>

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace {

using namespace capi_test;

TEST(CApi, VersionAndStatusNames) {
    EXPECT_EQ(mr_api_version() >> 16, static_cast<uint32_t>(MR_API_VERSION_MAJOR));
    EXPECT_EQ(mr_api_version(), static_cast<uint32_t>(MR_API_VERSION));
    EXPECT_EQ(std::string(mr_version_string()).rfind("metariver ", 0), 0u) << mr_version_string();
    EXPECT_STREQ(mr_status_name(MR_OK), "MR_OK");
    EXPECT_STREQ(mr_status_name(MR_ERROR_BUFFER_TOO_SMALL), "MR_ERROR_BUFFER_TOO_SMALL");
    // An unknown code (C lets a caller pass any int): c99_test.c.
}

// No source: the default scene (a PBF river on the procedural valley).
TEST(CApi, TheDefaultWorldStepsAndCounts) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    EXPECT_EQ(world.error.code, MR_OK);
    EXPECT_STREQ(mr_world_last_error(world.w), "");
    const mr_terrain_info t = terrain_info(world);
    EXPECT_EQ(t.columns, mr::default_scene().source.width);
    EXPECT_EQ(t.rows, mr::default_scene().source.height);
    EXPECT_LT(t.min_y, t.max_y);
    world.step(30);
    const mr_stats s = world.stats();
    EXPECT_EQ(s.frame, 30u);
    EXPECT_NEAR(s.time_s, 30.0 * kDt, 1e-6) << "30 float steps summed";
    EXPECT_GT(s.active_particles, 0u);
    EXPECT_LE(s.active_particles, s.particle_slots);
    EXPECT_GT(s.surface_triangles, 0u);
    EXPECT_GT(s.simulate_ms, 0.0);
}

TEST(CApi, APresetAndAScaleOverride) {
    mr_world_desc d = mr_world_desc_default();
    d.preset = "paper-bowl";
    d.area_scale = 2.0f;
    d.height_scale = 3.0f;
    World world(d);
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const mr_terrain_info t = terrain_info(world);
    EXPECT_EQ(t.columns, 33) << "paper-bowl: the 33 x 33 procedural bowl";
    EXPECT_FLOAT_EQ(t.area_scale, 2.0f);
    EXPECT_LE(t.max_y, 3.0f + 1e-4f) << "heights in [0, 1] times height_scale";
    std::vector<char> text(1 << 20);
    size_t length = 0;
    ASSERT_EQ(mr_world_scene_toml(world.w, text.data(), text.size(), &length), MR_OK);
    EXPECT_TRUE(contains(text.data(), "preset = \"paper-bowl\"")) << "the text starts from the world's preset";
    EXPECT_EQ(std::strlen(text.data()), length);
}

TEST(CApi, SceneTomlAndSceneFile) {
    const std::string toml = "[terrain]\nheight_scale = 11.5\n";
    mr_world_desc d = mr_world_desc_default();
    d.scene_toml = toml.c_str();
    World from_text(d);
    ASSERT_EQ(from_text.status, MR_OK) << from_text.error.message;
    const std::string path = temp_file("scene.toml", toml);
    d = mr_world_desc_default();
    d.scene_file = path.c_str();
    World from_file(d);
    ASSERT_EQ(from_file.status, MR_OK) << from_file.error.message;
    for (const World* w : {&from_text, &from_file}) {
        size_t length = 0;
        EXPECT_EQ(mr_world_scene_toml(w->w, nullptr, 0, &length), MR_ERROR_BUFFER_TOO_SMALL);
        ASSERT_GT(length, 0u);
        std::string text(length + 1, '\0');
        ASSERT_EQ(mr_world_scene_toml(w->w, text.data(), text.size(), &length), MR_OK) << w->last_error();
        EXPECT_TRUE(contains(text, "height_scale = 11.5")) << "the key read from the scene";
    }
    EXPECT_EQ(terrain_heights(from_text), terrain_heights(from_file));
    std::filesystem::remove(path);
}

TEST(CApi, AHeightmapFileReplacesTheTerrain) {
    const std::string png = std::string(METARIVER_SOURCE_DIR) + "/assets/heightmaps/real/pyrenees.png";
    auto map = mr::load_heightmap_png(png);
    ASSERT_TRUE(map.ok()) << map.error().message;
    mr_world_desc d = mr_world_desc_default();
    d.heightmap_file = png.c_str();
    World world(d);
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const mr_terrain_info t = terrain_info(world);
    EXPECT_EQ(t.columns, map->width);
    EXPECT_EQ(t.rows, map->height);
    world.step(5);
    EXPECT_EQ(world.stats().frame, 5u);
}

// The caller's heights: row k along +z, column c along +x, come back from the terrain in
// the same order (times height_scale), whichever row orientation the scene uses.
TEST(CApi, HeightsComeBackInTheCallersOrder) {
    const int columns = 40, rows = 30;
    const std::vector<float> h = ramp(columns, rows);
    for (const char* toml : {"[terrain]\ncondition = \"none\"\n",
                             "[terrain]\ncondition = \"none\"\npaper_row_orientation = false\n"}) {
        mr_world_desc d = mr_world_desc_default();
        d.scene_toml = toml;
        d.heights = h.data();
        d.columns = columns;
        d.rows = rows;
        d.area_scale = 1.5f;
        d.height_scale = 10.0f;
        World world(d);
        ASSERT_EQ(world.status, MR_OK) << world.error.message;
        const mr_terrain_info t = terrain_info(world);
        ASSERT_EQ(t.columns, columns);
        ASSERT_EQ(t.rows, rows);
        EXPECT_FLOAT_EQ(t.area_scale, 1.5f);
        const std::vector<float> back = terrain_heights(world);
        for (size_t i = 0; i < h.size(); ++i) ASSERT_NEAR(back[i], 10.0f * h[i], 1e-4f) << toml << " sample " << i;
        EXPECT_NEAR(t.min_y, 0.0f, 1e-5f);
        EXPECT_NEAR(t.max_y, 10.0f, 1e-4f);
        world.step(3);
    }
}

// A PNG's rows run the other way: image row 0 (its top) is the far end, z = (rows - 1) s,
// in the paper's orientation (terrain.h). The caller's array of the image's rows bottom
// first is the same terrain as the file, river carving and all.
TEST(CApi, HeightsBottomRowFirstAreTheImagesTerrain) {
    const std::string png = std::string(METARIVER_SOURCE_DIR) + "/assets/heightmaps/real/alps.png";
    auto map = mr::load_heightmap_png(png);
    ASSERT_TRUE(map.ok()) << map.error().message;
    const int w = map->width, h = map->height;
    std::vector<float> heights(static_cast<size_t>(w) * h);
    for (int k = 0; k < h; ++k)
        for (int c = 0; c < w; ++c) heights[static_cast<size_t>(k) * w + c] = map->at(h - 1 - k, c);
    mr_world_desc d = mr_world_desc_default();
    d.heightmap_file = png.c_str();
    World from_file(d);
    ASSERT_EQ(from_file.status, MR_OK) << from_file.error.message;
    d.heightmap_file = nullptr;
    d.heights = heights.data();
    d.columns = w;
    d.rows = h;
    World from_heights(d);
    ASSERT_EQ(from_heights.status, MR_OK) << from_heights.error.message;
    EXPECT_EQ(terrain_heights(from_file), terrain_heights(from_heights));
}

TEST(CApi, HeightsWithTheDefaultSceneRunARiver) {
    const std::vector<float> h = ramp(48, 64);
    mr_world_desc d = mr_world_desc_default();
    d.heights = h.data();
    d.columns = 48;
    d.rows = 64;
    World world(d);
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(60);
    EXPECT_GT(world.stats().active_particles, 0u);
}

TEST(CApi, CreationRefusalsNameTheCulprit) {
    mr_world* w = reinterpret_cast<mr_world*>(0x1);
    mr_error e{};
    EXPECT_EQ(mr_world_create(nullptr, &w, &e), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(w, nullptr);
    EXPECT_TRUE(contains(e.message, "desc")) << e.message;
    const mr_world_desc def = mr_world_desc_default();
    EXPECT_EQ(mr_world_create(&def, nullptr, &e), MR_ERROR_NULL_ARGUMENT);
    EXPECT_TRUE(contains(e.message, "out_world")) << e.message;
    EXPECT_EQ(mr_world_create(&def, nullptr, nullptr), MR_ERROR_NULL_ARGUMENT) << "error may be NULL";

    mr_world_desc d = def;
    d.preset = "default";
    d.scene_toml = "";
    EXPECT_TRUE(contains(create_error(d, MR_ERROR_INVALID_ARGUMENT), "scene_toml, preset"));
    d = def;
    d.preset = "no-such-preset";
    const std::string unknown = create_error(d, MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(unknown, "preset") && contains(unknown, "no-such-preset") && contains(unknown, "paper-bowl"))
        << unknown;
    d = def;
    d.scene_toml = "[pbf]\nxsph = 7.0\n";
    const std::string key = create_error(d, MR_ERROR_SCENE);
    EXPECT_TRUE(contains(key, "pbf.xsph") && contains(key, "[0, 1]")) << key;
    d = def;
    d.scene_toml = "[pbf]\nno_such_key = 1\n";
    EXPECT_TRUE(contains(create_error(d, MR_ERROR_SCENE), "no_such_key"));
    d = def;
    d.scene_file = "/nonexistent/river.toml";
    EXPECT_TRUE(contains(create_error(d, MR_ERROR_IO), "/nonexistent/river.toml"));
    d = def;
    d.heightmap_file = "/nonexistent/map.png";
    const std::string png = create_error(d, MR_ERROR_IO);
    EXPECT_TRUE(contains(png, "heightmap_file") && contains(png, "/nonexistent/map.png")) << png;
    const std::string not_png = temp_file("not.png", "not a PNG");
    d.heightmap_file = not_png.c_str();
    const std::string corrupt = create_error(d, MR_ERROR_IO);
    EXPECT_TRUE(contains(corrupt, "heightmap_file") && contains(corrupt, "not.png")) << corrupt;
    const std::string bad_scene = temp_file("bad.toml", "[pbf]\nxsph = \"much\"\n");
    d = def;
    d.scene_file = bad_scene.c_str();
    const std::string scene = create_error(d, MR_ERROR_SCENE);
    EXPECT_TRUE(contains(scene, "bad.toml") && contains(scene, "pbf.xsph")) << scene;
    std::filesystem::remove(not_png);
    std::filesystem::remove(bad_scene);
    d = def;
    d.threads = -1;
    EXPECT_TRUE(contains(create_error(d, MR_ERROR_INVALID_ARGUMENT), "threads"));
    d.threads = 1000000;
    const std::string threads = create_error(d, MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(threads, "threads") && contains(threads, "[0, 1024]")) << threads;
    d = def;
    d.area_scale = -1.0f;
    EXPECT_TRUE(contains(create_error(d, MR_ERROR_INVALID_ARGUMENT), "area_scale"));
    d = def;
    d.height_scale = std::numeric_limits<float>::quiet_NaN();
    EXPECT_TRUE(contains(create_error(d, MR_ERROR_INVALID_ARGUMENT), "height_scale"));
}

TEST(CApi, BadHeightsAreRefusedNamingThem) {
    std::vector<float> h = ramp(8, 8);
    mr_world_desc d = mr_world_desc_default();
    d.heights = h.data();
    d.columns = 8;
    d.rows = 8;
    h[19] = std::numeric_limits<float>::quiet_NaN();
    std::string m = create_error(d, MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(m, "heights[19]") && contains(m, "row 2, column 3") && contains(m, "[0, 1]")) << m;
    h[19] = 1.5f;
    EXPECT_TRUE(contains(create_error(d, MR_ERROR_INVALID_ARGUMENT), "heights[19]"));
    h[19] = -0.25f;
    EXPECT_TRUE(contains(create_error(d, MR_ERROR_INVALID_ARGUMENT), "heights[19]"));
    h[19] = 0.5f;
    d.columns = 1;
    m = create_error(d, MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(m, "columns") && contains(m, "[2, 4097]")) << m;
    d.columns = 8;
    d.rows = 5000;
    EXPECT_TRUE(contains(create_error(d, MR_ERROR_INVALID_ARGUMENT), "rows"));
    d.rows = 8;
    d.heightmap_file = "x.png";
    m = create_error(d, MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(m, "heightmap_file") && contains(m, "heights")) << m;
}

// The paper's engine physics (Bullet): its presets leave the heightmap file to the caller,
// and its solver refuses the edits its registry entry refuses (MR_ERROR_UNSUPPORTED).
TEST(CApi, ABulletWorldRefusesPushAndSculpt) {
    mr_world_desc d = mr_world_desc_default();
    d.preset = "paper-engine";
    const std::string m = create_error(d, MR_ERROR_SCENE);
    EXPECT_TRUE(contains(m, "heightmap_file")) << m;
    const std::vector<float> h = ramp(17, 17);
    d.heights = h.data();
    d.columns = 17;
    d.rows = 17;
    if (!mr::test::kWithBullet) {  // METARIVER_WITH_BULLET=OFF: the solver is refused, naming the option
        const std::string off = create_error(d, MR_ERROR_SCENE);
        EXPECT_TRUE(contains(off, "METARIVER_WITH_BULLET")) << off;
        return;
    }
    World world(d);
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(10);
    const float at[3] = {8, 7, 8}, velocity[3] = {1, 0, 0};
    size_t pushed = 7;
    EXPECT_EQ(mr_world_push(world.w, at, 2.0f, velocity, &pushed), MR_ERROR_UNSUPPORTED);
    EXPECT_TRUE(contains(world.last_error(), "bullet")) << world.last_error();
    EXPECT_EQ(pushed, 7u) << "nothing written";
    const mr_brush brush{.x = 8, .z = 8, .radius = 3, .strength = 1, .mode = MR_BRUSH_RAISE, .target = 0};
    EXPECT_EQ(mr_world_sculpt(world.w, &brush), MR_ERROR_UNSUPPORTED);
    EXPECT_TRUE(contains(world.last_error(), "bullet")) << world.last_error();
    const float box[6] = {0, -5, 0, 2, 20, 2};
    const mr_status sinks = mr_world_set_sink_boxes(world.w, box, 1);
    EXPECT_EQ(sinks, MR_ERROR_UNSUPPORTED) << "Bullet reads no [[sink.box]]";
    EXPECT_TRUE(contains(world.last_error(), "sink.box")) << world.last_error();
}

}  // namespace
