// The lifecycle `run`, `render`, `view` and `bench` share (driver.h).
#include "driver.h"

#include "progress.h"
#include "report.h"

#include <metariver/io.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>

namespace mr::app {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

}  // namespace

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

std::string range_error(std::string_view option, long long v, long long lo, long long hi) {
    if (v >= lo && v <= hi) return {};
    return fmt::format("{}: must be in [{}, {}] (got {})", option, lo, hi, v);
}

std::string dt_error(double dt) {
    if (std::isfinite(dt) && dt > 0.0 && dt <= 1.0) return {};
    return fmt::format("--dt: must be in (0, 1] seconds (got {})", dt);
}

nlohmann::json stage_json(const std::vector<double>& ms) {
    const Percentiles p = percentiles(ms);
    return {{"median", p.median}, {"p95", p.p95}, {"mean", p.mean}, {"max", p.max}};
}

Status write_export_frame(Exporter& exporter, long long frame, double time_s, const Simulation& sim) {
    return exporter.write_frame(frame, time_s, sim.surface(), sim.particles(), sim.frame(),
                                sim.foam() ? &sim.foam()->particles() : nullptr, sim.view().bodies, sim.heightfield(),
                                &sim.terrain());
}

// ---- Outputs ----

Status Outputs::make_folder(std::string_view option, const std::string& path) {
    std::error_code ec;
    if (fs::exists(path, ec) && !fs::is_directory(path, ec))
        return Error{fmt::format("{} {}: exists and is not a folder", option, path)};
    if (fs::exists(path, ec)) return Ok{};
    if (!fs::create_directories(path, ec) || ec)
        return Error{fmt::format("{} {}: cannot create folder: {}", option, path, ec ? ec.message() : "unknown error")};
    folders_.push_back(path);
    return Ok{};
}

void Outputs::discard() {
    for (auto& hook : hooks_) hook();
    std::error_code ec;
    for (const auto& f : files_) fs::remove(f, ec);
    for (auto it = folders_.rbegin(); it != folders_.rend(); ++it) fs::remove_all(*it, ec);
    hooks_.clear();
    files_.clear();
    folders_.clear();
}

// ---- Driver ----

Driver::Driver(DriverDef def) : def_(std::move(def)) {}

Driver::~Driver() {
    if (!finished_) outputs_.discard();
}

int Driver::fail(int code, const std::string& message) {
    if (show_progress_) end_progress();
    show_progress_ = false;
    if (!def_.quiet) fmt::print(stderr, "metariver {}: {}\n", def_.command, message);
    exporter_.reset();  // removes the export's files: it did not finish
    outputs_.discard();
    exit_code_ = code;
    error_ = message;
    return code;
}

bool Driver::stop(int code, const std::string& message) {
    fail(code, message);
    return false;
}

bool Driver::resolve(const SceneOptions& options, bool need_heightmap) {
    auto def = options.resolve(need_heightmap);
    if (!def) return stop(kExitBadInput, def.error().message);
    scene_ = std::move(def.value());
    return true;
}

Result<ExportDef> Driver::export_def(const ExportOptions& exp, long long frames) const {
    auto e = exp.resolve(frames, scene_);
    if (!e) return e;
    e->frame_rate = 1.0 / (def_.dt * double(def_.steps));
    e->solver_dt = def_.dt;
    return e;
}

bool Driver::resolve_export(const ExportOptions& exp) {
    if (!exp.given()) return true;
    auto e = export_def(exp, def_.frames);
    if (!e) return stop(kExitBadInput, e.error().message);
    export_def_ = std::move(e.value());
    return true;
}

bool Driver::load_heightmap() {
    auto map = load_scene_heightmap(scene_);
    if (!map) return stop(kExitBadInput, map.error().message);
    map_ = std::move(map.value());
    return true;
}

bool Driver::create(const Heightmap* map) {
    if (!map && map_) map = &*map_;
    auto sim = map ? Simulation::create(scene_, *map) : Simulation::create(scene_);
    if (!sim) return stop(kExitBadInput, sim.error().message);
    sim_ = std::move(sim.value());
    if (def_.announce) announce();
    return true;
}

void Driver::announce() const {
    const Simulation& sim = *sim_;
    for (const std::string& w : sim.warnings()) fmt::print(stderr, "metariver {}: warning: {}\n", def_.command, w);
    if (const auto& z = sim.sizing())
        fmt::print("particles sized to the main channel ({:.0f} m, mean slope {:.3f}, sized for {:.2f} m/s): count {}, "
                   "flow_rate {:.1f}/s, spacing {:.3g} m{}\n",
                   z->channel_length_m, z->channel_slope, z->speed, sim.def().spawn.count,
                   sim.def().spawn.particles_per_second(), sim.def().pbf.spacing,
                   z->capped ? " (budget at its ceiling: the rate was lowered to fit)" : "");
    if (const ConditionReport& c = sim.terrain().condition_report(); c.mode != TerrainCondition::None)
        fmt::print("terrain.condition = {}: {} cells raised, {} lowered, largest change {:.2f} m ({:.0f} m^3)\n",
                   to_string(c.mode), c.cells_raised, c.cells_lowered, c.max_change_m, c.volume_m3);
}

