// The viewer's mouse buttons frame by frame (apps/metariver/view_support.h, FrameButton)
// and the source outlines (scene_markers), without a window: found by driving `metariver
// view` under Xvfb with xdotool, where a quick click with the drop-body tool dropped
// nothing, a right press after a fast cursor move panned the view by the whole move, and
// the default river's source was outlined on the terrain's corner, away from its water; and
// on a shallow-water scene the body, add-source and sink tools did nothing without a word,
// and move source left the grid's source where it was.
#include "view_support.h"
#include "view_tools.h"

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

/// The default valley with solver = "swe" (its river rule's source at the channel's head).
std::unique_ptr<Simulation> swe_valley() {
    SceneDef d = default_scene();
    d.solver = SolverKind::Swe;
    auto sim = Simulation::create(d);
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    return sim.ok() ? std::move(sim.value()) : nullptr;
}

/// One press of `tool` at `hit`, then the release: the error it gave.
std::string press(view::Tools& tools, Simulation& sim, view::Tools::Tool tool, const Vec3& hit,
                  std::optional<SceneDef>& edit) {
    tools.set_tool(tool);
    SceneDef def = sim.def();
    std::string error;
    tools.frame(sim, def, hit, true, 1.0 / 60.0, error, edit);
    tools.frame(sim, def, std::nullopt, false, 1.0 / 60.0, error, edit);
    return error;
}

TEST(ViewInput, ToolsTheGridsWaterCannotTakeSaySoAndDoNothing) {
    auto sim = swe_valley();
    ASSERT_TRUE(sim);
    const Vec3 hit = sim->terrain().bounds().center();
    view::Tools tools;
    using T = view::Tools;
    for (const auto& [tool, list] : {std::pair{T::AddSource, "[[particles.source]]"}, std::pair{T::AddSink, "[[sink.box]]"},
                                     std::pair{T::Remove, "[[sink.box]]"}}) {
        tools.set_tool(tool);
        const std::string why = tools.unavailable(*sim);
        EXPECT_NE(why.find("solver = \"swe\" reads no " + std::string(list) + "; "), std::string::npos) << why;
        std::optional<SceneDef> edit;
        EXPECT_EQ(press(tools, *sim, tool, hit, edit), why) << "a press says why";
        EXPECT_FALSE(edit) << why;
    }
    for (const T::Tool tool : {T::Pour, T::Raise, T::Flatten, T::Push, T::MoveSource, T::DropBody, T::RemoveBody}) {
        tools.set_tool(tool);
        EXPECT_EQ(tools.unavailable(*sim), "") << tool;
    }
    // Bodies float on the grid's water (rigid_bodies_grid.h): the drop tool drops one.
    {
        std::optional<SceneDef> edit;
        EXPECT_EQ(press(tools, *sim, T::DropBody, hit, edit), "");
        EXPECT_EQ(sim->bodies().size(), 1u);
    }
    // The same tool on the particle river drops its body.
    auto pbf = Simulation::create(default_scene());
    ASSERT_TRUE(pbf.ok()) << pbf.error().message;
    std::optional<SceneDef> edit;
    EXPECT_EQ(press(tools, *pbf.value(), T::DropBody, pbf.value()->terrain().bounds().center(), edit), "");
    EXPECT_EQ(pbf.value()->bodies().size(), 1u);
}

TEST(ViewInput, MoveSourceMovesTheGridsSource) {
    auto sim = swe_valley();
    ASSERT_TRUE(sim);
    const HeightfieldWater& w = *sim->heightfield();
    // A cell on the valley's side, away from the river: dry, then under the moved source.
    const int row = w.rows / 2, column = 4;
    const size_t k = size_t(row) * size_t(w.columns) + size_t(column);
    for (int f = 0; f < 30; ++f) sim->step(1.0f / 60.0f);
    ASSERT_EQ(w.depth[k], 0.0f);
    view::Tools tools;
    std::optional<SceneDef> edit;
    const Vec3 to{w.origin.x + float(column) * w.spacing, 0.0f, w.origin.z + float(row) * w.spacing};
    EXPECT_EQ(press(tools, *sim, view::Tools::MoveSource, to, edit), "");
    sim->step(1.0f / 60.0f);
    EXPECT_GT(w.depth[k], 0.0f) << "the grid's source pours at the new place";
}

}  // namespace
}  // namespace mr::app
