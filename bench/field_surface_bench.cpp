// W1 'metaball isosurface' (../shared/peers/README.md) on the fast path: the sparse
// compact-kernel field (SparseField::build) and block-parallel marching cubes
// (extract_surface_sparse), apart and together, for the issue's sizes
// (N, R) = (1000, 128), (10000, 128), (10000, 256). Balls from the pinned LCG (seed
// 12345), W1 kernel (RCOEF 0.3, ISO 80, SUB 12), R^3 samples over the unit cube.
//
//   bench_field_surface --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//   bench_field_surface --threads=1 ...   (oneTBB limited to 1 thread; default: all cores)
//
// Times are wall clock (UseRealTime: the work runs on oneTBB's threads); the CPU column
// is the whole process's CPU time (MeasureProcessCPUTime), which stays meaningful when
// other jobs load the machine and wall times inflate. Counters:
// triangles and vertices of the mesh, and the mean ms of each phase (field: bin, splat;
// surface: select, classify, offsets, emit) so a slow run says where its time went.
#include <metariver/sparse_field.h>
#include <metariver/surface.h>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace {

struct W1Case {
    std::vector<mr::Vec3> balls;
    mr::SparseFieldDef def;
};

const W1Case& w1_case(int n, int res) {
    static std::map<std::pair<int, int>, W1Case> cases;
    auto [it, added] = cases.try_emplace({n, res});
    if (added) {
        it->second.balls = mr::w1_balls(n);
        it->second.def = mr::SparseFieldDef{
            .kernel = mr::w1_kernel_for(n), .domain = mr::DomainMode::FixedBox, .box = mr::w1_grid(res)};
    }
    return it->second;
}

struct PhaseTotals {
    double bin = 0, splat = 0, select = 0, classify = 0, offsets = 0, emit = 0;
    void add(const mr::SparseFieldStats& f) {
        bin += f.ms_bin;
        splat += f.ms_splat;
    }
    void add(const mr::SurfaceStats& s) {
        select += s.ms_select;
        classify += s.ms_classify;
        offsets += s.ms_offsets;
        emit += s.ms_emit;
    }
    void report(benchmark::State& state, bool field, bool surface) const {
        const auto avg = [&](double ms) { return benchmark::Counter(ms / static_cast<double>(state.iterations())); };
        if (field) {
            state.counters["ms_bin"] = avg(bin);
            state.counters["ms_splat"] = avg(splat);
        }
        if (surface) {
            state.counters["ms_select"] = avg(select);
            state.counters["ms_classify"] = avg(classify);
            state.counters["ms_offsets"] = avg(offsets);
            state.counters["ms_emit"] = avg(emit);
        }
    }
};

void BM_W1_Field(benchmark::State& state) {
    const W1Case& c = w1_case(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
    mr::SparseField field;
    if (!field.build(c.balls, c.def)) state.SkipWithError("field build failed");  // warm-up
    PhaseTotals t;
    for (auto _ : state) {
        if (!field.build(c.balls, c.def)) state.SkipWithError("field build failed");
        t.add(field.stats());
    }
    t.report(state, true, false);
    state.counters["blocks"] = static_cast<double>(field.allocated_blocks());
}

void BM_W1_Surface(benchmark::State& state) {
    const W1Case& c = w1_case(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
    mr::SparseField field;
    if (!field.build(c.balls, c.def)) state.SkipWithError("field build failed");
    mr::SurfaceMesh mesh;
    mr::SurfaceWorkspace ws;
    mr::extract_surface_sparse(field, mr::kW1Iso, mesh, ws);  // warm-up
    PhaseTotals t;
    for (auto _ : state) {
        mr::extract_surface_sparse(field, mr::kW1Iso, mesh, ws);
        benchmark::DoNotOptimize(mesh.indices.data());
        t.add(ws.stats);
    }
    t.report(state, false, true);
    state.counters["triangles"] = static_cast<double>(mesh.triangle_count());
    state.counters["vertices"] = static_cast<double>(mesh.vertex_count());
}

void BM_W1_FieldSurface(benchmark::State& state) {
    const W1Case& c = w1_case(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
    mr::SparseField field;
    mr::SurfaceMesh mesh;
    mr::SurfaceWorkspace ws;
    if (!field.build(c.balls, c.def)) state.SkipWithError("field build failed");  // warm-up
    mr::extract_surface_sparse(field, mr::kW1Iso, mesh, ws);
    PhaseTotals t;
    for (auto _ : state) {
        if (!field.build(c.balls, c.def)) state.SkipWithError("field build failed");
        mr::extract_surface_sparse(field, mr::kW1Iso, mesh, ws);
        benchmark::DoNotOptimize(mesh.indices.data());
        t.add(field.stats());
        t.add(ws.stats);
    }
    t.report(state, true, true);
    state.counters["triangles"] = static_cast<double>(mesh.triangle_count());
}

void w1_sizes(benchmark::internal::Benchmark* b) {
    b->Args({1000, 128})->Args({10000, 128})->Args({10000, 256});
    b->ArgNames({"N", "R"});
    b->Unit(benchmark::kMillisecond);
    b->UseRealTime();
    b->MeasureProcessCPUTime();
    // The fastest repetition: the least disturbed by other jobs on a shared machine.
    b->ComputeStatistics("min", [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); });
}

BENCHMARK(BM_W1_Field)->Apply(w1_sizes);
BENCHMARK(BM_W1_Surface)->Apply(w1_sizes);
BENCHMARK(BM_W1_FieldSurface)->Apply(w1_sizes);

}  // namespace

int main(int argc, char** argv) {
    // --threads=N (ours, removed before Google Benchmark parses the rest).
    int threads = 0;
    int kept = 1;
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        if (arg.starts_with("--threads=")) {
            threads = std::atoi(argv[i] + 10);
        } else {
            argv[kept++] = argv[i];
        }
    }
    argc = kept;
    std::optional<tbb::global_control> limit;
    if (threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
    benchmark::AddCustomContext(
        "tbb_threads",
        std::to_string(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)));
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
