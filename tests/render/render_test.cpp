// Renderer tests, headless (EGL surfaceless): golden images of small fixed scenes,
// the "no GL object per frame / upload only what changed" contract, and the camera's
// picking ray. Every test skips (with the reason) when no EGL device can be created,
// so the suite passes on a machine without Mesa; on a machine with Mesa they run.
//
// Golden images live in tests/render/golden/. To re-record them after an intended
// change of the look: METARIVER_UPDATE_GOLDEN=1 ctest -R Golden (then look at them).
#include <metariver/io.h>
#include <metariver/render.h>

#include "bowl_drop.h"
#include "render_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

namespace fs = std::filesystem;
using namespace mr;
using test::pixels_differing;
using test::small_valley;
using test::stepped;

namespace {

struct Rendered {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;
};

Rendered render_scene(const SceneDef& def, int frames, int width, int height, const render::RenderSettings& settings,
                      const std::optional<std::string>& camera = std::nullopt) {
    auto sim = stepped(def, frames);
    auto renderer = render::Renderer::create();
    EXPECT_TRUE(renderer.ok()) << (renderer.ok() ? "" : renderer.error().message);
    Rendered out;
    if (!sim || !renderer.ok()) return out;
    render::Camera cam = render::frame_terrain(sim->terrain());
    if (camera) {
        EXPECT_TRUE(render::parse_camera(*camera, cam).ok());
    }
    render::fit_clip_planes(cam, sim->terrain());
    renderer.value()->set_scene(sim->view());
    renderer.value()->draw(cam, width, height, settings);
    renderer.value()->read_rgb(out.rgb);
    out.width = width;
    out.height = height;
    return out;
}

/// Compares with the stored golden image: per-channel max and mean absolute difference.
/// On failure writes NAME.actual.png and NAME.diff.png (difference x4) next to the
/// build output and prints their paths.
void expect_matches_golden(const std::string& name, const Rendered& img, int max_tolerance, double mean_tolerance) {
    const fs::path golden = fs::path(METARIVER_SOURCE_DIR) / "tests/render/golden" / (name + ".png");
    const fs::path out_dir = fs::path(METARIVER_TEST_OUTPUT_DIR);
    if (const char* u = std::getenv("METARIVER_UPDATE_GOLDEN"); u && std::string(u) == "1") {
        ASSERT_TRUE(write_png(golden.string(), img.rgb, img.width, img.height, 3).ok());
        GTEST_SKIP() << "re-recorded " << golden;
    }
    auto ref = load_image(golden.string(), 3);
    ASSERT_TRUE(ref.ok()) << ref.error().message << " (record it with METARIVER_UPDATE_GOLDEN=1)";
    if (ref->width != img.width || ref->height != img.height) {
        fs::create_directories(out_dir);
        const fs::path actual = out_dir / (name + ".actual.png");
        (void)write_png(actual.string(), img.rgb, img.width, img.height, 3);
        FAIL() << name << ": size " << img.width << "x" << img.height << ", golden " << ref->width << "x"
               << ref->height << "\n  golden: " << golden << "\n  actual: " << actual;
    }
    int max_diff = 0;
    double sum = 0.0;
    std::vector<uint8_t> diff(img.rgb.size());
    for (size_t i = 0; i < img.rgb.size(); ++i) {
        const int d = std::abs(static_cast<int>(img.rgb[i]) - static_cast<int>(ref->pixels[i]));
        max_diff = std::max(max_diff, d);
        sum += d;
        diff[i] = static_cast<uint8_t>(std::min(255, d * 4));
    }
    const double mean = sum / static_cast<double>(img.rgb.size());
    const bool ok = max_diff <= max_tolerance && mean <= mean_tolerance;
    if (!ok) {
        fs::create_directories(out_dir);
        const fs::path actual = out_dir / (name + ".actual.png"), diff_path = out_dir / (name + ".diff.png");
        (void)write_png(actual.string(), img.rgb, img.width, img.height, 3);
        (void)write_png(diff_path.string(), diff, img.width, img.height, 3);
        ADD_FAILURE() << name << ": max difference " << max_diff << " (allowed " << max_tolerance << "), mean "
                      << mean << " (allowed " << mean_tolerance << ")\n  golden: " << golden
                      << "\n  actual: " << actual << "\n  diff:   " << diff_path;
    }
}

// Tolerances. The images are rendered by the same shaders on Mesa's llvmpipe, which is
// deterministic on one machine (the same run gives identical bytes). They must still
// pass on another Mesa version or CPU (different LLVM code generation, SIMD width and
// rasteriser rounding): those move a triangle edge by a pixel or shift a colour by a
// few steps.
// - max 128 per channel: a pixel flipping between two neighbouring surfaces at an edge
//   (water and bank, terrain and its skirt) changes by less; a missing or extra layer
//   (sky, a particle, a box, the water) or a wrong colour moves pixels by more.
// - mean 1.5 per channel: edge flips touch a few percent of the pixels; any real change
//   of the look (lighting, tint, the camera) moves the mean by 5 or more.
constexpr int kMaxDiff = 128;
constexpr double kMeanDiff = 1.5;

}  // namespace

