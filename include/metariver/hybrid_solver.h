// metariver hybrid solver (`solver = "hybrid"`): the shallow-water grid (swe_solver.h) and
// PBF particles (pbf_solver.h) on one terrain, after Chentanez & Mueller 2010. Where the
// grid's water leaves the ground (the bed drops by more than hybrid.drop between a wet cell
// and its neighbour in the flow's direction: a cliff or a weir's edge) the volume that flows
// over the edge becomes PBF particles at the cell's velocity, taken from the cell in the same
// frame; particles that land on the grid's water, or come to rest on the ground, go back
// into the cell under them with their horizontal momentum. Both are drawn as one surface:
// the grid as a heightfield mesh, the particles as metaballs (docs/waterfalls.md).
#pragma once

#include <metariver/core.h>
#include <metariver/solver.h>
#include <metariver/swe_solver.h>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace mr {

class Terrain;
class Bvh;
class PbfSolver;
struct PbfDef;
struct CollisionDef;
struct IntegratorDef;

/// [hybrid]: when grid water becomes particles and back (solver = "hybrid").
struct HybridDef {
    /// Where the grid sheds (docs/waterfalls.md): a face whose bed drops by more than `drop`
    /// metres to the neighbour, and either as steep as `min_grade` (drop / cell size: a cliff
    /// or a weir's edge) or, with `launch` > 0, where the flow over it leaves the ground (a
    /// body thrown at the cell's speed along the bed it arrives on falls less than the bed
    /// over the cell: 2 u^2 (drop / dx - upstream grade) >= launch x g dx). On km cells a
    /// gentle reach drops more than `drop` between neighbours; the grade and the launch
    /// scale with the cell, so it sheds nothing.
    float drop = 1.0f;           ///< metres: a smaller bed drop at a wet cell's downstream face sheds nothing
    float min_grade = 1.0f;      ///< drop / cell size: a face this steep (1: 45 degrees) sheds (a cliff)
    float launch = 1.0f;         ///< the launch number a gentler face sheds at (1: the thrown water clears the bed; 0: only cliffs)
    float min_depth = 0.02f;     ///< metres: shallower cells shed nothing
    float min_speed = 0.05f;     ///< m/s: slower flow over the edge sheds nothing
    float absorb_age = 0.2f;     ///< seconds: a particle younger than this is not absorbed (it leaves the edge first)
    float absorb_depth = 0.01f;  ///< metres: a cell this deep or deeper takes a particle at or below its surface
    float rest_speed = 0.2f;     ///< m/s: a particle slower than this on the ground is at rest
    float rest_time = 1.0f;      ///< seconds at rest on the ground before it is absorbed wherever it lies
    /// The particle budget; water that would exceed it stays on the grid. PBF steps every
    /// slot of it (sorting, sleeping), active or not: keep it near what the falls hold.
    int max_particles = 5000;
    /// A pump (0: none): each frame pump_rate x dt m^3 (at most what the cells hold) is
    /// taken from the cells whose centres lie within pump_radius of pump_from (the cell
    /// under it at least), in proportion to their water, with its velocity, and put at
    /// rest into the cell under pump_to (x and z, metres; y unused), through the grid's
    /// exchange: the total water is unchanged and a closed waterfall keeps falling
    /// (docs/waterfalls.md).
    float pump_rate = 0.0f;    ///< m^3/s
    float pump_radius = 0.0f;  ///< metres
    Vec3 pump_from{0.0f};
    Vec3 pump_to{0.0f};
};

/// Water handed over since the solver was made: volumes in m^3, horizontal momenta in
/// m^4/s (volume x velocity; x and z), counted on each side of the exchange.
struct HybridStats {
    double to_particles = 0.0;  ///< volume taken from cells into particles
    double to_grid = 0.0;       ///< volume of particles absorbed into cells
    double lost = 0.0;          ///< volume of particles that left the terrain (PBF's respawns)
    double pumped = 0.0;        ///< volume the pump moved (HybridDef::pump_rate)
    uint64_t particles_made = 0, particles_absorbed = 0;
    double cell_momentum_out[2] = {0.0, 0.0};       ///< taken from cells with that volume
    double particle_momentum_in[2] = {0.0, 0.0};    ///< given to the new particles
    double particle_momentum_out[2] = {0.0, 0.0};   ///< carried by the absorbed particles
    double cell_momentum_in[2] = {0.0, 0.0};        ///< added to the cells
};

