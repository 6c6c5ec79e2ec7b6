// The viewer's mouse buttons frame by frame (apps/metariver/view_support.h, FrameButton)
// and the source outlines (scene_markers), without a window: found by driving `metariver
// view` under Xvfb with xdotool, where a quick click with the drop-body tool dropped
// nothing, a right press after a fast cursor move panned the view by the whole move, and
// the default river's source was outlined on the terrain's corner, away from its water.
#include "view_support.h"

#include <metariver/scene.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

namespace mr::app {
namespace {

TEST(ViewInput, AClickBetweenTwoFramesIsHeldForOneFrame) {
    FrameButton b;
    EXPECT_FALSE(b.next(false, false));
    // Pressed and released between frames: the polled state says up, the queue a press.
    EXPECT_TRUE(b.next(false, true)) << "the tools see the click";
    EXPECT_FALSE(b.dragging()) << "a press, not a drag";
    EXPECT_FALSE(b.next(false, false)) << "released the next frame";
    EXPECT_FALSE(b.dragging());
}

TEST(ViewInput, TheMotionBeforeAPressIsNoDrag) {
    FrameButton b;
    b.next(false, false);
    b.next(true, false);  // the frame of the press: the cursor may have jumped since the last frame
    EXPECT_TRUE(b.held());
    EXPECT_FALSE(b.dragging()) << "no pan by the motion before the press";
    b.next(true, false);
    EXPECT_TRUE(b.dragging()) << "held over two frames: the motion between them drags";
    b.release();  // the UI took the mouse
    EXPECT_FALSE(b.held());
    b.next(true, false);
    EXPECT_FALSE(b.dragging()) << "back from the UI: a new press";
}

TEST(ViewInput, TheSourceIsOutlinedWhereTheRunningSceneHasIt) {
    auto sim = Simulation::create(default_scene());  // spawn_center = "channel": resolved at create
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    const auto outline = [&] {
        const std::vector<MarkerBox> m = scene_markers(s);
        EXPECT_FALSE(m.empty());
        EXPECT_FALSE(m.front().sink);
        return (m.front().lo + m.front().hi) * 0.5f;
    };
    EXPECT_EQ(outline(), s.def().spawn.center);
    EXPECT_NE(s.requested().spawn.center, s.def().spawn.center) << "the requested centre is unresolved";
    // Over the main channel's head, where the water starts (not the terrain's corner).
    const auto [i, j] = s.main_channel().front();
    const float as = s.terrain().area_scale();
    const Vec3 c = outline();
    EXPECT_LT(glm::length(glm::vec2(c.x - float(j) * as, c.z - float(i) * as)), 4.0f * as) << c.x << " " << c.z;
    // A moved source is outlined where it went.
    const Vec3 to = c + Vec3(3.0f, 0.0f, 3.0f);
    ASSERT_TRUE(s.move_source(to).ok());
    EXPECT_EQ(outline(), to);
}

}  // namespace
}  // namespace mr::app
