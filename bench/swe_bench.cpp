// The shallow-water core (src/swe/shallow_water.h, issue 45): one rendered frame of 1/60 s
// (all its CFL substeps) on N x N grids at 1 m spacing.
//
//   bench_swe --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// Args: N, wet (1: every cell wet, 1 m of water sloshing over a bumpy bed; 0: a wet valley,
// a channel N/8 wide in a dry map, to show the cost follows the wet cells), order (1 or 2).
// Counters: ms_per_frame, substeps per frame, cell_updates/s (cells of the wet spans times
// stages, per second of wall clock), wet fraction of the grid.
#include "shallow_water.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <vector>

namespace {

mr::swe::ShallowWater make(int n, bool full, bool second) {
    std::vector<double> z(static_cast<size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double bumps = 0.2 * std::sin(0.05 * i) * std::cos(0.07 * j);
            const double across = full ? 0.0 : 0.05 * std::abs(j - n / 2);  // a V valley along x
            z[static_cast<size_t>(j) * n + i] = bumps + across + 0.001 * (n - i);
        }
    mr::swe::ShallowWaterDef def;
    def.second_order = second;
    def.manning = 0.03;
    def.west = def.east = def.south = def.north = {mr::swe::EdgeKind::Wall};
    mr::swe::ShallowWater w(n, n, 1.0, z, def);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double bed = w.bed(i, j);
            const double level = full ? 1.0 + 0.001 * n : 0.05 * (n / 16) + 0.001 * n;
            w.set_state(i, j, std::max(level - bed, 0.0));
        }
    w.balance_reset();
    return w;
}

void BM_SweFrame(benchmark::State& state) {
    const int n = static_cast<int>(state.range(0));
    mr::swe::ShallowWater w = make(n, state.range(1) != 0, state.range(2) == 2);
    for (int f = 0; f < 3; ++f) w.advance(1.0 / 60.0);  // warm up (spans, caches)
    const uint64_t steps0 = w.stats().substeps, cells0 = w.stats().cell_updates;
    double seconds = 0.0;
    int64_t frames = 0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        w.advance(1.0 / 60.0);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        ++frames;
    }
    size_t wet = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) wet += w.depth(i, j) > 0.0;
    state.counters["ms_per_frame"] = 1e3 * seconds / static_cast<double>(frames);
    state.counters["substeps"] = static_cast<double>(w.stats().substeps - steps0) / static_cast<double>(frames);
    state.counters["cell_updates_per_s"] = static_cast<double>(w.stats().cell_updates - cells0) / seconds;
    state.counters["wet_fraction"] = static_cast<double>(wet) / (static_cast<double>(n) * n);
}

BENCHMARK(BM_SweFrame)
    ->ArgsProduct({{256, 512, 1024, 2048}, {1, 0}, {2}})
    ->Args({1024, 1, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