bool Driver::check_stats() {
    if (def_.stats.empty()) return true;
    const fs::path p(def_.stats);
    const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        return stop(kExitBadInput, fmt::format("--stats {}: folder '{}' does not exist", def_.stats, dir.string()));
    if (fs::is_directory(p, ec))
        return stop(kExitBadInput, fmt::format("--stats {}: is a folder, expected a file path", def_.stats));
    return true;
}

bool Driver::begin_export() {
    if (!export_def_) return true;
    const auto& formats = export_def_->formats;
    if (!sim_->heightfield() && std::find(formats.begin(), formats.end(), ExportFormat::Npy) != formats.end())
        return stop(kExitBadInput, fmt::format("--format npy: solver \"{}\" has no heightfield water (npy writes a "
                                               "heightfield solver's grid: solver = \"swe\")",
                                               sim_->def().solver.name));
    std::signal(SIGXFSZ, SIG_IGN);  // a file size limit: an error from write(), not a kill
    auto e = Exporter::begin(*export_def_);
    if (!e) return stop(kExitBadInput, e.error().message);
    exporter_ = std::move(e.value());
    if (auto s = exporter_->write_terrain(sim_->terrain()); !s) return stop(kExitFailure, s.error().message);
    return true;
}

void Driver::warm_up() {
    const float dt = static_cast<float>(def_.dt);
    for (long long i = 0; i < def_.warmup; ++i) sim_->step(dt);
}

void Driver::record_stages(double step_ms, double export_ms) {
    const FrameTimings& t = sim_->last_timings();
    const double times[kStageCount] = {t.simulate_ms,
                                       t.field_ms,
                                       t.surface_ms,
                                       t.simulate_ms + t.foam_ms + t.field_ms + t.surface_ms,
                                       t.foam_ms,
                                       t.smoothing_ms,
                                       step_ms,
                                       export_ms};
    stage_ms_.push(times);
}

bool Driver::loop(const FrameWork& work) {
    const float dt = static_cast<float>(def_.dt);
    // 512 KiB for the eight columns, allocated before the first frame: runs of up to 1e8
    // frames in constant memory.
    stage_ms_ = Checkpoints(kTimingSamples, kStageCount);
    show_progress_ = progress_wanted(def_.progress, def_.frames);
    loop_start_ = Clock::now();
    for (long long f = 0; f < def_.frames; ++f) {
        const auto t0 = Clock::now();
        for (long long s = 0; s < def_.steps; ++s) sim_->step(dt);
        const double step_ms = ms_since(t0);
        if (!work(f)) return false;
        double export_ms = 0.0;
        if (exporter_ && exporter_->due(f)) {
            const auto t1 = Clock::now();
            if (auto s = write_export_frame(*exporter_, f, time_s(f), *sim_); !s)
                return stop(kExitFailure, s.error().message);
            export_ms = ms_since(t1);
        }
        record_stages(step_ms, export_ms);
        if (def_.report_every > 0 && (f + 1) % def_.report_every == 0) {
            fmt::print("{}\n", report_line(*sim_, steps_done(f)));
            std::fflush(stdout);
        }
        if (show_progress_) print_progress(f + 1, def_.frames, elapsed_s());
    }
    if (show_progress_) end_progress();
    show_progress_ = false;
    return true;
}

double Driver::elapsed_s() const { return std::chrono::duration<double>(Clock::now() - loop_start_).count(); }

bool Driver::finish(const std::function<nlohmann::json()>& stats) {
    if (!def_.stats.empty()) {
        if (auto s = write_file_atomic(def_.stats, stats().dump(2) + "\n"); !s)
            return stop(kExitFailure, s.error().message);
        outputs_.add_file(def_.stats);  // taken back if the export cannot finish
    }
    if (exporter_) {  // the manifest last: once it is there, the export is complete
        if (auto s = exporter_->finish(); !s) return stop(kExitFailure, s.error().message);
    }
    finished_ = true;
    return true;
}

void Driver::print_written() const {
    if (exporter_) print_export_summary(*exporter_);
    if (!def_.stats.empty()) fmt::print("wrote stats to {}\n", def_.stats);
}

}  // namespace mr::app
