// metariver Bullet solver: the paper's engine-physics mode (section 2.4) on Bullet
// Physics, plus the spring forces its future work proposes.
//
// Paper: "Real-time river simulation using metaballs", 2.4: each particle is a sphere
// collider with a rigid body, the terrain a mesh collider, gravity and collisions come
// from the engine, particles do not collide with each other, no springs. Here the
// engine is Bullet 3 (Debian's libbullet-dev: single precision, single-threaded). It
// spawns through the own solvers' Emitters part (solver_parts.h) and keeps their respawn
// rules and counters, so the two compare like with like. This header includes no
// Bullet header.
#pragma once

#include <metariver/particles.h>

#include <array>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

namespace mr {

enum class BulletTerrainShape {
    Mesh,         ///< btBvhTriangleMeshShape over Terrain's own triangles (the paper's mesh collider)
    Heightfield,  ///< btHeightfieldTerrainShape over the same samples and the same diagonal split
};
std::string_view to_string(BulletTerrainShape s);

/// Bullet settings of a scene (`[bullet]` in scene files). Gravity comes from
/// IntegratorDef::gravity; the spring constants from SpringDef (used only when
/// `springs` is true: the paper's engine mode has none).
struct BulletDef {
    BulletTerrainShape terrain = BulletTerrainShape::Mesh;
    /// Collider radius of every particle, metres, (0, 1e3]. 0.5: a unit-diameter sphere.
    /// The paper does not state its colliders' size; its metaball radius (2) is a field
    /// parameter, and spheres of radius 2 on a 17 x 17 terrain would not fit its channel.
    float sphere_radius = 0.5f;
    float mass = 1.0f;            ///< kg per sphere, (0, 1e6]
    float friction = 0.5f;        ///< Bullet's default contact friction, [0, 100]
    float restitution = 0.0f;     ///< bounciness, [0, 1]
    bool particle_collisions = false;  ///< spheres collide with each other (the paper: no)
    float fixed_dt = 1.0f / 60.0f;     ///< Bullet's internal fixed step, seconds, (0, 1]
    /// stepSimulation's maxSubSteps, [0, 1000]: internal steps per frame at most (the
    /// rest of the frame time is carried over); 0 = one variable step of the frame time.
    int max_substeps = 1;
    int solver_iterations = 10;   ///< sequential-impulse iterations, [1, 1000]
    /// Continuous collision detection: a sphere moving more than half its radius in one
    /// step is swept (swept-sphere radius 0.9 x radius) and stopped at the first hit.
    bool ccd = false;
    bool sleep = true;            ///< Bullet's deactivation of resting bodies (off when springs are on)
    bool springs = false;         ///< the paper's eq. 3 as external forces each internal step
};

/// Spheres on Bullet rigid bodies against the terrain. Spawns as SpringSolver does, through
/// the same Emitters part: one activation every spawn.interval frames (all at once for
/// 0) at a random point of the spawn volume (the same draws in the same order; a point
/// less than a radius above the ground is raised to a radius above it; no flow rate,
/// one source), respawn when a sphere's centre leaves
/// the terrain's x/z rectangle or falls below its bounds, and after every internal
/// step counts particle_steps, tunneled (centre more than kTunnelEpsilon below the
/// triangle mesh), respawned and collisions (sphere-terrain contact manifolds with at
/// least one contact point: resting spheres count every step). Positions and
/// velocities are Bullet's own (not interpolated), copied to particles() after each
/// frame. Deterministic for a seed (Bullet is serial here).
class BulletSolver final : public Solver {
public:
    /// `terrain` must outlive the solver (the mesh shape references its arrays).
    BulletSolver(const Terrain& terrain, SpawnDef spawn, SpringDef springs, IntegratorDef integrator,
                 BulletDef bullet, uint32_t seed);
    ~BulletSolver() override;
    BulletSolver(const BulletSolver&) = delete;
    BulletSolver& operator=(const BulletSolver&) = delete;

    /// Activates a particle when due, then stepSimulation(dt, max_substeps, fixed_dt)
    /// with dt = integrator.fixed_dt when set, else frame_dt (integrator.substeps is
    /// not used: Bullet substeps by its own fixed step).
    void step_frame(float frame_dt) override;
    const Particles& particles() const;
    const Particles* water_particles() const override { return &particles(); }
    const SolverCounters& counters() const override;
    uint64_t frame() const override;
    void set_spawn_center(const Vec3& center) override;
    void pour(const Vec3& center, int count) override;

    /// Closest hit of the segment from -> to on the terrain collider only (spheres
    /// ignored), in world coordinates. Tests compare both terrain shapes with this.
    std::optional<Vec3> raycast_terrain(const Vec3& from, const Vec3& to) const;
    /// Triangles of the terrain collider overlapping `box`, world coordinates, as
    /// Bullet's shape hands them to its collision algorithms (the heightfield builds
    /// them from samples; tests check they are Terrain's own triangles).
    std::vector<std::array<Vec3, 3>> terrain_triangles(const Aabb& box) const;
    /// Internal Bullet steps taken so far.
    uint64_t internal_steps() const;
    /// Spheres Bullet reports active (awake), of those spawned.
    size_t awake_count() const;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace mr
