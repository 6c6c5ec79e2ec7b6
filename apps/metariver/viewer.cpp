// The viewer's frame (viewer.h): fixed-step simulation decoupled from the display rate,
// orbit / pan / zoom, pour, the tools, keys, a dropped heightmap, the panel (every scene
// key: scene_panel.cpp; an edit applied live where Simulation::apply can, else a rebuilt
// Simulation, the heightmap reloaded only when the terrain changed), the stats overlay,
// screenshots and Record.
#include "viewer.h"

#include "scene_panel.h"
#include "view_drop.h"

#include <metariver/io.h>

// libepoxy's GL header first; GLFW must not pull in its own.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <cmath>

namespace mr::app {

Viewer::Viewer(GLFWwindow* window, Input& input, render::Renderer& renderer, render::RenderSettings draw,
               std::unique_ptr<Simulation> sim, Heightmap map, SceneDef def, ExportDef record, ViewerSettings settings)
    : window_(window),
      input_(input),
      renderer_(renderer),
      draw_(draw),
      sim_(std::move(sim)),
      map_(std::move(map)),
      def_(std::move(def)),
      edit_(def_),
      record_def_(std::move(record)),
      settings_(std::move(settings)),
      paused_(settings_.paused),
      toggle_recording_(settings_.record),
      sim_dt_(static_cast<float>(settings_.dt)) {
    renderer_.set_scene(sim_->view());
    camera_ = render::frame_terrain(sim_->terrain());
}

// Applies `next` to the running Simulation (Simulation::apply: the water keeps flowing),
// or rebuilds it where the edit needs that (terrain and heightmap only if they changed).
bool Viewer::apply(const SceneDef& next, bool live_edit) {
    if (auto v = validate(next); !v) {
        error_ = v.error().message;
        return false;
    }
    if (live_edit) {
        auto live = sim_->apply(next);
        if (!live) {
            error_ = live.error().message;
            return false;
        }
        if (live->applied) {
            renderer_.set_scene(sim_->view(), false);
            def_ = next;
            error_.clear();
            return true;
        }
    }
    if (recording_.on()) status_ = recording_.stop();  // a new simulation: the recording ends
    const bool terrain_changed = terrain_key(next) != terrain_key(def_);
    Heightmap next_map;
    if (terrain_changed) {
        auto m = load_scene_heightmap(next);
        if (!m) {
            error_ = m.error().message;
            return false;
        }
        next_map = std::move(m.value());
    }
    auto s = Simulation::create(next, terrain_changed ? next_map : map_);
    if (!s) {
        error_ = s.error().message;
        return false;
    }
    if (terrain_changed) map_ = std::move(next_map);
    sim_ = std::move(s.value());
    tools_.forget();  // the terrain is built again from its heightmap
    renderer_.set_scene(sim_->view(), terrain_changed);
    if (terrain_changed) camera_ = render::frame_terrain(sim_->terrain());
    def_ = next;
    error_.clear();
    accumulator_ = 0.0;
    return true;
}

void Viewer::undo_stroke() {
    if (!tools_.undo(*sim_)) return;
    renderer_.update_terrain(sim_->view(), tools_.changed());
    status_ = fmt::format("undid a stroke ({} left)", tools_.undo_steps());
}

// Exports the step just taken (Record); an error ends the recording, on screen.
void Viewer::record_step() {
    if (std::string e = recording_.step(*sim_, sim_dt_); !e.empty()) {
        error_ = e;
        fmt::print(stderr, "metariver view: {}\n", e);
    }
}

void Viewer::toggle_recording() {
    toggle_recording_ = false;
    if (recording_.on()) {
        status_ = recording_.stop();
    } else {
        record_def_.solver_dt = sim_dt_;
        record_def_.frame_rate = 1.0 / double(sim_dt_);
        status_ = recording_.start(record_def_, *sim_);
    }
    fmt::print("{}\n", status_);
}

// Fixed simulation step: as many steps as the real time allows, at most max_steps per
// display frame (the rest is dropped, not queued).
void Viewer::simulate(double elapsed) {
    steps_this_frame_ = 0;
    if (!paused_) {
        accumulator_ += std::min(elapsed, 0.25);
        while (accumulator_ >= sim_dt_ && steps_this_frame_ < max_steps_) {
            sim_->step(sim_dt_);
            if (recording_.on()) record_step();
            accumulator_ -= sim_dt_;
            ++steps_this_frame_;
        }
        if (accumulator_ >= sim_dt_) {
            steps_dropped_ += static_cast<uint64_t>(accumulator_ / sim_dt_);
            accumulator_ = std::fmod(accumulator_, static_cast<double>(sim_dt_));
        }
    } else if (step_once_) {
        sim_->step(sim_dt_);
        if (recording_.on()) record_step();
        ++steps_this_frame_;
    }
    step_once_ = false;
    steps_total_ += static_cast<uint64_t>(steps_this_frame_);
}

// Orbit (left drag), pan (right/middle drag), zoom (wheel), pour (click), the tools.
void Viewer::mouse(double elapsed, int win_w, int win_h) {
    double mx = 0, my = 0;
    glfwGetCursorPos(window_, &mx, &my);
    if (!ImGui::GetIO().WantCaptureMouse) {
        // A left click between two frames counts as held for one (the tools see it).
        const bool left = left_.next(glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS,
                                     input_.left_presses > 0);
        right_.next(glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
                        glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS,
                    false);
        const float dx = static_cast<float>(mx - last_x_), dy = static_cast<float>(my - last_y_);
        if (left && !left_.dragging()) {  // the press
            dragged_ = false;
            press_x_ = mx;
            press_y_ = my;
        } else if (left_.dragging()) {
            if (std::abs(mx - press_x_) + std::abs(my - press_y_) > 4.0) dragged_ = true;
            if (dragged_ && !tools_.active()) camera_.orbit(-0.3f * dx, 0.3f * dy);
        }
        // A tool: every frame the left button is held, where the cursor meets the terrain.
        std::optional<Vec3> hit;
        if (tools_.active() && left && win_w > 0 && win_h > 0) {
            hit = render::pick_terrain(camera_, float(mx), float(my), win_w, win_h, sim_->terrain(), sim_->bvh());
            if (tools_.drops_bodies()) {  // on the water where the ray meets it before the ground
                const render::Ray ray = render::pixel_ray(camera_, float(mx), float(my), win_w, win_h);
                const Aabb& b = sim_->terrain().bounds();
                water_.update(*sim_);
                const auto d = view::drop_point(ray.origin, ray.direction, hit, &water_,
                                                glm::length(camera_.eye() - b.center()) + glm::length(b.extent()));
                hit = d ? std::optional<Vec3>(d->point) : std::nullopt;
            }
        }
        std::optional<SceneDef> tool_edit;
        if (tools_.frame(*sim_, def_, hit, left, elapsed, error_, tool_edit))
            renderer_.update_terrain(sim_->view(), tools_.changed());  // only the rows it touched
        if (tool_edit && apply(*tool_edit)) edit_ = def_;
        if (tools_.source_moved()) edit_.spawn = def_.spawn;  // the panel shows the new centre
        if (tools_.active()) input_.clicks.clear();           // a tool does not pour
        for (const auto& click : input_.clicks) {
            if (win_w <= 0 || win_h <= 0) break;
            if (auto at = render::pick_terrain(camera_, static_cast<float>(click[0]), static_cast<float>(click[1]), win_w,
                                               win_h, sim_->terrain(), sim_->bvh())) {
                sim_->pour(*at + Vec3(0.0f, pour_height_, 0.0f), pour_count_);
                status_ = fmt::format("poured {} at ({:.1f}, {:.1f}, {:.1f})", pour_count_, at->x, at->y, at->z);
                fmt::print("{}\n", status_);
            }
        }
        if (right_.dragging())  // not the motion before the press
            camera_.pan(dx / static_cast<float>(std::max(win_h, 1)), dy / static_cast<float>(std::max(win_h, 1)));
        if (input_.scroll != 0.0f) camera_.zoom(std::pow(0.88f, input_.scroll));
    } else {
        left_.release();
        right_.release();
    }
    input_.scroll = 0.0f;
    input_.clicks.clear();
    input_.left_presses = 0;
    last_x_ = mx;
    last_y_ = my;
}

void Viewer::keys() {
    if (!ImGui::GetIO().WantCaptureKeyboard) {
        for (int key : input_.keys) {
            switch (key) {
                case GLFW_KEY_SPACE: paused_ = !paused_; break;
                case GLFW_KEY_N:
                case GLFW_KEY_RIGHT:
                    paused_ = true;
                    step_once_ = true;
                    break;
                case GLFW_KEY_R: apply(def_, false); break;
                case GLFW_KEY_Z:
                    if (glfwGetKey(window_, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                        glfwGetKey(window_, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS)
                        undo_stroke();
                    break;
                case GLFW_KEY_F12:
                case GLFW_KEY_P: want_screenshot_ = true; break;
                case GLFW_KEY_E: toggle_recording_ = true; break;
                case GLFW_KEY_F: camera_ = render::frame_terrain(sim_->terrain()); break;
                case GLFW_KEY_G:
                    draw_.shading = draw_.shading == render::WaterShading::Gouraud ? render::WaterShading::Realistic
                                                                                   : render::WaterShading::Gouraud;
                    break;
                case GLFW_KEY_B: draw_.bvh = !draw_.bvh; break;
                case GLFW_KEY_V: draw_.particles = !draw_.particles; break;
                case GLFW_KEY_O: draw_.foam = !draw_.foam; break;
                case GLFW_KEY_L: draw_.flow_detail = !draw_.flow_detail; break;
                case GLFW_KEY_ESCAPE: glfwSetWindowShouldClose(window_, GLFW_TRUE); break;
                default: break;
            }
        }
    }
    input_.keys.clear();
}

// A heightmap dropped on the window replaces the terrain.
void Viewer::load_dropped() {
    if (input_.dropped.empty()) return;
    SceneDef next = def_;
    next.source.kind = TerrainSource::File;
    next.source.heightmap = input_.dropped.back();
    input_.dropped.clear();
    if (apply(next)) {
        edit_ = def_;
        status_ = "loaded " + next.source.heightmap;
    }
}

void Viewer::panel(int win_h) {
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(400, static_cast<float>(std::min(win_h - 16, 700))), ImGuiCond_FirstUseEver);
    ImGui::Begin("metariver");
    ImGui::PushItemWidth(-170.0f);  // room for the labels on the right
    if (ImGui::Button(paused_ ? "Run (space)" : "Pause (space)")) paused_ = !paused_;
    ImGui::SameLine();
    if (ImGui::Button("Step (N)")) {
        paused_ = true;
        step_once_ = true;
    }
    ImGui::SameLine();
    if (ImGui::Button("Reset (R)")) apply(def_, false);
    ImGui::SameLine();
    if (ImGui::Button("Shot (P)")) want_screenshot_ = true;
    if (ImGui::Button(recording_.on() ? "Stop recording (E)" : "Record (E)")) toggle_recording_ = true;
    ImGui::SameLine();
    if (recording_.on())
        ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "REC %zu frames -> %s", recording_.exporter->frames().size(),
                           record_def_.dir.c_str());
    else
        ImGui::TextDisabled("exports to %s", record_def_.dir.c_str());
    ImGui::DragFloat("sim step (s)", &sim_dt_, 0.0005f, 0.001f, 0.1f, "%.4f", ImGuiSliderFlags_AlwaysClamp);
    ImGui::DragInt("max steps/frame", &max_steps_, 0.1f, 1, 64, "%d", ImGuiSliderFlags_AlwaysClamp);
    ImGui::DragInt("pour count", &pour_count_, 0.5f, 1, 10000, "%d", ImGuiSliderFlags_AlwaysClamp);
    ImGui::DragFloat("pour height (m)", &pour_height_, 0.05f, 0.0f, 50.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
    tools_.ui(*sim_);
    if (ImGui::Button("Undo stroke (Ctrl+Z)")) undo_stroke();
    ImGui::SameLine();
    if (ImGui::Button("Save terrain")) {
        auto saved = save_terrain_and_scene(*sim_, def_, ".");
        (saved ? status_ : error_) = saved ? saved.value() : saved.error().message;
    }
    ImGui::SameLine();
    ImGui::TextDisabled("%zu strokes", tools_.undo_steps());
    ImGui::TextDisabled("click terrain: pour (tool pour) | drag: orbit or brush | right drag: pan | wheel: zoom");
    ImGui::TextDisabled("drop a PNG heightmap on the window to load it");
    if (ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) {
        ImGui::Checkbox("terrain", &draw_.terrain);
        ImGui::SameLine();
        ImGui::Checkbox("water", &draw_.water);
        ImGui::SameLine();
        ImGui::Checkbox("sky", &draw_.sky);
        ImGui::SameLine();
        ImGui::Checkbox("fog", &draw_.fog);
        int shading = draw_.shading == render::WaterShading::Gouraud ? 1 : 0;
        ImGui::RadioButton("realistic water", &shading, 0);
        ImGui::SameLine();
        ImGui::RadioButton("Gouraud (paper, G)", &shading, 1);
        draw_.shading = shading ? render::WaterShading::Gouraud : render::WaterShading::Realistic;
        ImGui::Checkbox("particles (V)", &draw_.particles);
        ImGui::SameLine();
        ImGui::DragFloat("##radius", &draw_.particle_radius, 0.01f, 0.02f, 5.0f, "r %.2f m");
        ImGui::Checkbox("foam and spray (O)", &draw_.foam);
        ImGui::SameLine();
        ImGui::Checkbox("flow detail (L)", &draw_.flow_detail);
        ImGui::Checkbox("sources and sinks", &show_markers_);
        ImGui::Checkbox("AABB tree (B)", &draw_.bvh);
        ImGui::SameLine();
        ImGui::SliderInt("depth##bvh", &draw_.bvh_level, -1, 16, draw_.bvh_level < 0 ? "leaves" : "%d");
        ImGui::ColorEdit3("deep water", &draw_.water_color.x, ImGuiColorEditFlags_NoInputs);
        ImGui::SameLine();
        ImGui::DragFloat("absorption", &draw_.water_absorption, 0.005f, 0.0f, 5.0f);
        ImGui::DragFloat3("sun", &draw_.sun_direction.x, 0.01f, -1.0f, 1.0f);
        if (settings_.texture) ImGui::Checkbox("terrain texture", &draw_.terrain_texture);
    }
    if (scene_editor(edit_)) {
        if (!apply(edit_)) { /* keep the edit on screen with its error */ }
    }
    if (!error_.empty()) ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.3f, 1.0f), "%s", error_.c_str());
    if (!status_.empty()) ImGui::TextWrapped("%s", status_.c_str());
    ImGui::PopItemWidth();
    ImGui::End();
}

