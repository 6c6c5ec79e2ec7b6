// Live changes to a running Simulation (issue 14): apply() for edited scenes, sculpt()
// and restore() for the terrain, push() and move_source() for the water and its source.
#include <metariver/pbf_solver.h>
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include "simulation_impl.h"
#include "simulation_internal.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace mr {

namespace {
/// A key whose change needs a new Simulation (Simulation::apply): its edit rule in the
/// table (SceneKey::edit); the Bullet world is built once from its defs.
bool needs_rebuild(const SceneKey& k, const SceneDef& d) {
    return k.edit == KeyEdit::Rebuild || (k.edit == KeyEdit::Solver && d.solver == SolverKind::Bullet);
}

/// Copies the value of key `k` from `from` into `to`.
void copy_key(const SceneKey& k, const SceneDef& from, SceneDef& to) {
    copy_field(k.field(const_cast<SceneDef&>(from)), k.field(to));  // `from` only read
}

/// Copies every entry of list `l` from `from` into `to`.
void copy_list(const SceneList& l, const SceneDef& from, SceneDef& to) {
    SceneDef& src = const_cast<SceneDef&>(from);  // only read
    l.resize(to, l.size(from));
    for (size_t i = 0; i < l.size(from); ++i)
        for (const SceneListKey& k : l.keys) copy_field(k.item(src, i), k.item(to, i));
}
}  // namespace

Result<ApplyResult> Simulation::Impl::apply(const SceneDef& next) {
    if (auto v = validate(next); !v) return v.error();
    ApplyResult r;
    SceneDef edited = def_;
    for (const SceneKey& k : scene_keys()) {
        if (key_value_toml(k, requested_) == key_value_toml(k, next)) continue;
        r.keys.emplace_back(k.name);
        const bool word = k.words.current && (k.words.current(requested_) >= 0 || k.words.current(next) >= 0);
        if (r.rebuild_key.empty() && (word || needs_rebuild(k, requested_))) r.rebuild_key = std::string(k.name);
        if (r.rebuild_key.empty()) copy_key(k, next, edited);
    }
    for (const SceneList& l : scene_lists()) {  // sources and sinks: in place
        if (list_toml(l, requested_) == list_toml(l, next)) continue;
        r.keys.emplace_back(l.name);
        if (r.rebuild_key.empty()) copy_list(l, next, edited);
    }
    if (!r.rebuild_key.empty()) return r;
    if (auto f = detail::field_box_fits(edited.field, terrain_); !f) return f.error();
    if (auto v = validate_on_terrain(edited, terrain_); !v) return v.error();
    if (requested_.swe.rain_mask != next.swe.rain_mask)
        if (auto m = detail::rain_mask_readable(edited); !m) return m.error();
    // The solver takes the keys it reads by its registry entry's rule (the budget's key
    // asks for a rebuild above, so a refusal is not reached).
    const bool bodies_changed = requested_.bodies != next.bodies;
    if (bodies_changed) {  // checked before anything changes (replace_bodies checks again)
        if (!next.bodies.empty() && !body_host())
            return Error{fmt::format("bodies: solver = \"{}\" has no bodies (use solver = \"pbf\", \"swe\" or \"hybrid\")",
                                     solver_entry_.kind.name)};
        for (const BodyDef& b : next.bodies)
            if (auto v = validate_body(b); !v) return v.error();
    }
    const bool taken = !solver_entry_.apply || solver_entry_.apply(*solver_, edited);
    if (!taken) {
        r.rebuild_key = "particles.count";
        return r;
    }
    if (bodies_changed) {
        if (auto b = replace_bodies(next.bodies); !b) return b.error();
        edited.bodies = next.bodies;
        if (std::find(r.keys.begin(), r.keys.end(), "bodies") == r.keys.end()) r.keys.emplace_back("bodies");
    }
    const bool foam_changed = std::any_of(r.keys.begin(), r.keys.end(), [](const std::string& k) {
        return k.starts_with("foam.") || k == "forces.gravity" || k == "pbf.kernel_radius";
    });
    def_ = edited;
    requested_ = next;
    configure_field();
    if (foam_changed) make_foam();
    r.applied = true;
    return r;
}

void Simulation::Impl::measure_main_channel(const SpawnDef& asked) const {
    main_path_ = detail::main_channel_path(terrain_, channel_, asked, def_.spawn.center);
    coverage_ = ChannelCoverage(terrain_, main_path_);
}

