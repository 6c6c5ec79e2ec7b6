// The rigid-body solver the PBF water is coupled with (bodies.h): position-based rigid
// bodies after Mueller et al. 2020 ("Detailed rigid body simulation with extended position
// based dynamics"): each substep predicts the poses (gravity), the water's reactions and the
// contacts (terrain, other bodies) correct the predicted poses with the generalized inverse
// masses, and the velocities are the poses' change over the substep. Friction is Coulomb's
// at the position level (static while the tangential slip is below friction x the normal
// correction). Serial and in a fixed order: the same result for any thread count.
#pragma once

#include <metariver/terrain.h>

#include "rigid_shapes.h"

#include <span>
#include <vector>

namespace mr {

struct RigidBody {
    uint32_t id = 0;
    RigidShape shape;
    Vec3 size{0.0f};  ///< BodyDef::size
    float density = 500.0f, friction = 0.5f;
    float mass = 0.0f, inv_mass = 0.0f;
    glm::mat3 inv_inertia_local{0.0f};
    Vec3 x{0.0f}, v{0.0f}, w{0.0f};  ///< centre of mass, velocity, angular velocity (world)
    glm::quat q{1, 0, 0, 0};
    Vec3 x_prev{0.0f};                ///< at the substep's start
    glm::quat q_prev{1, 0, 0, 0};
    Vec3 lift{0.0f};                  ///< the water's position-level impulses this substep (kg m)
    float submerged = 0.0f;           ///< share under the water (the buoyancy measured, smoothed)

    glm::mat3 inv_inertia_world() const {
        const glm::mat3 R = glm::mat3_cast(q);
        return R * inv_inertia_local * glm::transpose(R);
    }
    Vec3 to_world(const Vec3& local) const { return x + q * local; }
    Vec3 to_local(const Vec3& world) const { return glm::conjugate(q) * (world - x); }
    /// Signed distance of a world point and the outward normal there (world).
    float sdf(const Vec3& world, Vec3& normal) const {
        Vec3 n;
        const float d = shape.sdf(to_local(world), n);
        normal = q * n;
        return d;
    }
    /// sdf()'s distance alone (the same value, cheaper).
    float distance(const Vec3& world) const { return shape.distance(to_local(world)); }
    /// True when the bounding ball alone shows `world` at least `pad` outside the body, so
    /// that sdf() would give >= pad (the margin outgrows its rounding): a cheap test first.
    /// Primitives only: a mesh's distance outside is a lower bound (false for them).
    bool outside_by(const Vec3& world, float pad) const {
        if (shape.kind == BodyShape::ConvexMesh || shape.kind == BodyShape::TriangleMesh) return false;
        const Vec3 d = world - x;
        const float r = (shape.bound + pad) * 1.0001f + 1e-5f;
        return glm::dot(d, d) > r * r;
    }
    /// A position-level impulse p (kg m) at world point at.
    void apply(const Vec3& p, const Vec3& at);
    /// Generalized inverse mass along n at world point at.
    float inv_mass_along(const Vec3& n, const Vec3& at) const;
};

class RigidBodies {
public:
    Result<uint32_t> add(const BodyDef& def);
    Status remove(uint32_t id);
    Status set_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                      const Vec3& angular_velocity);
    bool empty() const { return bodies_.empty(); }
    size_t size() const { return bodies_.size(); }
    std::vector<RigidBody>& all() { return bodies_; }
    const std::vector<RigidBody>& all() const { return bodies_; }

    /// Substep start: gravity and the predicted poses.
    void predict(float dt, float gravity);
    /// After the water's iterations: terrain and body-body contacts.
    void contacts(const Terrain& terrain, float dt);
    /// Substep end: the velocities from the poses' change, the submerged share measured.
    void velocities(float dt, float gravity);
    /// The states after a frame (rebuilt by update_states()).
    std::span<const BodyState> states() const { return states_; }
    void update_states();

private:
    void terrain_contacts(const Terrain& terrain, float dt);
    void body_contacts();
    std::vector<RigidBody> bodies_;
    std::vector<BodyState> states_;
    uint32_t next_id_ = 1;
};

}  // namespace mr
