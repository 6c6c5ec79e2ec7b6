// The lifecycle that `run`, `render`, `view` and `bench` share (issue 42): the scene from
// the command line, the Simulation, the frame loop (steps, stage times, report lines,
// the progress bar, the export's frames), the --stats JSON, the --export session, the
// outputs a failure takes back, and the exit code. Each command keeps what is its own:
// run its OBJ sequence and river statistics (run_stats.h), render the renderer and the
// frames or video, view the window, bench the scenarios and their tables.
//
// A command makes one Driver, then calls its steps in order; a step returns false when it
// failed, and then the driver has printed the one-line error ("metariver COMMAND: ..."),
// ended the progress bar, taken back what the command wrote, and holds the exit code:
//
//     Driver d({.command = "run", .frames = n, .stats = path});
//     if (!d.resolve(o.scene) || !d.resolve_export(o.exp) || !d.create() || !d.check_stats() ||
//         !d.begin_export() || !d.loop(work) || !d.finish(stats_json))
//         return d.exit_code();
#pragma once

#include "commands.h"
#include "export_options.h"

#include <metariver/checkpoints.h>
#include <metariver/export.h>
#include <metariver/scene.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mr::app {

/// "OPTION: must be in [lo, hi] (got v)" when v is outside [lo, hi], else empty.
std::string range_error(std::string_view option, long long v, long long lo, long long hi);
/// "--dt: must be in (0, 1] seconds (got dt)" unless 0 < dt <= 1, else empty.
std::string dt_error(double dt);
/// Milliseconds since `t0` on the steady clock (the commands' stage and wall times).
double ms_since(std::chrono::steady_clock::time_point t0);
/// {"median", "p95", "mean", "max"} of `ms` (a stage in the --stats JSON).
nlohmann::json stage_json(const std::vector<double>& ms);
/// Writes `sim`'s latest frame (water, particles, the foam's when it makes foam) as
/// frame `frame` at `time_s` simulated seconds (run, render, view's Record).
Status write_export_frame(Exporter& exporter, long long frame, double time_s, const Simulation& sim);

/// What a command wrote, taken back when it fails part-way: discard() runs the hooks
/// (a video encoder closed before its file goes), removes the files, then the folders
/// the command created with everything in them. Folders that were there stay.
class Outputs {
public:
    /// Records a file the command wrote.
    void add_file(std::string path) { files_.push_back(std::move(path)); }
    /// Creates the folder `path` when it is missing (recorded: discard() removes it).
    /// Error naming `option`: it exists and is not a folder, or cannot be created.
    Status make_folder(std::string_view option, const std::string& path);
    /// Runs `hook` first in discard().
    void on_discard(std::function<void()> hook) { hooks_.push_back(std::move(hook)); }
    /// Files recorded so far.
    size_t files() const { return files_.size(); }
    /// Takes back everything recorded; recorded nothing afterwards.
    void discard();

private:
    std::vector<std::function<void()>> hooks_;
    std::vector<std::string> files_;
    std::vector<std::string> folders_;  ///< created by this command
};

/// What a command asks of the driver.
struct DriverDef {
    std::string command;         ///< "run", "render", ...: errors read "metariver COMMAND: ..."
    long long frames = 1;        ///< frames loop() produces (render: images), >= 1
    long long steps = 1;         ///< simulation steps per frame (render --steps), >= 1
    long long warmup = 0;        ///< simulation steps warm_up() takes before the first frame
    double dt = 1.0 / 60.0;      ///< seconds per simulation step, (0, 1]
    bool progress = false;       ///< the progress bar (drawn only on a terminal, for >= 10 frames)
    long long report_every = 0;  ///< a report line (report.h) every N frames; 0: none
    std::string stats;           ///< --stats FILE (JSON); empty: none
    bool announce = false;       ///< create() prints the scene's warnings, the river's sizing, the conditioning
    bool quiet = false;          ///< errors are kept (error()), not printed (bench: a skipped row)
};

/// Stage-time records Driver::stage_ms() keeps (evenly spaced frames beyond): a command
/// that times stages of its own in a Checkpoints of this capacity keeps the same frames.
inline constexpr size_t kTimingSamples = size_t{1} << 13;

/// The columns of stage_ms(), one record per frame.
enum DriverStage : size_t {
    kStageSimulate,   ///< the solver (FrameTimings::simulate_ms of the frame's last step)
    kStageField,      ///< the metaball field
    kStageSurface,    ///< marching cubes and the smoothing
    kStageTotal,      ///< simulate + foam + field + surface
    kStageFoam,       ///< the diffuse particles (0 when off)
    kStageSmoothing,  ///< the smoothing alone (part of surface)
    kStageStepWall,   ///< wall time of the frame's `steps` steps
    kStageExport,     ///< wall time of the export's frame (0 when none was due)
    kStageCount
};

