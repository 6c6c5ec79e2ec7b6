// The bodies in the renderer (issue 44): each body's mesh drawn with its transform from
// SceneView::bodies (states built by hand here: the renderer reads plain data), seen
// where the body is, wood-coloured, and gone when RenderSettings::bodies is off.
#include <metariver/io.h>
#include <metariver/render.h>

#include "body_geometry.h"
#include "render_support.h"

#include <glm/gtc/quaternion.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

using namespace mr;
using test::pixels_differing;
using test::small_valley;
using test::stepped;

namespace {

/// A box of full extents `size` around the origin: 6 faces of 4 vertices, outward normals.
std::shared_ptr<const BodyMesh> box_mesh(Vec3 size) {
    auto m = std::make_shared<BodyMesh>();
    const Vec3 h = 0.5f * size;
    for (int axis = 0; axis < 3; ++axis)
        for (const float sign : {-1.0f, 1.0f}) {
            Vec3 n(0.0f);
            n[axis] = sign;
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            const auto first = static_cast<uint32_t>(m->positions.size());
            for (const auto& [a, b] : {std::pair{-1.0f, -1.0f}, {1.0f, -1.0f}, {1.0f, 1.0f}, {-1.0f, 1.0f}}) {
                Vec3 p = n * h;
                p[u] = a * h[u];
                p[v] = b * h[v];
                m->positions.push_back(p);
                m->normals.push_back(n);
            }
            for (const uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m->indices.push_back(first + i);
        }
    return m;
}

TEST(BodyGeometry, EachMeshUnderItsTransformAndBadMeshesLeftOut) {
    BodyState b;
    b.position = Vec3(10, 2, 3);
    b.orientation = glm::angleAxis(glm::radians(90.0f), Vec3(0, 1, 0));  // body x -> world -z
    b.mesh = box_mesh(Vec3(4, 1, 1));
    BodyState no_mesh;
    BodyState broken = b;
    auto bad = std::make_shared<BodyMesh>(*b.mesh);
    bad->indices.push_back(999);
    broken.mesh = bad;
    std::vector<BodyState> bodies{b, no_mesh, broken, b};
    std::vector<render::BodyVertex> v;
    std::vector<uint32_t> idx;
    render::build_body_geometry(bodies, v, idx);
    ASSERT_EQ(v.size(), 48u) << "two good bodies of 24 vertices";
    ASSERT_EQ(idx.size(), 72u);
    EXPECT_EQ(idx[36], 24u) << "the second body's indices follow its own vertices";
    Vec3 lo(1e9f), hi(-1e9f);
    for (size_t i = 0; i < 24; ++i) {
        lo = glm::min(lo, v[i].pos);
        hi = glm::max(hi, v[i].pos);
        EXPECT_NEAR(glm::length(v[i].normal), 1.0f, 1e-5f);
    }
    EXPECT_NEAR(lo.x, 9.5f, 1e-4f);
    EXPECT_NEAR(hi.x, 10.5f, 1e-4f);
    EXPECT_NEAR(lo.z, 1.0f, 1e-4f) << "the long axis turned onto z";
    EXPECT_NEAR(hi.z, 5.0f, 1e-4f);
    EXPECT_NEAR(lo.y, 1.5f, 1e-4f);
}

TEST(Renderer, ABodyShowsWhereItIsInWood) {
    REQUIRE_GL();
    auto sim = stepped(small_valley(), 5);
    ASSERT_TRUE(sim);
    const Aabb tb = sim->terrain().bounds();
    std::vector<BodyState> bodies(1);
    BodyState& b = bodies[0];
    b.id = 1;
    b.size = Vec3(6, 2, 2);
    b.position = Vec3(0.5f * (tb.min.x + tb.max.x), tb.max.y + 2.0f, 0.5f * (tb.min.z + tb.max.z));
    b.orientation = glm::angleAxis(glm::radians(30.0f), Vec3(0, 1, 0));
    b.mesh = box_mesh(b.size);

    auto r = render::Renderer::create();
    ASSERT_TRUE(r.ok()) << r.error().message;
    render::Renderer& renderer = *r.value();
    const render::Camera cam = render::frame_terrain(sim->terrain());
    const int w = 320, h = 200;
    render::RenderSettings s;
    std::vector<uint8_t> without, with, off;
    SceneView view = sim->view();
    renderer.set_scene(view);
    renderer.draw(cam, w, h, s);
    renderer.read_rgb(without);
    EXPECT_EQ(renderer.stats().bodies, 0u);
    const uint64_t objects = renderer.stats().gl_objects_created;

    view.bodies = bodies;
    view.frame += 1;  // a new frame of the same owner: its bodies are sent
    renderer.update(view);
    EXPECT_EQ(renderer.stats().bodies, 1u);
    EXPECT_EQ(renderer.stats().body_triangles, 12u);
    renderer.draw(cam, w, h, s);
    renderer.read_rgb(with);
    EXPECT_EQ(renderer.stats().gl_objects_created, objects) << "bodies reuse the renderer's GL objects";
    s.bodies = false;
    renderer.draw(cam, w, h, s);
    renderer.read_rgb(off);
    EXPECT_EQ(pixels_differing(off, without, 0), 0u) << "bodies off: the image without them";

    // The centre of the body's top face (lit by the sun) on screen: changed, and wood
    // (red over green over blue).
    const Vec3 top = b.position + Vec3(0.0f, 0.5f * b.size.y, 0.0f);
    const glm::vec4 c = cam.projection(float(w) / float(h)) * cam.view() * glm::vec4(top, 1.0f);
    const int px = int((c.x / c.w * 0.5f + 0.5f) * float(w)), py = int((0.5f - c.y / c.w * 0.5f) * float(h));
    ASSERT_TRUE(px >= 0 && px < w && py >= 0 && py < h) << px << "," << py;
    const uint8_t* at = &with[3 * (size_t(py) * size_t(w) + size_t(px))];
    const uint8_t* before = &without[3 * (size_t(py) * size_t(w) + size_t(px))];
    EXPECT_GT(std::abs(int(at[0]) - before[0]) + std::abs(int(at[1]) - before[1]) + std::abs(int(at[2]) - before[2]), 30);
    EXPECT_GT(at[0], at[1]);
    EXPECT_GT(at[1], at[2]);
    std::filesystem::create_directories(METARIVER_TEST_OUTPUT_DIR);
    (void)write_png(std::string(METARIVER_TEST_OUTPUT_DIR) + "/body.png", with, w, h, 3);  // to look at
    const size_t changed = pixels_differing(with, without, 20);
    std::printf("a 6 x 2 x 2 m body: %zu of %d pixels changed, top rgb %d %d %d\n", changed, w * h, at[0], at[1], at[2]);
    EXPECT_GT(changed, 50u);
    EXPECT_LT(changed, size_t(w * h) / 4) << "only where the body is";
}

}  // namespace
