// The water queries (include/metariver/water_query.h, issue 43) on the default river
// after 600 frames (10 s of flow): batches of 10,000 random points or rays (fixed seed,
// over the terrain's rectangle; half the rays aimed at surface vertices), the fast
// queries one call at a time on one thread (serial), their batch calls (oneTBB's
// threads), and the brute-force twins (every triangle, every active particle; serial);
// and WaterQuery::update(), there and on a 1000 x 700 valley (PBF and "swe").
//
//   bench_query --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Time per batch (wall clock); per_query divides it by the batch's size (seconds, with
// an SI prefix: 163n is 163 ns).
#include <metariver/scene.h>
#include <metariver/water_query.h>

#include <benchmark/benchmark.h>

#include <glm/geometric.hpp>

#include <memory>
#include <span>
#include <stdexcept>
#include <vector>

namespace {

constexpr int kBatch = 10'000;

/// The default river after 600 frames, with its queries updated and the batch's inputs.
struct River {
    std::unique_ptr<mr::Simulation> sim;
    mr::WaterQuery query;
    std::vector<float> xz;
    std::vector<mr::Vec3> points, origins, directions;
    float reach = 0.0f;
};

const River& river() {
    static River r = [] {
        River v;
        auto sim = mr::Simulation::create(mr::default_scene());
        if (!sim) throw std::runtime_error(sim.error().message);
        for (int f = 0; f < 600; ++f) sim.value()->step(1.0f / 60.0f);
        v.sim = std::move(sim.value());
        v.query.update(*v.sim);
        const mr::Aabb box = v.sim->terrain().mesh_bounds();
        const auto& vertices = v.sim->surface().positions;
        v.reach = 2.0f * glm::length(box.extent());
        mr::Lcg rng(600);
        for (int i = 0; i < kBatch; ++i) {
            const float x = rng.uniform(box.min.x, box.max.x), z = rng.uniform(box.min.z, box.max.z);
            v.xz.insert(v.xz.end(), {x, z});
            v.points.emplace_back(x, v.sim->terrain().height_mesh(x, z) + rng.uniform(0.0f, 2.0f), z);
            const mr::Vec3 o(rng.uniform(box.min.x, box.max.x), rng.uniform(box.min.y, box.max.y + 20.0f),
                             rng.uniform(box.min.z, box.max.z));
            v.origins.push_back(o);
            const mr::Vec3 random_dir(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
            v.directions.push_back(i % 2 == 0 ? vertices[rng.next_u32() % vertices.size()] - o : random_dir);
        }
        return v;
    }();
    return r;
}

void finish(benchmark::State& state, size_t per_iteration) {
    state.counters["per_query"] = benchmark::Counter(double(per_iteration),
                                                        benchmark::Counter::kIsIterationInvariantRate |
                                                            benchmark::Counter::kInvert);
    const River& r = river();
    state.counters["triangles"] = double(r.sim->surface().triangle_count());
    state.counters["particles"] = double(r.sim->particles().active_count());
}

/// Mode 0: the fast query, one call at a time (fast(i)); 1: its batch call (batch(out));
/// 2: the brute-force twin (brute(i)).
template <class Out, class Batch, class Fast, class Brute>
void run_modes(benchmark::State& state, Batch&& batch, Fast&& fast, Brute&& brute) {
    std::vector<Out> out(kBatch);
    const int64_t mode = state.range(0);
    for (auto _ : state) {
        if (mode == 1) batch(std::span<Out>(out));
        for (size_t i = 0; i < size_t(kBatch) && mode != 1; ++i) out[i] = mode == 0 ? fast(i) : brute(i);
        benchmark::DoNotOptimize(out.data());
    }
    finish(state, kBatch);
}

void BM_Sample(benchmark::State& state) {
    const River& r = river();
    run_modes<mr::WaterSample>(
        state, [&](std::span<mr::WaterSample> out) { r.query.sample(r.xz, out); },
        [&](size_t i) { return r.query.sample(r.xz[2 * i], r.xz[2 * i + 1]); },
        [&](size_t i) { return mr::sample_water_brute(*r.sim, r.xz[2 * i], r.xz[2 * i + 1]); });
}

void BM_VelocityAt(benchmark::State& state) {
    const River& r = river();
    run_modes<mr::Vec3>(
        state, [&](std::span<mr::Vec3> out) { r.query.velocity_at(r.points, out); },
        [&](size_t i) { return r.query.velocity_at(r.points[i]); },
        [&](size_t i) { return mr::water_velocity_brute(*r.sim, r.points[i]); });
}

void BM_Raycast(benchmark::State& state) {
    const River& r = river();
    run_modes<mr::WaterRayHit>(
        state, [&](std::span<mr::WaterRayHit> out) { r.query.raycast(r.origins, r.directions, r.reach, out); },
        [&](size_t i) { return r.query.raycast(r.origins[i], r.directions[i], r.reach); },
        [&](size_t i) { return mr::raycast_water_brute(*r.sim, r.origins[i], r.directions[i], r.reach); });
}

void BM_Update(benchmark::State& state) {
    const River& r = river();
    mr::WaterQuery q;
    for (auto _ : state) {
        q.update(*r.sim);
        benchmark::ClobberMemory();
    }
    finish(state, 1);
}

/// A 1000 x 700 procedural valley (the map size of the shallow-water bench) after 30
/// frames of a PBF river (solver 0) or the "swe" grid (solver 1): update()'s cost at a
/// real map size, where what it copies of the terrain and the grid shows.
const mr::Simulation& large_map(int64_t solver) {
    static std::unique_ptr<mr::Simulation> sims[2];
    std::unique_ptr<mr::Simulation>& s = sims[solver == 0 ? 0 : 1];
    if (!s) {
        mr::SceneDef d = mr::default_scene();
        d.source.width = 1000;
        d.source.height = 700;
        if (solver != 0) d.solver = mr::SolverKind::Swe;
        auto sim = mr::Simulation::create(d);
        if (!sim) throw std::runtime_error(sim.error().message);
        for (int f = 0; f < 30; ++f) sim.value()->step(1.0f / 60.0f);
        s = std::move(sim.value());
    }
    return *s;
}

void BM_UpdateLargeMap(benchmark::State& state) {
    const mr::Simulation& sim = large_map(state.range(0));
    mr::WaterQuery q;
    q.update(sim);  // the first update copies everything once; the timed ones are the per-frame cost
    for (auto _ : state) {
        q.update(sim);
        benchmark::ClobberMemory();
    }
    state.counters["triangles"] = double(sim.surface().triangle_count());
    state.counters["particles"] = double(sim.particles().active_count());
    state.counters["terrain_samples"] = double(sim.terrain().vertices().size());
}

void modes(benchmark::internal::Benchmark* b) {
    b->ArgName("mode")->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(BM_Sample)->Apply(modes);
BENCHMARK(BM_VelocityAt)->Apply(modes);
BENCHMARK(BM_Raycast)->Apply(modes);
BENCHMARK(BM_Update)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_UpdateLargeMap)->ArgName("swe")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
