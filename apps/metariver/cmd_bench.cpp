// `metariver bench`: per-stage timings of the project's workloads, and (with --peers)
// the installed peers on the same workloads in the same run, side by side.
// Scenarios: the paper's scenes (own physics, as the paper), the springs river at
// 1k/10k/50k/100k particles (fast pipeline), the PBF river at 4k/16k/50k/100k in steady
// flow, W1, W2 and W3 exactly as ../shared/peers/README.md and pbf_anchor/README.md
// define them, the export of the default river in each format (docs/export.md) and the
// default river on each --heightmap (maps).
// Medians and p95 over measured frames; with --json also a plot (SVG) of ms per frame
// against particles beside it. The workloads themselves: bench_scenarios.cpp.
#include "commands.h"
#include "bench_peers.h"
#include "bench_plot.h"
#include "bench_scenarios.h"
#include "driver.h"

#include <metariver/io.h>
#include <metariver/workloads.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>
#include <thread>
#include <unistd.h>

namespace mr::app {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct BenchOptions {
    std::string scenario;
    int balls = 0;
    int res = 0;
    int spheres = 0;
    int particles = 0;
    bool particles_given = false;  ///< --particles was on the command line (0 is then an error)
    int nx = 0;
    bool nx_given = false;
    int frames = 0;
    int warmup = -1;  ///< -1: per scenario
    int threads = 0;
    std::string json_path;
    std::string maps_dir = "../shared/heightmaps/metawater";
    std::vector<std::string> heightmaps;  ///< --heightmap: scenario maps, the default river on each
    std::string peers_dir = "bench/peers";
    bool peers = false;
    bool gpu = false;  ///< --gpu: w1's field and w3's step also on the GPU (gpu_field.h, gpu_pbf.h)
};

json machine_json(int threads) {
    json m;
    std::ifstream cpu("/proc/cpuinfo");
    std::string line, model = "unknown";
    while (std::getline(cpu, line))
        if (line.rfind("model name", 0) == 0) {
            model = line.substr(line.find(':') + 2);
            break;
        }
    m["cpu"] = model;
    m["hardware_threads"] = std::thread::hardware_concurrency();
    m["threads_used"] = threads;
    std::ifstream os("/etc/os-release");
    while (std::getline(os, line))
        if (line.rfind("PRETTY_NAME=", 0) == 0) m["os"] = line.substr(13, line.size() - 14);
#ifdef __VERSION__
    m["compiler"] = std::string("g++ ") + __VERSION__;
#endif
    return m;
}

json result_json(const ScenarioResult& r, int threads) {
    json j;
    j["scenario"] = r.name;
    j["params"] = r.params;
    j["particles"] = r.particles;
    j["triangles"] = r.triangles;
    j["threads"] = threads;
    j["quality"] = r.quality;
    if (!r.note.empty()) j["note"] = r.note;
    json stages = json::object();
    for (const auto& s : r.stage_order) {
        const Percentiles p = percentiles(r.stage_ms.at(s));
        stages[s] = {{"median_ms", p.median}, {"p95_ms", p.p95}, {"samples", r.stage_ms.at(s).size()}};
    }
    j["stages"] = stages;
    return j;
}

void print_table(const std::vector<ScenarioResult>& results) {
    fmt::print("{:<24} {:<9} {:>10} {:>10} {:>10} {:>11}  {}\n", "scenario", "stage", "median ms", "p95 ms",
               "particles", "triangles", "quality");
    for (const auto& r : results) {
        if (r.stage_order.empty()) {
            fmt::print("{:<24} {}\n", r.name, r.note);
            continue;
        }
        bool first = true;
        for (const auto& s : r.stage_order) {
            const Percentiles p = percentiles(r.stage_ms.at(s));
            fmt::print("{:<24} {:<9} {:>10.3f} {:>10.3f} {:>10} {:>11}  {}\n", first ? r.name : "", s, p.median, p.p95,
                       first ? std::to_string(r.particles) : "", first ? std::to_string(r.triangles) : "",
                       first ? r.quality.dump() : "");
            first = false;
        }
        if (!r.note.empty()) fmt::print("{:<24} note: {}\n", "", r.note);
    }
}

/// The PBF river rows once more, times and plausibility on one line each: speed must
/// never silently buy a worse river.
void print_pbf_summary(const std::vector<ScenarioResult>& results) {
    bool header = false;
    for (const auto& r : results) {
        if (r.name.rfind("pbf ", 0) != 0 || r.stage_order.empty()) continue;
        if (!header) {
            fmt::print("\nPBF river in steady flow: ms per frame, median [p95] (smoothing: part of surface); "
                       "plausibility beside\n");
            fmt::print("{:<11} {:>9} {:>7} {:>17} {:>15} {:>15} {:>15} {:>15} {:>17} {:>9} {:>7} {:>7} {:>9} {:>8}\n",
                       "scenario", "particles", "spacing", "simulate", "foam", "field", "surface", "smoothing", "total",
                       "coverage", "out/in", "spray", "tunneled", "guarded");
            header = true;
        }
        const auto cell = [&](const char* stage) {
            if (!r.stage_ms.count(stage)) return std::string("-");  // foam off
            const Percentiles p = percentiles(r.stage_ms.at(stage));
            return fmt::format("{:.2f} [{:.2f}]", p.median, p.p95);
        };
        const json& q = r.quality;
        fmt::print("{:<11} {:>9} {:>7.3f} {:>17} {:>15} {:>15} {:>15} {:>15} {:>17} {:>9.2f} {:>7.2f} {:>7.4f} {:>9} {:>8}\n",
                   r.name, r.particles, r.params.value("spacing", 0.0), cell("simulate"), cell("foam"), cell("field"),
                   cell("surface"), cell("smoothing"), cell("total"), q.value("channel_coverage", 0.0), q.value("outflow_over_inflow", 0.0),
                   q.value("spray_fraction", 0.0), q.value("tunneled", 0), q.value("guarded", 0));
    }
}

/// ms per frame against particles: the PBF river's stages, our W3 step and the anchor's.
PlotDef bench_plot(const std::vector<ScenarioResult>& results, const json& peers) {
    PlotDef plot{.title = "metariver bench: ms per frame (median) vs particles",
                 .budget_ms = 1000.0 / 60.0,
                 .budget_label = "16.7 ms = 60 fps"};
    const char* colors[] = {"#1f77b4", "#8c564b", "#2ca02c", "#9467bd", "#000000"};
    const char* stages[] = {"simulate", "foam", "field", "surface", "total"};
    for (int k = 0; k < 5; ++k) {
        PlotSeries s{.name = fmt::format("PBF river {}", stages[k]), .color = colors[k]};
        for (const auto& r : results)
            if (r.name.rfind("pbf ", 0) == 0 && r.stage_ms.count(stages[k]))
                s.points.emplace_back(double(r.particles), percentiles(r.stage_ms.at(stages[k])).median);
        plot.series.push_back(std::move(s));
    }
    PlotSeries w3{.name = "W3 block: our PBF step", .color = "#d62728"};
    for (const auto& r : results)
        if (r.name.rfind("w3 ", 0) == 0 && r.stage_ms.count("step"))
            w3.points.emplace_back(double(r.particles), percentiles(r.stage_ms.at("step")).median);
    plot.series.push_back(std::move(w3));
    PlotSeries w3_gpu{.name = "W3 block: our PBF step, GPU", .color = "#9467bd"};
    for (const auto& r : results)
        if (r.name.rfind("w3-gpu ", 0) == 0 && r.stage_ms.count("step"))
            w3_gpu.points.emplace_back(double(r.particles), percentiles(r.stage_ms.at("step")).median);
    if (!w3_gpu.points.empty()) plot.series.push_back(std::move(w3_gpu));
    PlotSeries anchor{.name = "W3 block: PBF anchor", .color = "#ff7f0e", .dashed = true};
    if (peers.is_object() && peers.contains("rows"))
        for (const json& row : peers["rows"])
            if (row.value("workload", "") == "w3")
                anchor.points.emplace_back(row.value("n", 0.0), row.value("median_ms", 0.0));
    plot.series.push_back(std::move(anchor));
    return plot;
}

/// The scenarios --scenario (and --heightmap) chose and what they run on.
struct BenchPlan {
    int threads = 0;                  ///< --threads, or every core
    std::vector<std::string> chosen;  ///< --scenario a,b: several in one run (one JSON, one plot); empty: all but maps
    /// Scenario maps: every scene resolved and its heightmap read and checked before
    /// anything runs (a broken map is an error, not a skipped row); the simulations use
    /// what was read.
    struct MapScene {
        std::string file;
        SceneDef def;
        Heightmap map;
    };
    std::vector<MapScene> maps;

