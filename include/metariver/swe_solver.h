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
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace mr {

class Terrain;  // terrain.h

/// swe.discharge, swe.time_scale, swe.init_max_time = "auto" (resolved by the solver).
inline constexpr float kSweAuto = -1.0f;
/// swe.discharge = "auto": the discharge of uniform (Manning) flow kSweRiverDepth deep over
/// one cell's width on the main channel's mean slope (a river at least a cell wide, at any scale).
inline constexpr float kSweRiverDepth = 0.3f;  ///< metres
/// The least slope that rule and the steady spin-up take (a flat map).
inline constexpr float kSweLeastSlope = 1e-3f;
/// swe.init_max_time = "auto": this many times the main channel's length (at least half the
/// map's diagonal) over 0.5 m/s.
inline constexpr float kSweInitCrossings = 8.0f;
/// swe.init_max_time = "auto" is also at least this many residence times: the volume the
/// map holds over the inflow per second (a lake's level or a sheet settles over it: the
/// procedural flat map's sheet over 14 of them).
inline constexpr double kSweInitResidences = 20.0;
/// swe.init_max_work's default: the steady spin-up stops after this many cell updates
/// whatever its time cap (a warning; about a minute on two cores), and after one substep per
/// kSweInitCellUpdatesPerSubstep of them (1,200,000 by default: they bound a map of few wet
/// cells, whose substeps cost more than their cells; western_usa at real scale needed more
/// than 400,000).
inline constexpr uint64_t kSweInitMaxCellUpdates = 6'000'000'000;
inline constexpr uint64_t kSweInitCellUpdatesPerSubstep = 5000;
inline constexpr uint64_t kSweInitMaxSubsteps = kSweInitMaxCellUpdates / kSweInitCellUpdatesPerSubstep;

/// How the water starts (swe.init).
enum class SweInit {
    Dry,     ///< the map dry (or the lake of initial_level)
    Steady,  ///< spun up before frame 0 until what leaves matches what comes in
};
std::string_view to_string(SweInit i);

/// What the map's four edges are (swe.edges).
enum class SweEdges {
    Open,     ///< transmissive: the state outside copies the edge cell's
    Outfall,  ///< a free overfall: the water leaves at its critical depth, nothing comes in
};
std::string_view to_string(SweEdges e);

/// [[swe.sources]]: a discharge at a point or spread evenly over the cells of a line.
enum class SweSourceShape { Point, Line };
std::string_view to_string(SweSourceShape s);
/// Most entries of [[swe.sources]] and of [[swe.sinks]].
inline constexpr size_t kMaxSweSources = 64;
struct SweSource {
    SweSourceShape shape = SweSourceShape::Point;
    Vec3 start{0.0f};  ///< metres (x, z; y unused): the point, or the line's first end
    Vec3 end{0.0f};    ///< the line's other end (Line only)
    float discharge = 1.0f;  ///< m^3/s
    bool operator==(const SweSource&) const = default;
};
/// [[swe.sinks]]: removes up to `discharge` m^3/s from the cells within `radius` of
/// `center` (0: the one cell under it), never more than they hold.
struct SweSink {
    Vec3 center{0.0f};
    float radius = 0.0f;
    float discharge = 1.0f;
    bool operator==(const SweSink&) const = default;
};

/// [swe]: the shallow-water solver's keys (solver = "swe").
struct SweDef {
    float manning = 0.03f;         ///< Manning's n, s/m^(1/3) (0.03: a natural channel); 0: frictionless
    float cfl = 0.45f;             ///< Courant number of the adaptive time step, (0, 0.5]
    float dry_depth = 1e-3f;       ///< metres: shallower water has no velocity
    bool second_order = true;      ///< MUSCL + Heun (false: first order, half the cost)
    /// The main source, m^3/s at source_center; 0: none; kSweAuto: the river rule above
    /// (kSweRiverDepth) unless the scene has initial_level or [[swe.sources]] (then 0).
    float discharge = kSweAuto;
    /// Metres (x, z; y unused): where the source pours. auto_source: the particle source's
    /// resolved centre (particles.spawn_center, the head of the main channel by default).
    Vec3 source_center{0.0f};
    bool auto_source = true;
    float rain = 0.0f;             ///< mm/h over the whole map (or the circle below)
    /// Metres (x, z): with rain_radius > 0, rain falls only within rain_radius of it.
    Vec3 rain_center{0.0f};
    float rain_radius = 0.0f;      ///< metres; 0: the whole map
    /// A grayscale PNG (path; "" none) over the whole map: each cell's rain is swe.rain times
    /// the image's value there (0 black .. 1 white, the first channel), the image stretched
    /// over the grid (bilinear) when its size differs. With rain_radius too: both apply.
    std::string rain_mask;
    /// Simulated seconds per second of frame time; kSweAuto: area_scale (1 at 1 m per
    /// sample; a km-cell DEM runs hours a second).
    float time_scale = 1.0f;
    SweInit init = SweInit::Dry;
    /// The map's edges (docs/shallow-water.md, "The map's edges"): an outfall by default (an
    /// open edge left rivers over flat floors pooling against it).
    SweEdges edges = SweEdges::Outfall;
    /// Steady spin-up: stops when |outflow + sunk - inflow| over a window is below this share
    /// of the inflow (and the storage's change too).
    float init_tolerance = 0.005f;
    /// Steady spin-up: simulated seconds at most; kSweAuto: kSweInitCrossings x the main
    /// channel's length over 0.5 m/s.
    float init_max_time = kSweAuto;
    /// Steady spin-up: cell updates it spends at most (its wall time), and one substep per
    /// kSweInitCellUpdatesPerSubstep of them, whatever init_max_time says.
    float init_max_work = float(kSweInitMaxCellUpdates);
    /// Metres (terrain height): cells whose bed lies below it are the sea, a sink that takes
    /// every drop reaching it (counted as sunk); NaN: none. On a DEM at --real-scale the sea
    /// is at -metres_min of its sidecar.
    float sea_level = std::nanf("");
    std::vector<SweSource> sources;  ///< [[swe.sources]]
    std::vector<SweSink> sinks;      ///< [[swe.sinks]]
    /// Metres: a still lake up to this level at the start (every sample below it wet);
    /// NaN: the map starts dry.
    float initial_level = std::nanf("");
    /// Metres: with initial_level, the lake only where z >= dam_z (held upstream by a dam
    /// across the map at z = dam_z that is gone at the start: a dam break); NaN: everywhere.
    float dam_z = std::nanf("");
};

/// Volumes in m^3 since the solver was made.
struct SweBalance {
    double initial = 0.0, inflow = 0.0, rain = 0.0, outflow = 0.0, sunk = 0.0, stored = 0.0;
    double exchanged = 0.0;  ///< net volume other solvers put in (the hybrid), negative: taken
    /// initial + inflow + rain + exchanged - outflow - sunk - stored (round-off).
    double error() const { return initial + inflow + rain + exchanged - outflow - sunk - stored; }
};

/// swe.rain_mask read and stretched over a grid of `columns` x `rows` cells: a weight in
/// [0, 1] per cell (row-major, column fastest); an error naming the key and the file when
/// the image cannot be read.
Result<std::vector<double>> load_rain_mask(const std::string& path, int columns, int rows);

/// What the steady spin-up (swe.init = "steady") did before frame 0.
struct SweInitReport {
    bool ran = false;
    bool converged = false;       ///< within init_tolerance before the cap
    double simulated_s = 0.0;     ///< simulated seconds spun up
    double wall_ms = 0.0;         ///< what it cost
    uint64_t substeps = 0;
    uint64_t cell_updates = 0;
    bool work_capped = false;          ///< stopped by swe.init_max_work, not by the time cap
    double outflow_over_inflow = 0.0;  ///< (outflow + sunk) / (inflow + rain) over the last window
};

namespace swe {
class ShallowWater;
struct PointSource;
struct Lake;
class LakeLevels;
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
    /// Interaction (swe_edit.cpp): pours count x kPourVolume m^3 at once over the cells
    /// within kPourRadius cells of `center` (counted as inflow in balance()); pushes
    /// the wet cells within `radius` (2D) by velocity x (1 - (d / radius)^2)^2 (returns
    /// how many); a sculpted bed reaches the core, each cell keeping its depth.
    static constexpr double kPourVolume = 0.125;  // m^3: a particle of the default river (0.5 m)
    static constexpr double kPourRadius = 2.0;
    void pour(const Vec3& center, int count) override;
    /// The main source follows the particle source's centre (Simulation::move_source, the
    /// viewer's move source) while swe.source_center is auto; a set centre stays.
    void set_spawn_center(const Vec3& center) override;
    size_t push(const Vec3& center, float radius, const Vec3& velocity) override;
    void terrain_edited(const Terrain& terrain, int i0, int i1, int j0, int j1) override;

    /// Rain per cell set at run time (Simulation::set_rain, the C API's mr_world_set_rain):
    /// mm/h, row-major like HeightfieldWater (rows x columns values, each finite in
    /// [0, kMaxRainRate]). It replaces swe.rain, rain_center, rain_radius and rain_mask
    /// until an empty span clears it (the scene's rain again); live edits keep it. Error
    /// naming `mm_per_h` (its size or the first bad value; nothing changed). O(cells).
    static constexpr float kMaxRainRate = 1e4f;  // mm/h, swe.rain's range
    Status set_rain(std::span<const float> mm_per_h);
    /// Whether set_rain's rates are in force.
    bool rain_set() const { return !rain_rates_.empty(); }
    /// Live edit of friction, CFL, dry depth, order, discharge, rain, the time scale, the
    /// sources and sinks (the initial lake and swe.init need a new solver: false, nothing
    /// changed).
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
    /// step_frame without showing the new state: for a solver that changes the core after
    /// the step and calls refresh() (the hybrid; publishing twice cost it 5 us a frame).
    void advance_frame(float frame_dt);
    /// swe.discharge and swe.time_scale with "auto" resolved.
    float discharge() const { return discharge_; }
    float time_scale() const { return time_scale_; }
    /// Simulated seconds since frame 0 (the spin-up not counted).
    double simulated_s() const;
    /// The main channel from the source's cell to where it leaves the map (the drainage
    /// network's D8 path): its length (m) and mean slope (at least kSweLeastSlope).
    float channel_length() const { return channel_length_; }
    float channel_slope() const { return channel_slope_; }
    const SweInitReport& init_report() const { return init_; }

private:
    void apply_def();
    /// The core's rain from set_rain's rates, else the scene's rain keys.
    void apply_rain();
    void publish();
    void spin_up(swe::LakeLevels& lakes);
    /// swe.init = "steady": the depressions the sources' water can reach (every one under
    /// rain over the whole map) start full to their spill level, as a steady river leaves them.
    /// `starts`: the sources' cells (column, row). Returns the lakes it filled.
    std::vector<swe::Lake> fill_depressions(const std::vector<std::pair<int, int>>& starts);
    void add_sources(std::vector<swe::PointSource>& out) const;

    SweDef def_;
    Vec3 source_{0.0f};
    std::unique_ptr<swe::ShallowWater> core_;
    HeightfieldWater water_;
    SolverCounters counters_;
    uint64_t frame_ = 0, last_substeps_ = 0, init_substeps_ = 0;
    int source_i_ = -1, source_j_ = -1;
    float discharge_ = 0.0f, time_scale_ = 1.0f;
    float channel_length_ = 0.0f, channel_slope_ = kSweLeastSlope;
    double start_time_ = 0.0;  ///< the core's time at frame 0
    SweInitReport init_;
    double poured_ = 0.0;  ///< m^3 pour() added (inflow)
    std::string mask_path_;           ///< the swe.rain_mask mask_ was read from
    std::vector<double> mask_;        ///< its weight per cell (empty: none, or unreadable)
    std::string mask_error_;          ///< why it could not be read (a warning)
    std::vector<float> rain_rates_;   ///< set_rain's mm/h per cell (empty: the scene's rain)
};

}  // namespace mr
