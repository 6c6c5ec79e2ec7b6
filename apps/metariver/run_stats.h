// What `metariver run` measures of the river while it runs and writes with --stats: the
// outflow at the sinks and per outlet, the wet-channel, spray and coverage fractions,
// the largest speed and density error, and the stats JSON built from them and the
// Simulation's final state (docs: the `run --stats` keys).
#pragma once

#include <metariver/checkpoints.h>
#include <metariver/emitters.h>
#include <metariver/scene.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <span>
#include <string>

namespace mr::app {

/// The river's plausibility over a run of `frames` frames: outflow at the sinks, exits
/// per outlet (issue 10), wet-channel and spray fractions and the main channel's coverage
/// (sampled every 10 frames over the second half; spray and coverage also at the last
/// frame), the largest speed and density error seen.
class RiverMeter {
public:
    RiverMeter(const Simulation& sim, long long frames);
    /// After frame `frame` (0-based), which ended at `time_s` simulated seconds.
    void record(const Simulation& sim, long long frame, double time_s);

    const FlowMeter& flow() const { return flow_; }
    const OutletMeter& outlets() const { return outlets_; }
    double wet_fraction() const { return wet_n_ ? wet_sum_ / double(wet_n_) : 0.0; }
    double density_error_mean() const { return wet_n_ ? density_mean_sum_ / double(wet_n_) : 0.0; }
    double spray_fraction() const { return spray_sum_ / double(std::max(spray_n_, 1LL)); }
    double channel_coverage() const { return coverage_sum_ / double(std::max(spray_n_, 1LL)); }
    float max_speed() const { return max_speed_; }
    float density_error_max() const { return density_max_; }
    /// The solver's time over every recorded frame (FrameTimings::simulate_ms), ms.
    double simulate_ms_total() const { return simulate_ms_total_; }
    /// Time steps of the busiest frame (a heightfield solver's CFL substeps; 0 for others).
    uint64_t max_substeps() const { return max_substeps_; }
    /// swe and the hybrid's grid: the balance and simulated time at the start of the second
    /// half and of the last quarter of the run (the rates of outflow over inflow and of
    /// storage); `lost`: the hybrid's particle volume lost off the terrain by then, m^3.
    struct SweMark {
        SweBalance balance;
        double time_s = 0.0;
        double lost = 0.0;
    };
    const SweMark& swe_half() const { return swe_half_; }
    const SweMark& swe_quarter() const { return swe_quarter_; }
    /// The hybrid: simulated seconds at the end of the first frame whose water left the map
    /// (the grid's edges and sinks, particles lost); -1 while none has.
    double first_grid_outflow_s() const { return first_grid_outflow_s_; }

private:
    long long frames_;
    FlowMeter flow_;
    OutletMeter outlets_;
    double wet_sum_ = 0.0, density_mean_sum_ = 0.0, spray_sum_ = 0.0, coverage_sum_ = 0.0;
    long long wet_n_ = 0, spray_n_ = 0;
    float max_speed_ = 0.0f, density_max_ = 0.0f;
    double simulate_ms_total_ = 0.0;
    uint64_t max_substeps_ = 0;
    SweMark swe_half_, swe_quarter_;
    double first_grid_outflow_s_ = -1.0;
};

/// The bodies after the last frame (bodies.h, from SceneView::bodies): count, mean
/// submerged fraction and speed, the largest speed, the inside_bodies counter (`inside`)
/// and one entry per body (id, shape, position, speed, submerged fraction, mass).
nlohmann::json bodies_json(std::span<const BodyState> bodies, uint64_t inside);

/// The run as `run --stats` writes it: the scene, the final state, the plausibility
/// (`meter`), the state hash and the stage times (`stage_ms`: driver.h's columns).
nlohmann::json run_stats_json(const Simulation& sim, const RiverMeter& meter, const Checkpoints& stage_ms,
                              long long frames, double dt);

/// The shallow-water grid's block of the stats (solver = "swe", and the hybrid's grid: the
/// balance, wet cells, substeps, the spin-up) and the hybrid's hand-over block; null for the
/// particle solvers. `run --stats` and `render --stats` write both.
nlohmann::json swe_stats_json(const Simulation& sim, const RiverMeter& meter, long long frames);
nlohmann::json hybrid_stats_json(const Simulation& sim, long long frames, double dt);

/// The line `run` prints at the end: counts, plausibility and the frame time.
std::string run_summary(const Simulation& sim, const RiverMeter& meter, const Checkpoints& stage_ms, long long frames);

}  // namespace mr::app
