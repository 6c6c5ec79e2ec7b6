// The workloads `metariver bench` times (apps/metariver/cmd_bench.cpp runs and prints
// them): a Simulation of any scene (the paper's scenes, the springs river, the default
// river on a heightmap), W1, W2 and W3 exactly as ../shared/peers/README.md and
// pbf_anchor/README.md define them, the PBF river in steady flow, and the export of the
// default river in each format. Each returns per-stage samples (ms) and quality numbers.
#pragma once

#include <metariver/scene.h>

#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

namespace mr::app {

using json = nlohmann::json;

/// One scenario's result: per-stage samples plus counts and quality numbers.
struct ScenarioResult {
    std::string name;
    json params = json::object();
    std::map<std::string, std::vector<double>> stage_ms;  // stage -> samples
    std::vector<std::string> stage_order;
    size_t particles = 0;
    size_t triangles = 0;
    json quality = json::object();  // tunneled, respawned, ...
    std::string note;

    void sample(const std::string& stage, double ms) {
        if (!stage_ms.count(stage)) stage_order.push_back(stage);
        stage_ms[stage].push_back(ms);
    }
};

/// Scenario maps: frames of flow before measuring (30 s).
constexpr int kMapsWarmupFrames = 1800;

/// Allowed sizes of the PBF river and of W3 (bad values exit 2 naming the range).
constexpr int kPbfMinParticles = 100, kPbfMaxParticles = 400'000;
constexpr int kW3MinNx = 4, kW3MaxNx = 100;  // nx = 100: 500,000 particles
constexpr int kW3GpuMaxNx = 250;              // --gpu: nx = 250: 7.8 million particles
/// The PBF river's warm-up: 40 s of flow; the default river's water reaches the outlet
/// after about 23 s and the particles on the terrain level off at 35-40 s
/// (docs/benchmarks.md).
constexpr int kPbfWarmupFrames = 2400;

/// A Simulation of `def`: `warmup` frames, then `frames` measured (stages simulate, foam
/// when the scene makes foam, field, surface, total; the river's plausibility in quality).
ScenarioResult bench_simulation(const std::string& name, const SceneDef& def, int warmup, int frames,
                                const std::string& note = {});
/// The same on a heightmap already loaded (load_scene_heightmap) for `def`.
ScenarioResult bench_simulation(const std::string& name, const SceneDef& def, const Heightmap& map, int warmup,
                                int frames, const std::string& note = {});
/// W1: n metaballs on an res^3 grid, field + surface.
ScenarioResult bench_w1(int n, int res, int frames);
ScenarioResult bench_w1_gpu(int n, int res, int frames);
/// W2: n spheres dropped on the W2 terrain (the springs solver as rigid spheres).
ScenarioResult bench_w2(int n);
/// The default PBF river resolved with about n particles, after `warmup` frames of flow.
ScenarioResult bench_pbf_river(int n, int warmup, int frames);
/// W3: the PBF anchor's block of nx * nx * nx/2 particles, `warmup` steps then `steps` timed.
ScenarioResult bench_w3(int nx, int warmup, int steps);
ScenarioResult bench_w3_gpu(int nx, int warmup, int steps);
/// Export cost by format of the default river (or `particles` of it) after `warmup` frames.
ScenarioResult bench_export(int particles, int warmup, int frames);
/// The default river after `warmup` frames, without bodies and with 20 logs dropped on its
/// water (bench_bodies.cpp): two rows, the second with its frame time's ratio to the first.
void bench_river_bodies(int warmup, int frames, std::vector<ScenarioResult>& out);
/// The waterfall preset with the grid alone and with the hybrid solver, and the default
/// river's cost per particle (bench_waterfall.cpp): three rows, the hybrid's with its bound.
void bench_waterfall(int warmup, int frames, std::vector<ScenarioResult>& out);

}  // namespace mr::app
