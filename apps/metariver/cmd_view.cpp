// `metariver view`: the interactive viewer. This file checks the options, builds the
// scene, opens a GLFW window (OpenGL 4.5 core) with Dear ImGui and runs the Viewer
// (viewer.h: orbit / pan / zoom, pause / step / reset, every scene key editable live,
// pour, the terrain and water tools, a dropped heightmap, screenshots, Record, the stats
// overlay) one display frame at a time until the window closes.
#include "commands.h"
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

int fail(int code, const std::string& message) {
    fmt::print(stderr, "metariver view: {}\n", message);
    return code;
}

int view(const ViewOptions& o) {
    const char* display = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    if ((!display || !*display) && (!wayland || !*wayland))
        return fail(kExitBadInput, "no display (DISPLAY and WAYLAND_DISPLAY are not set); render headless instead: "
                                   "metariver render --out out/render (PNG frames) or --out river.mp4");
    int width = 0, height = 0;
    {
        std::smatch m;
        if (!std::regex_match(o.size, m, std::regex("([0-9]{1,5})x([0-9]{1,5})")) ||
            (width = std::stoi(m[1].str())) < 64 || width > 8192 || (height = std::stoi(m[2].str())) < 64 || height > 8192)
            return fail(kExitBadInput, fmt::format("--size: expected WIDTHxHEIGHT with each in [64, 8192] (got '{}')", o.size));
    }
    if (!std::isfinite(o.dt) || o.dt <= 0.0 || o.dt > 1.0)
        return fail(kExitBadInput, fmt::format("--dt: must be in (0, 1] seconds (got {})", o.dt));
    if (o.frames < 0) return fail(kExitBadInput, fmt::format("--frames: must be >= 0 (got {})", o.frames));
    std::error_code ec;
    if (!fs::is_directory(o.screenshot_dir, ec))
        return fail(kExitBadInput, fmt::format("--screenshot-dir {}: not a folder", o.screenshot_dir));
    std::optional<Image> texture;
    if (!o.texture.empty()) {
        auto img = load_image(o.texture, 4);
        if (!img) return fail(kExitBadInput, "--texture " + img.error().message);
        texture = std::move(img.value());
    }
    auto resolved = o.scene.resolve();
    if (!resolved) return fail(kExitBadInput, resolved.error().message);
    SceneDef def = resolved.value();  // the scene as the user describes it (auto centre kept)
    // What Record writes: the export options, checked now; without --export, the folder
    // metariver_export (and the default format).
    ExportOptions exp = o.exp;
    if (!exp.enabled()) exp.dir = "metariver_export";
    auto record_def = exp.resolve(kMaxRecordFrames, def);
    if (!record_def) return fail(kExitBadInput, record_def.error().message);
    record_def->frame_rate = 1.0 / o.dt;
    record_def->solver_dt = o.dt;
    record_def->digits = 5;
    auto map_result = load_scene_heightmap(def);
    if (!map_result) return fail(kExitBadInput, map_result.error().message);
    Heightmap map = std::move(map_result.value());
    auto sim_result = Simulation::create(def, map);
    if (!sim_result) return fail(kExitBadInput, sim_result.error().message);
    std::unique_ptr<Simulation> sim = std::move(sim_result.value());

    static std::string glfw_error;
    glfwSetErrorCallback([](int, const char* msg) { glfw_error = msg ? msg : "unknown GLFW error"; });
    if (!glfwInit())
        return fail(kExitBadInput, fmt::format("cannot open the display ({}); render headless instead: metariver render",
                                               glfw_error));
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    const std::string title = fmt::format("metariver - {}", def.name);
    GLFWwindow* window = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!window) {
        glfwTerminate();
        return fail(kExitBadInput, fmt::format("cannot create an OpenGL 4.5 core window ({}); render headless instead: "
                                               "metariver render", glfw_error));
    }
    glfwMakeContextCurrent(window);
    glfwSwapInterval(o.vsync ? 1 : 0);

    Input input;
    install_input_callbacks(window, input);

    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;  // no imgui.ini next to the user's files
    ImGui::StyleColorsDark();
    ImGui::GetStyle().WindowRounding = 4.0f;
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 450 core");

    int code = kExitOk;
    {
        auto renderer_result = render::Renderer::create();
        if (!renderer_result) {
            code = fail(kExitFailure, renderer_result.error().message);
        } else {
            render::Renderer& renderer = *renderer_result.value();
            if (texture) {
                if (auto s = renderer.set_terrain_texture(texture->pixels, texture->width, texture->height); !s)
                    fmt::print(stderr, "metariver view: --texture {}: {} (drawing without it)\n", o.texture,
                               s.error().message);
            }
            render::RenderSettings draw;
            draw.particles = o.particles;
            draw.foam = o.foam;
            draw.flow_detail = sim->def().render.flow_detail;
            if (o.bvh_level) {
                draw.bvh = true;
                draw.bvh_level = *o.bvh_level;
            }
            Viewer viewer(window, input, renderer, draw, std::move(sim), std::move(map), def, *record_def,
                          ViewerSettings{.screenshot_dir = o.screenshot_dir,
                                         .screenshot = o.screenshot,
                                         .frames = o.frames,
                                         .dt = o.dt,
                                         .paused = o.paused,
                                         .record = o.record,
                                         .texture = texture.has_value()});
            auto t_last = std::chrono::steady_clock::now();
            for (long long frame = 0; !glfwWindowShouldClose(window); ++frame) {
                glfwPollEvents();
                const auto now = std::chrono::steady_clock::now();
                const double elapsed = std::chrono::duration<double>(now - t_last).count();
                t_last = now;
                viewer.frame(frame, elapsed);
            }
            viewer.finish();
        }
    }
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    gl::keep_loaded_libraries_under_asan();  // LeakSanitizer names Mesa's libraries at exit
    glfwDestroyWindow(window);
    glfwTerminate();
    return code;
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