TEST(RenderGolden, ValleyRealisticWater) {
    REQUIRE_GL();
    render::RenderSettings s;
    const Rendered img = render_scene(small_valley(), 90, 160, 120, s);
    expect_matches_golden("valley_realistic", img, kMaxDiff, kMeanDiff);
}

TEST(RenderGolden, BowlGouraudParticlesTree) {
    REQUIRE_GL();
    auto def = preset("paper-bowl");
    ASSERT_TRUE(def.ok());
    render::RenderSettings s;
    s.shading = render::WaterShading::Gouraud;
    s.particles = true;
    s.bvh = true;
    s.bvh_level = 1;
    s.particle_radius = 0.5f;
    const Rendered img = render_scene(def.value(), 120, 160, 120, s, std::string("35,50,22"));
    expect_matches_golden("bowl_gouraud_debug", img, kMaxDiff, kMeanDiff);
}

TEST(RenderGolden, StrictTerrainOnlyFromAbove) {
    REQUIRE_GL();
    SceneDef d = small_valley();
    d.source.kind = TerrainSource::Strict;
    d.source.width = 17;
    d.source.height = 17;
    d.terrain.height_scale = 7.0f;
    d.spawn.count = 1;
    render::RenderSettings s;
    s.water = false;
    const Rendered img = render_scene(d, 1, 128, 96, s, std::string("20,60,30"));
    expect_matches_golden("strict_terrain", img, kMaxDiff, kMeanDiff);
}

TEST(Renderer, NoGlObjectsPerFrameAndUploadsOnlyWhatChanged) {
    REQUIRE_GL();
    auto sim = stepped(small_valley(), 30);
    ASSERT_TRUE(sim);
    auto r = render::Renderer::create();
    ASSERT_TRUE(r.ok()) << r.error().message;
    render::Renderer& renderer = *r.value();
    renderer.set_scene(sim->view());
    const render::Camera cam = render::frame_terrain(sim->terrain());
    render::RenderSettings s;
    s.particles = true;
    s.bvh = true;
    renderer.draw(cam, 96, 64, s);
    const uint64_t objects = renderer.stats().gl_objects_created;
    for (int i = 0; i < 20; ++i) {
        sim->step(1.0f / 60.0f);
        renderer.update(sim->view());
        EXPECT_GT(renderer.stats().last_upload_bytes, 0u) << "the water moved: it must be sent";
        renderer.draw(cam, 96, 64, s);
    }
    EXPECT_EQ(renderer.stats().gl_objects_created, objects) << "draw()/update() must reuse GL objects";
    // Nothing moved: nothing is sent.
    renderer.update(sim->view());
    EXPECT_EQ(renderer.stats().last_upload_bytes, 0u);
    // An incomplete view (no particles) is refused, not read: the last upload stands.
    SceneView partial = sim->view();
    partial.particles = nullptr;
    partial.frame += 1;
    renderer.update(partial);
    renderer.set_scene(SceneView{});
    EXPECT_EQ(renderer.stats().last_upload_bytes, 0u);
    // A resize re-specifies the textures, still without new objects.
    renderer.draw(cam, 128, 80, s);
    EXPECT_EQ(renderer.stats().gl_objects_created, objects);
    std::vector<uint8_t> rgb;
    renderer.read_rgb(rgb);
    EXPECT_EQ(rgb.size(), 128u * 80u * 3u);
    EXPECT_GT(renderer.stats().water_triangles, 0u);
}

TEST(Renderer, ReportsGlVersion) {
    REQUIRE_GL();
    auto r = render::Renderer::create();
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_NE(r.value()->gl_description().find("4."), std::string::npos) << r.value()->gl_description();
}

// ---- camera and picking (no GL needed) ----