void Viewer::overlay(int win_w) {
    double mean_ms = 0.0;
    for (double v : recent_ms_) mean_ms += v;
    mean_ms = recent_ms_.empty() ? 0.0 : mean_ms / static_cast<double>(recent_ms_.size());
    ImGui::SetNextWindowPos(ImVec2(static_cast<float>(win_w) - 8.0f, 8.0f), ImGuiCond_Always, ImVec2(1.0f, 0.0f));
    ImGui::SetNextWindowBgAlpha(0.55f);
    ImGui::Begin("stats", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoInputs |
                     ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav);
    const FrameTimings& t = sim_->last_timings();
    const SolverCounters& c = sim_->counters();
    const render::RenderStats& rs = renderer_.stats();
    ImGui::Text("%.1f fps  (%.2f ms/frame)%s", mean_ms > 0 ? 1000.0 / mean_ms : 0.0, mean_ms, paused_ ? "  PAUSED" : "");
    ImGui::Text("sim frame %llu, %d step(s) this frame, dropped %llu", static_cast<unsigned long long>(sim_->frame()),
                steps_this_frame_, static_cast<unsigned long long>(steps_dropped_));
    ImGui::Text("simulate %.2f ms  field %.2f ms  surface %.2f ms (smoothing %.2f)", t.simulate_ms, t.field_ms,
                t.surface_ms, t.smoothing_ms);
    ImGui::Text("particles %zu / %zu", sim_->particles().active_count(), sim_->particles().size());
    if (const FoamSystem* foam = sim_->foam()) {
        const FoamStats& fs = foam->stats();
        ImGui::Text("foam %zu  spray %zu  bubbles %zu  (%.2f ms)", fs.foam, fs.spray, fs.bubbles, t.foam_ms);
    }
    ImGui::Text("water %zu triangles, terrain %zu", sim_->surface().triangle_count(), rs.terrain_triangles);
    ImGui::Text("tunneled %llu  guarded %llu  respawned %llu  collisions %llu", static_cast<unsigned long long>(c.tunneled),
                static_cast<unsigned long long>(c.guarded), static_cast<unsigned long long>(c.respawned),
                static_cast<unsigned long long>(c.collisions));
    ImGui::Text("upload %.1f KB/frame, GL objects %llu", static_cast<double>(rs.last_upload_bytes) / 1024.0,
                static_cast<unsigned long long>(rs.gl_objects_created));
    ImGui::End();
}

