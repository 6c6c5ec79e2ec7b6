// `metariver view`: the interactive viewer. This file checks the options, builds the
// scene, opens a GLFW window (OpenGL 4.5 core) with Dear ImGui and runs the Viewer
// (viewer.h: orbit / pan / zoom, pause / step / reset, every scene key editable live,
// pour, the terrain and water tools, a dropped heightmap, screenshots, Record, the stats
// overlay) one display frame at a time until the window closes.
#include "commands.h"
#include "driver.h"
#include "export_options.h"
#include "viewer.h"

#include <metariver/gl_context.h>
#include <metariver/io.h>
#include <metariver/render.h>

// libepoxy's GL header first; GLFW must not pull in its own.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <fmt/format.h>
#include <imgui.h>

#include <cmath>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <regex>

namespace mr::app {

namespace {

namespace fs = std::filesystem;

struct ViewOptions {
    SceneOptions scene;
    std::string size = "1280x720";
    std::string texture;
    std::string screenshot_dir = ".";
    std::string screenshot;      ///< written when the viewer closes (for scripts)
    long long frames = 0;        ///< close after this many display frames (0: when the window closes)
    double dt = 1.0 / 60.0;      ///< fixed simulation step, seconds
    bool vsync = true;
    bool paused = false;
    bool particles = false;
    bool foam = true;  ///< draw the diffuse particles (key O)
    std::optional<int> bvh_level;
    ExportOptions exp;    ///< Record (E): --export DIR (default metariver_export) --format ...
    bool record = false;  ///< --record: start recording at once
};

/// Frame numbers a recording may reach (its --range is checked against them).
constexpr long long kMaxRecordFrames = 1'000'000'000;

/// What the options say beyond the scene, checked: the window size and the texture.
struct ViewSetup {
    int width = 0, height = 0;
    std::optional<Image> texture;
};

/// Every option but the scene's and the recording's, checked into `setup` (bad input).
Status check_options(const ViewOptions& o, ViewSetup& setup) {
    const char* display = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    if ((!display || !*display) && (!wayland || !*wayland))
        return Error{"no display (DISPLAY and WAYLAND_DISPLAY are not set); render headless instead: "
                     "metariver render --out out/render (PNG frames) or --out river.mp4"};
    std::smatch m;
    int& width = setup.width;
    int& height = setup.height;
    if (!std::regex_match(o.size, m, std::regex("([0-9]{1,5})x([0-9]{1,5})")) ||
        (width = std::stoi(m[1].str())) < 64 || width > 8192 || (height = std::stoi(m[2].str())) < 64 || height > 8192)
        return Error{fmt::format("--size: expected WIDTHxHEIGHT with each in [64, 8192] (got '{}')", o.size)};
    if (auto e = dt_error(o.dt); !e.empty()) return Error{e};
    if (o.frames < 0) return Error{fmt::format("--frames: must be >= 0 (got {})", o.frames)};
    std::error_code ec;
    if (!fs::is_directory(o.screenshot_dir, ec))
        return Error{fmt::format("--screenshot-dir {}: not a folder", o.screenshot_dir)};
    if (!o.texture.empty()) {
        auto img = load_image(o.texture, 4);
        if (!img) return Error{"--texture " + img.error().message};
        setup.texture = std::move(img.value());
    }
    return Ok{};
}

/// The window with its OpenGL 4.5 core context and Dear ImGui on it; closed, with
/// ImGui and GLFW shut down, when it goes.
class GlWindow {
public:
    /// Opens the window; error (the display cannot be opened, or has no OpenGL 4.5
    /// core) with GLFW's message.
    static Result<std::unique_ptr<GlWindow>> open(int width, int height, const std::string& title, bool vsync) {
        static std::string glfw_error;
        glfwSetErrorCallback([](int, const char* msg) { glfw_error = msg ? msg : "unknown GLFW error"; });
        if (!glfwInit())
            return Error{fmt::format("cannot open the display ({}); render headless instead: metariver render",
                                     glfw_error)};
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        GLFWwindow* window = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (!window) {
            glfwTerminate();
            return Error{fmt::format("cannot create an OpenGL 4.5 core window ({}); render headless instead: "
                                     "metariver render", glfw_error)};
        }
        glfwMakeContextCurrent(window);
        glfwSwapInterval(vsync ? 1 : 0);
        return std::unique_ptr<GlWindow>(new GlWindow(window));
    }
    GlWindow(const GlWindow&) = delete;
    GlWindow& operator=(const GlWindow&) = delete;
    ~GlWindow() {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
        gl::keep_loaded_libraries_under_asan();  // LeakSanitizer names Mesa's libraries at exit
        glfwDestroyWindow(window_);
        glfwTerminate();
    }

