// The viewer's mouse buttons frame by frame (apps/metariver/view_support.h, FrameButton),
// without a window: found by driving `metariver view` under Xvfb with xdotool, where a
// quick click with the drop-body tool dropped nothing and a right press after a fast
// cursor move panned the view by the whole move.
#include "view_support.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace mr::app
