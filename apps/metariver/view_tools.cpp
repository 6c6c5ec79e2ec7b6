#include "view_tools.h"

#include "view_drop.h"

#include <metariver/scene_keys.h>

#include <imgui.h>

#include <glm/geometric.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace mr::view {

namespace {
constexpr size_t kMostUndo = 200;       ///< drags kept for undo; the oldest go first
constexpr float kMostPushSpeed = 10.0f;  ///< m/s a push gives the water at most
constexpr float kMostThrowSpeed = 20.0f;  ///< m/s a throw gives a body at most

/// The scene list `name` ([[particles.source]], [[sink.box]], [[bodies]]).
const SceneList& scene_list(std::string_view name) {
    for (const SceneList& l : scene_lists())
        if (l.name == name) return l;
    return scene_lists().front();  // (every name asked for is in the table)
}

constexpr const char* kToolNames[] = {"pour",        "raise",      "lower",      "smooth",
                                      "flatten",     "push water", "move source", "add source",
                                      "add sink box", "remove source / sink", "drop / throw body", "remove body"};

}  // namespace

std::string Tools::unavailable(const Simulation& sim) const {
    const SceneDef& d = sim.def();
    const std::string_view solver = sim.solver_entry().kind.name;
    const char* name = kToolNames[tool_];
    const bool grid = sim.grid() != nullptr;
    // The grid's solvers read none of the particle lists (the key table's readers say only
    // that Bullet reads no [[sink.box]] and the hybrid no [[particles.source]]).
    const auto list = [&](std::string_view list_name, std::string_view instead) -> std::string {
        const SceneList& l = scene_list(list_name);
        if (l.readers(d) && !grid) return "";
        return fmt::format("{}: solver = \"{}\" reads no [[{}]]{}", name, solver, l.name,
                           grid ? instead : fmt::format(" (read by {})", l.readers.text));
    };
    switch (tool_) {
        case Raise: case Lower: case Smooth: case Flatten:
            if (!sim.solver_entry().no_sculpt.empty()) return fmt::format("{}: solver = \"{}\" {}", name, solver, sim.solver_entry().no_sculpt);
            return "";
        case Push:
            if (!sim.solver_entry().no_push.empty()) return fmt::format("{}: solver = \"{}\" {}", name, solver, sim.solver_entry().no_push);
            return "";
        case MoveSource:
            if (grid && !d.swe.auto_source)
                return fmt::format("{}: swe.source_center is set ({:.1f}, {:.1f}); the grid's source stays there (edit "
                                   "it in the panel's [swe])", name, d.swe.source_center.x, d.swe.source_center.z);
            return "";
        case AddSource: return list("particles.source", "; the grid's sources are [[swe.sources]] in the panel's [swe]");
        case AddSink: case Remove: return list("sink.box", "; the grid's sinks are [[swe.sinks]] in the panel's [swe]");
        case DropBody: case RemoveBody:  // the grid's water floats them too (swe, hybrid)
            return scene_list("bodies").readers(d) ? "" : list("bodies", "");
        default: return "";
    }
}

