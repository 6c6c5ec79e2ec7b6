// The viewer's drop / throw body tool without a window (apps/metariver/view_drop.h): a
// click over the river drops the body on the water's surface, over dry ground on the
// ground; the body is held over that point; a drag throws it with the cursor's velocity.
#include "view_drop.h"

#include <metariver/scene.h>
#include <metariver/water_query.h>

#include <gtest/gtest.h>

namespace mr {
namespace {

TEST(ViewDrop, AClickOverTheRiverDropsOnTheWaterOverDryGroundOnTheGround) {
    auto sim = Simulation::create(default_scene());
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    for (int f = 0; f < 180; ++f) s.step(1.0f / 60.0f);
    WaterQuery water;
    water.update(s);
    const float as = s.terrain().area_scale();
    // The deepest water along the main channel, and a dry corner of the terrain.
    Vec3 wet(0.0f);
    float depth = 0.0f;
    for (const auto& [i, j] : s.main_channel()) {
        const WaterSample w = water.sample(float(j) * as, float(i) * as);
        if (w.depth > depth) depth = w.depth, wet = Vec3(float(j) * as, w.surface_y, float(i) * as);
    }
    ASSERT_GT(depth, 0.2f) << "no water in the channel after 3 s";
    const Vec3 down(0.0f, -1.0f, 0.0f);
    const Vec3 ground(wet.x, s.terrain().height_mesh(wet.x, wet.z), wet.z);
    const Vec3 origin(wet.x, wet.y + 30.0f, wet.z);
    const auto on = view::drop_point(origin, down, ground, &water, 100.0f);
    ASSERT_TRUE(on.has_value());
    EXPECT_TRUE(on->on_water);
    EXPECT_NEAR(on->point.y, wet.y, 0.05f) << "not on the water's surface";
    EXPECT_GT(on->point.y, ground.y + 0.2f);
    // Without the water (or with a ray the water does not meet first): the ground.
    const auto bare = view::drop_point(origin, down, ground, nullptr, 100.0f);
    ASSERT_TRUE(bare.has_value());
    EXPECT_FALSE(bare->on_water);
    EXPECT_EQ(bare->point, ground);
    const float cx = 1.0f, cz = 1.0f;  // a corner of the valley: its slopes are dry
    ASSERT_EQ(water.sample(cx, cz).depth, 0.0f);
    const Vec3 dry(cx, s.terrain().height_mesh(cx, cz), cz);
    const auto off = view::drop_point(dry + Vec3(0.0f, 30.0f, 0.0f), down, dry, &water, 100.0f);
    ASSERT_TRUE(off.has_value());
    EXPECT_FALSE(off->on_water);
    EXPECT_EQ(off->point, dry);
    // A ray that meets neither.
    EXPECT_FALSE(view::drop_point(Vec3(wet.x, wet.y + 30.0f, wet.z), Vec3(0.0f, 1.0f, 0.0f), std::nullopt, &water, 100.0f));
    // Held over the point by the body's reach and the lift.
    const Vec3 held = view::held_position(*on, BodyShape::Box, Vec3(2.0f, 0.0f, 0.0f), 1.0f);
    EXPECT_EQ(held, on->point + Vec3(0.0f, 2.0f, 0.0f));
    EXPECT_FLOAT_EQ(view::body_reach(BodyShape::Capsule, Vec3(0.2f, 1.2f, 0.0f)), 0.8f);
    EXPECT_FLOAT_EQ(view::body_reach(BodyShape::Sphere, Vec3(0.5f, 0.0f, 0.0f)), 0.5f);
}

TEST(ViewDrop, ADragThrowsWithTheCursorsHorizontalVelocity) {
    const Vec3 v = view::cursor_velocity(Vec3(0.0f), Vec3(1.0f, 5.0f, 2.0f), 0.5, 1.0f, 20.0f);
    EXPECT_EQ(v, Vec3(2.0f, 0.0f, 4.0f));  // metres over the ground per second, not up
    EXPECT_EQ(view::cursor_velocity(Vec3(0.0f), Vec3(1.0f, 0.0f, 0.0f), 0.5, 3.0f, 20.0f), Vec3(6.0f, 0.0f, 0.0f));
    const Vec3 fast = view::cursor_velocity(Vec3(0.0f), Vec3(30.0f, 0.0f, 40.0f), 1.0, 1.0f, 20.0f);
    EXPECT_NEAR(glm::length(fast), 20.0f, 1e-4f);  // capped
    EXPECT_NEAR(fast.x / fast.z, 0.75f, 1e-5f);    // in the drag's direction
    EXPECT_EQ(view::cursor_velocity(Vec3(0.0f), Vec3(1.0f), 0.0, 1.0f, 20.0f), Vec3(0.0f));  // no time: no throw
}

}  // namespace
}  // namespace mr
