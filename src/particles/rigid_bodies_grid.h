// Rigid bodies floating on a heightfield's water (solver = "swe" and "hybrid"; bodies.h):
// the same position-based bodies as PBF's (rigid_bodies.h: gravity, terrain and body-body
// contacts with friction), pushed by the grid's water through forces computed from the
// water's surface and velocity, one way:
//  - buoyancy: each body is cut into cells (kGridCellsPerAxis per axis of its box, the
//    cells whose centre lies inside the shape, their volumes scaled to the shape's); a
//    cell's submerged share is its vertical extent under the water's level there (bed +
//    depth, bilinear over the wet samples); the hydrostatic pressure's force on it,
//    rho_w g V_sub (-d eta/dx, 1, -d eta/dz), acts at the cell's centre (the torque
//    rights a box). Exact for a level box: its draft is (density / 1000) x its height;
//  - drag towards the water's depth-averaged velocity (vertical: 0) on the submerged part:
//    per cell rho_w V_sub (kGridDragLinear + kGridDragQuadratic / L |u_rel|) u_rel, L the
//    body's size (volume^(1/3)); taken implicitly (the body's velocity relaxes towards the
//    submerged cells' weighted water velocity, any density stays stable), its angular
//    velocity damped at the same rate.
// One way: the grid's water does not feel the bodies (its depth, velocity and mass balance
// are unchanged by them). Serial and in a fixed order: the same result for any thread count.
#pragma once

#include <metariver/solver.h>

#include "rigid_bodies.h"

#include <span>
#include <vector>

namespace mr {

/// Cells per axis of a body's box for its buoyancy (5^3 = 125 at most per body).
inline constexpr int kGridCellsPerAxis = 5;
/// Drag on a body's submerged volume: kg/s per kg of water displaced (a floating body's heave
/// decays as exp(-kGridDragLinear t / 2): 1/e in one second), and its quadratic part per
/// metre of the body's size (a drag coefficient 1 over half the size's cross-section).
inline constexpr float kGridDragLinear = 2.0f;
inline constexpr float kGridDragQuadratic = 0.5f;
/// Substeps of the bodies per rendered frame (a floating body's heave at 500 kg/m^3 and
/// 0.1 m high turns 0.1 rad a substep of 1/240 s: far from the explicit step's limit of 2).
inline constexpr int kGridBodySubsteps = 4;

/// Bodies on a grid's water (Simulation's for a solver with water_heightfield() and no bodies of its own).
class GridBodies {
public:
    Result<uint32_t> add(const BodyDef& def);
    Status remove(uint32_t id);
    Status set_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                      const Vec3& angular_velocity);
    bool empty() const { return bodies_.empty(); }
    std::span<const BodyState> states() const { return bodies_.states(); }

    /// One frame of `frame_dt` seconds on the water `w` (over `terrain`'s samples: its bed).
    void step(const HeightfieldWater& w, const Terrain& terrain, float frame_dt, float gravity);

    /// The water's level (bed + depth, bilinear over the wet samples) and velocity at (x, z);
    /// false where none of the four samples around it is wet (or off the grid).
    static bool water_at(const HeightfieldWater& w, const Terrain& terrain, float x, float z, float& level, Vec3& velocity);

private:
    /// A body's volume cells in its own frame: centre (xyz) and volume (w), and the cells' half size.
    struct Cells {
        std::vector<glm::vec4> cells;
        Vec3 half{0.0f};
        float length = 1.0f;  ///< volume^(1/3), the drag's size
    };
    static Cells make_cells(const RigidShape& shape);
    /// The water's forces on body `b` over dt: velocities changed, its submerged share returned.
    float push(RigidBody& b, const Cells& c, const HeightfieldWater& w, const Terrain& terrain, float dt, float gravity) const;

    RigidBodies bodies_;
    std::vector<Cells> cells_;  ///< per body, in bodies_.all()'s order
};

}  // namespace mr
