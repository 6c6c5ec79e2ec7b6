// Simulation's bodies (bodies.h, issues 44 and 45): the PBF solver holds them and couples
// them with its water (src/particles/pbf_bodies.cpp); on a heightfield's water (swe,
// hybrid) the Simulation holds them and the grid's water pushes them, one way
// (src/particles/rigid_bodies_grid.h); other solvers have none.
#include <metariver/pbf_solver.h>
#include <metariver/scene.h>

#include "rigid_bodies_grid.h"
#include "simulation_impl.h"

#include <fmt/format.h>

namespace mr {

void GridBodiesDelete::operator()(GridBodies* b) const { delete b; }

namespace {

Error no_bodies(const SolverEntry& e) {
    return Error{fmt::format("bodies: solver = \"{}\" has no bodies (use solver = \"pbf\", \"swe\" or \"hybrid\")", e.kind.name)};
}

}  // namespace

Simulation::Impl::BodyHost Simulation::Impl::body_host() {
    if (auto* pbf = dynamic_cast<PbfSolver*>(solver_.get())) return BodyHost{.pbf = pbf};
    if (!solver_ || !solver_->water_heightfield()) return BodyHost{};
    if (!grid_bodies_) grid_bodies_.reset(new GridBodies());
    return BodyHost{.grid = grid_bodies_.get()};
}

Result<uint32_t> Simulation::Impl::BodyHost::add(const BodyDef& def) const {
    return pbf ? pbf->add_body(def) : grid->add(def);
}
Status Simulation::Impl::BodyHost::remove(uint32_t id) const { return pbf ? pbf->remove_body(id) : grid->remove(id); }
Status Simulation::Impl::BodyHost::set_motion(uint32_t id, const Vec3& position, const glm::quat& orientation,
                                              const Vec3& velocity, const Vec3& angular_velocity) const {
    return pbf ? pbf->set_body_motion(id, position, orientation, velocity, angular_velocity)
               : grid->set_motion(id, position, orientation, velocity, angular_velocity);
}

void Simulation::Impl::step_grid_bodies(float frame_dt) {
    if (!grid_bodies_ || grid_bodies_->empty()) return;
    if (const HeightfieldWater* w = solver_->water_heightfield()) grid_bodies_->step(*w, terrain_, frame_dt, def_.integrator.gravity);
}

Status Simulation::Impl::add_scene_bodies(const std::vector<BodyDef>& bodies) {
    scene_body_ids_.clear();
    if (bodies.empty()) return Ok{};
    const BodyHost host = body_host();
    if (!host) return no_bodies(solver_entry_);
    if (bodies.size() > kMaxBodies) return Error{fmt::format("bodies: at most {} bodies (got {})", kMaxBodies, bodies.size())};
    for (const BodyDef& b : bodies) {
        auto r = host.add(b);
        if (!r) return r.error();
        scene_body_ids_.push_back(r.value());
    }
    return Ok{};
}

// apply() of a scene whose [[bodies]] changed (def_.bodies to `bodies`), after the whole
// list was checked: an entry whose definition is unchanged keeps its body (id, pose,
// motion), the old entries left over are removed and the new ones added at their
// positions. Bodies not from the list (add_body: the viewer's drops) stay as they are.
Status Simulation::Impl::replace_bodies(const std::vector<BodyDef>& bodies) {
    const BodyHost host = body_host();
    if (!host) return bodies.empty() ? Status(Ok{}) : Status(no_bodies(solver_entry_));
    if (bodies.size() > kMaxBodies) return Error{fmt::format("bodies: at most {} bodies (got {})", kMaxBodies, bodies.size())};
    for (const BodyDef& b : bodies)
        if (auto v = validate_body(b); !v) return v;
    const std::vector<BodyDef>& old = def_.bodies;
    std::vector<bool> kept(scene_body_ids_.size(), false);
    std::vector<int64_t> ids(bodies.size(), -1);  // per new entry: the old body it keeps
    for (size_t j = 0; j < bodies.size(); ++j)
        for (size_t i = 0; i < scene_body_ids_.size() && i < old.size(); ++i)
            if (!kept[i] && old[i] == bodies[j]) {
                kept[i] = true;
                ids[j] = scene_body_ids_[i];
                break;
            }
    for (size_t i = 0; i < scene_body_ids_.size(); ++i)
        if (!kept[i]) (void)host.remove(scene_body_ids_[i]);  // (a body removed live: already gone)
    std::vector<uint32_t> now;
    for (size_t j = 0; j < bodies.size(); ++j) {
        if (ids[j] < 0) {
            auto r = host.add(bodies[j]);
            if (!r) return r.error();
            ids[j] = r.value();
        }
        now.push_back(uint32_t(ids[j]));
    }
    scene_body_ids_ = std::move(now);
    return Ok{};
}

std::span<const BodyState> Simulation::Impl::bodies() const {
    if (const auto* pbf = dynamic_cast<const PbfSolver*>(solver_.get())) return pbf->bodies();
    return grid_bodies_ ? grid_bodies_->states() : std::span<const BodyState>{};
}

Result<uint32_t> Simulation::add_body(const BodyDef& body) {
    const Impl::BodyHost host = impl_->body_host();
    if (!host) return no_bodies(impl_->solver_entry_);
    if (auto v = validate_body(body); !v) return v.error();  // the scene file's ranges
    return impl_->run([&] { return host.add(body); });
}

Status Simulation::remove_body(uint32_t id) {
    const Impl::BodyHost host = impl_->body_host();
    if (!host) return Error{fmt::format("id: no body {}", id)};
    return host.remove(id);
}

Status Simulation::set_body_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                                   const Vec3& angular_velocity) {
    const Impl::BodyHost host = impl_->body_host();
    if (!host) return Error{fmt::format("id: no body {}", id)};
    return host.set_motion(id, position, orientation, velocity, angular_velocity);
}

std::span<const BodyState> Simulation::bodies() const { return impl_->bodies(); }

}  // namespace mr
