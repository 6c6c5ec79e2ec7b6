// Rigid bodies two-way coupled with the PBF water (bodies.h; the solver in rigid_bodies.h).
//
// A body is water at rest to the density constraint, as the terrain is with the wall
// density (pbf.cpp): rho_i counts the share of particle i's kernel that lies inside the
// body, with the body's surface taken as the plane at the body's signed distance d from
// x_i (Koschier and Bender 2017's density maps in closed form for a half space: the
// poly6 kernel's mass beyond a plane at distance d is
//   share(d) = 315 / (256 h^9) int_d^h (h^2 - z^2)^4 dz,  1 at d = -h, 0 at d = h),
// and grad C_i gains d share/dd times the body's normal. The correction lambda_i grad
// pushes the particle off the body; the body takes the opposite position-level impulse,
// m (the water a particle stands for, 1000 kg/m^3 x spacing^3) times the particle's
// share of the correction, at the particle (Macklin et al. 2014's two-way coupling).
// After each iteration a particle whose centre is inside a body is moved to its surface,
// the body again taking the reaction. The pair sums are antisymmetric, so what holds a
// body up is what the water under it weighs: buoyancy and drag are not modelled but what
// the density constraint does.
//
// Honest count: after the whole step (contacts of the bodies included, sleeping too) a
// particle whose centre is inside a body (signed distance < 0) is counted in
// SolverCounters::inside_bodies, then moved out (the guard, as for the terrain).
//
// Each particle meets one body, the nearest one whose bounding sphere (+ h) holds it
// (body_of_, per step after binning; the spheres binned over x and z, body_cells.h). The reactions are summed serially in slot order:
// the same result for any thread count.
#include <metariver/pbf_solver.h>

#include "pbf_state.h"
#include "pbf_stages.h"

#include <algorithm>
#include <cmath>

namespace mr {

namespace {

/// Spacings off a body's surface where a particle pushed out of it is put.
constexpr float kBodySkin = 1e-3f;

/// Most a pass of the water's reactions accelerates a body, in g (and turns it, rad/s^2):
/// water pushed out of a body placed in it must not launch it.
constexpr float kBodyMaxAccel = 5.0f;
constexpr float kBodyMaxTurnAccel = 50.0f;

/// The water's drag on a body (Akinci et al. 2012's boundary viscosity, in XSPH's form):
/// per second a particle's velocity relative to the body's surface relaxes at this rate
/// (1 - exp(-rate dt) per step), times the body's share of its kernel; the body takes the
/// opposite momentum.
constexpr float kBodyDragRate = 3.0f;

/// Per body its centre and (bound + margin)^2: a particle farther cannot meet it.
void bounding_spheres(const std::vector<RigidBody>& bodies, float margin, std::vector<glm::vec4>& out) {
    out.resize(bodies.size());
    for (size_t b = 0; b < bodies.size(); ++b) {
        const float r = bodies[b].shape.bound + margin;
        out[b] = glm::vec4(bodies[b].x, r * r);
    }
}

}  // namespace

// A body placed (added, or moved by set_body_motion) takes its volume from the water at
// once: the particles it covers go to its surface, without a reaction (the body did not
// push them; a reaction would launch it). Not counted as inside_bodies: no step ended so.
void PbfSolver::clear_body_volume(uint32_t id) {
    const std::vector<RigidBody>& bodies = st_->bodies_.all();
    const auto it = std::find_if(bodies.begin(), bodies.end(), [&](const RigidBody& b) { return b.id == id; });
    if (it == bodies.end()) return;
    Particles& p = water_.pool.particles;
    const float skin = kBodySkin * pbf_.spacing;
    for_each_slot(water_.pool.active(), 1024, [&](size_t i) {
        if (!p.active[i]) return;
        const Vec3 d = p.position[i] - it->x;
        if (glm::dot(d, d) > it->shape.bound * it->shape.bound) return;
        Vec3 n;
        const float sd = it->sdf(p.position[i], n);
        if (sd < 0.0f) p.position[i] += (skin - sd) * n;
    });
}

Result<uint32_t> PbfSolver::add_body(const BodyDef& def) {
    auto id = st_->bodies_.add(def);
    if (id) clear_body_volume(id.value());
    return id;
}
Status PbfSolver::remove_body(uint32_t id) { return st_->bodies_.remove(id); }
Status PbfSolver::set_body_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                                  const Vec3& angular_velocity) {
    auto r = st_->bodies_.set_motion(id, position, orientation, velocity, angular_velocity);
    if (r) clear_body_volume(id);
    return r;
}
std::span<const BodyState> PbfSolver::bodies() const { return st_->bodies_.states(); }

