// The cost of a sculpt stroke under a running river (issue 14: "only the touched region"):
// Simulation::sculpt (the brush, the tree's refit, the drainage network and the main
// channel measured again, the water lifted onto the new ground) against its parts, on the
// default valley and on real DEMs of the shared folder (METARIVER_SHARED_DIR).
//
//   bench_edit --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Each stroke raises 1 cm with a 4 m brush at the middle of the terrain (so its heights
// change but the river does not notice); wall clock.
#include <metariver/emitters.h>
#include <metariver/scene.h>

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <stdexcept>
#include <string>

namespace {

/// The map's default river after 60 frames ("" : the built-in valley).
mr::Simulation& river(const std::string& map) {
    static std::map<std::string, std::unique_ptr<mr::Simulation>> sims;
    auto& s = sims[map];
    if (!s) {
        mr::SceneDef d = mr::default_scene();
        if (!map.empty()) {  // the default river on the PNG at the automatic scale
            d.source.kind = mr::TerrainSource::File;
            d.source.heightmap = std::string(METARIVER_SHARED_DIR) + "/heightmaps/real/" + map + ".png";
        }
        auto sim = mr::Simulation::create(d);
        if (!sim) throw std::runtime_error(sim.error().message);
        s = std::move(sim.value());
        for (int f = 0; f < 60; ++f) s->step(1.0f / 60.0f);
    }
    return *s;
}

const char* const kMaps[] = {"", "alps", "western_usa"};

void BM_SculptStroke(benchmark::State& state) {
    mr::Simulation& s = river(kMaps[state.range(0)]);
    const mr::Aabb b = s.terrain().bounds();
    const mr::Brush brush{.x = 0.5f * (b.min.x + b.max.x), .z = 0.5f * (b.min.z + b.max.z), .radius = 4.0f,
                          .strength = 0.01f, .mode = mr::BrushMode::Raise};
    for (auto _ : state) {
        auto e = s.sculpt(brush);
        benchmark::DoNotOptimize(e);
    }
    state.SetLabel(kMaps[state.range(0)][0] ? kMaps[state.range(0)] : "valley");
    state.counters["samples"] = double(s.terrain().columns()) * double(s.terrain().rows());
}
BENCHMARK(BM_SculptStroke)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ChannelMapBuild(benchmark::State& state) {
    const mr::Terrain& t = river(kMaps[state.range(0)]).terrain();
    for (auto _ : state) {
        auto m = mr::ChannelMap::build(t);
        benchmark::DoNotOptimize(m);
    }
    state.SetLabel(kMaps[state.range(0)][0] ? kMaps[state.range(0)] : "valley");
}
BENCHMARK(BM_ChannelMapBuild)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