bool Tools::frame(Simulation& sim, SceneDef& def, const std::optional<Vec3>& hit, bool left, double frame_s,
                  std::string& error, std::optional<SceneDef>& edit) {
    bool changed = false;
    source_moved_ = false;
    if (!active() || !left) {
        if (dragging_ && !undo_.empty() && undo_.back().empty()) undo_.pop_back();
        if (undo_.size() > kMostUndo) undo_.erase(undo_.begin());
        dragging_ = false;
        last_hit_.reset();
        grabbed_.reset();  // a carried body goes on with its last velocity
        return false;
    }
    if (!hit) return false;
    if (const std::string why = unavailable(sim); !why.empty()) {  // said once per press, nothing done
        if (!dragging_) error = why;
        dragging_ = true;
        return false;
    }
    if (tool_ == DropBody) {
        drag_body(sim, *hit, frame_s, error);
        return false;
    }
    if (tool_ == RemoveBody) {  // once per press
        if (!dragging_) remove_body(sim, *hit, error);
        dragging_ = true;
        return false;
    }
    if (tool_ >= MoveSource) {  // once per press
        if (dragging_) return false;
        dragging_ = true;
        if (tool_ == MoveSource) {
            const Vec3 c = *hit + Vec3(0.0f, def.spawn.half_extent.y + def.spawn.auto_height, 0.0f);
            if (auto m = sim.move_source(c); !m) {
                error = m.error().message;
            } else {
                def.spawn.center = c;
                def.spawn.auto_center = def.spawn.auto_channel = false;
                source_moved_ = true;
            }
        } else {
            edit = click_edit(def, *hit, error);
        }
        return false;
    }
    if (!dragging_) {
        dragging_ = true;
        target_ = hit->y;
        if (tool_ != Push) undo_.emplace_back();
    }
    if (tool_ == Push) {
        // The water under the cursor takes the cursor's velocity over the ground.
        if (last_hit_ && frame_s > 0.0) {
            const Vec3 v = cursor_velocity(*last_hit_, *hit, frame_s, push_gain_, kMostPushSpeed);
            if (auto p = sim.push(*hit, radius_, v); !p) error = p.error().message;
        }
        last_hit_ = hit;
        return false;
    }
    constexpr BrushMode kModes[] = {BrushMode::Raise, BrushMode::Raise, BrushMode::Lower, BrushMode::Smooth,
                                    BrushMode::Flatten};
    const Brush b{.x = hit->x, .z = hit->z, .radius = radius_, .strength = strength_, .mode = kModes[tool_],
                  .target = target_};
    if (auto e = sim.sculpt(b); !e) {
        error = e.error().message;
    } else if (!e->empty()) {
        changed_ = TerrainEdit{.i0 = e->i0, .j0 = e->j0, .i1 = e->i1, .j1 = e->j1, .before = {}};
        undo_.back().push_back(std::move(e.value()));
        changed = true;
    }
    return changed;
}

std::optional<SceneDef> Tools::click_edit(const SceneDef& def, const Vec3& hit, std::string& error) const {
    SceneDef next = def;
    if (tool_ == AddSource) {
        if (next.spawn.sources.size() >= kMaxMoreSources) {
            error = fmt::format("particles.source: at most {} more sources; remove one first", kMaxMoreSources);
            return std::nullopt;
        }
        // The main source's size and height over the ground, at the tool's rate.
        next.spawn.sources.push_back(SourceDef{.center = hit + Vec3(0.0f, def.spawn.half_extent.y + def.spawn.auto_height, 0.0f),
                                               .half_extent = def.spawn.half_extent,
                                               .flow_rate = source_rate_});
    } else if (tool_ == AddSink) {
        if (next.sink.boxes.size() >= kMaxMoreSinks) {
            error = fmt::format("sink.box: at most {} more sink boxes; remove one first", kMaxMoreSinks);
            return std::nullopt;
        }
        next.sink.boxes.push_back(SinkBox{hit - Vec3(radius_), hit + Vec3(radius_)});
    } else {  // Remove: the added source or sink box nearest the click (x, z), within the radius
        float best = radius_;
        int source = -1, box = -1;
        auto consider = [&](const Vec3& c, int s, int b) {
            const float d = std::hypot(c.x - hit.x, c.z - hit.z);
            if (d <= best) best = d, source = s, box = b;
        };
        for (size_t k = 0; k < def.spawn.sources.size(); ++k) consider(def.spawn.sources[k].center, int(k), -1);
        for (size_t k = 0; k < def.sink.boxes.size(); ++k)
            consider(0.5f * (def.sink.boxes[k].min + def.sink.boxes[k].max), -1, int(k));
        if (source >= 0) next.spawn.sources.erase(next.spawn.sources.begin() + source);
        else if (box >= 0) next.sink.boxes.erase(next.sink.boxes.begin() + box);
        else {
            error = fmt::format("remove: no added source or sink box within {:.1f} m of the click (the main source "
                                "is moved, or turned off with its flow rate)",
                                radius_);
            return std::nullopt;
        }
    }
    return next;
}

