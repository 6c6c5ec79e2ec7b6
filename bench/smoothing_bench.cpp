// The surface stage of the default river with and without its smoothing (issue 11: "the
// surface stage stays within 1.5x its current cost"): marching cubes over the river's
// sparse field (extract_surface_sparse), then smooth_surface as the scene's [surface]
// says, on the field of the default river after 600 frames (10 s of flow, steady outflow).
//
//   bench_smoothing --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Rows: 0 the mesh as extracted (method none), 1 the default scene's smoothing. Counters:
// marching cubes alone (ms_mc: it runs slower in row 1, where the smoothing's passes
// come between two extractions), the smoothing's phases (ms per iteration: weights, fans,
// steps, normals), the moving vertices, the mesh's size. Wall clock (oneTBB's threads do
// the work).
#include <metariver/scene.h>
#include <metariver/surface.h>

#include <benchmark/benchmark.h>

#include <chrono>
#include <memory>
#include <stdexcept>

namespace {

/// The default river after 600 frames (its field is the one the surface stage reads).
const mr::Simulation& river() {
    static std::unique_ptr<mr::Simulation> s = [] {
        auto sim = mr::Simulation::create(mr::default_scene());
        if (!sim) throw std::runtime_error(sim.error().message);
        for (int f = 0; f < 600; ++f) sim.value()->step(1.0f / 60.0f);
        return std::move(sim.value());
    }();
    return *s;
}

void BM_RiverSurface(benchmark::State& state) {
    const mr::Simulation& s = river();
    mr::SmoothingDef def = s.def().smoothing;
    if (state.range(0) == 0) def.method = mr::SmoothingMethod::None;
    if (state.range(1) >= 0) def.iterations = int(state.range(1));
    const mr::SmoothingField weights{.field = &s.sparse_field(), .kernel = mr::poly6_kernel(s.def().field.radius, 1.0f),
                                     .threshold = s.def().field.threshold};
    const mr::SmoothingGround ground = mr::smoothing_ground(s.terrain());
    mr::SurfaceMesh mesh;
    mr::SurfaceWorkspace ws;
    mr::SmoothingWorkspace sws;
    double w = 0, r = 0, st = 0, n = 0, mc = 0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        mr::extract_surface_sparse(s.sparse_field(), s.def().field.threshold, mesh, ws);
        mc += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        mr::smooth_surface(mesh, def, sws, &weights, &ground);
        benchmark::DoNotOptimize(mesh.positions.data());
        w += sws.stats.ms_weights, r += sws.stats.ms_rings, st += sws.stats.ms_smooth, n += sws.stats.ms_normals;
    }
    const auto avg = [&](double ms) { return benchmark::Counter(ms / static_cast<double>(state.iterations())); };
    state.counters["ms_weights"] = avg(w);
    state.counters["ms_mc"] = avg(mc);
    state.counters["ms_fans"] = avg(r);
    state.counters["ms_steps"] = avg(st);
    state.counters["ms_normals"] = avg(n);
    state.counters["listed"] = double(sws.stats.triangles);
    state.counters["hidden"] = static_cast<double>(sws.stats.hidden);
    state.counters["moving"] = static_cast<double>(sws.stats.moving);
    state.counters["vertices"] = static_cast<double>(mesh.vertex_count());
    state.SetLabel(std::string(mr::to_string(def.method)));
}
BENCHMARK(BM_RiverSurface)->Args({0,-1})->Args({1,-1})->Args({1,1})->Args({1,2})->Args({1,4})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
