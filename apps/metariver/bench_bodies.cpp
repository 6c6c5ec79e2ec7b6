// `metariver bench --scenario bodies`: the default river with and without 20 logs (issue
// 44's cost bound: the logs add at most 20 % to the frame).
#include "bench_scenarios.h"

#include <metariver/io.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>

namespace mr::app {

namespace {

/// The median (robust to the other processes of a shared machine): the one cmd_bench prints.
double median(std::vector<double> v) { return percentiles(std::move(v)).median; }

/// n round logs (capsules 0.2 m x 1.6 m, 500 kg/m^3) on the water along the main channel.
void drop_logs(Simulation& s, int n) {
    const auto path = s.main_channel();
    const float as = s.terrain().area_scale();
    const Particles& p = s.particles();
    for (int k = 0; k < n; ++k) {
        const auto [i, j] = path[path.size() * size_t(k + 1) / size_t(n + 2)];
        const Vec3 c(float(j) * as, 0.0f, float(i) * as);
        float top = s.terrain().height_mesh(c.x, c.z);
        for (size_t q = 0; q < p.size(); ++q)
            if (p.active[q] && std::hypot(p.position[q].x - c.x, p.position[q].z - c.z) < 1.5f) top = std::max(top, p.position[q].y);
        (void)s.add_body(BodyDef{.shape = BodyShape::Capsule, .size = Vec3(0.2f, 1.2f, 0.0f), .density = 500.0f,
                                 .position = c + Vec3(0.0f, top + 0.5f, 0.0f)});
    }
}

/// CPU seconds of the whole process so far (every thread): the work a frame does, which
/// the other processes of a shared machine do not inflate as they do the wall clock.
double process_cpu_ms() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

/// One row's frames: wall ("simulate", "total") and process CPU ("cpu") per frame.
void measure(Simulation& s, int frames, ScenarioResult& r, std::vector<double>& total, std::vector<double>& cpu) {
    total.clear();
    cpu.clear();
    for (int f = 0; f < frames; ++f) {
        const double c0 = process_cpu_ms();
        s.step(1.0f / 60.0f);
        cpu.push_back(process_cpu_ms() - c0);
        const FrameTimings& t = s.last_timings();
        total.push_back(t.simulate_ms + t.foam_ms + t.field_ms + t.surface_ms);
        r.sample("simulate", t.simulate_ms);
        r.sample("total", total.back());
        r.sample("cpu", cpu.back());
    }
}

}  // namespace

// The two rivers are warmed up alike, then measured in kRepetitions alternating blocks
// (without, with): both meet the same load of a shared machine, and each block gives a
// ratio of the medians; the row reports the median of the blocks' ratios and their range.
void bench_river_bodies(int warmup, int frames, std::vector<ScenarioResult>& out) {
    constexpr int kRepetitions = 5;
    constexpr int kLogs = 20;
    ScenarioResult rows[2];
    std::unique_ptr<Simulation> sims[2];
    const SceneDef def = default_scene();
    for (int k = 0; k < 2; ++k) {
        rows[k].name = k ? fmt::format("default + {} logs", kLogs) : "default (no bodies)";
        auto sim = Simulation::create(def);
        if (!sim) {
            rows[k].note = "skipped: " + sim.error().message;
            out.push_back(std::move(rows[k]));
            return;
        }
        sims[k] = std::move(sim.value());
        for (int f = 0; f < warmup; ++f) sims[k]->step(1.0f / 60.0f);
        if (k) drop_logs(*sims[k], kLogs);
        for (int f = 0; f < 60; ++f) sims[k]->step(1.0f / 60.0f);  // the drop's splash (both rows alike)
    }
    const uint64_t inside0 = sims[1]->counters().inside_bodies;
    const int block = std::max(1, frames / kRepetitions);
    std::vector<double> wall_ratio, cpu_ratio, total[2], cpu[2];
    for (int rep = 0; rep < kRepetitions; ++rep) {
        for (int k = 0; k < 2; ++k) measure(*sims[k], block, rows[k], total[k], cpu[k]);
        wall_ratio.push_back(median(total[1]) / std::max(1e-9, median(total[0])));
        cpu_ratio.push_back(median(cpu[1]) / std::max(1e-9, median(cpu[0])));
    }
    for (int k = 0; k < 2; ++k) {
        Simulation& s = *sims[k];
        ScenarioResult& r = rows[k];
        r.particles = s.particles().active_count();
        r.triangles = s.surface().triangle_count();
        r.params = {{"scene", def.name}, {"bodies", s.bodies().size()}, {"warmup", warmup}, {"frames", block * kRepetitions},
                    {"repetitions", kRepetitions}};
        r.note = fmt::format("{} warm-up frames, {} blocks of {} frames alternating with the other row", warmup, kRepetitions, block);
    }
    const auto [wlo, whi] = std::minmax_element(wall_ratio.begin(), wall_ratio.end());
    const auto [clo, chi] = std::minmax_element(cpu_ratio.begin(), cpu_ratio.end());
    rows[1].quality = {{"inside_bodies", sims[1]->counters().inside_bodies - inside0},
                       {"frame_ratio", median(wall_ratio)},
                       {"cpu_ratio", median(cpu_ratio)},
                       {"frame_ratios", wall_ratio},
                       {"cpu_ratios", cpu_ratio}};
    rows[1].note = fmt::format("{} logs dropped on the water after {} frames; median over {} blocks of the median frame's ratio "
                               "to the river's without them: wall {:.2f}x ({:.2f}-{:.2f}), CPU {:.2f}x ({:.2f}-{:.2f})",
                               sims[1]->bodies().size(), warmup, kRepetitions, median(wall_ratio), *wlo, *whi, median(cpu_ratio),
                               *clo, *chi);
    out.push_back(std::move(rows[0]));
    out.push_back(std::move(rows[1]));
}

}  // namespace mr::app
