// metariver shallow-water solver (`solver = "swe"`): the 2D Saint-Venant equations on the
// terrain's grid, depth and velocity per sample (HeightfieldWater), from the core in
// src/swe/shallow_water.h (Audusse et al. 2004's hydrostatic reconstruction with HLL fluxes:
// well balanced, depth-positive, wetting and drying; Manning friction; adaptive CFL step).
// The terrain's edges are open (water leaves the map); a point source in m^3/s, rain in mm/h
// and a still lake up to a level set the water. Validated against SWASHES
// (docs/shallow-water.md).
#pragma once

#include <metariver/core.h>
#include <metariver/solver.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace mr {

class Terrain;  // terrain.h

/// [swe]: the shallow-water solver's keys (solver = "swe").
struct SweDef {
    float manning = 0.03f;         ///< Manning's n, s/m^(1/3) (0.03: a natural channel); 0: frictionless
    float cfl = 0.45f;             ///< Courant number of the adaptive time step, (0, 0.5]
    float dry_depth = 1e-3f;       ///< metres: shallower water has no velocity
    bool second_order = true;      ///< MUSCL + Heun (false: first order, half the cost)
    float discharge = 0.0f;        ///< the source, m^3/s at source_center; 0: none
    /// Metres (x, z; y unused): where the source pours. auto_source: the particle source's
    /// resolved centre (particles.spawn_center, the head of the main channel by default).
    Vec3 source_center{0.0f};
    bool auto_source = true;
    float rain = 0.0f;             ///< mm/h over the whole map
    /// Metres: a still lake up to this level at the start (every sample below it wet);
    /// NaN: the map starts dry.
    float initial_level = std::nanf("");
    /// Metres: with initial_level, the lake only where z >= dam_z (held upstream by a dam
    /// across the map at z = dam_z that is gone at the start: a dam break); NaN: everywhere.
    float dam_z = std::nanf("");
};

/// Volumes in m^3 since the solver was made.
struct SweBalance {
    double initial = 0.0, inflow = 0.0, rain = 0.0, outflow = 0.0, stored = 0.0;
    /// initial + inflow + rain - outflow - stored (round-off).
    double error() const { return initial + inflow + rain - outflow - stored; }
};

namespace swe {
class ShallowWater;
}

class SweSolver final : public Solver {
public:
    /// On the terrain's grid (its heights as the bed, its spacing), its four edges open.
    /// `gravity`: m/s^2 (the scene's integrator.gravity).
    SweSolver(const Terrain& terrain, const SweDef& def, Vec3 resolved_source, float gravity = 9.81f);
    ~SweSolver() override;
    SweSolver(const SweSolver&) = delete;
    SweSolver& operator=(const SweSolver&) = delete;

    /// Advances frame_dt seconds in CFL substeps (counted in counters().substeps).
    void step_frame(float frame_dt) override;
    const SolverCounters& counters() const override { return counters_; }
    uint64_t frame() const override { return frame_; }
    const HeightfieldWater* water_heightfield() const override { return &water_; }
    std::vector<std::string> warnings() const override;

    /// Live edit of friction, CFL, dry depth, order, discharge and rain (the source's
    /// place and the initial lake need a new solver: false, nothing changed).
    bool set_params(const SweDef& def, Vec3 resolved_source);
    SweBalance balance() const;
    const SweDef& def() const { return def_; }
    /// Time steps of the latest step_frame.
    uint64_t last_substeps() const { return last_substeps_; }
    /// The core, for a solver that exchanges water with the grid between frames (the
    /// hybrid solver); call refresh() after changing its state.
    swe::ShallowWater& core() { return *core_; }
    const swe::ShallowWater& core() const { return *core_; }
    /// Shows the core's current state in water_heightfield().
    void refresh() { publish(); }

private:
    void apply_def();
    void publish();

    SweDef def_;
    Vec3 source_{0.0f};
    std::unique_ptr<swe::ShallowWater> core_;
    HeightfieldWater water_;
    SolverCounters counters_;
    uint64_t frame_ = 0, last_substeps_ = 0;
    int source_i_ = -1, source_j_ = -1;
};

}  // namespace mr