void Simulation::Impl::refresh_channel() const {
    if (channel_stale_.empty()) return;
    const SampleRect r = channel_stale_;
    channel_stale_ = {};
    channel_.update(terrain_, r.i0, r.i1, r.j0, r.j1);
    measure_main_channel(def_.spawn);
}

Status Simulation::Impl::move_source(const Vec3& center) {
    SceneDef moved = def_;
    moved.spawn.center = center;
    moved.spawn.auto_center = moved.spawn.auto_channel = false;
    if (!std::isfinite(center.x + center.y + center.z)) return Error{"particles.spawn_center: must be finite"};
    if (auto v = validate_on_terrain(moved, terrain_); !v) return v.error();
    def_.spawn = moved.spawn;
    requested_.spawn.center = center;
    requested_.spawn.auto_center = requested_.spawn.auto_channel = false;
    solver_->set_spawn_center(center);
    if (!channel_stale_.empty()) refresh_channel();  // updates the network and measures from the new centre
    else measure_main_channel(def_.spawn);
    return Ok{};
}

Result<size_t> Simulation::Impl::push(const Vec3& center, float radius, const Vec3& velocity) {
    if (!solver_entry_.no_push.empty())
        return Error{fmt::format("push: solver = \"{}\" {}", solver_entry_.kind.name, solver_entry_.no_push)};
    if (!std::isfinite(radius) || !(radius > 0.0f))
        return Error{fmt::format("push: radius: must be finite and > 0 metres (got {})", radius)};
    if (!std::isfinite(center.x + center.y + center.z) || !std::isfinite(velocity.x + velocity.y + velocity.z))
        return Error{"push: centre and velocity: must be finite"};
    return solver_->push(center, radius, velocity);
}

Result<TerrainEdit> Simulation::Impl::sculpt(const Brush& brush) {
    if (!solver_entry_.no_sculpt.empty())
        return Error{fmt::format("sculpt: solver = \"{}\" {}", solver_entry_.kind.name, solver_entry_.no_sculpt)};
    auto e = terrain_.sculpt(brush);
    if (!e) return e.error();
    after_terrain_edit(e.value());
    return e;
}

void Simulation::Impl::restore(const TerrainEdit& edit) {
    if (!solver_entry_.no_sculpt.empty()) return;
    terrain_.restore(edit);
    after_terrain_edit(edit);
}

void Simulation::Impl::after_terrain_edit(const TerrainEdit& e) {
    if (e.empty()) return;
    bvh_.refit_heights(terrain_);
    solver_->terrain_edited(terrain_, e.i0, e.i1, e.j0, e.j1);
    // The network is updated over the changed samples when next read (refresh_channel).
    SampleRect& r = channel_stale_;
    r = {std::min(r.i0, e.i0), std::max(r.i1, e.i1), std::min(r.j0, e.j0), std::max(r.j1, e.j1)};
    // The triangles of the cells around the changed samples moved: particles over them
    // that are now under the ground (plus the collision's clearance) go up onto it, with
    // no downward speed, and start their next step there (not a crossing to count).
    const float s = terrain_.area_scale();
    const Vec3 o = terrain_.vertices().front();
    const float xa = o.x + float(e.j0 - 1) * s, xb = o.x + float(e.j1 + 1) * s;
    const float za = o.z + float(e.i0 - 1) * s, zb = o.z + float(e.i1 + 1) * s;
    const float clearance = def_.collision.radius + def_.collision.offset;
    Particles* water = solver_->editable_particles();  // null: no particles to lift
    for (size_t i = 0; water && i < water->size(); ++i) {
        Particles& p = *water;
        if (!p.active[i]) continue;
        Vec3& x = p.position[i];
        if (x.x < xa || x.x > xb || x.z < za || x.z > zb || !terrain_.contains_xz(x.x, x.z)) continue;
        const float g = terrain_.height_mesh(x.x, x.z) + clearance;
        if (x.y >= g) continue;
        x.y = g;
        p.last_position[i] = x;
        p.velocity[i].y = std::max(p.velocity[i].y, 0.0f);
        ++terrain_lifts_;
    }
    solver_->set_spawn_center(def_.spawn.center);  // the source's lattice over the new ground
}

}  // namespace mr
