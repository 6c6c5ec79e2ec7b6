// `metariver run`'s measurements and its --stats JSON (run_stats.h).
#include "run_stats.h"

#include "driver.h"

#include <metariver/foam.h>
#include <metariver/hybrid_solver.h>
#include <metariver/io.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>
#include <vector>

namespace mr::app {

namespace {

using json = nlohmann::json;

/// The shallow-water grid of the run: the swe solver itself or the hybrid's; null for the
/// particle solvers.
const SweSolver* grid_of(const Simulation& sim) {
    if (const auto* h = dynamic_cast<const HybridSolver*>(&sim.solver())) return &h->grid();
    return dynamic_cast<const SweSolver*>(&sim.solver());
}

/// Volume that left the map so far, m^3: the grid's open edges and sinks, and for the
/// hybrid the particles lost off the terrain.
double left_the_map(const SweBalance& b, double lost) { return b.outflow + b.sunk + lost; }

/// The hybrid's outflow, by volume: the grid's edges and sinks and the particles lost, in
/// m^3 since the start and per second over the second half, and over the second half's
/// inflow (the swe block's outflow_over_inflow, with the particles lost).
struct HybridOutflow {
    double m3 = 0.0, m3_per_s = 0.0, over_inflow = 0.0;
};

std::optional<HybridOutflow> hybrid_outflow(const Simulation& sim, const RiverMeter& m) {
    const auto* h = dynamic_cast<const HybridSolver*>(&sim.solver());
    if (!h) return std::nullopt;
    const SweBalance b = h->grid().balance();
    const RiverMeter::SweMark& half = m.swe_half();
    const double out = left_the_map(b, h->stats().lost), out_half = out - left_the_map(half.balance, half.lost);
    const double in_half = b.inflow - half.balance.inflow + b.rain - half.balance.rain;
    const double seconds = h->grid().simulated_s() - half.time_s;
    return HybridOutflow{out, seconds > 0.0 ? out_half / seconds : 0.0, in_half > 0.0 ? out_half / in_half : 0.0};
}

/// One entry per outlet: cell [row, col], position [x, z] (metres), drainage cells,
/// particles over the run, rate over the second half, whether it is the main channel's.
json outlets_json(const OutletMeter& m, const OutletMeter::Summary& s) {
    json a = json::array();
    for (size_t k = 0; k < m.outlets().size(); ++k) {
        const OutletMeter::Outlet& o = m.outlets()[k];
        a.push_back({{"cell", {o.row, o.column}},
                     {"position", {o.x, o.z}},
                     {"accumulation", o.accumulation},
                     {"particles", s.outlets[k].particles},
                     {"rate_per_s", s.outlets[k].rate},
                     {"main", o.main}});
    }
    return a;
}

/// The main outlet's rate over the second half over the inflow every source asked for
/// (not capped); 0 without inflow.
double outflow_over_inflow(const Simulation& sim, const OutletMeter::Summary& os) {
    const double inflow = sim.def().spawn.total_particles_per_second();
    return inflow > 0.0 ? os.main.rate / inflow : 0.0;
}

json terrain_json(const Terrain& t) {
    const ConditionReport& cond = t.condition_report();
    return {{"columns", t.columns()},
            {"rows", t.rows()},
            {"triangles", t.triangle_count()},
            {"area_scale", t.area_scale()},
            {"condition",
             {{"mode", std::string(to_string(cond.mode))},
              {"cells_raised", cond.cells_raised},
              {"cells_lowered", cond.cells_lowered},
              {"max_change_m", cond.max_change_m},
              {"volume_m3", cond.volume_m3}}}};
}

json plausibility_json(const Simulation& sim, const RiverMeter& m) {
    const SolverCounters& c = sim.counters();
    const FlowMeter::Summary fs = m.flow().summary();
    const OutletMeter::Summary os = m.outlets().summary();
    const Percentiles final_speed = percentiles(sim.active_speeds());
    json j = {{"tunneled", c.tunneled},
            {"guarded", c.guarded},
            {"inside_bodies", c.inside_bodies},
            {"respawned", c.respawned},
            {"emitted", c.emitted},
            {"sunk", c.sunk},
            {"outflow_per_s", fs.rate},
            {"outflow_windows_per_s", {fs.windows[0], fs.windows[1], fs.windows[2], fs.windows[3]}},
            {"first_outflow_s", fs.first_outflow_s},
            {"outflow_steady", fs.steady},
            {"wet_channel_fraction", m.wet_fraction()},
            {"density_error_mean", m.density_error_mean()},
            {"density_error_max", m.density_error_max()},
            {"max_speed", m.max_speed()},
            {"final_speed", {{"median", final_speed.median}, {"p95", final_speed.p95}, {"max", final_speed.max}}},
            {"spray_fraction", m.spray_fraction()},
            {"outflow_over_inflow", outflow_over_inflow(sim, os)},
            {"time_to_outlet_s", os.main.first_s},
            {"channel_coverage", m.channel_coverage()},
            {"main_channel_cells", sim.main_channel().size()},
            {"main_channel", sim.main_channel()},  // [row, column] from the source to the outlet
            {"outlets", outlets_json(m.outlets(), os)},
            {"outlet_other", {{"particles", os.other.particles}, {"rate_per_s", os.other.rate}}}};
    // The hybrid's water leaves through the grid's edges, not as particles at sinks: its
    // outflow by volume, and the first outflow and the ratio over inflow by volume too.
    if (const std::optional<HybridOutflow> h = hybrid_outflow(sim, m)) {
        j["outflow_m3"] = h->m3;
        j["outflow_m3_per_s"] = h->m3_per_s;
        j["outflow_over_inflow"] = h->over_inflow;
        j["first_outflow_s"] = m.first_grid_outflow_s();
    }
    return j;
}

/// Diffuse particles at the last frame ([foam], issue 11), and the potentials of the
/// active fluid particles (what the [foam] thresholds are set against); null when off.
json foam_json(const Simulation& sim) {
    const FoamSystem* f = sim.foam();
    if (!f) return nullptr;
    const FoamStats& fs = f->stats();
    json j = {{"spray", fs.spray},
              {"foam", fs.foam},
              {"bubbles", fs.bubbles},
              {"total", fs.total()},
              {"max_particles", sim.def().foam.max_particles},
              {"generated_total", fs.generated_total},
              {"capped_total", fs.capped_total}};
    const Particles& fp = sim.particles();
    auto potential = [&](std::span<const float> v) {
        std::vector<double> a;
        for (size_t i = 0; i < v.size(); ++i)
            if (fp.active[i]) a.push_back(double(v[i]));
        const Percentiles q = percentiles(std::move(a));
        return json{{"median", q.median}, {"p95", q.p95}, {"max", q.max}};
    };
    j["potentials"] = {{"trapped_air", potential(f->trapped_air())},
                       {"wave_crest", potential(f->wave_crest())},
                       {"kinetic_energy", potential(f->kinetic_energy())}};
    return j;
}

json stage_ms_json(const Simulation& sim, const Checkpoints& stage_ms) {
    json j = {{"simulate", stage_json(stage_ms.column(kStageSimulate))},
              {"field", stage_json(stage_ms.column(kStageField))},
              {"surface", stage_json(stage_ms.column(kStageSurface))},
              {"total", stage_json(stage_ms.column(kStageTotal))}};
    if (sim.foam()) j["foam"] = stage_json(stage_ms.column(kStageFoam));
    // Part of surface (not in total).
    if (smoothing_on(sim.def())) j["smoothing"] = stage_json(stage_ms.column(kStageSmoothing));
    return j;
}

/// The shallow-water grid's numbers (solver = "swe", and the hybrid's grid); null for the
/// particle solvers. Volumes in m^3 since the start (exchanged: net volume the hybrid's
/// particles gave the grid, negative: taken); balance_error_relative: (initial + inflow +
/// rain + exchanged - outflow - sunk - stored) over what came in (initial + inflow + rain).
json swe_json(const Simulation& sim, const RiverMeter& m, long long frames) {
    const SweSolver* swe = grid_of(sim);
    if (!swe) return nullptr;
    const HeightfieldWater& w = *swe->water_heightfield();
    const float dry = swe->def().dry_depth;
    const auto wet = std::count_if(w.depth.begin(), w.depth.end(), [&](float h) { return h > dry; });
    const SweBalance b = swe->balance();
    const double in = b.initial + b.inflow + b.rain;
    const SolverCounters& c = sim.counters();
    const double seconds = m.simulate_ms_total() / 1000.0;
    // The river's columns: over the second half, what left (edges and sinks) over what came
    // in; over the last quarter, the storage's change over what came in (steady: <= 1 %).
    const auto came_in = [&](const SweBalance& from) { return b.inflow - from.inflow + b.rain - from.rain; };
    const double in_half = came_in(m.swe_half().balance), in_quarter = came_in(m.swe_quarter().balance);
    const double storage = in_quarter > 0.0 ? std::abs(b.stored - m.swe_quarter().balance.stored) / in_quarter : 0.0;
    const double minutes = swe->simulated_s() / 60.0;
    const SweInitReport& init = swe->init_report();
    return {{"grid", {{"rows", w.rows}, {"columns", w.columns}, {"spacing_m", w.spacing}}},
            {"discharge_m3_s", swe->discharge()},
            {"time_scale", swe->time_scale()},
            {"simulated_s", swe->simulated_s()},
            {"channel_length_m", swe->channel_length()},
            {"channel_slope", swe->channel_slope()},
            {"outflow_over_inflow", in_half > 0.0 ? (b.outflow - m.swe_half().balance.outflow + b.sunk - m.swe_half().balance.sunk) / in_half : 0.0},
            {"storage_change_over_inflow", storage},
            {"steady", in_quarter > 0.0 && storage <= 0.01},
            {"balance_error_relative_per_min", in > 0.0 && minutes > 0.0 ? std::abs(b.error()) / in / minutes : 0.0},
            {"init", {{"mode", std::string(to_string(swe->def().init))}, {"converged", init.converged},
                      {"simulated_s", init.simulated_s}, {"wall_ms", init.wall_ms}, {"substeps", init.substeps},
                      {"cell_updates", init.cell_updates}, {"work_capped", init.work_capped},
                      {"outflow_over_inflow", init.outflow_over_inflow}}},
            {"wet_cells", wet},
            {"wet_fraction", w.size() ? double(wet) / double(w.size()) : 0.0},
            {"volume_m3", {{"initial", b.initial}, {"inflow", b.inflow}, {"rain", b.rain},
                           {"outflow", b.outflow}, {"sunk", b.sunk}, {"stored", b.stored},
                           {"exchanged", b.exchanged}}},
            {"balance_error_m3", b.error()},
            {"balance_error_relative", in > 0.0 ? std::abs(b.error()) / in : 0.0},
            {"substeps", c.substeps},
            {"substeps_per_frame", {{"mean", frames > 0 ? double(c.substeps) / double(frames) : 0.0},
                                    {"max", m.max_substeps()}}},
            {"cell_updates", c.cell_updates},
            {"cell_updates_per_s", seconds > 0.0 ? double(c.cell_updates) / seconds : 0.0},
            {"max_speed_m_s", c.max_speed}};
}

/// run's line for the grid (from swe_json): empty for the particle solvers.
std::string swe_summary(const Simulation& sim, const RiverMeter& m, long long frames) {
    const json j = swe_json(sim, m, frames);
    if (j.is_null()) return {};
    const json& v = j["volume_m3"];
    const json& init = j["init"];
    const std::string spun = init["mode"] == "steady"
                                 ? fmt::format(", spun up {:.4g} s before frame 0 in {:.0f} ms ({})", init["simulated_s"].get<double>(),
                                               init["wall_ms"].get<double>(), init["converged"].get<bool>() ? "steady" : "at its cap")
                                 : std::string();
    const double exchanged = v["exchanged"].get<double>();
    const std::string with_particles =
        dynamic_cast<const HybridSolver*>(&sim.solver()) ? fmt::format(" {:+.4g} exchanged with the particles", exchanged) : std::string();
    return fmt::format("\nswe: {} wet cells ({:.1f} %), stored {:.4g} m^3 of initial {:.4g} + inflow {:.4g} + rain {:.4g} "
                       "- outflow {:.4g} - sunk {:.4g}{}, balance error {:.2e} of what came in, {:.2f} substeps a frame (max {}), "
                       "{:.2f} M cell updates/s, {:.3g} m^3/s at the source, time scale {:.4g}, channel coverage {:.0f} %{}",
                       j["wet_cells"].get<long long>(), 100.0 * j["wet_fraction"].get<double>(),
                       v["stored"].get<double>(), v["initial"].get<double>(), v["inflow"].get<double>(),
                       v["rain"].get<double>(), v["outflow"].get<double>(), v["sunk"].get<double>(), with_particles, j["balance_error_relative"].get<double>(),
                       j["substeps_per_frame"]["mean"].get<double>(), j["substeps_per_frame"]["max"].get<uint64_t>(),
                       j["cell_updates_per_s"].get<double>() / 1e6, j["discharge_m3_s"].get<double>(),
                       j["time_scale"].get<double>(), 100.0 * m.channel_coverage(), spun);
}

/// The hybrid solver's hand-over (solver = "hybrid"); null for other solvers. Volumes in m^3
/// since the start and per simulated second; the total is the grid's volume plus the active
/// particles', the grid's balance error includes what was exchanged.
json hybrid_json(const Simulation& sim, long long frames, double dt) {
    const auto* h = dynamic_cast<const HybridSolver*>(&sim.solver());
    if (!h) return nullptr;
    const HybridStats& st = h->stats();
    const double seconds = double(frames) * dt;
    const auto per_s = [&](double v) { return seconds > 0.0 ? v / seconds : 0.0; };
    return {{"to_particles_m3", st.to_particles},
            {"to_grid_m3", st.to_grid},
            {"to_particles_m3_per_s", per_s(st.to_particles)},
            {"to_grid_m3_per_s", per_s(st.to_grid)},
            {"lost_m3", st.lost},
            {"particles_made", st.particles_made},
            {"particles_absorbed", st.particles_absorbed},
            {"particle_volume_m3", h->particle_volume()},
            {"total_volume_m3", h->total_volume()},
            {"grid_balance_error_m3", h->grid_balance_error()},
            {"shed_faces", {{"cliff", h->cliff_faces()}, {"launch", h->launch_faces()}}},
            {"momentum_m4_s", {{"cells_out", {st.cell_momentum_out[0], st.cell_momentum_out[1]}},
                               {"particles_in", {st.particle_momentum_in[0], st.particle_momentum_in[1]}},
                               {"particles_out", {st.particle_momentum_out[0], st.particle_momentum_out[1]}},
                               {"cells_in", {st.cell_momentum_in[0], st.cell_momentum_in[1]}}}}};
}

/// run's line for solver = "hybrid" (from hybrid_json): empty for other solvers.
std::string hybrid_summary(const Simulation& sim, const RiverMeter& m, long long frames) {
    const json j = hybrid_json(sim, frames, 0.0);
    if (j.is_null()) return {};
    const HybridOutflow out = hybrid_outflow(sim, m).value_or(HybridOutflow{});
    return fmt::format("\nhybrid: {:.3f} m^3 to particles ({} particles), {:.3f} m^3 to the grid ({} particles), "
                       "{:.4f} m^3 lost off the terrain; total {:.4g} m^3 (grid balance error {:.2e} m^3); "
                       "outflow {:.4g} m^3 ({:.3g} m^3/s = {:.2f} of inflow over the second half, first at {:.2f} s)",
                       j["to_particles_m3"].get<double>(), j["particles_made"].get<uint64_t>(), j["to_grid_m3"].get<double>(),
                       j["particles_absorbed"].get<uint64_t>(), j["lost_m3"].get<double>(),
                       j["total_volume_m3"].get<double>(), j["grid_balance_error_m3"].get<double>(), out.m3, out.m3_per_s,
                       out.over_inflow, m.first_grid_outflow_s());
}

}  // namespace

json bodies_json(std::span<const BodyState> bodies, uint64_t inside) {
    json each = json::array();
    double submerged = 0.0, speed = 0.0;
    float max_speed = 0.0f;
    for (const BodyState& b : bodies) {
        const float v = glm::length(b.velocity);
        submerged += b.submerged_fraction;
        speed += v;
        max_speed = std::max(max_speed, v);
        each.push_back({{"id", b.id},
                        {"shape", to_string(b.shape)},
                        {"position", {b.position.x, b.position.y, b.position.z}},
                        {"speed", v},
                        {"submerged_fraction", b.submerged_fraction},
                        {"mass", b.mass}});
    }
    const double n = static_cast<double>(std::max<size_t>(bodies.size(), 1));
    return {{"count", bodies.size()},
            {"submerged_fraction_mean", submerged / n},
            {"speed_mean", speed / n},
            {"speed_max", max_speed},
            {"inside_bodies", inside},
            {"bodies", each}};
}

json swe_stats_json(const Simulation& sim, const RiverMeter& meter, long long frames) { return swe_json(sim, meter, frames); }
json hybrid_stats_json(const Simulation& sim, long long frames, double dt) { return hybrid_json(sim, frames, dt); }

RiverMeter::RiverMeter(const Simulation& sim, long long frames)
    : frames_(frames), outlets_(sim.terrain(), sim.channel(), sim.main_channel().back()) {}

void RiverMeter::record(const Simulation& sim, long long f, double time_s) {
    flow_.record(time_s, sim.counters().sunk);
    outlets_.record(time_s, sim.last_exits());
    max_speed_ = std::max(max_speed_, sim.counters().max_speed);
    density_max_ = std::max(density_max_, sim.counters().density_error_max);
    simulate_ms_total_ += sim.last_timings().simulate_ms;
    if (const SweSolver* swe = grid_of(sim)) {
        const auto* h = dynamic_cast<const HybridSolver*>(&sim.solver());
        const double lost = h ? h->stats().lost : 0.0;
        const SweBalance b = swe->balance();
        max_substeps_ = std::max(max_substeps_, swe->last_substeps());
        if (f == frames_ / 2 - 1) swe_half_ = {b, swe->simulated_s(), lost};
        if (f == 3 * frames_ / 4 - 1) swe_quarter_ = {b, swe->simulated_s(), lost};
        if (h && first_grid_outflow_s_ < 0.0 && left_the_map(b, lost) > 0.0) first_grid_outflow_s_ = time_s;
    }
    const bool sampled = 2 * f >= frames_ && f % 10 == 0;
    if (sampled) {
        wet_sum_ += sim.wet_fraction();
        density_mean_sum_ += sim.counters().density_error_mean;
        ++wet_n_;
    }
    if (sampled || f == frames_ - 1) {
        spray_sum_ += sim.spray_fraction();
        coverage_sum_ += sim.channel_coverage();
        ++spray_n_;
    }
}

json run_stats_json(const Simulation& sim, const RiverMeter& meter, const Checkpoints& stage_ms, long long frames,
                    double dt) {
    const SceneDef& d = sim.def();
    const SolverCounters& c = sim.counters();
    json j;
    j["scene"] = d.name;
    j["seed"] = d.seed;
    j["frames"] = frames;
    j["dt"] = dt;
    j["solver"] = std::string(to_string(d.solver));
    j["collision"] = std::string(to_string(d.collision.mode));
    j["field_kernel"] = std::string(to_string(d.field.kernel));
    j["terrain"] = terrain_json(sim.terrain());
    if (const auto& z = sim.sizing())
        j["sizing"] = {{"channel_length_m", z->channel_length_m}, {"channel_slope", z->channel_slope},
                       {"speed_m_s", z->speed}, {"count", d.spawn.count},
                       {"flow_rate", d.spawn.particles_per_second()}, {"capped", z->capped},
                       {"spacing", d.pbf.spacing}, {"prefilled", sim.prefilled()}};
    j["particles_total"] = sim.particles().size();
    j["particles_active"] = sim.particles().active_count();
    j["triangles"] = sim.surface().triangle_count();
    j["vertices"] = sim.surface().vertex_count();
    j["field_grid"] = sim.field_dims();
    // The last frame's smoothing ([surface], issue 11).
    const SmoothingStats& sm = sim.smoothing_stats();
    j["surface_smoothing"] = {{"method", std::string(to_string(d.smoothing.method))},
                              {"moving_vertices", sm.moving},
                              {"pinned_vertices", sm.pinned},
                              {"hidden_vertices", sm.hidden},
                              {"mean_weight", sm.mean_weight},
                              {"volume_change_m3", sm.volume_change}};
    j["field_overflows"] = sim.field_overflows();
    j["field_windows"] = {{"frames", sim.field_windows()}, {"most_particles_left_out", sim.field_left_out()}};
    j["particle_steps"] = c.particle_steps;
    j["collisions"] = c.collisions;
    j["tunneled"] = c.tunneled;
    j["respawned"] = c.respawned;
    j["guarded"] = c.guarded;
    j["plausibility"] = plausibility_json(sim, meter);
    j["state_hash"] = fmt::format("{:016x}", sim.state_hash());
    j["stage_ms"] = stage_ms_json(sim, stage_ms);
    j["foam"] = foam_json(sim);
    j["bodies"] = bodies_json(sim.view().bodies, c.inside_bodies);
    j["swe"] = swe_json(sim, meter, frames);
    j["hybrid"] = hybrid_json(sim, frames, dt);
    return j;
}

std::string run_summary(const Simulation& sim, const RiverMeter& meter, const Checkpoints& stage_ms, long long frames) {
    const SolverCounters& c = sim.counters();
    const FlowMeter::Summary fs = meter.flow().summary();
    const OutletMeter::Summary os = meter.outlets().summary();
    const Percentiles final_speed = percentiles(sim.active_speeds());
    const Percentiles tot = percentiles(stage_ms.column(kStageTotal));
    const std::span<const BodyState> bodies = sim.view().bodies;
    std::string with_bodies;  // nothing without bodies: the line stays as it was
    if (!bodies.empty()) {
        const json b = bodies_json(bodies, c.inside_bodies);
        with_bodies = fmt::format(", {} bodies (submerged {:.0f} %, speed mean {:.2f} m/s, {} particle-steps inside)",
                                  bodies.size(), 100.0 * b["submerged_fraction_mean"].get<double>(),
                                  b["speed_mean"].get<double>(), c.inside_bodies);
    }
    return fmt::format("{}: {} frames, {}/{} particles active, surface {} triangles / {} vertices, "
                       "tunneled {}, guarded {}, respawned {}, outflow {:.1f}/s ({}), main outlet {:.1f}/s = {:.2f} of "
                       "inflow (first at {:.2f} s), channel coverage {:.0f} %, wet {:.0f} %, spray {:.1f} %, "
                       "final speed p95 {:.2f} m/s{}, frame median {:.3f} ms (p95 {:.3f})",
                       sim.def().name, frames, sim.particles().active_count(), sim.particles().size(),
                       sim.surface().triangle_count(), sim.surface().vertex_count(), c.tunneled, c.guarded,
                       c.respawned, fs.rate, fs.steady ? "steady" : "not steady", os.main.rate,
                       outflow_over_inflow(sim, os), os.main.first_s, 100.0 * meter.channel_coverage(),
                       100.0 * meter.wet_fraction(), 100.0 * meter.spray_fraction(), final_speed.p95, with_bodies, tot.median,
                       tot.p95) + swe_summary(sim, meter, frames) + hybrid_summary(sim, meter, frames);
}

}  // namespace mr::app