void Viewer::markers(int win_w, int win_h) {
    if (!show_markers_ || win_w <= 0 || win_h <= 0) return;
    const glm::mat4 m = camera_.projection(float(win_w) / float(win_h)) * camera_.view();
    ImDrawList* dl = ImGui::GetBackgroundDrawList();
    auto project = [&](const Vec3& p, ImVec2& out) {
        const glm::vec4 c = m * glm::vec4(p, 1.0f);
        if (c.w <= 1e-4f) return false;  // behind the camera
        out = ImVec2((c.x / c.w * 0.5f + 0.5f) * float(win_w), (0.5f - c.y / c.w * 0.5f) * float(win_h));
        return true;
    };
    auto box = [&](const Vec3& lo, const Vec3& hi, ImU32 colour, const std::string& label) {
        ImVec2 q[8];
        for (int k = 0; k < 8; ++k)
            if (!project(Vec3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z), q[k])) return;
        constexpr int kEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3}, {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
        for (const auto& e : kEdges) dl->AddLine(q[e[0]], q[e[1]], colour, 2.0f);
        dl->AddText(q[6], colour, label.c_str());
    };
    for (const MarkerBox& b : scene_markers(*sim_)) {  // where the running scene has them
        const ImU32 colour = b.sink ? IM_COL32(255, 90, 70, 255)
                                    : b.number == 0 ? IM_COL32(80, 230, 255, 255) : IM_COL32(90, 140, 255, 255);
        const std::string name = b.sink ? "sink" : "source";
        box(b.lo, b.hi, colour, b.number == 0 ? name : fmt::format("{} {}", name, b.number));
    }
}

