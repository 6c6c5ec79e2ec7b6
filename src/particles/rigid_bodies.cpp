// Position-based rigid bodies (rigid_bodies.h): prediction, contacts with the terrain and
// between bodies with Coulomb friction, and the velocities from the poses' change.
#include "rigid_bodies.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace mr {

namespace {

/// Contact passes over all contacts per substep (Gauss-Seidel).
constexpr int kContactPasses = 2;
/// Metres per second at most that an overlap with the ground is undone.
constexpr float kMaxDepenetration = 1.0f;
/// Water's density for the measured submerged share, kg/m^3.
constexpr float kWaterDensity = 1000.0f;

glm::quat rotate_by(const glm::quat& q, const Vec3& dtheta) {
    const glm::quat dq(0.0f, dtheta.x, dtheta.y, dtheta.z);
    return glm::normalize(q + 0.5f * (dq * q));
}

struct Contact {
    RigidBody* a;
    RigidBody* b;     ///< null: the terrain
    Vec3 local_a;     ///< the sample on a, in a's frame
    Vec3 n;           ///< pushes a out (world)
    float depth;      ///< > 0: penetration, metres
};

// One contact's normal correction and its position-level Coulomb friction.
void resolve(const Contact& c, float friction) {
    RigidBody& a = *c.a;
    const Vec3 p = a.to_world(c.local_a);
    const float wa = a.inv_mass_along(c.n, p);
    const float wb = c.b ? c.b->inv_mass_along(c.n, p) : 0.0f;
    if (wa + wb <= 0.0f) return;
    const float dl = c.depth / (wa + wb);
    a.apply(dl * c.n, p);
    if (c.b) c.b->apply(-dl * c.n, p);
    // Slip of the contact point over the substep (a's point against b's material point).
    const Vec3 pa = a.to_world(c.local_a);
    Vec3 dp = pa - (a.x_prev + a.q_prev * c.local_a);
    if (c.b) {
        const Vec3 lb = c.b->to_local(pa);
        dp -= pa - (c.b->x_prev + c.b->q_prev * lb);
    }
    const Vec3 dt = dp - glm::dot(dp, c.n) * c.n;
    const float slip = glm::length(dt);
    if (slip < 1e-9f) return;
    const Vec3 t = dt / slip;
    const float wta = a.inv_mass_along(t, pa), wtb = c.b ? c.b->inv_mass_along(t, pa) : 0.0f;
    const float lt = std::min(slip / (wta + wtb), friction * dl);
    a.apply(-lt * t, pa);
    if (c.b) c.b->apply(lt * t, pa);
}

}  // namespace

void RigidBody::apply(const Vec3& p, const Vec3& at) {
    x += p * inv_mass;
    q = rotate_by(q, inv_inertia_world() * glm::cross(at - x, p));
}

float RigidBody::inv_mass_along(const Vec3& n, const Vec3& at) const {
    const Vec3 rn = glm::cross(at - x, n);
    return inv_mass + glm::dot(rn, inv_inertia_world() * rn);
}

Result<uint32_t> RigidBodies::add(const BodyDef& def) {
    if (bodies_.size() >= kMaxBodies) return Error{fmt::format("bodies: at most {} bodies", kMaxBodies)};
    auto shape = make_shape(def);
    if (!shape) return shape.error();
    RigidBody b;
    b.id = next_id_++;
    b.shape = std::move(shape.value());
    b.size = def.size;
    b.density = def.density;
    b.friction = def.friction;
    b.mass = def.density * b.shape.volume;
    b.inv_mass = 1.0f / b.mass;
    b.inv_inertia_local = glm::inverse(def.density * b.shape.inertia_unit);
    b.x = b.x_prev = def.position;
    b.q = b.q_prev = rotation_from_degrees(def.rotation);
    b.v = def.velocity;
    b.w = def.angular_velocity;
    bodies_.push_back(std::move(b));
    update_states();
    return bodies_.back().id;
}

Status RigidBodies::remove(uint32_t id) {
    const auto it = std::find_if(bodies_.begin(), bodies_.end(), [&](const RigidBody& b) { return b.id == id; });
    if (it == bodies_.end()) return Error{fmt::format("id: no body {}", id)};
    bodies_.erase(it);
    update_states();
    return Ok{};
}