    GLFWwindow* window() const { return window_; }
    Input& input() { return input_; }

private:
    explicit GlWindow(GLFWwindow* window) : window_(window) {
        install_input_callbacks(window_, input_);
        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        ImGuiIO& io = ImGui::GetIO();
        io.IniFilename = nullptr;  // no imgui.ini next to the user's files
        ImGui::StyleColorsDark();
        ImGui::GetStyle().WindowRounding = 4.0f;
        ImGui_ImplGlfw_InitForOpenGL(window_, true);
        ImGui_ImplOpenGL3_Init("#version 450 core");
    }

    GLFWwindow* window_;
    Input input_;
};

/// The Viewer over the driver's Simulation, one display frame at a time until the window
/// closes. Exit 1 when the renderer cannot be made.
int run_viewer(Driver& d, GlWindow& w, const ViewOptions& o, const ViewSetup& setup, const ExportDef& record) {
    auto renderer_result = render::Renderer::create();
    if (!renderer_result) return d.fail(kExitFailure, renderer_result.error().message);
    render::Renderer& renderer = *renderer_result.value();
    if (setup.texture) {
        const Image& t = *setup.texture;
        if (auto s = renderer.set_terrain_texture(t.pixels, t.width, t.height); !s)
            fmt::print(stderr, "metariver view: --texture {}: {} (drawing without it)\n", o.texture, s.error().message);
    }
    render::RenderSettings draw;
    draw.particles = o.particles;
    draw.foam = o.foam;
    draw.flow_detail = d.sim().def().render.flow_detail;
    if (o.bvh_level) {
        draw.bvh = true;
        draw.bvh_level = *o.bvh_level;
    }
    Viewer viewer(w.window(), w.input(), renderer, draw, d.take_simulation(), d.take_heightmap(), d.scene(), record,
                  ViewerSettings{.screenshot_dir = o.screenshot_dir,
                                 .screenshot = o.screenshot,
                                 .frames = o.frames,
                                 .dt = o.dt,
                                 .paused = o.paused,
                                 .record = o.record,
                                 .texture = setup.texture.has_value()});
    auto t_last = std::chrono::steady_clock::now();
    for (long long frame = 0; !glfwWindowShouldClose(w.window()); ++frame) {
        glfwPollEvents();
        const auto now = std::chrono::steady_clock::now();
        const double elapsed = std::chrono::duration<double>(now - t_last).count();
        t_last = now;
        viewer.frame(frame, elapsed);
    }
    viewer.finish();
    return kExitOk;
}

int view(const ViewOptions& o) {
    Driver d({.command = "view", .dt = o.dt});
    ViewSetup setup;
    if (auto s = check_options(o, setup); !s) return d.fail(kExitBadInput, s.error().message);
    // The scene as the user describes it (auto centre kept) is what the viewer edits.
    if (!d.resolve(o.scene)) return d.exit_code();
    // What Record writes: the export options, checked now; without --export, the folder
    // metariver_export (and the default format).
    ExportOptions exp = o.exp;
    if (!exp.enabled()) exp.dir = "metariver_export";
    auto record = d.export_def(exp, kMaxRecordFrames);
    if (!record) return d.fail(kExitBadInput, record.error().message);
    record->digits = 5;
    if (!d.load_heightmap() || !d.create()) return d.exit_code();
    auto window = GlWindow::open(setup.width, setup.height, fmt::format("metariver - {}", d.scene().name), o.vsync);
    if (!window) return d.fail(kExitBadInput, window.error().message);
    return run_viewer(d, *window.value(), o, setup, record.value());
}

}  // namespace

void register_view(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<ViewOptions>();
    CLI::App* cmd = app.add_subcommand("view", "interactive viewer (needs a display; see `render` for headless)");
    cmd->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    opts->scene.add_to(*cmd);
    cmd->add_option("--size", opts->size, "window size WIDTHxHEIGHT (default 1280x720)");
    cmd->add_option("--dt", opts->dt, "fixed simulation step in seconds (default 1/60)");
    cmd->add_option("--texture", opts->texture, "image draped over the terrain (PNG/JPEG)");
    cmd->add_option("--screenshot-dir", opts->screenshot_dir, "folder for screenshots (key P or F12) (default .)");
    cmd->add_option("--frames", opts->frames, "close after this many display frames (default: when the window closes)");
    cmd->add_option("--screenshot", opts->screenshot, "with --frames: write a screenshot of the last frame to this PNG");
    cmd->add_flag("!--no-vsync", opts->vsync, "do not wait for the display's refresh (measure fps)");
    cmd->add_flag("--paused", opts->paused, "start paused");
    cmd->add_flag("--particles", opts->particles, "debug: draw the particles as spheres");
    cmd->add_flag("!--no-foam", opts->foam, "start without drawing foam and spray (key O toggles; [foam] makes them)");
    cmd->add_option("--bvh", opts->bvh_level, "debug: draw the AABB tree's boxes at this depth (-1: the leaves)");
    opts->exp.add_to(*cmd);  // what Record (E) writes; frame numbers count from the start of a recording
    cmd->add_flag("--record", opts->record, "start recording (the export options) at once; it stops when the window closes");
    cmd->callback([opts, &action] { action = [opts] { return view(*opts); }; });
}

}  // namespace mr::app