void Viewer::draw(int fb_w, int fb_h, bool last) {
    render::fit_clip_planes(camera_, sim_->terrain());
    renderer_.update(sim_->view());
    if (fb_w > 0 && fb_h > 0) {
        draw_.time_s = static_cast<float>(static_cast<double>(sim_->frame()) * sim_dt_);
        renderer_.draw(camera_, fb_w, fb_h, draw_);
        renderer_.present_to_default_framebuffer();
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fb_w, fb_h);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (want_screenshot_ || (last && !settings_.screenshot.empty())) {
        const std::string path =
            (last && !settings_.screenshot.empty()) ? settings_.screenshot : next_screenshot_path(settings_.screenshot_dir);
        if (auto s = screenshot(path, fb_w, fb_h); s) status_ = "screenshot: " + path;
        else status_ = s.error().message;
        fmt::print("{}\n", status_);
        want_screenshot_ = false;
    }
}

void Viewer::frame(long long n, double elapsed) {
    if (toggle_recording_) toggle_recording();  // before this frame's steps, so they are recorded
    if (n > 0) {
        frame_ms_.push_back(elapsed * 1000.0);
        recent_ms_.push_back(elapsed * 1000.0);
        if (recent_ms_.size() > 60) recent_ms_.pop_front();
    }
    simulate(elapsed);
    int fb_w = 0, fb_h = 0, win_w = 0, win_h = 0;
    glfwGetFramebufferSize(window_, &fb_w, &fb_h);
    glfwGetWindowSize(window_, &win_w, &win_h);
    mouse(elapsed, win_w, win_h);
    keys();
    load_dropped();

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    panel(win_h);
    overlay(win_w);
    markers(win_w, win_h);
    ImGui::Render();

    const bool last = settings_.frames > 0 && n + 1 >= settings_.frames;
    draw(fb_w, fb_h, last);
    glfwSwapBuffers(window_);
    if (last) glfwSetWindowShouldClose(window_, GLFW_TRUE);
}

void Viewer::finish() {
    if (recording_.on()) fmt::print("{}\n", recording_.stop());
    const Percentiles p = percentiles(frame_ms_);
    fmt::print("view: {} display frames, frame time median {:.2f} ms ({:.1f} fps), p95 {:.2f} ms; "
               "{} simulation steps of {:.4f} s; {}\n",
               frame_ms_.size() + 1, p.median, p.median > 0 ? 1000.0 / p.median : 0.0, p.p95, steps_total_, sim_dt_,
               renderer_.gl_description());
}

}  // namespace mr::app