class HybridSolver final : public Solver {
public:
    /// The grid on the terrain's samples ([swe] keys; its edges open), the particles with
    /// `pbf` (its spacing^3 is each particle's volume) and no source of their own.
    HybridSolver(const Terrain& terrain, const Bvh& bvh, const HybridDef& def, const SweDef& swe, Vec3 resolved_source,
                 const PbfDef& pbf, const CollisionDef& collision, const IntegratorDef& integrator);
    ~HybridSolver() override;
    HybridSolver(const HybridSolver&) = delete;
    HybridSolver& operator=(const HybridSolver&) = delete;

    /// Sheds water over the edges into particles, steps the grid, steps the particles,
    /// absorbs the particles that landed.
    void step_frame(float frame_dt) override;
    const SolverCounters& counters() const override { return counters_; }
    uint64_t frame() const override { return frame_; }
    const Particles* water_particles() const override;
    const HeightfieldWater* water_heightfield() const override;
    std::vector<std::string> warnings() const override;
    /// The grid's main source moves (SweSolver::set_spawn_center).
    void set_spawn_center(const Vec3& center) override { grid_->set_spawn_center(center); }

    const HybridDef& def() const { return def_; }
    /// The faces that can shed (find_edges()): those as steep as hybrid.min_grade (cliffs),
    /// and the gentler convex ones where a fast enough flow launches.
    size_t cliff_faces() const { return cliff_faces_; }
    size_t launch_faces() const { return launch_faces_; }
    const HybridStats& stats() const { return stats_; }
    const SweSolver& grid() const { return *grid_; }
    SweSolver& grid() { return *grid_; }
    const PbfSolver& particles() const { return *pbf_; }
    /// One particle's volume, m^3 (pbf.spacing^3).
    double particle_volume() const { return particle_volume_; }
    /// Grid volume + active particles x particle volume, m^3.
    double total_volume() const;
    /// Horizontal momentum of the grid plus that of the particles, m^4/s (x, z).
    std::array<double, 2> total_momentum() const;
    /// The grid's mass balance error, m^3 (initial + inflow + rain + exchanged - outflow -
    /// sunk - stored: round-off).
    double grid_balance_error() const;
    /// Volume that left the grid through the terrain's open edges, m^3.
    double grid_outflow() const;
    /// Live edit of [hybrid] and the grid's [swe] keys (false: a rebuild is needed).
    bool set_params(const HybridDef& def, const SweDef& swe, Vec3 resolved_source);

private:
    /// The cells with a face that can shed (the bed drops by more than def_.drop, as steep
    /// as def_.min_grade or convex where def_.launch is on), in row-major order, with a bit
    /// per face (kDi/kDj's order).
    void find_edges();
    void shed(float frame_dt);
    void shed_cell(int i, int j, int dir, double volume, float frame_dt);
    void absorb(float frame_dt);
    /// Moves HybridDef::pump_rate x frame_dt from pump_from's cell to pump_to's.
    void pump(float frame_dt);
    /// Adds (volume > 0) or takes (volume < 0) water with horizontal momentum (m^4/s) at
    /// cell (i, j) of the grid; returns the volume moved.
    double exchange(int i, int j, double volume, double momentum_x, double momentum_z);

    HybridDef def_;
    std::unique_ptr<SweSolver> grid_;
    std::unique_ptr<PbfSolver> pbf_;
    HybridStats stats_;
    SolverCounters counters_;
    uint64_t frame_ = 0, respawned_seen_ = 0;
    double particle_volume_ = 0.0;
    std::vector<double> owed_;       ///< per cell: volume due over its edges not yet a whole particle
    std::vector<uint8_t> sheds_;     ///< per cell: shed over an edge this frame (absorbs nothing)
    struct EdgeCell {
        int i, j;
        uint8_t faces;   ///< bit d: the bed drops by more than def_.drop towards face d
        uint8_t cliffs;  ///< bit d: ... and at least def_.min_grade steeply (sheds at any speed)
        /// Per face that is not a cliff: drop / dx less the grade the water arrives on
        /// (> 0: convex); it sheds where 2 u^2 bend >= def_.launch g dx.
        std::array<float, 4> bend;
    };
    /// Whether a face of e with the flow `along` (m/s) towards it sheds this frame.
    bool launches(const EdgeCell& e, int d, double along) const;
    std::vector<EdgeCell> edges_;    ///< from find_edges(): the every-cell scan done once
    std::vector<float> rest_time_;   ///< per particle id: seconds at rest on the ground
    std::vector<Vec3> new_pos_, new_vel_;
    uint64_t shed_count_ = 0;        ///< particles made so far (their placement's sequence)
    size_t cliff_faces_ = 0, launch_faces_ = 0;
    float gravity_ = 9.81f;          ///< m/s^2: the launch rule's
};

}  // namespace mr
