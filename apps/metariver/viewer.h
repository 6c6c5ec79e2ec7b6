// The interactive viewer as a class (issue 14: the app is thin): one display frame at a
// time over a running Simulation, with its parts — the camera, the fixed-step clock, the
// tools (view_tools.h), the recording (view_support.h), the panel and the stats overlay.
// cmd_view.cpp parses the options, opens the window and the GL/ImGui context, and runs
// frame() until the window closes.
#pragma once

#include "view_support.h"
#include "view_tools.h"

#include <metariver/export.h>
#include <metariver/render.h>
#include <metariver/scene.h>
#include <metariver/water_query.h>

#include <deque>
#include <memory>
#include <string>
#include <vector>

struct GLFWwindow;

namespace mr::app {

/// What the viewer needs of its command line (cmd_view.cpp fills and checks it).
struct ViewerSettings {
    std::string screenshot_dir = ".";
    std::string screenshot;  ///< written at the last frame (with frames > 0)
    long long frames = 0;    ///< close after this many display frames (0: when the window closes)
    double dt = 1.0 / 60.0;  ///< fixed simulation step, seconds
    bool paused = false;
    bool record = false;     ///< start recording at once
    bool texture = false;    ///< a terrain texture was uploaded (the panel offers it)
};

class Viewer {
public:
    /// `map`: the heightmap `sim` was built from (kept: an edit that leaves the terrain
    /// alone rebuilds on it); `def`: the scene as the user describes it; `record`: what
    /// Record writes. The renderer and window outlive the viewer.
    Viewer(GLFWwindow* window, Input& input, render::Renderer& renderer, render::RenderSettings draw,
           std::unique_ptr<Simulation> sim, Heightmap map, SceneDef def, ExportDef record, ViewerSettings settings);
    Viewer(const Viewer&) = delete;
    Viewer& operator=(const Viewer&) = delete;

    /// One display frame `n` (input, simulation steps, panel, draw, screenshot) after
    /// `elapsed` seconds of real time; asks the window to close after the last one.
    void frame(long long n, double elapsed);
    /// Ends a recording and prints the frame-time summary.
    void finish();

private:
    bool apply(const SceneDef& next, bool live_edit = true);
    void undo_stroke();
    void record_step();
    void toggle_recording();
    void simulate(double elapsed);
    void mouse(double elapsed, int win_w, int win_h);
    void keys();
    void load_dropped();
    void panel(int win_h);
    void overlay(int win_w);
    /// Outlines of the sources (cyan: the main one, blue: the added ones) and the sink
    /// boxes (red), numbered as the scene's lists are, over the 3D view.
    void markers(int win_w, int win_h);
    void draw(int fb_w, int fb_h, bool last);

    GLFWwindow* window_;
    Input& input_;
    render::Renderer& renderer_;
    render::RenderSettings draw_;
    render::Camera camera_;
    std::unique_ptr<Simulation> sim_;
    Heightmap map_;
    SceneDef def_;   ///< the running scene as the user describes it
    SceneDef edit_;  ///< the panel's copy
    ExportDef record_def_;
    ViewerSettings settings_;
    WaterQuery water_;   ///< the drop body tool's water (updated while it drags)
    view::Tools tools_;  ///< the left button as a terrain brush or a hand on the water
    Recording recording_;

    std::string status_, error_;
    bool paused_ = false, step_once_ = false, want_screenshot_ = false, toggle_recording_ = false;
    float sim_dt_;
    int max_steps_ = 4;  ///< per display frame; beyond that the sim runs slow
    int pour_count_ = 20;
    float pour_height_ = 1.0f;
    double accumulator_ = 0.0;
    uint64_t steps_total_ = 0, steps_dropped_ = 0;
    int steps_this_frame_ = 0;
    std::deque<double> recent_ms_;  ///< for the fps readout
    std::vector<double> frame_ms_;  ///< every frame, for the summary
    double press_x_ = 0, press_y_ = 0, last_x_ = 0, last_y_ = 0;
    FrameButton left_, right_;  ///< right: the right or middle button (pan)
    bool dragged_ = false;
    bool show_markers_ = true;
};

}  // namespace mr::app
