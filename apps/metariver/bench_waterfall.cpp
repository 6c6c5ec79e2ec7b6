// `metariver bench --scenario waterfall`: issue 46's cost bound. The waterfall preset with the
// grid alone (solver = "swe") and with the hybrid, and the default particle river's cost per
// particle: the hybrid should cost at most the grid plus the particles it holds at that cost.
#include "bench_scenarios.h"

#include <metariver/hybrid_solver.h>
#include <metariver/io.h>

#include <fmt/format.h>

#include <algorithm>

namespace mr::app {

namespace {

/// The median (robust to the other processes of a shared machine): the one cmd_bench prints.
double median(std::vector<double> v) { return percentiles(std::move(v)).median; }

/// One row: `def` after `warmup` frames, `frames` measured; the mean active particles.
ScenarioResult measure(const std::string& name, const SceneDef& def, int warmup, int frames, double& mean_particles) {
    ScenarioResult r;
    r.name = name;
    auto sim = Simulation::create(def);
    if (!sim) {
        r.note = "skipped: " + sim.error().message;
        return r;
    }
    Simulation& s = *sim.value();
    for (int f = 0; f < warmup; ++f) s.step(1.0f / 60.0f);
    double particles = 0.0;
    for (int f = 0; f < frames; ++f) {
        s.step(1.0f / 60.0f);
        const FrameTimings& t = s.last_timings();
        r.sample("simulate", t.simulate_ms);
        r.sample("total", t.simulate_ms + t.foam_ms + t.field_ms + t.surface_ms);
        particles += double(s.particles().active_count());
    }
    mean_particles = frames > 0 ? particles / double(frames) : 0.0;
    r.particles = s.particles().active_count();
    r.triangles = s.surface().triangle_count();
    r.params = {{"scene", def.name}, {"solver", std::string(to_string(def.solver))}, {"warmup", warmup}, {"frames", frames}};
    r.quality = {{"mean_particles", mean_particles}};
    if (const auto* h = dynamic_cast<const HybridSolver*>(&s.solver()))
        r.quality["to_particles_m3"] = h->stats().to_particles, r.quality["to_grid_m3"] = h->stats().to_grid;
    return r;
}

}  // namespace

void bench_waterfall(int warmup, int frames, std::vector<ScenarioResult>& out) {
    SceneDef grid = preset("waterfall").value();
    grid.solver = SolverKind::Swe;
    double n_grid = 0.0, n_hybrid = 0.0, n_river = 0.0;
    ScenarioResult g = measure("waterfall: the grid alone (swe)", grid, warmup, frames, n_grid);
    ScenarioResult h = measure("waterfall: hybrid", preset("waterfall").value(), warmup, frames, n_hybrid);
    // The particle river's cost per particle: the default river's solver step over its particles.
    ScenarioResult p = measure("default river (per-particle cost)", default_scene(), 600, frames, n_river);
    const double per_particle = n_river > 0.0 ? median(p.stage_ms["simulate"]) / n_river : 0.0;
    p.quality["simulate_us_per_particle"] = 1e3 * per_particle;
    p.note = fmt::format("{:.0f} particles, {:.3f} us of simulate per particle", n_river, 1e3 * per_particle);
    const double bound = median(g.stage_ms["simulate"]) + n_hybrid * per_particle;
    const double got = median(h.stage_ms["simulate"]);
    h.quality["simulate_bound_ms"] = bound;
    h.quality["simulate_over_bound"] = bound > 0.0 ? got / bound : 0.0;
    h.note = fmt::format("{:.0f} particles; simulate {:.2f} ms against the grid's {:.2f} + {:.0f} x {:.3f} us = {:.2f} ms "
                         "({:.2f}x the bound)",
                         n_hybrid, got, median(g.stage_ms["simulate"]), n_hybrid, 1e3 * per_particle, bound,
                         bound > 0.0 ? got / bound : 0.0);
    for (ScenarioResult* r : {&g, &h, &p}) out.push_back(std::move(*r));
}

}  // namespace mr::app
