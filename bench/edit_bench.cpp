// The cost of a sculpt stroke under a running river (issue 14: "only the touched region"):
// the stroke alone, the network built from scratch, and a stroke with the network read
// after it (updated over the stroke's samples).
// Simulation::sculpt (the brush, the tree's refit, the drainage network and the main
// channel measured again, the water lifted onto the new ground) against its parts, on the
// default valley and on real DEMs of the shared folder (METARIVER_SHARED_DIR).
//
//   bench_edit --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Each stroke raises (and the next lowers) 1 cm with a 4 m brush at the middle of the
// terrain (so its heights change but the river does not notice); wall clock.
#include <metariver/drainage.h>
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
    mr::Brush b2 = brush;
    bool up = true;
    for (auto _ : state) {  // up and down again: the terrain does not drift over the run
        b2.mode = up ? mr::BrushMode::Raise : mr::BrushMode::Lower;
        up = !up;
        auto e = s.sculpt(b2);
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

// A stroke and the network read after it (Simulation::channel(): ChannelMap::update over
// the stroke's samples). Range 1: 0 the quiet stroke above (1 cm at the middle), 1 a dam:
// 1 m up, then down again, across the main channel halfway down it (the river reroutes
// and comes back; alternate iterations).
void BM_StrokeThenChannel(benchmark::State& state) {
    mr::Simulation& s = river(kMaps[state.range(0)]);
    const mr::Aabb b = s.terrain().bounds();
    mr::Brush brush{.x = 0.5f * (b.min.x + b.max.x), .z = 0.5f * (b.min.z + b.max.z), .radius = 4.0f, .strength = 0.01f};
    if (state.range(1) == 1) {
        const auto path = s.main_channel();
        const auto [i, j] = path[path.size() / 2];
        const mr::Vec3 o = s.terrain().vertices().front();
        brush = mr::Brush{.x = o.x + float(j) * s.terrain().area_scale(), .z = o.z + float(i) * s.terrain().area_scale(),
                          .radius = 3.0f * s.terrain().area_scale(), .strength = 1.0f};
    }
    bool up = true;
    for (auto _ : state) {
        brush.mode = up ? mr::BrushMode::Raise : mr::BrushMode::Lower;
        up = !up;
        auto e = s.sculpt(brush);
        benchmark::DoNotOptimize(e);
        benchmark::DoNotOptimize(s.channel().main_head());
    }
    state.SetLabel(std::string(kMaps[state.range(0)][0] ? kMaps[state.range(0)] : "valley") +
                   (state.range(1) ? " dam" : " quiet"));
}
BENCHMARK(BM_StrokeThenChannel)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