// Per particle of the step: the nearest body within reach (its signed distance), or -1,
// and the second nearest (water between two bodies that touch meets both).
void PbfSolver::assign_bodies(const Stage& s) {
    State& st = *st_;
    const Particles& p = water_.pool.particles;
    const std::vector<RigidBody>& bodies = st.bodies_.all();
    // Sized for every slot; only the active prefix is read (particles.h), so only it is set.
    const size_t n = water_.pool.active();
    st.body_of_.resize(p.size());
    st.body2_of_.resize(p.size());
    st.body_grad_.resize(p.size());
    st.body_dx_.resize(p.size());
    st.body2_dx_.resize(p.size());
    std::fill_n(st.body_of_.begin(), n, -1);
    std::fill_n(st.body2_of_.begin(), n, -1);
    std::fill_n(st.body_grad_.begin(), n, Vec3(0.0f));
    std::fill_n(st.body_dx_.begin(), n, Vec3(0.0f));
    std::fill_n(st.body2_dx_.begin(), n, Vec3(0.0f));
    st.body_near_.clear();
    if (!st.body_coupling_on_) return;
    const float reach = s.k.h + pbf_.spacing;  // the iterations move a particle at most 1.5 spacings
    bounding_spheres(bodies, reach, st.body_reach_);
    st.body_cells_.build(st.body_reach_);
    const glm::vec4* const spheres = st.body_reach_.data();
    for_each_slot(n, 256, [&](size_t i) {
        if (!p.active[i]) return;
        const Vec3 x = p.position[i];
        float best = reach, second = reach;
        st.body_cells_.visit(x, [&](size_t b) {  // the broad phase: the cell's bodies, their compact spheres
            const Vec3 d = x - Vec3(spheres[b]);
            if (glm::dot(d, d) > spheres[b].w) return false;
            const float sd = bodies[b].distance(x);
            if (sd < best) {
                second = best, st.body2_of_[i] = st.body_of_[i];
                best = sd, st.body_of_[i] = int32_t(b);
            } else if (sd < second) {
                second = sd, st.body2_of_[i] = int32_t(b);
            }
            return false;
        });
    });
    st.body_near_.clear();  // the later passes walk these only (serial: slot order)
    for (size_t i = 0; i < n; ++i)
        if (st.body_of_[i] >= 0) st.body_near_.push_back(uint32_t(i));
}

// The bodies' share of the kernels (the density pass's C and grad C), body_grad_.
float pbf_body_share(const RigidBody& body, const BodyShare& bs, const Vec3& x, Vec3& grad) {
    if (body.outside_by(x, bs.h)) {  // share(d >= h) = 0
        grad = Vec3(0.0f);
        return 0.0f;
    }
    Vec3 n;
    const float d = body.sdf(x, n);
    grad = bs.slope(d) * n;
    return bs.share(d);
}

