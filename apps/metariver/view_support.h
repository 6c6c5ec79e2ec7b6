// The viewer's parts outside its loop: recording, input queued from GLFW's callbacks,
// the back buffer to PNG (cmd_view.cpp).
#pragma once

#include <metariver/export.h>
#include <metariver/scene.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

struct GLFWwindow;

namespace mr::app {

/// A recording in the viewer: an export session fed every simulation step while it runs,
/// frame numbers counted from its start.
struct Recording {
    std::unique_ptr<Exporter> exporter;
    long long next_frame = 0;

    bool on() const { return exporter != nullptr; }
    /// Starts an export session (folder, terrain); the message says what happened.
    std::string start(const ExportDef& def, const Simulation& sim);
    /// Writes the step just taken when it is due; an error ends the recording (its files go).
    std::string step(const Simulation& sim, double dt);
    /// Writes the manifest; the files stay.
    std::string stop();
};

/// State shared with GLFW's callbacks (through the window's user pointer).
/// Events are queued by callbacks, not read from the button/key state once per frame:
/// at a few frames per second a click (press and release) fits between two frames.
struct Input {
    float scroll = 0.0f;
    std::vector<std::string> dropped;
    std::vector<int> keys;           ///< keys pressed since the last frame
    double press_x = 0.0, press_y = 0.0;
    std::vector<std::array<double, 2>> clicks;  ///< left press+release without moving, window coordinates
    int left_presses = 0;  ///< left presses since the last frame (a click between frames is one)
};

/// One mouse button as the viewer's frames see it. GLFW's polled state misses a click that
/// fits between two frames (at a few frames per second a quick click does), and the
/// cursor's motion since the last frame is a drag only when the button was held then too:
/// the motion before a press is not (it panned the view by the whole jump).
class FrameButton {
public:
    /// The next frame: `down` the polled state, `pressed` whether a press was queued since
    /// the last frame. Returns whether the button counts as held this frame.
    bool next(bool down, bool pressed) {
        was_ = now_;
        now_ = down || pressed;
        return now_;
    }
    bool held() const { return now_; }
    /// Held this frame and the one before: the cursor's motion between them is a drag.
    bool dragging() const { return now_ && was_; }
    /// The UI took the mouse: not held.
    void release() { now_ = was_ = false; }

private:
    bool now_ = false, was_ = false;
};

/// A box the viewer outlines over the scene: a source or a sink box, in metres.
struct MarkerBox {
    Vec3 lo{0.0f}, hi{0.0f};
    bool sink = false;
    int number = 0;  ///< 0: the main source / sink; k: the scene's k-th extra one
};
/// The sources and sink boxes of the running scene, where they are: from sim.def() (the
/// automatic centre resolved, a moved source where it went), not the scene as requested
/// (whose "channel" or "auto" centre is the unresolved (0, 0, 0): the outline sat on the
/// terrain's corner). At least 0.2 m each way, as the emitters read the size.
std::vector<MarkerBox> scene_markers(const Simulation& sim);

/// Points the window's user pointer at `input` and installs the callbacks that fill it
/// (before ImGui's backend, which chains to them).
void install_input_callbacks(GLFWwindow* window, Input& input);

/// What decides whether a scene edit needs the terrain (and tree) rebuilt and uploaded.
std::string terrain_key(const SceneDef& d);

/// The first metariver_screenshot_NNN.png in `dir` that does not exist yet.
std::string next_screenshot_path(const std::string& dir);

/// Reads the window's back buffer (scene and UI) and writes it as a PNG.
Status screenshot(const std::string& path, int width, int height);

/// Saves the running terrain (sculpted, carved) as DIR/metariver_terrain_NNN.png with its
/// sidecar (write_terrain_heightmap) and the scene that loads it back as
/// DIR/metariver_scene_NNN.toml (the heightmap at its saved scale, condition "none": the
/// channel is in the heights already). Returns what it wrote, one line.
Result<std::string> save_terrain_and_scene(const Simulation& sim, const SceneDef& def, const std::string& dir);

}  // namespace mr::app