void Tools::drag_body(Simulation& sim, const Vec3& hit, double frame_s, std::string& error) {
    const auto shape = static_cast<BodyShape>(body_shape_);
    // Held a metre over the water where the click's ray met it first, else over the ground.
    const Vec3 at = held_position(DropPoint{hit, false}, shape, body_size_, 1.0f);
    if (!dragging_) {
        dragging_ = true;
        last_hit_ = hit;
        auto id = sim.add_body(BodyDef{.shape = shape, .size = body_size_, .density = body_density_, .position = at});
        if (!id) error = id.error().message;
        else grabbed_ = id.value();
        return;
    }
    if (!grabbed_) return;
    const auto bodies = sim.bodies();
    const auto it = std::find_if(bodies.begin(), bodies.end(), [&](const BodyState& b) { return b.id == *grabbed_; });
    if (it == bodies.end()) {  // removed meanwhile (the scene was edited)
        grabbed_.reset();
        return;
    }
    const Vec3 v = last_hit_ && frame_s > 0.0 ? cursor_velocity(*last_hit_, hit, frame_s, throw_gain_, kMostThrowSpeed)
                                              : Vec3(0.0f);
    if (auto m = sim.set_body_motion(*grabbed_, at, it->orientation, v, Vec3(0.0f)); !m) error = m.error().message;
    last_hit_ = hit;
}

void Tools::remove_body(Simulation& sim, const Vec3& hit, std::string& error) const {
    const BodyState* nearest = nullptr;
    float best = 0.0f;
    for (const BodyState& b : sim.bodies()) {
        const float d = std::hypot(b.position.x - hit.x, b.position.z - hit.z) - body_reach(b.shape, b.size);
        if (d <= radius_ && (!nearest || d < best)) nearest = &b, best = d;
    }
    if (!nearest) {
        error = fmt::format("remove body: no body within {:.1f} m of the click", radius_);
        return;
    }
    if (auto r = sim.remove_body(nearest->id); !r) error = r.error().message;
}

bool Tools::undo(Simulation& sim) {
    if (undo_.empty()) return false;
    changed_ = TerrainEdit{};
    for (auto e = undo_.back().rbegin(); e != undo_.back().rend(); ++e) {
        sim.restore(*e);
        if (changed_.empty()) {
            changed_ = TerrainEdit{.i0 = e->i0, .j0 = e->j0, .i1 = e->i1, .j1 = e->j1, .before = {}};
        } else {
            changed_.i0 = std::min(changed_.i0, e->i0);
            changed_.j0 = std::min(changed_.j0, e->j0);
            changed_.i1 = std::max(changed_.i1, e->i1);
            changed_.j1 = std::max(changed_.j1, e->j1);
        }
    }
    undo_.pop_back();
    return true;
}

void Tools::ui(const Simulation& sim) {
    ImGui::Combo("tool (left button)", &tool_,
                 "pour / orbit\0raise\0lower\0smooth\0flatten\0push water\0move source\0add source\0add sink "
                 "box\0remove source / sink\0drop / throw body\0remove body\0");
    if (const std::string why = unavailable(sim); !why.empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.75f, 0.3f, 1.0f));
        ImGui::TextWrapped("%s", why.c_str());
        ImGui::PopStyleColor();
        return;
    }
    if (!active() || tool_ == MoveSource) return;
    if (tool_ == DropBody) {
        ImGui::Combo("body shape", &body_shape_, "box\0sphere\0capsule\0");
        ImGui::DragFloat3("body size (m)", &body_size_.x, 0.01f, 0.0f, 50.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip("box: extents x, y, z; sphere: radius x; capsule: radius x, length y (bodies.size)");
        ImGui::DragFloat("body density (kg/m^3)", &body_density_, 5.0f, 1.0f, 100000.0f, "%.0f",
                         ImGuiSliderFlags_AlwaysClamp);
        ImGui::DragFloat("throw gain", &throw_gain_, 0.01f, 0.0f, 5.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
        return;
    }
    if (tool_ == AddSource) {
        ImGui::DragFloat("new source's flow rate", &source_rate_, 0.5f, 0.0f, 1e4f, "%.1f", ImGuiSliderFlags_AlwaysClamp);
        return;
    }
    ImGui::DragFloat("tool radius (m)", &radius_, 0.05f, 0.1f, 200.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
    if (tool_ == AddSink || tool_ == Remove || tool_ == RemoveBody) return;  // the box's half size; how near a click removes
    if (tool_ == Push) {
        ImGui::DragFloat("push gain", &push_gain_, 0.01f, 0.0f, 5.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
        return;
    }
    const bool metres = tool_ == Raise || tool_ == Lower;
    ImGui::DragFloat(metres ? "brush m per frame" : "brush share per frame", &strength_, 0.002f, 0.0f,
                     metres ? 10.0f : 1.0f, "%.3f", ImGuiSliderFlags_AlwaysClamp);
}

}  // namespace mr::view