Status RigidBodies::set_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                               const Vec3& angular_velocity) {
    const auto it = std::find_if(bodies_.begin(), bodies_.end(), [&](const RigidBody& b) { return b.id == id; });
    if (it == bodies_.end()) return Error{fmt::format("id: no body {}", id)};
    const auto finite = [](const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    if (!finite(position)) return Error{"position: must be finite"};
    if (!(std::isfinite(orientation.w) && finite(Vec3(orientation.x, orientation.y, orientation.z))) ||
        glm::length(orientation) < 1e-6f)
        return Error{"orientation: must be a finite, non-zero quaternion"};
    if (!finite(velocity)) return Error{"velocity: must be finite"};
    if (!finite(angular_velocity)) return Error{"angular_velocity: must be finite"};
    it->x = it->x_prev = position;
    it->q = it->q_prev = glm::normalize(orientation);
    it->v = velocity;
    it->w = angular_velocity;
    update_states();
    return Ok{};
}

void RigidBodies::predict(float dt, float gravity) {
    for (RigidBody& b : bodies_) {
        b.x_prev = b.x;
        b.q_prev = b.q;
        b.lift = Vec3(0.0f);
        b.v.y -= gravity * dt;
        b.x += b.v * dt;
        b.q = rotate_by(b.q, b.w * dt);
    }
}

namespace {
// True when a body's bounding sphere is above the ground under its square (the centre and
// the four corners: a cheap test that skips the samples of a floating body).
bool clear_of_ground(const Terrain& terrain, const RigidBody& b) {
    const float r = b.shape.bound, low = b.x.y - r;
    for (const Vec3& o : {Vec3(0, 0, 0), Vec3(-r, 0, -r), Vec3(r, 0, -r), Vec3(-r, 0, r), Vec3(r, 0, r)}) {
        const Vec3 q = b.x + o;
        if (!terrain.contains_xz(q.x, q.z) || terrain.height_mesh(q.x, q.z) >= low) return false;
    }
    // Between the corners the ground may rise by the slope over half the square's diagonal.
    const Vec3 n = terrain.contains_xz(b.x.x, b.x.z) ? terrain.normal_mesh(b.x.x, b.x.z) : Vec3(0, 1, 0);
    const float slope = n.y > 1e-3f ? std::sqrt(std::max(0.0f, 1.0f - n.y * n.y)) / n.y : 1e3f;
    return terrain.height_mesh(b.x.x, b.x.z) + 1.5f * r * slope + 0.5f * r < low;
}

/// Metres added to a body's box of samples: more than the rounding of their world
/// positions (coordinates up to 10 km) and of the ground's interpolation.
constexpr float kSampleBoxMargin = 0.01f;

/// The cells' index range along one axis under [lo, hi] (Terrain::height_mesh's cell of a
/// coordinate, clamped the same way: monotone in the coordinate).
std::pair<int, int> cell_range(float lo, float hi, float s, int n) {
    const float extent = float(n - 1) * s;
    const auto index = [&](float x) {
        const float c = x < 0.0f ? 0.0f : (x > extent ? extent : x);
        return std::clamp(int(c / s), 0, n - 2);
    };
    return {index(lo), index(hi)};
}

/// Above this height no sample of the body can be under the ground: the highest grid
/// sample of the terrain's cells under the box of its samples (the mesh's triangles
/// interpolate their corners, so the ground under the box is no higher), and the lowest
/// point of that box. Without a terrain or with a non-finite pose: no bound (+inf, -inf).
std::pair<float, float> ground_bound(const Terrain& terrain, const RigidBody& b) {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    const glm::mat3 R = glm::mat3_cast(b.q);
    Vec3 half(kSampleBoxMargin);
    for (int c = 0; c < 3; ++c) half += glm::abs(R[c]) * b.shape.sample_extent[c];
    const Vec3 lo = b.x - half, hi = b.x + half;
    if (terrain.columns() < 2 || terrain.rows() < 2 || !std::isfinite(lo.x + lo.y + lo.z + hi.x + hi.y + hi.z))
        return {kInf, -kInf};
    const float s = terrain.area_scale();
    const auto [j0, j1] = cell_range(lo.x, hi.x, s, terrain.columns());
    const auto [i0, i1] = cell_range(lo.z, hi.z, s, terrain.rows());
    float top = -kInf;
    for (int i = i0; i <= i1 + 1; ++i)
        for (int j = j0; j <= j1 + 1; ++j) top = std::max(top, terrain.sample(i, j));
    return {top + kSampleBoxMargin, lo.y};
}
}  // namespace

void RigidBodies::terrain_contacts(const Terrain& terrain, float dt) {
    for (RigidBody& b : bodies_) {
        // Skipped where no sample can be under the ground (the same contacts, fewer
        // queries); the bound again after a contact moved the body.
        auto [top, lowest] = ground_bound(terrain, b);
        if (lowest >= top || clear_of_ground(terrain, b)) continue;
        for (const Vec3& s : b.shape.samples) {
            const Vec3 p = b.to_world(s);
            if (p.y >= top || !terrain.contains_xz(p.x, p.z)) continue;
            const float ground = terrain.height_mesh(p.x, p.z);
            if (p.y >= ground) continue;
            const Vec3 n = terrain.normal_mesh(p.x, p.z);
            // An overlap the substep started with (a body placed or moved into the ground,
            // the ground sculpted up) goes at most kMaxDepenetration m/s: a full push
            // would become the velocity of a launch.
            const Vec3 was = b.x_prev + b.q_prev * s;
            float depth = (ground - p.y) * n.y;
            if (terrain.contains_xz(was.x, was.z)) {
                const float old = std::max(0.0f, (terrain.height_mesh(was.x, was.z) - was.y) * n.y);
                depth -= std::max(0.0f, old - kMaxDepenetration * dt);  // the overlap left this substep
            }
            if (depth > 0.0f) {
                resolve(Contact{&b, nullptr, s, n, depth}, b.friction);
                top = ground_bound(terrain, b).first;
            }
        }
    }
}

void RigidBodies::body_contacts() {
    for (size_t i = 0; i < bodies_.size(); ++i)
        for (size_t j = i + 1; j < bodies_.size(); ++j) {
            RigidBody& a = bodies_[i];
            RigidBody& b = bodies_[j];
            const float reach = a.shape.bound + b.shape.bound;
            if (glm::dot(a.x - b.x, a.x - b.x) > reach * reach) continue;
            const float mu = 0.5f * (a.friction + b.friction);
            for (int side = 0; side < 2; ++side) {
                RigidBody& p = side ? b : a;  // p's samples against q's distance
                RigidBody& q = side ? a : b;
                for (const Vec3& s : p.shape.samples) {
                    Vec3 n;
                    const float d = q.sdf(p.to_world(s), n);
                    if (d < 0.0f) resolve(Contact{&p, &q, s, n, -d}, mu);
                }
            }
        }
}

void RigidBodies::contacts(const Terrain& terrain, float dt) {
    for (int pass = 0; pass < kContactPasses; ++pass) {
        body_contacts();
        terrain_contacts(terrain, dt);
    }
}

void RigidBodies::velocities(float dt, float gravity) {
    const float inv_dt = 1.0f / dt;
    for (RigidBody& b : bodies_) {
        b.v = (b.x - b.x_prev) * inv_dt;
        glm::quat dq = b.q * glm::conjugate(b.q_prev);
        if (dq.w < 0.0f) dq = -dq;
        b.w = 2.0f * Vec3(dq.x, dq.y, dq.z) * inv_dt;
        const float weight = kWaterDensity * gravity * b.shape.volume * dt * dt;
        const float share = weight > 0.0f ? std::clamp(b.lift.y / weight, 0.0f, 1.0f) : 0.0f;
        b.submerged += 0.05f * (share - b.submerged);
    }
}

void RigidBodies::update_states() {
    states_.resize(bodies_.size());
    for (size_t i = 0; i < bodies_.size(); ++i) {
        const RigidBody& b = bodies_[i];
        states_[i] = BodyState{.id = b.id,
                               .shape = b.shape.kind,
                               .size = b.size,
                               .position = b.x,
                               .orientation = b.q,
                               .velocity = b.v,
                               .angular_velocity = b.w,
                               .mass = b.mass,
                               .volume = b.shape.volume,
                               .submerged_fraction = b.submerged,
                               .mesh = b.shape.mesh};
    }
}

}  // namespace mr
