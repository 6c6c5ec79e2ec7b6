// `metariver view`: the interactive viewer. A GLFW window (OpenGL 4.5 core) with Dear
// ImGui: orbit / pan / zoom, pause / step / reset, every scene key the scene reads
// editable (scene_panel.cpp, listed from the table of scene keys; an edit is applied to
// the running Simulation where it can be (Simulation::apply: the water keeps flowing),
// else the Simulation is rebuilt from the edited SceneDef, the heightmap reloaded only
// when the terrain changed), click on the terrain to pour water, drop a heightmap file on
// the window to load it, a screenshot key, a Record button that exports the frames
// (docs/export.md), and a stats overlay. The simulation runs at a fixed time step,
// decoupled from the display rate.
#include "commands.h"
#include "export_options.h"
#include "scene_panel.h"
#include "view_support.h"
#include "view_tools.h"

#include <metariver/export.h>
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

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <memory>
#include <regex>
#include <vector>

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
            renderer.set_scene(sim->view());
            render::Camera camera = render::frame_terrain(sim->terrain());
            render::RenderSettings settings;
            settings.particles = o.particles;
            settings.foam = o.foam;
            settings.flow_detail = sim->def().render.flow_detail;
            if (o.bvh_level) {
                settings.bvh = true;
                settings.bvh_level = *o.bvh_level;
            }

            SceneDef edit = def;
            std::string status, error;
            bool paused = o.paused, step_once = false;
            float sim_dt = static_cast<float>(o.dt);
            int max_steps = 4;          // per display frame; beyond that the sim runs slow
            int pour_count = 20;
            float pour_height = 1.0f;
            view::Tools tools;  // the left button as a terrain brush or a hand on the water
            double accumulator = 0.0;
            uint64_t steps_total = 0, steps_dropped = 0;
            int steps_this_frame = 0;
            bool want_screenshot = false;
            Recording recording;
            bool toggle_recording = o.record;
            std::deque<double> recent_ms;   // for the fps readout
            std::vector<double> frame_ms;   // every frame, for the summary
            double press_x = 0, press_y = 0;
            bool left_down = false, dragged = false;
            double last_x = 0, last_y = 0;

            // Applies `next` to the running Simulation (Simulation::apply: the water keeps
            // flowing), or rebuilds it where the edit needs that (terrain and heightmap
            // only if they changed).
            auto apply = [&](const SceneDef& next, bool live_edit = true) -> bool {
                if (auto v = validate(next); !v) {
                    error = v.error().message;
                    return false;
                }
                if (live_edit) {
                    auto live = sim->apply(next);
                    if (!live) {
                        error = live.error().message;
                        return false;
                    }
                    if (live->applied) {
                        renderer.set_scene(sim->view(), false);
                        def = next;
                        error.clear();
                        return true;
                    }
                }
                if (recording.on()) status = recording.stop();  // a new simulation: the recording ends
                const bool terrain_changed = terrain_key(next) != terrain_key(def);
                Heightmap next_map;
                if (terrain_changed) {
                    auto m = load_scene_heightmap(next);
                    if (!m) {
                        error = m.error().message;
                        return false;
                    }
                    next_map = std::move(m.value());
                }
                auto s = Simulation::create(next, terrain_changed ? next_map : map);
                if (!s) {
                    error = s.error().message;
                    return false;
                }
                if (terrain_changed) map = std::move(next_map);
                sim = std::move(s.value());
                tools.forget();  // the terrain is built again from its heightmap
                renderer.set_scene(sim->view(), terrain_changed);
                if (terrain_changed) camera = render::frame_terrain(sim->terrain());
                def = next;
                error.clear();
                accumulator = 0.0;
                return true;
            };

            auto undo_stroke = [&] {
                if (!tools.undo(*sim)) return;
                renderer.update_terrain(sim->view(), tools.changed());
                status = fmt::format("undid a stroke ({} left)", tools.undo_steps());
            };

            // Exports the step just taken (Record); an error ends the recording, on screen.
            auto record_step = [&] {
                if (std::string e = recording.step(*sim, sim_dt); !e.empty()) {
                    error = e;
                    fmt::print(stderr, "metariver view: {}\n", e);
                }
            };

            auto t_last = std::chrono::steady_clock::now();
            for (long long frame = 0; !glfwWindowShouldClose(window); ++frame) {
                glfwPollEvents();
                if (toggle_recording) {  // before this frame's steps, so they are recorded
                    toggle_recording = false;
                    if (recording.on()) {
                        status = recording.stop();
                    } else {
                        record_def->solver_dt = sim_dt;
                        record_def->frame_rate = 1.0 / double(sim_dt);
                        status = recording.start(*record_def, *sim);
                    }
                    fmt::print("{}\n", status);
                }
                const auto now = std::chrono::steady_clock::now();
                const double elapsed = std::chrono::duration<double>(now - t_last).count();
                t_last = now;
                if (frame > 0) {
                    frame_ms.push_back(elapsed * 1000.0);
                    recent_ms.push_back(elapsed * 1000.0);
                    if (recent_ms.size() > 60) recent_ms.pop_front();
                }

                // Fixed simulation step: run as many steps as the real time allows, at
                // most max_steps per display frame (the rest is dropped, not queued).
                steps_this_frame = 0;
                if (!paused) {
                    accumulator += std::min(elapsed, 0.25);
                    while (accumulator >= sim_dt && steps_this_frame < max_steps) {
                        sim->step(sim_dt);
                        if (recording.on()) record_step();
                        accumulator -= sim_dt;
                        ++steps_this_frame;
                    }
                    if (accumulator >= sim_dt) {
                        steps_dropped += static_cast<uint64_t>(accumulator / sim_dt);
                        accumulator = std::fmod(accumulator, static_cast<double>(sim_dt));
                    }
                } else if (step_once) {
                    sim->step(sim_dt);
                    if (recording.on()) record_step();
                    ++steps_this_frame;
                }
                step_once = false;
                steps_total += static_cast<uint64_t>(steps_this_frame);

                int fb_w = 0, fb_h = 0, win_w = 0, win_h = 0;
                glfwGetFramebufferSize(window, &fb_w, &fb_h);
                glfwGetWindowSize(window, &win_w, &win_h);

                // ---- mouse: orbit (left drag), pan (right/middle drag), zoom (wheel), pour (click) ----
                double mx = 0, my = 0;
                glfwGetCursorPos(window, &mx, &my);
                if (!io.WantCaptureMouse) {
                    const bool left = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
                    const bool right = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
                                       glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
                    const float dx = static_cast<float>(mx - last_x), dy = static_cast<float>(my - last_y);
                    if (left && !left_down) {
                        left_down = true;
                        dragged = false;
                        press_x = mx;
                        press_y = my;
                    } else if (left && left_down) {
                        if (std::abs(mx - press_x) + std::abs(my - press_y) > 4.0) dragged = true;
                        if (dragged && !tools.active()) camera.orbit(-0.3f * dx, 0.3f * dy);
                    } else if (!left) {
                        left_down = false;
                    }
                    // A tool: every frame the left button is held, where the cursor meets the terrain.
                    std::optional<Vec3> hit;
                    if (tools.active() && left && win_w > 0 && win_h > 0)
                        hit = render::pick_terrain(camera, float(mx), float(my), win_w, win_h, sim->terrain(), sim->bvh());
                    std::optional<SceneDef> tool_edit;
                    if (tools.frame(*sim, def, hit, left, elapsed, error, tool_edit))
                        renderer.update_terrain(sim->view(), tools.changed());  // only the rows it touched
                    if (tool_edit && apply(*tool_edit)) edit = def;
                    if (tools.source_moved()) edit.spawn = def.spawn;  // the panel shows the new centre
                    if (tools.active()) input.clicks.clear();  // a tool does not pour
                    for (const auto& click : input.clicks) {
                        if (win_w <= 0 || win_h <= 0) break;
                        if (auto hit = render::pick_terrain(camera, static_cast<float>(click[0]), static_cast<float>(click[1]),
                                                            win_w, win_h, sim->terrain(), sim->bvh())) {
                            sim->pour(*hit + Vec3(0.0f, pour_height, 0.0f), pour_count);
                            status = fmt::format("poured {} at ({:.1f}, {:.1f}, {:.1f})", pour_count, hit->x, hit->y, hit->z);
                            fmt::print("{}\n", status);
                        }
                    }
                    if (right) camera.pan(dx / static_cast<float>(std::max(win_h, 1)), dy / static_cast<float>(std::max(win_h, 1)));
                    if (input.scroll != 0.0f) camera.zoom(std::pow(0.88f, input.scroll));
                } else {
                    left_down = false;
                }
                input.scroll = 0.0f;
                input.clicks.clear();
                last_x = mx;
                last_y = my;

                // ---- keys ----
                if (!io.WantCaptureKeyboard) {
                    for (int key : input.keys) {
                        switch (key) {
                            case GLFW_KEY_SPACE: paused = !paused; break;
                            case GLFW_KEY_N:
                            case GLFW_KEY_RIGHT:
                                paused = true;
                                step_once = true;
                                break;
                            case GLFW_KEY_R: apply(def, false); break;
                            case GLFW_KEY_Z:
                                if (glfwGetKey(window, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                                    glfwGetKey(window, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS)
                                    undo_stroke();
                                break;
                            case GLFW_KEY_F12:
                            case GLFW_KEY_P: want_screenshot = true; break;
                            case GLFW_KEY_E: toggle_recording = true; break;
                            case GLFW_KEY_F: camera = render::frame_terrain(sim->terrain()); break;
                            case GLFW_KEY_G:
                                settings.shading = settings.shading == render::WaterShading::Gouraud
                                                       ? render::WaterShading::Realistic
                                                       : render::WaterShading::Gouraud;
                                break;
                            case GLFW_KEY_B: settings.bvh = !settings.bvh; break;
                            case GLFW_KEY_V: settings.particles = !settings.particles; break;
                            case GLFW_KEY_O: settings.foam = !settings.foam; break;
                            case GLFW_KEY_L: settings.flow_detail = !settings.flow_detail; break;
                            case GLFW_KEY_ESCAPE: glfwSetWindowShouldClose(window, GLFW_TRUE); break;
                            default: break;
                        }
                    }
                }
                input.keys.clear();

                // ---- a dropped heightmap replaces the terrain ----
                if (!input.dropped.empty()) {
                    SceneDef next = def;
                    next.source.kind = TerrainSource::File;
                    next.source.heightmap = input.dropped.back();
                    input.dropped.clear();
                    if (apply(next)) {
                        edit = def;
                        status = "loaded " + next.source.heightmap;
                    }
                }

                // ---- UI ----
                ImGui_ImplOpenGL3_NewFrame();
                ImGui_ImplGlfw_NewFrame();
                ImGui::NewFrame();
                ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
                ImGui::SetNextWindowSize(ImVec2(400, static_cast<float>(std::min(win_h - 16, 700))), ImGuiCond_FirstUseEver);
                ImGui::Begin("metariver");
                ImGui::PushItemWidth(-170.0f);  // room for the labels on the right
                if (ImGui::Button(paused ? "Run (space)" : "Pause (space)")) paused = !paused;
                ImGui::SameLine();
                if (ImGui::Button("Step (N)")) {
                    paused = true;
                    step_once = true;
                }
                ImGui::SameLine();
                if (ImGui::Button("Reset (R)")) apply(def, false);
                ImGui::SameLine();
                if (ImGui::Button("Shot (P)")) want_screenshot = true;
                if (ImGui::Button(recording.on() ? "Stop recording (E)" : "Record (E)")) toggle_recording = true;
                ImGui::SameLine();
                if (recording.on())
                    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "REC %zu frames -> %s", recording.exporter->frames().size(),
                                       record_def->dir.c_str());
                else
                    ImGui::TextDisabled("exports to %s", record_def->dir.c_str());
                ImGui::DragFloat("sim step (s)", &sim_dt, 0.0005f, 0.001f, 0.1f, "%.4f", ImGuiSliderFlags_AlwaysClamp);
                ImGui::DragInt("max steps/frame", &max_steps, 0.1f, 1, 64, "%d", ImGuiSliderFlags_AlwaysClamp);
                ImGui::DragInt("pour count", &pour_count, 0.5f, 1, 10000, "%d", ImGuiSliderFlags_AlwaysClamp);
                ImGui::DragFloat("pour height (m)", &pour_height, 0.05f, 0.0f, 50.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
                tools.ui();
                if (ImGui::Button("Undo stroke (Ctrl+Z)")) undo_stroke();
                ImGui::SameLine();
                if (ImGui::Button("Save terrain")) {
                    auto saved = save_terrain_and_scene(*sim, def, ".");
                    (saved ? status : error) = saved ? saved.value() : saved.error().message;
                }
                ImGui::SameLine();
                ImGui::TextDisabled("%zu strokes", tools.undo_steps());
                ImGui::TextDisabled("click terrain: pour (tool pour) | drag: orbit or brush | right drag: pan | wheel: zoom");
                ImGui::TextDisabled("drop a PNG heightmap on the window to load it");
                if (ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) {
                    ImGui::Checkbox("terrain", &settings.terrain);
                    ImGui::SameLine();
                    ImGui::Checkbox("water", &settings.water);
                    ImGui::SameLine();
                    ImGui::Checkbox("sky", &settings.sky);
                    ImGui::SameLine();
                    ImGui::Checkbox("fog", &settings.fog);
                    int shading = settings.shading == render::WaterShading::Gouraud ? 1 : 0;
                    ImGui::RadioButton("realistic water", &shading, 0);
                    ImGui::SameLine();
                    ImGui::RadioButton("Gouraud (paper, G)", &shading, 1);
                    settings.shading = shading ? render::WaterShading::Gouraud : render::WaterShading::Realistic;
                    ImGui::Checkbox("particles (V)", &settings.particles);
                    ImGui::SameLine();
                    ImGui::DragFloat("##radius", &settings.particle_radius, 0.01f, 0.02f, 5.0f, "r %.2f m");
                    ImGui::Checkbox("foam and spray (O)", &settings.foam);
                    ImGui::SameLine();
                    ImGui::Checkbox("flow detail (L)", &settings.flow_detail);
                    ImGui::Checkbox("AABB tree (B)", &settings.bvh);
                    ImGui::SameLine();
                    ImGui::SliderInt("depth##bvh", &settings.bvh_level, -1, 16, settings.bvh_level < 0 ? "leaves" : "%d");
                    ImGui::ColorEdit3("deep water", &settings.water_color.x, ImGuiColorEditFlags_NoInputs);
                    ImGui::SameLine();
                    ImGui::DragFloat("absorption", &settings.water_absorption, 0.005f, 0.0f, 5.0f);
                    ImGui::DragFloat3("sun", &settings.sun_direction.x, 0.01f, -1.0f, 1.0f);
                    if (texture) ImGui::Checkbox("terrain texture", &settings.terrain_texture);
                }
                if (scene_editor(edit)) {
                    if (!apply(edit)) { /* keep the edit on screen with its error */ }
                }
                if (!error.empty()) ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.3f, 1.0f), "%s", error.c_str());
                if (!status.empty()) ImGui::TextWrapped("%s", status.c_str());
                ImGui::PopItemWidth();
                ImGui::End();

                // Stats overlay.
                double mean_ms = 0.0;
                for (double v : recent_ms) mean_ms += v;
                mean_ms = recent_ms.empty() ? 0.0 : mean_ms / static_cast<double>(recent_ms.size());
                ImGui::SetNextWindowPos(ImVec2(static_cast<float>(win_w) - 8.0f, 8.0f), ImGuiCond_Always, ImVec2(1.0f, 0.0f));
                ImGui::SetNextWindowBgAlpha(0.55f);
                ImGui::Begin("stats", nullptr,
                             ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoInputs |
                                 ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav);
                const FrameTimings& t = sim->last_timings();
                const SolverCounters& c = sim->counters();
                const render::RenderStats& rs = renderer.stats();
                ImGui::Text("%.1f fps  (%.2f ms/frame)%s", mean_ms > 0 ? 1000.0 / mean_ms : 0.0, mean_ms, paused ? "  PAUSED" : "");
                ImGui::Text("sim frame %llu, %d step(s) this frame, dropped %llu", static_cast<unsigned long long>(sim->frame()),
                            steps_this_frame, static_cast<unsigned long long>(steps_dropped));
                ImGui::Text("simulate %.2f ms  field %.2f ms  surface %.2f ms", t.simulate_ms, t.field_ms, t.surface_ms);
                ImGui::Text("particles %zu / %zu", sim->particles().active_count(), sim->particles().size());
                if (const FoamSystem* foam = sim->foam()) {
                    const FoamStats& fs = foam->stats();
                    ImGui::Text("foam %zu  spray %zu  bubbles %zu  (%.2f ms)", fs.foam, fs.spray, fs.bubbles, t.foam_ms);
                }
                ImGui::Text("water %zu triangles, terrain %zu", sim->surface().triangle_count(), rs.terrain_triangles);
                ImGui::Text("tunneled %llu  guarded %llu  respawned %llu  collisions %llu",
                            static_cast<unsigned long long>(c.tunneled), static_cast<unsigned long long>(c.guarded),
                            static_cast<unsigned long long>(c.respawned), static_cast<unsigned long long>(c.collisions));
                ImGui::Text("upload %.1f KB/frame, GL objects %llu", static_cast<double>(rs.last_upload_bytes) / 1024.0,
                            static_cast<unsigned long long>(rs.gl_objects_created));
                ImGui::End();
                ImGui::Render();

                // ---- draw ----
                render::fit_clip_planes(camera, sim->terrain());
                renderer.update(sim->view());
                if (fb_w > 0 && fb_h > 0) {
                    settings.time_s = static_cast<float>(static_cast<double>(sim->frame()) * sim_dt);
                    renderer.draw(camera, fb_w, fb_h, settings);
                    renderer.present_to_default_framebuffer();
                }
                glBindFramebuffer(GL_FRAMEBUFFER, 0);
                glViewport(0, 0, fb_w, fb_h);
                ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
                const bool last = o.frames > 0 && frame + 1 >= o.frames;
                if (want_screenshot || (last && !o.screenshot.empty())) {
                    const std::string path = (last && !o.screenshot.empty()) ? o.screenshot : next_screenshot_path(o.screenshot_dir);
                    if (auto s = screenshot(path, fb_w, fb_h); s) status = "screenshot: " + path;
                    else status = s.error().message;
                    fmt::print("{}\n", status);
                    want_screenshot = false;
                }
                glfwSwapBuffers(window);
                if (last) glfwSetWindowShouldClose(window, GLFW_TRUE);
            }
            if (recording.on()) fmt::print("{}\n", recording.stop());
            const Percentiles p = percentiles(frame_ms);
            fmt::print("view: {} display frames, frame time median {:.2f} ms ({:.1f} fps), p95 {:.2f} ms; "
                       "{} simulation steps of {:.4f} s; {}\n",
                       frame_ms.size() + 1, p.median, p.median > 0 ? 1000.0 / p.median : 0.0, p.p95, steps_total, sim_dt,
                       renderer.gl_description());
        }
    }
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    render::keep_loaded_libraries_under_asan();  // LeakSanitizer names Mesa's libraries at exit
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
