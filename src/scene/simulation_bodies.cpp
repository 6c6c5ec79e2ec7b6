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
    scene_body_ids_.clear();
    if (bodies.empty()) return Ok{};
    PbfSolver* pbf = pbf_of(solver_.get());
    if (!pbf) return no_bodies(solver_entry_);
    if (bodies.size() > kMaxBodies) return Error{fmt::format("bodies: at most {} bodies (got {})", kMaxBodies, bodies.size())};
    for (const BodyDef& b : bodies) {
        auto r = pbf->add_body(b);
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
    PbfSolver* pbf = pbf_of(solver_.get());
    if (!pbf) return bodies.empty() ? Status(Ok{}) : Status(no_bodies(solver_entry_));
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
        if (!kept[i]) (void)pbf->remove_body(scene_body_ids_[i]);  // (a body removed live: already gone)
    std::vector<uint32_t> now;
    for (size_t j = 0; j < bodies.size(); ++j) {
        if (ids[j] < 0) {
            auto r = pbf->add_body(bodies[j]);
            if (!r) return r.error();
            ids[j] = r.value();
        }
        now.push_back(uint32_t(ids[j]));
    }
    scene_body_ids_ = std::move(now);
    return Ok{};
}

std::span<const BodyState> Simulation::Impl::bodies() const {
    const PbfSolver* pbf = dynamic_cast<const PbfSolver*>(solver_.get());
    return pbf ? pbf->bodies() : std::span<const BodyState>{};
}

Result<uint32_t> Simulation::add_body(const BodyDef& body) {
    PbfSolver* pbf = pbf_of(impl_->solver_.get());
    if (!pbf) return no_bodies(impl_->solver_entry_);
    if (auto v = validate_body(body); !v) return v.error();  // the scene file's ranges
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
