// Simulation's bodies (bodies.h, issue 44): the PBF solver holds them and couples them with
// its water (src/particles/pbf_bodies.cpp); other solvers have none.
#include <metariver/pbf_solver.h>
#include <metariver/scene.h>

#include "simulation_impl.h"

#include <fmt/format.h>

namespace mr {

namespace {

PbfSolver* pbf_of(Solver* s) { return dynamic_cast<PbfSolver*>(s); }

Error no_bodies(const SolverEntry& e) {
    return Error{fmt::format("bodies: solver = \"{}\" has no bodies (use solver = \"pbf\")", e.kind.name)};
}

}  // namespace

Status Simulation::Impl::add_scene_bodies(const std::vector<BodyDef>& bodies) {
    if (bodies.empty()) return Ok{};
    PbfSolver* pbf = pbf_of(solver_.get());
    if (!pbf) return no_bodies(solver_entry_);
    if (bodies.size() > kMaxBodies) return Error{fmt::format("bodies: at most {} bodies (got {})", kMaxBodies, bodies.size())};
    for (const BodyDef& b : bodies)
        if (auto r = pbf->add_body(b); !r) return r.error();
    return Ok{};
}

// apply() of a scene whose [[bodies]] changed: the bodies are rebuilt in place (the
// Simulation and its water stay; every body is made again from the new list, with new
// ids, at the list's positions), after the whole list was checked: on an error nothing
// changed.
Status Simulation::Impl::replace_bodies(const std::vector<BodyDef>& bodies) {
    PbfSolver* pbf = pbf_of(solver_.get());
    if (!pbf) return bodies.empty() ? Status(Ok{}) : Status(no_bodies(solver_entry_));
    if (bodies.size() > kMaxBodies) return Error{fmt::format("bodies: at most {} bodies (got {})", kMaxBodies, bodies.size())};
    for (const BodyDef& b : bodies)
        if (auto v = validate_body(b); !v) return v;
    std::vector<uint32_t> ids;
    for (const BodyState& s : pbf->bodies()) ids.push_back(s.id);
    for (uint32_t id : ids) (void)pbf->remove_body(id);
    return add_scene_bodies(bodies);
}

std::span<const BodyState> Simulation::Impl::bodies() const {
    const PbfSolver* pbf = dynamic_cast<const PbfSolver*>(solver_.get());
    return pbf ? pbf->bodies() : std::span<const BodyState>{};
}

Result<uint32_t> Simulation::add_body(const BodyDef& body) {
    PbfSolver* pbf = pbf_of(impl_->solver_.get());
    if (!pbf) return no_bodies(impl_->solver_entry_);
    return impl_->run([&] { return pbf->add_body(body); });
}

Status Simulation::remove_body(uint32_t id) {
    PbfSolver* pbf = pbf_of(impl_->solver_.get());
    if (!pbf) return Error{fmt::format("id: no body {}", id)};
    return pbf->remove_body(id);
}

Status Simulation::set_body_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                                   const Vec3& angular_velocity) {
    PbfSolver* pbf = pbf_of(impl_->solver_.get());
    if (!pbf) return Error{fmt::format("id: no body {}", id)};
    return pbf->set_body_motion(id, position, orientation, velocity, angular_velocity);
}

std::span<const BodyState> Simulation::bodies() const { return impl_->bodies(); }

}  // namespace mr