namespace {

/// Out of the nearest body and the second (`a`, `b`: indices or -1) to just off their
/// surfaces: alternately, for water between two bodies that touch; what is still inside
/// both after that (a gap narrower than the skin) leaves along the touching surfaces
/// (the normals' sum, or up the contact plane). The moves into `dxa`, `dxb` (the
/// bodies' reactions); true when it ends outside both.
bool leave_bodies(const std::vector<RigidBody>& bodies, int32_t a, int32_t b, float skin, Vec3& x, Vec3& dxa, Vec3& dxb) {
    const auto out_of = [&](int32_t k, Vec3& dx) {
        if (k < 0 || bodies[size_t(k)].outside_by(x, 0.0f) || bodies[size_t(k)].distance(x) >= 0.0f) return false;
        Vec3 n;
        const float d = bodies[size_t(k)].sdf(x, n);
        const Vec3 out = (skin - d) * n;  // to just off the surface: rounding keeps it outside
        x += out;
        dx += out;
        return true;
    };
    for (int round = 0; round < 4; ++round) {
        const bool moved_a = out_of(a, dxa);
        const bool moved_b = out_of(b, dxb);
        if (!moved_a && !moved_b) return true;
        if (b < 0) return !out_of(a, dxa);
    }
    // Squeezed: along the two surfaces, out of the gap, in steps of a skin's doubling.
    Vec3 na, nb;
    bodies[size_t(a)].sdf(x, na);
    bodies[size_t(b)].sdf(x, nb);
    Vec3 e = na + nb;
    if (glm::dot(e, e) < 0.01f) e = Vec3(0.0f, 1.0f, 0.0f) - na.y * na;
    if (glm::dot(e, e) < 1e-6f) e = glm::cross(na, Vec3(1.0f, 0.0f, 0.0f));
    e = glm::normalize(e);
    for (float step = skin; step < 1e3f * skin; step *= 2.0f) {
        if (bodies[size_t(a)].distance(x) >= 0.0f && bodies[size_t(b)].distance(x) >= 0.0f) return true;
        x += step * e;
        dxa += 0.5f * step * e;
        dxb += 0.5f * step * e;
    }
    return false;
}

}  // namespace

// After an iteration's corrections: a particle inside its body (or the second nearest)
// goes to the surface. At the step's end (`into_velocity`, after the bodies' contacts and
// velocities) the reaction goes into the bodies' velocities, not their poses: a body moved
// then would cover other water.
void PbfSolver::push_out_of_bodies(const Stage& s, bool into_velocity) {
    State& st = *st_;
    Particles& p = water_.pool.particles;
    const std::vector<RigidBody>& bodies = st.bodies_.all();
    const float skin = kBodySkin * pbf_.spacing;
    const std::vector<uint32_t>& near = st.body_near_;
    for_each_slot(near.size(), 64, [&](size_t k) {
        const uint32_t i = near[k];
        leave_bodies(bodies, st.body_of_[i], st.body2_of_[i], skin, p.position[i], st.body_dx_[i], st.body2_dx_[i]);
    });
    react_on_bodies(s.dt, into_velocity);
}

// The opposite of the particles' body corrections (body_dx_, then cleared) on the bodies:
// on their predicted poses, or (into_velocity) on their velocities (a step of dt).
void PbfSolver::react_on_bodies(float dt, bool into_velocity) {
    State& st = *st_;
    std::vector<RigidBody>& bodies = st.bodies_.all();
    const Particles& p = water_.pool.particles;
    const float m = 1000.0f * pbf_.spacing * pbf_.spacing * pbf_.spacing;
    std::vector<Vec3> impulse(bodies.size(), Vec3(0.0f)), torque(bodies.size(), Vec3(0.0f));
    const auto react = [&](int32_t b, const Vec3& at, Vec3& dx) {
        if (b < 0 || dx == Vec3(0.0f)) return;
        const Vec3 P = -m * dx;
        impulse[size_t(b)] += P;
        torque[size_t(b)] += glm::cross(at - bodies[size_t(b)].x, P);
        dx = Vec3(0.0f);
    };
    for (const uint32_t i : st.body_near_) {  // serial, in slot order: deterministic
        react(st.body_of_[i], p.position[i], st.body_dx_[i]);
        react(st.body2_of_[i], p.position[i], st.body2_dx_[i]);
    }
    const float max_move = kBodyMaxAccel * water_.integrator.gravity * dt * dt;
    const float max_turn = kBodyMaxTurnAccel * dt * dt;
    for (size_t b = 0; b < bodies.size(); ++b) {
        RigidBody& body = bodies[b];
        Vec3 dx = impulse[b] * body.inv_mass;
        Vec3 dtheta = body.inv_inertia_world() * torque[b];
        // A body lighter than the water pushing it would overshoot: at most this far per pass.
        if (const float l = glm::length(dx); l > max_move) dx *= max_move / l;
        if (const float a = glm::length(dtheta); a > max_turn) dtheta *= max_turn / a;
        body.lift += impulse[b];
        if (into_velocity) {
            body.v += dx / dt;
            body.w += dtheta / dt;
            continue;
        }
        body.x += dx;
        body.q = glm::normalize(body.q + 0.5f * (glm::quat(0.0f, dtheta.x, dtheta.y, dtheta.z) * body.q));
    }
}

