// The viewer's hands-on tools (issue 14): the left button as a terrain brush (raise,
// lower, smooth, flatten: Simulation::sculpt) with undo per drag, a hand that pushes
// the water (Simulation::push), or a click that moves the main source
// (Simulation::move_source), adds a source or a sink box, or removes the added source or
// sink box nearest to it (live scene edits: [[particles.source]], [[sink.box]]), drops a
// body (a box, sphere or capsule: Simulation::add_body) where it is clicked and throws it
// with the drag (Simulation::set_body_motion), or removes the body nearest the click. The
// window code feeds it the cursor's terrain hit each frame; the panel's controls are its ui().
#pragma once

#include <metariver/scene.h>

#include <optional>
#include <string>
#include <vector>

namespace mr::view {

class Tools {
public:
    enum Tool { Pour = 0, Raise, Lower, Smooth, Flatten, Push, MoveSource, AddSource, AddSink, Remove, DropBody, RemoveBody };

    /// True when the left button belongs to a tool (not to pouring and orbiting).
    bool active() const { return tool_ != Pour; }
    Tool tool() const { return static_cast<Tool>(tool_); }
    void set_tool(Tool t) { tool_ = t; }
    /// Why the current tool does nothing on `sim`'s scene, one line naming the solver and
    /// what it reads instead; "" when it works. The panel shows it under the tool, and a
    /// press gives it as the error (a grid's water takes no bodies, no [[particles.source]]
    /// and no [[sink.box]]: it was silent).
    std::string unavailable(const Simulation& sim) const;
    /// True when the left button drops bodies (its hit is then the water's surface where
    /// the click's ray meets it first: view_drop.h).
    bool drops_bodies() const { return tool_ == DropBody; }
    /// One display frame: `hit` where the cursor's ray meets the terrain (none: off the
    /// terrain; the water first for drops_bodies()), `left` whether the button is held, `frame_s` the display frame's
    /// seconds. Returns true when the terrain changed (upload it again); an error goes
    /// to `error`. `def` is the viewer's scene: moving the source writes the new centre
    /// into it; adding or removing a source or sink fills `edit` with the scene to apply.
    bool frame(Simulation& sim, SceneDef& def, const std::optional<Vec3>& hit, bool left, double frame_s,
               std::string& error, std::optional<SceneDef>& edit);
    /// Undoes the newest brush drag (its strokes newest first: bit for bit). Returns
    /// whether there was one.
    bool undo(Simulation& sim);
    /// The samples the latest frame() or undo() that changed the terrain touched (the
    /// renderer uploads the rows around them: Renderer::update_terrain).
    const TerrainEdit& changed() const { return changed_; }
    /// The Simulation was rebuilt: its terrain is the heightmap's again.
    void forget() { undo_.clear(); }
    size_t undo_steps() const { return undo_.size(); }
    /// Whether the last frame() moved the source (the caller's copies of the scene follow).
    bool source_moved() const { return source_moved_; }
    /// The panel's controls (Dear ImGui; inside the caller's window), with unavailable(sim).
    void ui(const Simulation& sim);

private:
    /// The scene after a click of AddSource, AddSink or Remove at `hit` (none, and an
    /// error, when the list is full or nothing is near enough to remove).
    std::optional<SceneDef> click_edit(const SceneDef& def, const Vec3& hit, std::string& error) const;
    /// DropBody: the press adds the body above `hit`, the drag carries it there with the
    /// cursor's velocity, the release lets it go with that velocity (a throw).
    void drag_body(Simulation& sim, const Vec3& hit, double frame_s, std::string& error);
    /// RemoveBody: the body nearest `hit` (x, z) within the radius plus its size.
    void remove_body(Simulation& sim, const Vec3& hit, std::string& error) const;

    int tool_ = Pour;
    float radius_ = 3.0f;
    float strength_ = 0.1f;  ///< brushes: m (raise, lower) or share (smooth, flatten) per frame
    float push_gain_ = 1.0f; ///< push: water velocity per cursor velocity
    float source_rate_ = 20.0f;  ///< add source: its flow rate (particles.flow_rate's unit)
    float target_ = 0.0f;    ///< flatten: the height where the drag began
    int body_shape_ = 0;     ///< drop body: box, sphere, capsule (BodyShape's first three)
    Vec3 body_size_{2.0f, 0.5f, 0.5f};  ///< drop body: BodyDef::size
    float body_density_ = 500.0f;       ///< drop body: kg/m^3
    float throw_gain_ = 1.0f;           ///< drop body: body velocity per cursor velocity
    std::optional<uint32_t> grabbed_;   ///< drop body: the body the drag carries
    bool dragging_ = false;
    bool source_moved_ = false;
    std::optional<Vec3> last_hit_;
    std::vector<std::vector<TerrainEdit>> undo_;  ///< one entry per drag, newest last
    TerrainEdit changed_;                         ///< changed(): the rectangle only, no heights
};

}  // namespace mr::view
