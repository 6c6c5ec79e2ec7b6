// The shallow-water river's surface stage (issue 45): append_heightfield_surface on a
// 1000 x 700 grid, as `run` calls it each frame (a reused scratch and mesh, the solver's
// velocity and rows' wet spans). The bed is value noise (three octaves, hashed from the
// sample, fixed), the water its lakes below one level: the level is the bed's quantile
// at the wet percent, so 12 % wet has lakes with long, ragged shorelines like the river of
// the random 1000 x 700 map (11.7-14.7 % wet: 106k vertices, 199k triangles at 14.7 %),
// and 100 % is every sample wet (no shoreline).
//
//   bench_heightfield_surface --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Counters: ms_per_frame (wall), cpu_ms_per_frame (the process's CPU time: meaningful on
// a loaded machine), ns_per_wet_sample, triangles, vertices, wet_fraction.
#include <metariver/surface.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <vector>

namespace {

double process_cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// A value in [0, 1) from the lattice point (i, j) of octave o.
float lattice(int i, int j, int o) {
    uint32_t h = uint32_t(i) * 0x8da6b343u ^ uint32_t(j) * 0xd8163841u ^ uint32_t(o) * 0xcb1ab31fu;
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    return float(h >> 8) / 16777216.0f;
}

/// Bilinear value noise of period `cell` samples at (i, j).
float noise(int i, int j, int cell, int o) {
    const int a = i / cell, b = j / cell;
    const float u = float(i % cell) / float(cell), v = float(j % cell) / float(cell);
    return (1 - u) * (1 - v) * lattice(a, b, o) + u * (1 - v) * lattice(a + 1, b, o) + (1 - u) * v * lattice(a, b + 1, o) +
           u * v * lattice(a + 1, b + 1, o);
}

struct River {
    int rows = 0, columns = 0;
    std::vector<mr::Vec3> bed, velocity;
    std::vector<float> depth;
    std::vector<int> first, last;
};

River make(int rows, int columns, int wet_percent) {
    River r{.rows = rows, .columns = columns};
    const float spacing = 0.5f;
    std::vector<float> height;
    for (int i = 0; i < rows; ++i)
        for (int j = 0; j < columns; ++j) {
            const float h = 8.0f * noise(i, j, 64, 0) + 3.0f * noise(i, j, 16, 1) + 0.6f * noise(i, j, 4, 2);
            r.bed.emplace_back(spacing * float(j), h, spacing * float(i));
            height.push_back(h);
        }
    std::vector<float> sorted = height;
    const size_t at = std::min(sorted.size() - 1, sorted.size() * size_t(wet_percent) / 100);
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(at), sorted.end());
    const float level = wet_percent >= 100 ? sorted.back() + 1.0f : sorted[at];
    r.first.assign(size_t(rows), columns);
    r.last.assign(size_t(rows), -1);
    for (int i = 0; i < rows; ++i)
        for (int j = 0; j < columns; ++j) {
            const size_t k = size_t(i) * size_t(columns) + size_t(j);
            const float d = std::max(level - height[k], 0.0f);
            r.depth.push_back(d);
            r.velocity.emplace_back(d > 0.0f ? mr::Vec3(1.0f + 0.1f * noise(i, j, 8, 3), 0.0f, 0.2f) : mr::Vec3(0.0f));
            if (d > 0.0f) {
                r.first[size_t(i)] = std::min(r.first[size_t(i)], j);
                r.last[size_t(i)] = j;
            }
        }
    return r;
}

void BM_HeightfieldSurface(benchmark::State& state) {
    const River r = make(int(state.range(1)), int(state.range(0)), int(state.range(2)));
    mr::HeightfieldScratch scratch;
    mr::SurfaceMesh mesh;
    std::vector<mr::Vec3> vertex_velocity;
    const auto frame = [&] {
        mesh.clear();
        vertex_velocity.clear();
        mr::append_heightfield_surface(r.bed, r.depth, r.rows, r.columns, mesh, &scratch, r.velocity, &vertex_velocity, {},
                                       r.first, r.last);
    };
    frame();  // warm: the scratch and the mesh's capacity
    double seconds = 0.0;
    int64_t frames = 0;
    const double cpu0 = process_cpu_seconds();
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        frame();
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        benchmark::DoNotOptimize(mesh.indices.data());
        ++frames;
    }
    const double cpu = process_cpu_seconds() - cpu0;
    const double wet = double(std::count_if(r.depth.begin(), r.depth.end(), [](float d) { return d > 0.005f; }));
    state.counters["ms_per_frame"] = 1e3 * seconds / double(frames);
    state.counters["cpu_ms_per_frame"] = 1e3 * cpu / double(frames);
    state.counters["ns_per_wet_sample"] = 1e9 * cpu / double(frames) / std::max(wet, 1.0);
    state.counters["triangles"] = double(mesh.triangle_count());
    state.counters["vertices"] = double(mesh.vertex_count());
    state.counters["wet_fraction"] = wet / double(r.depth.size());
}

}  // namespace

BENCHMARK(BM_HeightfieldSurface)
    ->ArgNames({"nx", "ny", "wet%"})
    ->Args({1000, 700, 12})   // the random map's river: lakes and shorelines
    ->Args({1000, 700, 100})  // every sample wet
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
