// The shallow-water core (src/swe/shallow_water.h, issue 45): one rendered frame of 1/60 s
// (all its CFL substeps) on nx x ny grids at 1 m spacing, and the machine's memory bandwidth.
//
//   bench_swe --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// BM_StreamTriad: a[i] = b[i] + s c[i] over three arrays of 2^24 doubles (128 MiB each, far
// beyond the caches) on every core, counted as STREAM counts it (24 bytes per element).
// BM_SweFrame args: nx, ny, wet percent, order (1 or 2). 100: every cell wet, 1 m or more of
// water sloshing over a bumpy bed sloping along x; below 100: a V valley along x with water
// in its middle rows only (the percent of the rows), the rest dry, to show the cost follows
// the wet cells. Counters: ms_per_frame, substeps per frame, cell_updates_per_s (cells of the
// active spans times stages, per second of wall clock), ns_per_cell_update, wet_fraction,
// bytes_per_s (cell updates per second times the bytes a cell update must move, below) and
// bandwidth_fraction (bytes_per_s over the triad's bytes per second on the same machine).
//
// Bytes a cell update must move (the state streamed through memory, caches not counted):
// per stage the state in (h, hu, hv) and the bed, and the state out: 7 doubles = 56 bytes.
// A second-order substep is the time step's pass (reads the state, 3 doubles), two stages
// and Heun's average (the second stage also reads the starting state, 3 doubles; the rain and
// friction are done in the same pass): 3 + 7 + 10 = 20 doubles per cell for two updates,
// 80 bytes per cell update. First order: 3 + 7 (the rain and friction done on each row as
// it is written, the new state swapped in) = 10 doubles, 80 bytes.
#include "shallow_water.h"

#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <vector>

namespace {

/// Bytes per second of the triad, the best of `repeats` sweeps (measured once per process).
double triad_once(std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& c) {
    const auto t0 = std::chrono::steady_clock::now();
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, a.size(), 1 << 16),
        [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) a[i] = b[i] + 3.0 * c[i];
        },
        tbb::static_partitioner());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return 24.0 * static_cast<double>(a.size()) / s;
}

/// CPU seconds of the whole process (every thread): on a shared machine the wall clock
/// also counts the time other processes held the cores.
double process_cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

constexpr size_t kTriadSize = size_t{1} << 24;

double stream_bandwidth() {
    static const double bw = [] {
        std::vector<double> a(kTriadSize, 0.0), b(kTriadSize, 1.0), c(kTriadSize, 2.0);
        double best = 0.0;
        for (int k = 0; k < 10; ++k) best = std::max(best, triad_once(a, b, c));
        return best;
    }();
    return bw;
}

void BM_StreamTriad(benchmark::State& state) {
    std::vector<double> a(kTriadSize, 0.0), b(kTriadSize, 1.0), c(kTriadSize, 2.0);
    double bytes = 0.0, seconds = 0.0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        triad_once(a, b, c);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        bytes += 24.0 * static_cast<double>(kTriadSize);
    }
    benchmark::DoNotOptimize(a.data());
    state.counters["bytes_per_s"] = bytes / seconds;
}

mr::swe::ShallowWater make(int nx, int ny, int wet_percent, bool second) {
    const bool full = wet_percent >= 100;
    const int n = std::max(nx, ny);
    std::vector<double> z(static_cast<size_t>(nx) * ny);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const double bumps = 0.2 * std::sin(0.05 * i) * std::cos(0.07 * j);
            const double across = full ? 0.0 : 0.05 * std::abs(j - ny / 2);  // a V valley along x
            z[static_cast<size_t>(j) * nx + i] = bumps + across + 0.001 * (nx - i);
        }
    mr::swe::ShallowWaterDef def;
    def.second_order = second;
    def.manning = 0.03;
    def.west = def.east = def.south = def.north = {mr::swe::EdgeKind::Wall};
    mr::swe::ShallowWater w(nx, ny, 1.0, z, def);
    const double half = 0.5 * ny * wet_percent / 100.0;  // wet rows each side of the middle
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const double depth = full ? 1.0 + 0.001 * n - w.bed(i, j) : 0.05 * (half - std::abs(j - ny / 2));
            w.set_state(i, j, std::max(depth, 0.0));
        }
    w.balance_reset();
    return w;
}

void BM_SweFrame(benchmark::State& state) {
    const int nx = static_cast<int>(state.range(0)), ny = static_cast<int>(state.range(1));
    const bool second = state.range(3) == 2;
    mr::swe::ShallowWater w = make(nx, ny, static_cast<int>(state.range(2)), second);
    for (int f = 0; f < 3; ++f) w.advance(1.0 / 60.0);  // warm up (spans, caches)
    const uint64_t steps0 = w.stats().substeps, cells0 = w.stats().cell_updates;
    double seconds = 0.0;
    int64_t frames = 0;
    const double cpu0 = process_cpu_seconds();
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        w.advance(1.0 / 60.0);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        ++frames;
    }
    const double cpu = process_cpu_seconds() - cpu0;
    size_t wet = 0;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) wet += w.depth(i, j) > 0.0;
    const double updates = static_cast<double>(w.stats().cell_updates - cells0);
    const double bytes_per_update = 80.0;
    state.counters["ms_per_frame"] = 1e3 * seconds / static_cast<double>(frames);
    state.counters["cpu_ms_per_frame"] = 1e3 * cpu / static_cast<double>(frames);
    state.counters["substeps"] = static_cast<double>(w.stats().substeps - steps0) / static_cast<double>(frames);
    state.counters["cell_updates_per_s"] = updates / seconds;
    state.counters["ns_per_cell_update"] = 1e9 * seconds / std::max(updates, 1.0);
    state.counters["wet_fraction"] = static_cast<double>(wet) / (static_cast<double>(nx) * ny);
    state.counters["bytes_per_s"] = bytes_per_update * updates / seconds;
    state.counters["bandwidth_fraction"] = bytes_per_update * updates / seconds / stream_bandwidth();
}

BENCHMARK(BM_StreamTriad)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(0.5);

BENCHMARK(BM_SweFrame)
    ->ArgNames({"nx", "ny", "wet%", "order"})
    // Fully wet squares, second order.
    ->Args({256, 256, 100, 2})
    ->Args({512, 512, 100, 2})
    ->Args({1024, 1024, 100, 2})
    ->Args({2048, 2048, 100, 2})
    // The target's grid: fully wet, and a river (a valley 15 % wet), both orders.
    ->Args({1000, 700, 100, 2})
    ->Args({1000, 700, 15, 2})
    ->Args({1000, 700, 100, 1})
    ->Args({1000, 700, 15, 1})
    // Linear in wet cells: the same 1024^2 valley 10, 25 and 50 % wet (100 %: the row above).
    ->Args({1024, 1024, 10, 2})
    ->Args({1024, 1024, 25, 2})
    ->Args({1024, 1024, 50, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
