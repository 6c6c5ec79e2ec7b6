// Progress reports for long runs (`run` and `render` --report-every N; scripts/soak.sh
// reads them): resident memory, the particle counters and whether they add up, and
// any non-finite particle or surface value.
#pragma once

#include <metariver/scene.h>

#include <string>

namespace mr::app {

/// Resident memory of this process (VmRSS in /proc/self/status), kB; -1 when unknown.
long resident_kb();

/// Active particles minus what the counters say should be active; 0 when they add up.
/// Flow-rate and PBF sources: every particle comes from the pool through `emitted` and
/// leaves through `sunk` (and, for PBF, out of bounds through `respawned`), so
/// active = emitted - sunk (- respawned). Interval spawning: one particle every
/// spawn_interval frames (all at frame 0 for interval 0), so active = min(budget, due).
long long counter_balance(const Simulation& sim, long long frames_done);

/// One line: "report frame=F rss_kb=R total=T active=A pooled=P emitted=E sunk=S
/// respawned=X balance=B nonfinite=N triangles=K" after `frames_done` frames; nonfinite
/// counts active particles with a non-finite position or velocity and non-finite
/// surface vertices.
std::string report_line(const Simulation& sim, long long frames_done);

}  // namespace mr::app
