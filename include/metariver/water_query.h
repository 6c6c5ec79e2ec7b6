// metariver water queries: what gameplay code and tools ask of the water of the latest
// frame. The surface height, depth and flow velocity at a point (x, z); the flow velocity
// at a 3D point; a ray's first hit on the water surface. Each has a brute-force twin
// (every particle, every triangle) that the tests compare it with.
#pragma once

#include <metariver/core.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace mr {

class Simulation;
struct SceneView;

/// The water at a point (x, z) of the ground plane.
struct WaterSample {
    /// The vertical line at (x, z) crosses the water surface (at least one triangle of the
    /// surface mesh lies over or under the point).
    bool wet = false;
    /// The highest crossing of the vertical line with the surface mesh, metres (world y);
    /// the terrain's height there when not wet.
    float surface_y = 0.0f;
    /// surface_y minus the terrain's height (Terrain::height_mesh) at (x, z), metres, >= 0;
    /// 0 when not wet.
    float depth = 0.0f;
    /// The flow at the surface: velocity_at((x, surface_y, z)), m/s; zero when not wet.
    Vec3 velocity{0.0f};
};

/// A ray's first hit on the water surface mesh.
struct WaterRayHit {
    bool hit = false;
    float t = 0.0f;       ///< distance along the (normalised) direction, metres
    Vec3 point{0.0f};     ///< origin + t * direction
    Vec3 normal{0.0f};    ///< the hit triangle's geometric normal, unit, facing the ray's origin
    uint32_t triangle = 0;  ///< index of the hit triangle in the surface mesh (indices / 3)
};

/// Queries over one frame of a Simulation's water: the surface mesh (Simulation::surface())
/// and the particles (Simulation::particles()) or the heightfield water. Build it once per
/// frame with update() (its cost: a grid of the surface's triangles and one of the active
/// particles, linear in both, and a copy of a heightfield water's grid; the terrain (its
/// height_mesh gives the depth) is copied only when its Terrain::revision() changed: the
/// first update, a sculpt or undo, another Simulation; buffers are reused from frame to
/// frame); then every query is const and safe to call from several
/// threads at once. Results describe the frame update() saw until the next update().
/// Measured on the default river at frame 600 (27,604 triangles, 1,487 particles; one
/// thread of a 2-vCPU AMD EPYC guest, docs/benchmarks.md "Water queries"): update() 1.1 ms;
/// a query: sample 76 ns, velocity_at 16 ns, raycast 0.84 us (the twins: 272 us, 2.4 us,
/// 361 us). A non-finite input answers "not wet" (surface_y 0), zero velocity, no hit;
/// in a batch only that point does (the C API and Python answer so too, with no error).
class WaterQuery {
public:
    WaterQuery();
    ~WaterQuery();
    WaterQuery(WaterQuery&&) noexcept;
    WaterQuery& operator=(WaterQuery&&) noexcept;

    /// Takes the latest frame of `sim` (copies what the queries need; `sim` may step on).
    void update(const Simulation& sim);

    /// The water at (x, z); not wet outside the surface.
    WaterSample sample(float x, float z) const;
    /// The flow velocity at p: the kernel-weighted mean, weight (1 - r^2/R^2)^3, of the
    /// velocities of the active particles within R = flow_radius(def) of p (the
    /// heightfield's velocity at (p.x, p.z) where its water is wet there); zero when none.
    Vec3 velocity_at(const Vec3& p) const;
    /// The first hit of the ray origin + t * direction, 0 <= t <= max_t, on the surface
    /// mesh (either side of a triangle). `direction` need not be unit; zero: no hit.
    WaterRayHit raycast(const Vec3& origin, const Vec3& direction, float max_t) const;

    /// Batches of the three (parallel over the points; out.size() must equal the input's:
    /// otherwise the shorter is answered and the rest of `out` set to not wet / zero / no hit).
    void sample(std::span<const float> xz, std::span<WaterSample> out) const;
    void velocity_at(std::span<const Vec3> points, std::span<Vec3> out) const;
    void raycast(std::span<const Vec3> origins, std::span<const Vec3> directions, float max_t,
                 std::span<WaterRayHit> out) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// The brute-force twins the tests and the bench compare with: every triangle, every
/// active particle, no acceleration structure.
WaterSample sample_water_brute(const Simulation& sim, float x, float z);
Vec3 water_velocity_brute(const Simulation& sim, const Vec3& p);
WaterRayHit raycast_water_brute(const Simulation& sim, const Vec3& origin, const Vec3& direction, float max_t);

}  // namespace mr