    bool want(std::string_view s) const {
        return chosen.empty() || std::find(chosen.begin(), chosen.end(), s) != chosen.end();
    }
};

/// --scenario into plan.chosen; the one-line error names the known scenarios.
Status parse_scenarios(const BenchOptions& o, BenchPlan& plan) {
    const std::vector<std::string> known = {"paper", "river", "pbf", "w1", "w2", "w3", "export", "maps", "bodies", "waterfall"};
    if (o.scenario.empty() && !o.heightmaps.empty()) plan.chosen.push_back("maps");  // --heightmap alone: just those
    for (std::string rest = o.scenario; !rest.empty();) {
        const size_t comma = rest.find(',');
        plan.chosen.push_back(rest.substr(0, comma));
        rest = comma == std::string::npos ? "" : rest.substr(comma + 1);
        if (std::find(known.begin(), known.end(), plan.chosen.back()) == known.end())
            return Error{fmt::format("--scenario: must be one or more (comma-separated) of paper, river, pbf, w1, w2, "
                                     "w3, export, maps (got '{}')",
                                     o.scenario)};
    }
    return Ok{};
}

/// The sizes and counts, checked for the chosen scenarios (one line naming the option).
Status check_sizes(const BenchOptions& o, const BenchPlan& plan) {
    if (plan.want("pbf") && o.particles_given && (o.particles < kPbfMinParticles || o.particles > kPbfMaxParticles))
        return Error{fmt::format("--particles: the PBF river must have [{}, {}] particles (got {})", kPbfMinParticles,
                                 kPbfMaxParticles, o.particles)};
    const int nx_max = o.gpu ? kW3GpuMaxNx : kW3MaxNx;
    if (o.nx_given && (o.nx < kW3MinNx || o.nx > nx_max))
        return Error{fmt::format("--nx: must be in [{}, {}]{} (nx * nx * nx/2 particles; got {})", kW3MinNx, nx_max,
                                 o.gpu ? " with --gpu" : fmt::format(" ({} with --gpu)", kW3GpuMaxNx), o.nx)};
    if (o.warmup < -1 || o.warmup > 100000)
        return Error{fmt::format("--warmup: must be in [0, 100000] (got {})", o.warmup)};
    if (o.balls < 0 || o.balls > 10'000'000 || o.res < 0 || (o.res != 0 && o.res < 2) || o.res > 1024)
        return Error{"--balls must be in [1, 10000000] and --res in [2, 1024]"};
    if (o.spheres < 0 || o.spheres > 1'000'000 || o.particles < 0 || o.particles > kMaxParticles ||
        (o.particles_given && o.particles == 0))
        return Error{fmt::format("--spheres must be in [1, 1000000], --particles in [1, {}]", kMaxParticles)};
    if (o.frames < 0 || o.frames > 100000)
        return Error{fmt::format("--frames: must be in [1, 100000] (got {})", o.frames)};
    return Ok{};
}

/// Scenario maps: each --heightmap's scene (the default river on it, as `run --heightmap
/// FILE`) and the map read, through a driver each.
Status load_maps(const BenchOptions& o, BenchPlan& plan) {
    if (!o.heightmaps.empty() && !plan.want("maps"))
        return Error{fmt::format("--heightmap: only for scenario maps (--scenario {})", o.scenario)};
    if (!plan.want("maps") || plan.chosen.empty()) return Ok{};
    if (o.heightmaps.empty()) return Error{"--scenario maps: needs --heightmap FILE[,FILE...]"};
    for (const std::string& file : o.heightmaps) {
        SceneOptions so;
        so.heightmap = file;
        Driver d({.command = "bench", .quiet = true});
        if (!d.resolve(so) || !d.load_heightmap()) return Error{"--heightmap: " + d.error()};
        plan.maps.push_back({file, d.scene(), d.take_heightmap()});
    }
    return Ok{};
}

/// Every option checked and the plan made before anything runs.
Status make_plan(const BenchOptions& o, BenchPlan& plan) {
    plan.threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
    if (o.threads < 0 || o.threads > 256)
        return Error{fmt::format("--threads: must be in [0, 256] (got {})", o.threads)};
    if (auto s = parse_scenarios(o, plan); !s) return s;
    if (auto s = check_sizes(o, plan); !s) return s;
    if (auto s = load_maps(o, plan); !s) return s;
    if (!o.json_path.empty()) {
        const fs::path dir = fs::path(o.json_path).parent_path();
        std::error_code ec;
        if (!dir.empty() && !fs::is_directory(dir, ec))
            return Error{fmt::format("--json {}: folder '{}' does not exist", o.json_path, dir.string())};
    }
    return Ok{};
}

/// The paper's scenes (own physics and pipeline; 1500 frames fill every spawn slot), on
/// the paper's heightmaps from --maps where the preset needs one.
void run_paper(const BenchOptions& o, std::vector<ScenarioResult>& results) {
    struct PaperScene {
        const char* preset;
        const char* map;
    };
    for (const PaperScene& ps : {PaperScene{"paper-full", "strict17.png"}, PaperScene{"paper-nile", "nile.png"},
                                 PaperScene{"paper-bowl", "bowl.png"}}) {
        SceneDef d = preset(ps.preset).value();
        const fs::path map = fs::path(o.maps_dir) / ps.map;
        if (fs::exists(map)) {
            d.source.kind = TerrainSource::File;
            d.source.heightmap = map.string();
        } else if (d.source.kind == TerrainSource::File) {
            const std::string note = "skipped: " + map.string() + " not found (--maps DIR)";
            results.push_back(ScenarioResult{.name = ps.preset, .note = note});
            continue;
        }
        results.push_back(bench_simulation(ps.preset, d, 1500, o.frames ? o.frames : 300));
    }
}

/// The springs river at each size, the default scene (the PBF river, measured once it has
/// filled the channel), the PBF river at about n particles in steady flow (big rivers
/// measure fewer frames: the warm-up dominates the wall time anyway).
void run_rivers(const BenchOptions& o, const BenchPlan& plan, std::vector<ScenarioResult>& results) {
    const int frames = o.frames;
    if (plan.want("river")) {
        std::vector<int> sizes = {1000, 10000, 50000, 100000};
        if (o.particles) sizes = {o.particles};
        for (int n : sizes) {
            const int f = frames ? frames : (n >= 50000 ? 60 : 120);
            results.push_back(bench_simulation(fmt::format("river {}", n), river_scene(n), 30, f));
        }
        if (!o.particles)
            results.push_back(bench_simulation("default (pbf river)", default_scene(), 600, frames ? frames : 120));
    }
    if (plan.want("pbf")) {
        std::vector<int> sizes = {4000, 16000, 50000, 100000};
        if (o.particles) sizes = {o.particles};
        const int warmup = o.warmup >= 0 ? o.warmup : kPbfWarmupFrames;
        for (int n : sizes) {
            const int f = frames ? frames : (n > 50000 ? 30 : n > 16000 ? 60 : 120);
            ScenarioResult r = bench_pbf_river(n, warmup, f);
            if (r.note.empty())
                r.note = fmt::format("{} warm-up frames ({:.0f} s of flow), {} measured frames{}", warmup, warmup / 60.0,
                                     f, !frames && n > 16000 ? " (fewer for large rivers)" : "");
            results.push_back(std::move(r));
        }
    }
}

/// W1, W2 and W3 at the peers' sizes (or the one asked for); the sizes go to --peers.
void run_workloads(const BenchOptions& o, const BenchPlan& plan, std::vector<ScenarioResult>& results,
                   PeerRequest& peers) {
    const int frames = o.frames;
    if (plan.want("w1")) {
        std::vector<std::pair<int, int>> cases = {{50, 32}, {1000, 64}, {1000, 128}, {10000, 128}, {10000, 256}};
        if (o.balls || o.res) cases = {{o.balls ? o.balls : 1000, o.res ? o.res : 128}};
        for (auto [n, res] : cases) {
            results.push_back(bench_w1(n, res, frames ? frames : 10));
            if (o.gpu) results.push_back(bench_w1_gpu(n, res, frames ? frames : 10));
        }
        peers.w1_cases = cases;
    }
    if (plan.want("w2")) {
        std::vector<int> sizes = {1000, 10000};
        if (o.spheres) sizes = {o.spheres};
        for (int n : sizes) results.push_back(bench_w2(n));
        peers.w2_sizes = sizes;
    }
    if (plan.want("w3")) {
        // The anchor's sizes (pbf_anchor/README.md): 16,384, 48,668 and 97,556 particles.
        std::vector<int> sides = {32, 46, 58};
        if (o.nx) sides = {o.nx};
        // --gpu: the GPU step alone past the CPU's range (the CPU would take minutes).
        for (int nx : sides)
            if (nx <= kW3MaxNx) results.push_back(bench_w3(nx, o.warmup >= 0 ? o.warmup : 3, frames ? frames : 20));
        if (o.gpu)
            for (int nx : sides) results.push_back(bench_w3_gpu(nx, o.warmup >= 0 ? o.warmup : 3, frames ? frames : 20));
        std::erase_if(sides, [](int nx) { return nx > kW3MaxNx; });
        peers.w3_nx = sides;
    }
}

/// Every chosen scenario, in the tables' order.
std::vector<ScenarioResult> run_scenarios(const BenchOptions& o, const BenchPlan& plan, PeerRequest& peers) {
    std::vector<ScenarioResult> results;
    if (plan.want("paper")) run_paper(o, results);
    run_rivers(o, plan, results);
    run_workloads(o, plan, results, peers);
    // The default river on each --heightmap (as `run --heightmap FILE`), surface on, measured
    // after 30 s of flow (the channel starts full: particles.prefill): the frame budget
    // of the river table (docs/river.md).
    for (const BenchPlan::MapScene& m : plan.maps)
        results.push_back(bench_simulation(fmt::format("default on {}", fs::path(m.file).filename().string()), m.def,
                                           m.map, o.warmup >= 0 ? o.warmup : kMapsWarmupFrames,
                                           o.frames ? o.frames : 120));
    if (plan.want("export")) results.push_back(bench_export(o.particles, 600, o.frames ? o.frames : 30));
    if (plan.want("bodies")) bench_river_bodies(o.warmup >= 0 ? o.warmup : 600, o.frames ? o.frames : 300, results);
    if (plan.want("waterfall")) bench_waterfall(o.warmup >= 0 ? o.warmup : 300, o.frames ? o.frames : 300, results);
    return results;
}

/// bench_peers.cpp: the installed peers on the same sizes, printed beside ours.
json run_peers_beside(const std::vector<ScenarioResult>& results, const PeerRequest& request, int threads) {
    std::vector<std::string> missing;
    const std::vector<PeerRow> peer_rows = run_peers(request, missing);
    std::vector<OursRow> ours;
    const auto med = [](const ScenarioResult& r, const char* s) {
        return r.stage_ms.count(s) ? percentiles(r.stage_ms.at(s)).median : 0.0;
    };
    for (const auto& r : results)
        if (r.params.contains("N") && r.params.contains("R") && r.name.rfind("w1 ", 0) == 0)  // not the GPU rows
            ours.push_back({.workload = "w1", .n = r.params["N"].get<int>(), .r = r.params["R"].get<int>(),
                            .field_surface_ms = med(r, "total"), .surface_ms = med(r, "surface"),
                            .triangles = r.triangles});
        else if (r.params.contains("spheres"))
            ours.push_back({.workload = "w2", .n = r.params["spheres"].get<int>(), .step_ms = med(r, "step")});
        else if (r.params.contains("nx") && r.name.rfind("w3 ", 0) == 0)  // not the GPU rows
            ours.push_back({.workload = "w3", .n = int(r.particles), .r = r.params["nx"].get<int>(),
                            .step_ms = med(r, "step")});
    return print_peers_side_by_side(ours, peer_rows, missing, threads);
}

/// --json: the machine and every result, and the plot beside it (bench.json -> bench.svg)
/// when a PBF river or W3 ran.
Status write_results(const std::string& path, const std::vector<ScenarioResult>& results, const json* peers,
                     int threads) {
    json j;
    j["machine"] = machine_json(threads);
    json arr = json::array();
    for (const auto& r : results) arr.push_back(result_json(r, threads));
    j["results"] = arr;
    if (peers) j["peers"] = *peers;
    const bool plotted = std::any_of(results.begin(), results.end(), [](const ScenarioResult& r) {
        return r.name.rfind("pbf ", 0) == 0 || r.name.rfind("w3", 0) == 0;
    });
    const std::string svg_path = fs::path(path).replace_extension(".svg").string();
    if (plotted) j["plot"] = svg_path;
    if (auto s = write_file_atomic(path, j.dump(2) + "\n"); !s) return s;
    fmt::print("wrote {}\n", path);
    if (plotted) {
        if (auto s = write_file_atomic(svg_path, plot_svg(bench_plot(results, peers ? *peers : json()))); !s) return s;
        fmt::print("wrote {}\n", svg_path);
    }
    return Ok{};
}

int run_bench(const BenchOptions& o) {
    Driver d({.command = "bench"});  // the exit code and the one-line errors
    BenchPlan plan;
    if (auto s = make_plan(o, plan); !s) return d.fail(kExitBadInput, s.error().message);
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(plan.threads));
    PeerRequest peer_request{.peers_dir = o.peers_dir, .threads = plan.threads};  // the W1/W2 sizes run, for --peers
    const std::vector<ScenarioResult> results = run_scenarios(o, plan, peer_request);
    print_table(results);
    print_pbf_summary(results);
    std::optional<json> peers;
    if (o.peers) peers = run_peers_beside(results, peer_request, plan.threads);
    if (!o.json_path.empty())
        if (auto s = write_results(o.json_path, results, peers ? &*peers : nullptr, plan.threads); !s)
            return d.fail(kExitFailure, s.error().message);
    return kExitOk;
}

}  // namespace