// Drag (kBodyDragRate): the water at a body and the body exchange momentum along their
// relative velocity, after the step's velocities are known. With k_i = m (1 - exp(-rate dt)) share_i
// the body's velocity becomes the weighted mean (M v + sum k_i v_i) / (M + sum k_i) and
// each particle moves (1 - exp(-rate dt)) share_i of the way to the body's surface velocity: the
// momentum is conserved and a body lighter than the water around it does not overshoot.
// (The drag's torque is left out.)
void PbfSolver::drag_bodies(const Stage& s) {
    State& st = *st_;
    Particles& p = water_.pool.particles;
    std::vector<RigidBody>& bodies = st.bodies_.all();
    const BodyShare bs(s.k.h);
    const float relax = 1.0f - std::exp(-kBodyDragRate * s.dt);
    std::vector<float>& share = st.lambda_;  // free after the iterations; read at body_near_ only
    const std::vector<uint32_t>& near = st.body_near_;
    for_each_slot(near.size(), 64, [&](size_t k) {
        const uint32_t i = near[k];
        const RigidBody& body = bodies[size_t(st.body_of_[i])];
        share[i] = body.outside_by(p.position[i], s.k.h) ? 0.0f : relax * bs.share(body.distance(p.position[i]));
    });
    std::vector<Vec3> momentum(bodies.size(), Vec3(0.0f));
    std::vector<float> weight(bodies.size(), 0.0f);
    for (const uint32_t i : near) {  // serial, in slot order: deterministic
        if (share[i] <= 0.0f) continue;
        const size_t b = size_t(st.body_of_[i]);
        momentum[b] += (s.body_mass * share[i]) * p.velocity[i];
        weight[b] += s.body_mass * share[i];
    }
    for (size_t b = 0; b < bodies.size(); ++b)
        bodies[b].v = (bodies[b].mass * bodies[b].v + momentum[b]) / (bodies[b].mass + weight[b]);
    for_each_slot(near.size(), 64, [&](size_t k) {
        const uint32_t i = near[k];
        if (share[i] <= 0.0f) return;
        const RigidBody& body = bodies[size_t(st.body_of_[i])];
        const Vec3 vb = body.v + glm::cross(body.w, p.position[i] - body.x);
        p.velocity[i] += share[i] * (vb - p.velocity[i]);
    });
}

// The honest count at the step's end, then the guard: out to the surface, the velocity
// into the body removed (relative to the body's surface there).
void PbfSolver::count_inside_bodies(const Stage&) {
    State& st = *st_;
    Particles& p = water_.pool.particles;
    const std::vector<RigidBody>& bodies = st.bodies_.all();
    const size_t active = water_.pool.active();  // the active prefix (particles.h)
    std::vector<uint8_t> inside(active, 0);
    bounding_spheres(bodies, 0.0f, st.body_reach_);  // every particle against every body (binned): honest
    st.body_cells_.build(st.body_reach_);
    const glm::vec4* const spheres = st.body_reach_.data();
    for_each_slot(active, 256, [&](size_t i) {
        if (!p.active[i]) return;
        const Vec3 x = p.position[i];
        st.body_cells_.visit(x, [&](size_t b) {
            const Vec3 d = x - Vec3(spheres[b]);
            if (glm::dot(d, d) > spheres[b].w) return false;
            const RigidBody& body = bodies[b];
            if (body.distance(x) >= 0.0f) return false;
            Vec3 n;
            const float sd = body.sdf(x, n);
            inside[i] = 1;
            p.position[i] = x + (kBodySkin * pbf_.spacing - sd) * n;
            const Vec3 vb = body.v + glm::cross(body.w, p.position[i] - body.x);
            const float vn = glm::dot(p.velocity[i] - vb, n);
            if (vn < 0.0f) p.velocity[i] -= vn * n;
            return true;
        });
    });
    uint64_t count = 0;
    for (uint8_t c : inside) count += c;
    water_.pool.counters.inside_bodies += count;
}

}  // namespace mr