class Driver {
public:
    explicit Driver(DriverDef def);
    /// Takes back the outputs unless finish() succeeded.
    ~Driver();
    Driver(const Driver&) = delete;
    Driver& operator=(const Driver&) = delete;

    // ---- load ----
    /// The scene the command line describes (SceneOptions::resolve). Bad input: exit 2.
    bool resolve(const SceneOptions& options, bool need_heightmap = true);
    /// The scene to run when it does not come from SceneOptions.
    void set_scene(SceneDef scene) { scene_ = std::move(scene); }
    /// `exp` checked against the scene for `frames` frames; frame rate 1 / (dt * steps),
    /// solver_dt dt. Bad input is the error.
    Result<ExportDef> export_def(const ExportOptions& exp, long long frames) const;
    /// When any export option was given: export_def(exp, frames), kept for begin_export().
    bool resolve_export(const ExportOptions& exp);
    /// Reads or generates the scene's heightmap (kept; create() builds on it). Exit 2.
    bool load_heightmap();
    /// Creates the Simulation of the scene: on `map` when given, else on the heightmap
    /// load_heightmap() read, else Simulation::create reads it. Bad scene: exit 2.
    bool create(const Heightmap* map = nullptr);

    // ---- outputs ----
    /// --stats: its folder exists and the path is not a folder. Exit 2.
    bool check_stats();
    /// The export resolve_export() kept: its folder, and the terrain once; no-op without
    /// one. Exit 2 for the folder, 1 for the terrain.
    bool begin_export();
    Outputs& outputs() { return outputs_; }

    // ---- step ----
    /// Takes def.warmup simulation steps (not measured, nothing written).
    void warm_up();
    /// The command's work for frame `frame` (0-based) after its steps; false after fail().
    using FrameWork = std::function<bool(long long frame)>;
    /// Frames 0 .. frames-1: each `steps` steps, then `work`, then the export's frame when
    /// due, the stage times, a report line every report_every frames and the progress bar.
    /// Stops at the first failure.
    bool loop(const FrameWork& work);
    /// Simulation steps taken by the end of `frame` (warm-up included).
    long long steps_done(long long frame) const { return def_.warmup + (frame + 1) * def_.steps; }
    /// Simulated seconds at the end of `frame`.
    double time_s(long long frame) const { return double(steps_done(frame)) * def_.dt; }
    /// Stage times in ms (DriverStage columns), constant memory however many frames:
    /// kTimingSamples records, thinned as Checkpoints does.
    const Checkpoints& stage_ms() const { return stage_ms_; }
    /// Wall-clock seconds since loop() started.
    double elapsed_s() const;

    // ---- end ----
    /// Writes `stats()` to --stats (when given), then the export's manifest (last: once it
    /// is there, the export is complete). Afterwards the outputs stay. Exit 1.
    bool finish(const std::function<nlohmann::json()>& stats);
    /// After the command's summary line: the export's summary and "wrote stats to FILE".
    void print_written() const;
    /// Fails with `code` and `message` (printed unless quiet), the bar ended and the
    /// outputs taken back; returns `code`.
    int fail(int code, const std::string& message);
    /// fail(code, message), then false: what a step that failed returns (the command's
    /// own steps too: FrameWork).
    bool stop(int code, const std::string& message);
    /// kExitOk, or the code of the failure.
    int exit_code() const { return exit_code_; }
    /// The failure's message (empty while none).
    const std::string& error() const { return error_; }

    const DriverDef& def() const { return def_; }
    const SceneDef& scene() const { return scene_; }
    Simulation& sim() { return *sim_; }
    const Simulation& sim() const { return *sim_; }
    Exporter* exporter() { return exporter_.get(); }
    /// Hands the Simulation (and the heightmap load_heightmap() read) to the command (view).
    std::unique_ptr<Simulation> take_simulation() { return std::move(sim_); }
    Heightmap take_heightmap() { return std::move(*map_); }

private:
    void announce() const;
    void record_stages(double step_ms, double export_ms);

    DriverDef def_;
    SceneDef scene_;
    std::optional<Heightmap> map_;
    std::optional<ExportDef> export_def_;
    std::unique_ptr<Simulation> sim_;
    std::unique_ptr<Exporter> exporter_;  ///< removes its files unless finish() succeeded
    Outputs outputs_;
    Checkpoints stage_ms_;
    std::chrono::steady_clock::time_point loop_start_{};
    bool show_progress_ = false;
    bool finished_ = false;
    int exit_code_ = kExitOk;
    std::string error_;
};

}  // namespace mr::app