void register_bench(CLI::App& app, std::function<int()>& action) {
    auto o = std::make_shared<BenchOptions>();
    CLI::App* cmd = app.add_subcommand("bench", "time every stage on the project's workloads (and peers with --peers)");
    cmd->add_option("--scenario", o->scenario,
                    "one or more (comma-separated) of paper, river, pbf, w1, w2, w3, export, maps, bodies, waterfall (default: all but maps; "
                    "with --heightmap: maps)");
    cmd->add_option("--balls", o->balls, "W1: number of balls");
    cmd->add_option("--res", o->res, "W1: samples per axis");
    cmd->add_option("--spheres", o->spheres, "W2: number of spheres");
    CLI::Option* particles = cmd->add_option(
        "--particles", o->particles,
        fmt::format("river, export: number of particles; pbf: particles in steady flow, [{}, {}]", kPbfMinParticles,
                    kPbfMaxParticles));
    CLI::Option* nx = cmd->add_option("--nx", o->nx, fmt::format("w3: block side, nx * nx * nx/2 particles, [{}, {}]",
                                                                 kW3MinNx, kW3MaxNx));
    cmd->add_option("--warmup", o->warmup, "frames (w3: steps) before measuring (default: per scenario)");
    cmd->add_option("--frames", o->frames, "measured frames per scenario (default: per scenario)");
    cmd->add_option("--threads", o->threads, "worker threads (default: all cores)");
    cmd->add_option("--json", o->json_path, "write the results as JSON");
    cmd->add_option("--maps", o->maps_dir, "folder with the paper's heightmaps (default ../shared/heightmaps/metawater)");
    cmd->add_option("--heightmap", o->heightmaps,
                    "scenario maps: the default river on each of these PNG heightmaps (comma-separated), as `run "
                    "--heightmap FILE`, surface on, after 1800 warm-up frames")
        ->delimiter(',');
    cmd->add_flag("--peers", o->peers, "also run the installed peers on the same workloads");
    cmd->add_flag("--gpu", o->gpu,
                  "w1, w3: also run the field (w1) and the PBF step (w3) on the GPU (OpenGL 4.5 compute through "
                  "headless EGL; --nx up to 250)");
    cmd->add_option("--peers-dir", o->peers_dir, "folder with the peer drivers (default bench/peers)");
    cmd->callback([o, &action, particles, nx] {
        o->particles_given = particles->count() > 0;
        o->nx_given = nx->count() > 0;
        action = [o] { return run_bench(*o); };
    });
}

}  // namespace mr::app
