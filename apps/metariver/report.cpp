#include "report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace mr::app {

long resident_kb() {
    std::FILE* f = std::fopen("/proc/self/status", "r");
    if (!f) return -1;
    long kb = -1;
    char line[256];
    while (std::fgets(line, sizeof line, f)) {
        if (std::strncmp(line, "VmRSS:", 6) == 0) {
            kb = std::strtol(line + 6, nullptr, 10);
            break;
        }
    }
    std::fclose(f);
    return kb;
}

long long counter_balance(const Simulation& sim, long long frames_done) {
    const SceneDef& d = sim.def();
    const SolverCounters& c = sim.counters();
    const long long active = static_cast<long long>(sim.particles().active_count());
    const long long total = static_cast<long long>(sim.particles().size());
    long long expected = 0;
    if (sim.solver_entry().respawn_to_pool)  // PBF's lattice source
        expected = static_cast<long long>(c.emitted) - static_cast<long long>(c.sunk) - static_cast<long long>(c.respawned);
    else if (d.spawn.has_rate())
        expected = static_cast<long long>(c.emitted) - static_cast<long long>(c.sunk);
    else if (d.spawn.interval == 0)
        expected = total;
    else
        expected = std::min(total, (frames_done + d.spawn.interval - 1) / d.spawn.interval);
    return active - expected;
}

std::string report_line(const Simulation& sim, long long frames_done) {
    const Particles& p = sim.particles();
    const auto finite = [](const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    size_t nonfinite = 0;
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i] && (!finite(p.position[i]) || !finite(p.velocity[i]))) ++nonfinite;
    for (const Vec3& v : sim.surface().positions) nonfinite += !finite(v);
    const SolverCounters& c = sim.counters();
    const size_t active = p.active_count();
    return fmt::format("report frame={} rss_kb={} total={} active={} pooled={} emitted={} sunk={} respawned={} "
                       "balance={} nonfinite={} triangles={}",
                       frames_done, resident_kb(), p.size(), active, p.size() - active, c.emitted, c.sunk, c.respawned,
                       counter_balance(sim, frames_done), nonfinite, sim.surface().triangle_count());
}

}  // namespace mr::app