TEST(Renderer, TerrainTextureChecksItsBufferAndTheGlLimit) {
    // Issue 13: the pixel buffer's size and GL_MAX_TEXTURE_SIZE were not checked.
    REQUIRE_GL();
    auto r = render::Renderer::create();
    ASSERT_TRUE(r.ok()) << r.error().message;
    std::vector<uint8_t> px(4 * 4 * 4, 200);
    EXPECT_TRUE(r.value()->set_terrain_texture(px, 4, 4).ok());
    const auto short_buffer = r.value()->set_terrain_texture(std::span(px).first(60), 4, 4);
    ASSERT_FALSE(short_buffer.ok());
    EXPECT_NE(short_buffer.error().message.find("needs 64"), std::string::npos) << short_buffer.error().message;
    std::vector<uint8_t> wide(size_t(4) * 100'000, 1);
    const auto too_wide = r.value()->set_terrain_texture(wide, 100'000, 1);
    ASSERT_FALSE(too_wide.ok());
    EXPECT_NE(too_wide.error().message.find("GL_MAX_TEXTURE_SIZE"), std::string::npos) << too_wide.error().message;
    EXPECT_TRUE(r.value()->set_terrain_texture({}, 0, 0).ok()) << "empty turns it off";
}

TEST(Camera, PickingRayHitsTheTerrainUnderTheScreenCentre) {
    auto sim = stepped(small_valley(), 0);
    ASSERT_TRUE(sim);
    const Terrain& t = sim->terrain();
    render::Camera cam = render::frame_terrain(t);
    // Aim at a point on the ground; the centre pixel's ray must come back to it.
    const float x = 10.0f, z = 20.0f;
    cam.target = Vec3(x, t.height_mesh(x, z), z);
    cam.distance = 30.0f;
    render::fit_clip_planes(cam, t);
    auto hit = render::pick_terrain(cam, 320.0f, 240.0f, 640, 480, t, sim->bvh());
    ASSERT_TRUE(hit.has_value());
    // Tolerance: float rounding of the unprojection over ~30 m (about 1e-5 relative).
    EXPECT_NEAR(hit->x, x, 1e-2f);
    EXPECT_NEAR(hit->z, z, 1e-2f);
    EXPECT_NEAR(hit->y, t.height_mesh(x, z), 1e-2f);
    // A ray into the sky misses.
    cam.pitch_deg = -30.0f;  // eye below the target, looking up
    cam.target.y += 200.0f;
    EXPECT_FALSE(render::pick_terrain(cam, 320.0f, 240.0f, 640, 480, t, sim->bvh()).has_value());
}

TEST(Camera, ParseCameraChecksItsInput) {
    render::Camera c;
    EXPECT_TRUE(render::parse_camera("30,40,50", c).ok());
    EXPECT_FLOAT_EQ(c.yaw_deg, 30.0f);
    EXPECT_FLOAT_EQ(c.distance, 50.0f);
    EXPECT_TRUE(render::parse_camera("0,10,5,1,2,3", c).ok());
    EXPECT_FLOAT_EQ(c.target.z, 3.0f);
    EXPECT_FALSE(render::parse_camera("30,40", c).ok());
    EXPECT_FALSE(render::parse_camera("a,b,c", c).ok());
    EXPECT_FALSE(render::parse_camera("0,95,10", c).ok());
    EXPECT_FALSE(render::parse_camera("0,10,-1", c).ok());
}

TEST(Camera, FromAboveFitsTheWholeTerrainIntoTheView) {
    // Wide and tall rectangles with relief, into wide and tall views: every corner of
    // the terrain's box (at the lowest and the highest ground) lands inside the image,
    // and the fit is tight (some corner beyond 85 % of the half width or height).
    for (const auto& [w, h] : {std::pair{121, 31}, std::pair{17, 65}}) {
        Heightmap m = flat_heightmap(w, h);
        for (size_t i = 0; i < m.samples.size(); ++i) m.samples[i] = float(i % 7) / 6.0f;
        auto t = Terrain::build(m, TerrainDef{.area_scale = 2.0f, .height_scale = 20.0f});
        ASSERT_TRUE(t.ok()) << t.error().message;
        const Aabb& b = t.value().bounds();
        for (const float aspect : {16.0f / 9.0f, 9.0f / 16.0f}) {
            const render::Camera cam = render::frame_terrain_from_above(t.value(), aspect);
            EXPECT_GE(cam.pitch_deg, 85.0f);
            const glm::mat4 vp = cam.projection(aspect) * cam.view();
            float reach = 0.0f;
            for (const float x : {b.min.x, b.max.x})
                for (const float y : {b.min.y, b.max.y})
                    for (const float z : {b.min.z, b.max.z}) {
                        const glm::vec4 c = vp * glm::vec4(x, y, z, 1.0f);
                        ASSERT_GT(c.w, 0.0f) << "a corner behind the camera";
                        const float nx = c.x / c.w, ny = c.y / c.w, nz = c.z / c.w;
                        EXPECT_LE(std::abs(nx), 1.0f) << w << "x" << h << " aspect " << aspect;
                        EXPECT_LE(std::abs(ny), 1.0f) << w << "x" << h << " aspect " << aspect;
                        EXPECT_LE(std::abs(nz), 1.0f) << "clipped by the near or far plane";
                        reach = std::max({reach, std::abs(nx), std::abs(ny)});
                    }
            EXPECT_GT(reach, 0.85f) << w << "x" << h << " aspect " << aspect << ": the terrain fills too little";
        }
    }
}

TEST(Camera, TheDefaultFramingSeesTheBottomOfADeepBowl) {
    // A bowl 33 m across and 24 m deep (the paper's maps are that steep): at the 32
    // degrees that suit ordinary relief the near rim hides the bottom, where the water
    // gathers. The framing looks down more steeply there; a valley keeps 32 degrees.
    SceneDef d = small_valley();
    d.source = {.kind = TerrainSource::Bowl, .heightmap = {}, .width = 33, .height = 33, .seed = 7};
    d.terrain.height_scale = 24.0f;
    auto sim = stepped(d, 0);
    ASSERT_TRUE(sim);
    const Terrain& t = sim->terrain();
    const render::Camera cam = render::frame_terrain(t);
    const Vec3 bottom(16.0f, t.height_mesh(16.0f, 16.0f), 16.0f);
    const int w = 640, h = 360;
    const glm::vec4 c = cam.projection(float(w) / float(h)) * cam.view() * glm::vec4(bottom, 1.0f);
    ASSERT_GT(c.w, 0.0f);
    const float px = (c.x / c.w * 0.5f + 0.5f) * float(w), py = (0.5f - c.y / c.w * 0.5f) * float(h);
    ASSERT_TRUE(px >= 0.0f && px < float(w) && py >= 0.0f && py < float(h)) << "the bottom is outside the image";
    auto hit = render::pick_terrain(cam, px, py, w, h, t, sim->bvh());
    ASSERT_TRUE(hit.has_value());
    EXPECT_LT(glm::length(*hit - bottom), 1.0f) << "the ray to the bottom hits the rim at (" << hit->x << ", " << hit->y
                                                << ", " << hit->z << ")";
    SceneDef flat = small_valley();
    flat.terrain.height_scale = 2.0f;
    auto low = stepped(flat, 0);
    ASSERT_TRUE(low);
    EXPECT_FLOAT_EQ(render::frame_terrain(low->terrain()).pitch_deg, 32.0f) << "ordinary relief";
}

/// A splash: 1500 PBF particles thrown down into the procedural bowl (the default
/// river's fluid and [foam]), broken water within a few frames.
SceneDef splash_scene() {
    SceneDef d = test::bowl_drop(1500, Vec3(16, 7, 16), Vec3(3, 1.5f, 3));
    d.name = "foam splash";
    d.spawn.initial_velocity = Vec3(4.0f, -8.0f, 0.0f);
    d.foam.enabled = true;
    return d;
}

TEST(Renderer, FoamAppearsWhiteOnTheWaterAndCanBeTurnedOff) {
    REQUIRE_GL();
    auto sim = stepped(splash_scene(), 45);
    ASSERT_TRUE(sim);
    Simulation& s = *sim;
    ASSERT_NE(s.foam(), nullptr);
    const FoamStats& fs = s.foam()->stats();
    ASSERT_GT(fs.foam + fs.spray, 50u) << "the splash must make foam or spray";
    auto r = render::Renderer::create();
    ASSERT_TRUE(r.ok()) << r.error().message;
    render::Renderer& renderer = *r.value();
    renderer.set_scene(s.view());
    EXPECT_EQ(renderer.stats().foam_particles, fs.total());
    render::Camera cam = render::frame_terrain(s.terrain());
    cam.distance *= 0.6f;
    render::fit_clip_planes(cam, s.terrain());
    const int w = 320, h = 200;
    render::RenderSettings on, off;
    off.foam = false;
    std::vector<uint8_t> with, without;
    renderer.draw(cam, w, h, on);
    renderer.read_rgb(with);
    renderer.draw(cam, w, h, off);
    renderer.read_rgb(without);
    // Foam pixels: near white with foam, clearly darker without it (water, terrain).
    size_t foam_pixels = 0;
    for (size_t p = 0; p < size_t(w) * size_t(h); ++p) {
        const uint8_t* a = &with[3 * p];
        const uint8_t* b = &without[3 * p];
        const bool white = a[0] > 200 && a[1] > 200 && a[2] > 200;
        const int gain = (int(a[0]) + a[1] + a[2]) - (int(b[0]) + b[1] + b[2]);
        foam_pixels += white && gain > 60;
    }
    std::printf("foam splash: %zu spray, %zu foam, %zu bubbles; %zu foam pixels of %d\n", fs.spray, fs.foam,
                fs.bubbles, foam_pixels, w * h);
    EXPECT_GT(foam_pixels, 40u) << "foam must show as white on the water";
}

/// Draws `sim` at two flow-clock times, flow detail on and off, close up.
struct TwoTimes {
    std::vector<uint8_t> on0, on1, off0, off1;
};
TwoTimes draw_at_two_times(const Simulation& s, float t0, float t1) {
    auto r = render::Renderer::create();
    EXPECT_TRUE(r.ok());
    TwoTimes out;
    if (!r.ok()) return out;
    render::Renderer& renderer = *r.value();
    renderer.set_scene(s.view());
    render::Camera cam = render::frame_terrain(s.terrain());
    cam.distance *= 0.6f;
    render::fit_clip_planes(cam, s.terrain());
    render::RenderSettings on, off;
    on.foam = off.foam = false;
    off.flow_detail = false;
    auto draw = [&](render::RenderSettings st, float t, std::vector<uint8_t>& rgb) {
        st.time_s = t;
        renderer.draw(cam, 320, 200, st);
        renderer.read_rgb(rgb);
    };
    draw(on, t0, out.on0);
    draw(on, t1, out.on1);
    draw(off, t0, out.off0);
    draw(off, t1, out.off1);
    return out;
}

TEST(Renderer, FlowDetailMovesOnFlowingWaterAndLeavesStillWaterAlone) {
    REQUIRE_GL();
    // Flowing: the splash thrown sideways across the bowl, 30 frames in (metres per second).
    SceneDef flowing = splash_scene();
    flowing.foam.enabled = false;
    auto f = stepped(flowing, 30);
    ASSERT_TRUE(f);
    ASSERT_GT(f->counters().max_speed, 2.0f * render::kFlowDetailFullSpeed) << "the splash must be fast";
    const TwoTimes fl = draw_at_two_times(*f, 2.0f, 2.35f);  // the same particles, 0.35 s apart
    const size_t moved = pixels_differing(fl.on0, fl.on1, 6);
    std::printf("flowing: %zu of %d pixels change between the two times with flow detail\n", moved, 320 * 200);
    EXPECT_GT(moved, 500u) << "the texture must move along the flow";
    EXPECT_EQ(fl.off0, fl.off1) << "without flow detail the time changes nothing";
    EXPECT_GT(pixels_differing(fl.on0, fl.off0, 6), 500u) << "flow detail must show on fast water";

    // Still: a small pool settled until every particle sleeps (velocity exactly 0).
    SceneDef still = test::bowl_drop(700, Vec3(16, 1.5f, 16), Vec3(2.5f, 0.5f, 2.5f));
    still.foam.enabled = false;
    auto p = stepped(still, 0);
    ASSERT_TRUE(p);
    int frames = 0;
    for (; frames < 1200; ++frames) {
        p->step(1.0f / 60.0f);
        if (frames > 60 && p->counters().max_speed < render::kFlowDetailMinSpeed) break;
    }
    std::printf("still pool: max speed %.4f m/s after %d frames\n", p->counters().max_speed, frames + 1);
    ASSERT_LT(p->counters().max_speed, render::kFlowDetailMinSpeed) << "the pool must come to rest";
    const TwoTimes st = draw_at_two_times(*p, 2.0f, 2.35f);
    EXPECT_EQ(st.on0, st.on1) << "still water: the flow detail adds nothing, at any time";
    EXPECT_EQ(st.on0, st.off0) << "still water with flow detail is the water without it (a mirror stays a mirror)";
}
