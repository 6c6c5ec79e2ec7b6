// The shallow-water core: a finite-volume solver of the 2D Saint-Venant equations on a
// uniform cell-centred grid, driven by the "swe" solver (swe_solver.h) and by the SWASHES
// validation tests (tests/swe) on analytic beds without a Terrain.
//
// Scheme: HLL fluxes (Harten, Lax, van Leer 1983, Einfeldt's wave speeds) on the hydrostatic
// reconstruction of Audusse, Bouchut, Bristeau, Klein and Perthame 2004 (SIAM J. Sci. Comput.
// 25(6)): well balanced (a lake at rest over any bed stays at rest to round-off) and
// depth-positive; optional second order (MUSCL, minmod slopes of depth, surface and velocity,
// with Heun's SSP-RK2 in time and Audusse's centred bed-slope term). Manning friction is
// implicit (at second order in each of Heun's stages, and only Heun's average clipped at
// depth 0, so that the step stays positive and conservative at km cells and steps of 10^2-10^3 s);
// the time step is adaptive under the CFL limit.
//
// Layout: structure of arrays (bed, depth, two discharges) of doubles on a grid with one ghost
// cell on each side (the edges' conditions), row-major, row j along y (the terrain's z), and
// a second state for the stages' outputs. A stage is one sweep over the rows (swe_stage.h):
// velocities, slopes and faces live in a few rolling rows, not in arrays.
// Dry cells are skipped: each row keeps the span of columns that are wet or near wet cells of
// its own or its neighbouring rows, so a step costs the wet spans, not the grid. Chunks of rows
// run in parallel (TBB); a face row between two chunks is computed by both from the same
// inputs and every sum runs in row order, so the result is the same on any number of threads.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace mr::swe {

struct FinishRow;

/// What happens at one edge of the grid.
enum class EdgeKind {
    Wall,       ///< reflective: nothing crosses
    Open,       ///< transmissive: water leaves freely (its volume counted as outflow)
    /// A free overfall: the map ends in a drop. The ghost is a dry cell far below the edge
    /// cell, so that the face solves the wet/dry Riemann problem of Audusse's reconstruction:
    /// the flow leaves at its critical depth (a lake at rest drains at (8/27) sqrt(g) h^1.5
    /// per metre of edge) and nothing ever flows in. Counted as outflow.
    Outfall,
    // The inflow kinds last (update_spans: the whole grid is active).
    Discharge,  ///< inflow of `value` m^2/s per metre of edge (depth extrapolated)
    Depth,      ///< the depth outside held at `value` metres (velocity extrapolated)
};

struct Edge {
    EdgeKind kind = EdgeKind::Wall;
    double value = 0.0;  ///< m^2/s (Discharge) or metres (Depth)
};

struct ShallowWaterDef {
    double gravity = 9.81;      ///< m/s^2
    double cfl = 0.45;          ///< Courant number of the adaptive step, (0, 0.5]
    double dry_depth = 1e-6;    ///< metres: below it a cell's velocity is zero
    double manning = 0.0;       ///< Manning's n, s/m^(1/3); 0: no friction
    bool second_order = false;  ///< MUSCL + Heun instead of first order + Euler
    Edge west, east, south, north;  ///< x = 0, x = max, y = 0, y = max
};

/// A point source: `discharge` m^3/s into cell (i, j); negative: a sink taking up to
/// |discharge| m^3/s out of the cell, never more than it holds. A line source is a list of
/// point sources (each costs a few operations per substep).
struct PointSource {
    int i = 0, j = 0;
    double discharge = 0.0;
};

/// Volumes in m^3 since construction (or reset_balance()).
struct MassBalance {
    double initial = 0.0;   ///< stored at the start
    double inflow = 0.0;    ///< point sources and inflow edges
    double rain = 0.0;
    double exchanged = 0.0; ///< net volume added by exchange() (negative: taken)
    double outflow = 0.0;   ///< left through the edges
    double sunk = 0.0;      ///< taken by sinks (negative point sources)
    double stored = 0.0;    ///< now
    /// initial + inflow + rain + exchanged - outflow - sunk - stored: zero up to round-off.
    double error() const { return initial + inflow + rain + exchanged - outflow - sunk - stored; }
};

struct StepStats {
    uint64_t substeps = 0;      ///< time steps taken
    uint64_t cell_updates = 0;  ///< cells updated (active spans), summed over substeps
    uint64_t clipped = 0;       ///< negative depths set to zero (should stay 0)
};

class ShallowWater {
public:
    /// nx x ny cells of size dx metres; `bed` (nx * ny, row-major, i fastest) in metres.
    ShallowWater(int nx, int ny, double dx, std::span<const double> bed, const ShallowWaterDef& def);

    int nx() const { return nx_; }
    int ny() const { return ny_; }
    double dx() const { return dx_; }
    double time() const { return time_; }
    const ShallowWaterDef& def() const { return def_; }
    void set_def(const ShallowWaterDef& def) { def_ = def; }

