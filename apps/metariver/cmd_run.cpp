// `metariver run`: headless simulation of a scene for N frames; optional export of the
// water and particles (--export: obj, ply, glb, vdb; docs/export.md), the earlier
// water-only OBJ sequence (--obj-dir) and a JSON stats file. Deterministic for a seed.
// All inputs are checked before anything is written; a failure part-way removes what
// this run wrote.
#include "commands.h"
#include "export_options.h"
#include "progress.h"
#include "report.h"

#include <metariver/export.h>
#include <metariver/checkpoints.h>
#include <metariver/io.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

namespace mr::app {

namespace {

namespace fs = std::filesystem;

struct RunOptions {
    SceneOptions scene;
    long long frames = 300;
    double dt = 1.0 / 60.0;
    std::string stats;
    std::string obj_dir;
    std::optional<long long> obj_every;  ///< --obj-every; unset = every frame
    ExportOptions exp;                   ///< --export DIR --format ... --every N --range A:B
    bool progress = true;                ///< --no-progress: no bar on a terminal
    long long report_every = 0;          ///< --report-every: a report line every N frames (0: none)
};

constexpr long long kMaxFrames = 100'000'000;
/// Stage-time samples kept per stage (evenly spaced frames beyond; 256 KiB for the four
/// stages, allocated before the first frame).
constexpr size_t kTimingSamples = size_t{1} << 13;
constexpr long long kMaxObjEvery = 1'000'000'000;

int fail(int code, const std::string& message) {
    fmt::print(stderr, "metariver run: {}\n", message);
    return code;
}

/// Checks that `path`'s folder exists, so a long run does not fail only at the end.
Status check_output_file(const std::string& option, const std::string& path) {
    const fs::path p(path);
    const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        return Error{fmt::format("{} {}: folder '{}' does not exist", option, path, dir.string())};
    if (fs::is_directory(p, ec)) return Error{fmt::format("{} {}: is a folder, expected a file path", option, path)};
    return Ok{};
}

nlohmann::json stage_json(const std::vector<double>& ms) {
    const Percentiles p = percentiles(ms);
    return {{"median", p.median}, {"p95", p.p95}, {"mean", p.mean}, {"max", p.max}};
}

/// One entry per outlet: cell [row, col], position [x, z] (metres), drainage cells,
/// particles over the run, rate over the second half, whether it is the main channel's.
nlohmann::json outlets_json(const OutletMeter& m, const OutletMeter::Summary& s) {
    nlohmann::json a = nlohmann::json::array();
    for (size_t k = 0; k < m.outlets().size(); ++k) {
        const OutletMeter::Outlet& o = m.outlets()[k];
        a.push_back({{"cell", {o.row, o.column}},
                     {"position", {o.x, o.z}},
                     {"accumulation", o.accumulation},
                     {"particles", s.outlets[k].particles},
                     {"rate_per_s", s.outlets[k].rate},
                     {"main", o.main}});
    }
    return a;
}

int run(const RunOptions& o) {
    if (o.frames < 1 || o.frames > kMaxFrames)
        return fail(kExitBadInput, fmt::format("--frames: must be in [1, {}] (got {})", kMaxFrames, o.frames));
    if (!std::isfinite(o.dt) || o.dt <= 0.0 || o.dt > 1.0)
        return fail(kExitBadInput, fmt::format("--dt: must be in (0, 1] seconds (got {})", o.dt));
    if (o.obj_every && o.obj_dir.empty())
        return fail(kExitBadInput, "--obj-every: needs --obj-dir (the folder to write to)");
    if (o.obj_every && (*o.obj_every < 1 || *o.obj_every > kMaxObjEvery))
        return fail(kExitBadInput, fmt::format("--obj-every: must be in [1, {}] (got {})", kMaxObjEvery, *o.obj_every));
    if (o.report_every < 0 || o.report_every > kMaxObjEvery)
        return fail(kExitBadInput, fmt::format("--report-every: must be in [0, {}] (got {})", kMaxObjEvery, o.report_every));
    const long long obj_every = o.obj_every.value_or(1);
    auto def = o.scene.resolve();
    if (!def) return fail(kExitBadInput, def.error().message);
    std::optional<ExportDef> export_def;
    if (o.exp.given()) {
        auto e = o.exp.resolve(o.frames, def.value());
        if (!e) return fail(kExitBadInput, e.error().message);
        export_def = std::move(e.value());
        export_def->frame_rate = 1.0 / o.dt;
        export_def->solver_dt = o.dt;
    }

    auto sim_result = Simulation::create(def.value());
    if (!sim_result) return fail(kExitBadInput, sim_result.error().message);
    Simulation& sim = *sim_result.value();
    for (const std::string& w : sim.warnings()) fmt::print(stderr, "metariver run: warning: {}\n", w);
    if (const auto& z = sim.sizing())
        fmt::print("particles sized to the main channel ({:.0f} m, mean slope {:.3f}, sized for {:.2f} m/s): count {}, "
                   "flow_rate {:.1f}/s, spacing {:.3g} m{}\n",
                   z->channel_length_m, z->channel_slope, z->speed, sim.def().spawn.count,
                   sim.def().spawn.particles_per_second(), sim.def().pbf.spacing,
                   z->capped ? " (budget at its ceiling: the rate was lowered to fit)" : "");
    if (const ConditionReport& c = sim.terrain().condition_report(); c.mode != TerrainCondition::None)
        fmt::print("terrain.condition = {}: {} cells raised, {} lowered, largest change {:.2f} m ({:.0f} m^3)\n",
                   to_string(c.mode), c.cells_raised, c.cells_lowered, c.max_change_m, c.volume_m3);

    // The OBJ folder: created if missing; everything this run writes there is recorded
    // so a failure can take it back.
    bool created_dir = false;
    std::vector<std::string> written;
    auto cleanup = [&] {
        std::error_code ec;
        for (const auto& f : written) fs::remove(f, ec);
        if (created_dir) fs::remove(o.obj_dir, ec);
    };
    if (!o.obj_dir.empty()) {
        std::error_code ec;
        if (fs::exists(o.obj_dir, ec) && !fs::is_directory(o.obj_dir, ec))
            return fail(kExitBadInput, fmt::format("--obj-dir {}: exists and is not a folder", o.obj_dir));
        if (!fs::exists(o.obj_dir, ec)) {
            if (!fs::create_directories(o.obj_dir, ec) || ec)
                return fail(kExitBadInput, fmt::format("--obj-dir {}: cannot create folder: {}", o.obj_dir, ec.message()));
            created_dir = true;
        }
        const std::string terrain_path = (fs::path(o.obj_dir) / "terrain.obj").string();
        if (auto s = write_terrain_obj(terrain_path, sim.terrain()); !s) {
            cleanup();
            return fail(kExitBadInput, "--obj-dir: " + s.error().message);
        }
        written.push_back(terrain_path);
    }
    if (!o.stats.empty()) {  // checked after the OBJ folder, which may hold it
        if (auto s = check_output_file("--stats", o.stats); !s) {
            cleanup();
            return fail(kExitBadInput, s.error().message);
        }
    }
    // The export: its folder now (bad input), the terrain once; if the run fails, every
    // file it wrote goes (the Exporter removes them unless finish() succeeded).
    std::unique_ptr<Exporter> exporter;
    if (export_def) {
        std::signal(SIGXFSZ, SIG_IGN);  // a file size limit: an error from write(), not a kill
        auto e = Exporter::begin(*export_def);
        if (!e) {
            cleanup();
            return fail(kExitBadInput, e.error().message);
        }
        exporter = std::move(e.value());
        if (auto s = exporter->write_terrain(sim.terrain()); !s) {
            cleanup();
            return fail(kExitFailure, s.error().message);
        }
    }
    const bool show_progress = progress_wanted(o.progress, o.frames);
    const auto t_start = std::chrono::steady_clock::now();

    // Stage times (simulate, field, surface, total): every frame up to kTimingSamples,
    // then evenly spaced frames (Checkpoints), so memory stays constant for runs of up
    // to 1e8 frames; percentiles come from the kept samples.
    Checkpoints stage_ms(kTimingSamples, 6);
    const int digits = std::max(5, static_cast<int>(std::to_string(o.frames - 1).size()));
    // Plausibility: outflow at the sinks, wet-channel and spray fractions (sampled every
    // 10 frames over the second half; spray also at the last frame), largest speed and
    // density error seen.
    // Per outlet (issue 10): exits assigned to the terrain's outlets; the main channel's
    // coverage sampled with spray.
    FlowMeter flow;
    OutletMeter outlets(sim.terrain(), sim.channel(), sim.main_channel().back());
    double wet_sum = 0.0, density_mean_sum = 0.0, spray_sum = 0.0, coverage_sum = 0.0;
    long long wet_n = 0, spray_n = 0;
    float max_speed = 0.0f, density_max = 0.0f;
    for (long long f = 0; f < o.frames; ++f) {
        sim.step(static_cast<float>(o.dt));
        if (o.report_every > 0 && (f + 1) % o.report_every == 0) {
            fmt::print("{}\n", report_line(sim, f + 1));
            std::fflush(stdout);
        }
        flow.record(double(f + 1) * o.dt, sim.counters().sunk);
        outlets.record(double(f + 1) * o.dt, sim.last_exits());
        max_speed = std::max(max_speed, sim.counters().max_speed);
        density_max = std::max(density_max, sim.counters().density_error_max);
        if (2 * f >= o.frames && f % 10 == 0) {
            wet_sum += sim.wet_fraction();
            density_mean_sum += sim.counters().density_error_mean;
            ++wet_n;
        }
        if ((2 * f >= o.frames && f % 10 == 0) || f == o.frames - 1) {
            spray_sum += sim.spray_fraction();
            coverage_sum += sim.channel_coverage();
            ++spray_n;
        }
        const FrameTimings& t = sim.last_timings();
        const double times[6] = {t.simulate_ms, t.field_ms, t.surface_ms,
                                 t.simulate_ms + t.foam_ms + t.field_ms + t.surface_ms, t.foam_ms, t.smoothing_ms};
        stage_ms.push(times);
        if (!o.obj_dir.empty() && (f % obj_every == 0 || f == o.frames - 1)) {
            const std::string path = (fs::path(o.obj_dir) / fmt::format("surface_{:0{}}.obj", f, digits)).string();
            if (auto s = write_surface_obj(path, sim.surface(), fmt::format("metariver water surface, frame {}", f)); !s) {
                if (show_progress) end_progress();
                cleanup();
                return fail(kExitFailure, s.error().message);
            }
            written.push_back(path);
        }
        if (exporter && exporter->due(f)) {
            if (auto s = exporter->write_frame(f, double(f + 1) * o.dt, sim.surface(), sim.particles(), sim.frame(),
                                                 sim.foam() ? &sim.foam()->particles() : nullptr); !s) {
                if (show_progress) end_progress();
                cleanup();
                return fail(kExitFailure, s.error().message);
            }
        }
        if (show_progress)
            print_progress(f + 1, o.frames,
                           std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
    }
    if (show_progress) end_progress();

    const SolverCounters& c = sim.counters();
    const SceneDef& d = sim.def();
    const double spray = spray_sum / double(std::max(spray_n, 1LL));
    const Percentiles final_speed = percentiles(sim.active_speeds());
    const double coverage = coverage_sum / double(std::max(spray_n, 1LL));
    const OutletMeter::Summary os = outlets.summary();
    const double inflow = d.spawn.total_particles_per_second();  // every source, as asked, not capped
    const double over_inflow = inflow > 0.0 ? os.main.rate / inflow : 0.0;
    if (!o.stats.empty()) {
        nlohmann::json j;
        j["scene"] = d.name;
        j["seed"] = d.seed;
        j["frames"] = o.frames;
        j["dt"] = o.dt;
        j["solver"] = std::string(to_string(d.solver));
        j["collision"] = std::string(to_string(d.collision.mode));
        j["field_kernel"] = std::string(to_string(d.field.kernel));
        const ConditionReport& cond = sim.terrain().condition_report();
        j["terrain"] = {{"columns", sim.terrain().columns()},
                        {"rows", sim.terrain().rows()},
                        {"triangles", sim.terrain().triangle_count()},
                        {"area_scale", sim.terrain().area_scale()},
                        {"condition",
                         {{"mode", std::string(to_string(cond.mode))},
                          {"cells_raised", cond.cells_raised},
                          {"cells_lowered", cond.cells_lowered},
                          {"max_change_m", cond.max_change_m},
                          {"volume_m3", cond.volume_m3}}}};
        if (const auto& z = sim.sizing())
            j["sizing"] = {{"channel_length_m", z->channel_length_m}, {"channel_slope", z->channel_slope},
                           {"speed_m_s", z->speed}, {"count", d.spawn.count},
                           {"flow_rate", d.spawn.particles_per_second()}, {"capped", z->capped},
                           {"spacing", d.pbf.spacing}, {"prefilled", sim.prefilled()}};
        j["particles_total"] = sim.particles().size();
        j["particles_active"] = sim.particles().active_count();
        j["triangles"] = sim.surface().triangle_count();
        j["vertices"] = sim.surface().vertex_count();
        j["field_grid"] = sim.field_dims();
        // The last frame's smoothing ([surface], issue 11).
        const SmoothingStats& sm = sim.smoothing_stats();
        j["surface_smoothing"] = {{"method", std::string(to_string(d.smoothing.method))},
                                  {"moving_vertices", sm.moving},
                                  {"pinned_vertices", sm.pinned},
                                  {"hidden_vertices", sm.hidden},
                                  {"mean_weight", sm.mean_weight},
                                  {"volume_change_m3", sm.volume_change}};
        j["field_overflows"] = sim.field_overflows();
        j["particle_steps"] = c.particle_steps;
        j["collisions"] = c.collisions;
        j["tunneled"] = c.tunneled;
        j["respawned"] = c.respawned;
        j["guarded"] = c.guarded;
        const FlowMeter::Summary fs = flow.summary();
        j["plausibility"] = {
            {"tunneled", c.tunneled},
            {"guarded", c.guarded},
            {"respawned", c.respawned},
            {"emitted", c.emitted},
            {"sunk", c.sunk},
            {"outflow_per_s", fs.rate},
            {"outflow_windows_per_s", {fs.windows[0], fs.windows[1], fs.windows[2], fs.windows[3]}},
            {"first_outflow_s", fs.first_outflow_s},
            {"outflow_steady", fs.steady},
            {"wet_channel_fraction", wet_n ? wet_sum / double(wet_n) : 0.0},
            {"density_error_mean", wet_n ? density_mean_sum / double(wet_n) : 0.0},
            {"density_error_max", density_max},
            {"max_speed", max_speed},
            {"final_speed", {{"median", final_speed.median}, {"p95", final_speed.p95}, {"max", final_speed.max}}},
            {"spray_fraction", spray},
            {"outflow_over_inflow", over_inflow},
            {"time_to_outlet_s", os.main.first_s},
            {"channel_coverage", coverage},
            {"main_channel_cells", sim.main_channel().size()},
            {"main_channel", sim.main_channel()},  // [row, column] from the source to the outlet
            {"outlets", outlets_json(outlets, os)},
            {"outlet_other", {{"particles", os.other.particles}, {"rate_per_s", os.other.rate}}}};
        j["state_hash"] = fmt::format("{:016x}", sim.state_hash());
        j["stage_ms"] = {{"simulate", stage_json(stage_ms.column(0))},
                         {"field", stage_json(stage_ms.column(1))},
                         {"surface", stage_json(stage_ms.column(2))},
                         {"total", stage_json(stage_ms.column(3))}};
        if (sim.foam()) j["stage_ms"]["foam"] = stage_json(stage_ms.column(4));
        // Part of surface (not in total).
        if (smoothing_on(d)) j["stage_ms"]["smoothing"] = stage_json(stage_ms.column(5));
        // Diffuse particles at the last frame ([foam], issue 11).
        if (const FoamSystem* f = sim.foam()) {
            const FoamStats& fs = f->stats();
            j["foam"] = {{"spray", fs.spray},
                         {"foam", fs.foam},
                         {"bubbles", fs.bubbles},
                         {"total", fs.total()},
                         {"max_particles", d.foam.max_particles},
                         {"generated_total", fs.generated_total},
                         {"capped_total", fs.capped_total}};
            // The potentials of the active fluid particles at the last frame (what the
            // [foam] thresholds are set against).
            const Particles& fp = sim.particles();
            auto potential = [&](std::span<const float> v) {
                std::vector<double> a;
                for (size_t i = 0; i < v.size(); ++i)
                    if (fp.active[i]) a.push_back(double(v[i]));
                const Percentiles q = percentiles(std::move(a));
                return nlohmann::json{{"median", q.median}, {"p95", q.p95}, {"max", q.max}};
            };
            j["foam"]["potentials"] = {{"trapped_air", potential(f->trapped_air())},
                                       {"wave_crest", potential(f->wave_crest())},
                                       {"kinetic_energy", potential(f->kinetic_energy())}};
        } else {
            j["foam"] = nullptr;
        }
        if (auto s = write_file_atomic(o.stats, j.dump(2) + "\n"); !s) {
            cleanup();
            return fail(kExitFailure, s.error().message);
        }
    }
    if (exporter) {  // the manifest last: once it is there, the export is complete
        if (auto s = exporter->finish(); !s) {
            cleanup();
            std::error_code ec;
            if (!o.stats.empty()) fs::remove(o.stats, ec);
            return fail(kExitFailure, s.error().message);
        }
    }
    const Percentiles tot = percentiles(stage_ms.column(3));
    fmt::print("{}: {} frames, {}/{} particles active, surface {} triangles / {} vertices, "
               "tunneled {}, guarded {}, respawned {}, outflow {:.1f}/s ({}), main outlet {:.1f}/s = {:.2f} of "
               "inflow (first at {:.2f} s), channel coverage {:.0f} %, wet {:.0f} %, spray {:.1f} %, "
               "final speed p95 {:.2f} m/s, frame median {:.3f} ms (p95 {:.3f})\n",
               d.name, o.frames, sim.particles().active_count(), sim.particles().size(),
               sim.surface().triangle_count(), sim.surface().vertex_count(), c.tunneled, c.guarded, c.respawned,
               flow.summary().rate, flow.summary().steady ? "steady" : "not steady", os.main.rate, over_inflow,
               os.main.first_s, 100.0 * coverage, 100.0 * (wet_n ? wet_sum / double(wet_n) : 0.0), 100.0 * spray,
               final_speed.p95, tot.median, tot.p95);
    if (sim.field_overflows() > 0)
        fmt::print(stderr, "metariver run: warning: field: no surface on {} of {} frames: {}; lower field.resolution\n",
                   sim.field_overflows(), o.frames, sim.field_overflow_message());
    if (!o.obj_dir.empty()) fmt::print("wrote {} OBJ files to {}\n", written.size(), o.obj_dir);
    if (exporter) print_export_summary(*exporter);
    if (!o.stats.empty()) fmt::print("wrote stats to {}\n", o.stats);
    return kExitOk;
}

}  // namespace

void register_run(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<RunOptions>();
    CLI::App* cmd = app.add_subcommand("run", "simulate a scene headless; deterministic for a seed");
    opts->scene.add_to(*cmd);
    cmd->add_option("--frames", opts->frames, "frames to simulate (default 300)");
    cmd->add_option("--dt", opts->dt, "frame time in seconds (default 1/60)");
    cmd->add_option("--stats", opts->stats, "write run statistics as JSON to this file");
    cmd->add_option("--obj-dir", opts->obj_dir, "write the water surface (and the terrain) as OBJ to this folder");
    cmd->add_option("--obj-every", opts->obj_every,
                    "with --obj-dir: write every N-th frame's surface (0, N, 2N, ... and the last), [1, 1e9]; default 1");
    opts->exp.add_to(*cmd);
    cmd->add_flag("!--no-progress", opts->progress, "no progress bar (it is shown on a terminal only)");
    cmd->add_option("--report-every", opts->report_every,
                    "print a report line (resident memory, particle counters, non-finite values) every N frames; "
                    "scripts/soak.sh reads them");
    cmd->callback([opts, &action] { action = [opts] { return run(*opts); }; });
}

}  // namespace mr::app