    double bed(int i, int j) const { return z_[at(i, j)]; }
    double depth(int i, int j) const { return h_[at(i, j)]; }
    double discharge_x(int i, int j) const { return hu_[at(i, j)]; }
    double discharge_y(int i, int j) const { return hv_[at(i, j)]; }
    /// Sets a cell's state (depth >= 0, discharges in m^2/s); call balance_reset() after
    /// setting the initial state.
    void set_state(int i, int j, double depth, double qx = 0.0, double qy = 0.0);
    /// Changes a cell's bed, keeping its depth.
    void set_bed(int i, int j, double bed);

    void set_sources(std::vector<PointSource> sources) { sources_ = std::move(sources); }
    /// Rain over every cell, metres per second (ignored while a rain mask is set).
    void set_rain(double rate) { rain_ = rate; }
    /// Rain per cell, metres per second (nx * ny, row-major, i fastest; negative or
    /// non-finite rates read as 0, missing ones as 0); an empty vector: set_rain()'s rate
    /// everywhere again.
    void set_rain_mask(std::vector<double> rate);
    /// Adds `volume` m^3 to cell (i, j) with momentum (momentum_x, momentum_y) in m^4/s
    /// (volume times velocity); a negative volume takes water out, never more than the cell
    /// holds, and the momentum is scaled by the share actually moved (pass the cell's
    /// velocity times the volume to take water without changing the cell's velocity).
    /// Returns the volume moved (signed), counted in balance().exchanged. Between substeps
    /// (not during advance()); a cell outside the grid moves nothing.
    double exchange(int i, int j, double volume, double momentum_x, double momentum_y);

    /// Advances by `duration` seconds in CFL-limited substeps (the last one shortened).
    void advance(double duration);
    /// One substep of at most `max_dt` seconds; returns the step taken (0: nothing wet and
    /// nothing flowing in, time still advanced by max_dt).
    double step(double max_dt);

    const StepStats& stats() const { return stats_; }
    MassBalance balance() const;
    /// Starts the balance from the current state.
    void balance_reset();
    /// Row j's wet columns (0 <= j < ny): every cell of the row outside [first, second] has
    /// depth 0 (first > second: the whole row is dry). After a step the span is the wet
    /// cells' own; set_state(), exchange() and the sources only widen it until the next step.
    std::pair<int, int> wet_span(int j) const { return {wet_lo_[j], wet_hi_[j]}; }
    /// Sum of depth x cell area, m^3 (in row order: the same on any number of threads),
    /// over the wet spans (the dry rest adds exact zeros).
    double volume() const;
    /// Fastest wave |u| + sqrt(g h) over wet cells, m/s.
    double max_wave_speed() const;

private:
    size_t at(int i, int j) const { return static_cast<size_t>(j + 1) * stride_ + static_cast<size_t>(i + 1); }
    void fill_ghosts(std::vector<double>& h, std::vector<double>& hu, std::vector<double>& hv);
    void update_spans();
    double stable_dt();
    /// One stage from state (h, hu, hv) into `out` (see swe_stage.h); `w` weighs its edge
    /// volumes in the balance.
    void stage(int kind, std::vector<double>* const* in, std::vector<double>* const* out, double dt, double w,
               const FinishRow* finish = nullptr);
    /// Rain, friction and the wet spans over the state's active spans; then finish_tail().
    void finish_step(double dt);
    /// The rain's and the clipped depths' sums, then the sources.
    void finish_tail(double dt);
    FinishRow finish_template(double dt) const;
    /// Manning's c = dt g n^2 of a step of dt seconds.
    double manning_c(double dt) const;
    /// The point sources and sinks over dt seconds (after the step's fluxes).
    void apply_sources(double dt);
    /// Marks column i of row j wet (its span grows).
    void mark_wet(int i, int j);

    int nx_, ny_;
    double dx_;
    size_t stride_;
    ShallowWaterDef def_;
    double time_ = 0.0;
    std::vector<double> z_, h_, hu_, hv_;
    // A second state (h, hu, hv): a stage's output (Euler, Heun's first stage), zero outside
    // the columns each row wrote last (t_lo_, t_hi_), as the state is zero outside its spans.
    std::vector<double> t_[3];
    std::vector<int> t_lo_, t_hi_;
    std::vector<int> lo_, hi_;          // active span per row (lo > hi: none)
    std::vector<int> wet_lo_, wet_hi_;  // wet columns per row after the latest step
    std::vector<double> row_out_, row_in_, row_speed_;
    std::vector<uint64_t> row_clip_;
    std::vector<PointSource> sources_;
    double rain_ = 0.0;
    std::vector<double> rain_mask_;     // per cell (at()), empty: rain_ everywhere
    std::vector<int> rain_lo_, rain_hi_;  // columns with rain > 0 per row under the mask
    std::vector<double> row_rain_;        // the mask's volume per row of the latest finish_step
    MassBalance balance_;
    StepStats stats_;
};

}  // namespace mr::swe
