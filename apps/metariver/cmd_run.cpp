// `metariver run`: headless simulation of a scene for N frames; optional export of the
// water and particles (--export: obj, ply, glb, vdb; docs/export.md), the earlier
// water-only OBJ sequence (--obj-dir) and a JSON stats file. Deterministic for a seed.
// All inputs are checked before anything is written; a failure part-way removes what
// this run wrote. The lifecycle is the Driver's (driver.h); the OBJ sequence and the
// river's statistics (run_stats.h) are run's own.
#include "commands.h"
#include "driver.h"
#include "export_options.h"
#include "run_stats.h"

#include <metariver/io.h>
#include <metariver/sparse_field.h>

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace mr::app {

namespace {

namespace fs = std::filesystem;

struct RunOptions {
    SceneOptions scene;
    /// --frames (default 300), --dt, --stats, --no-progress, --report-every: a report line
    /// every N frames (0: none); the river's warnings, sizing and conditioning printed.
    DriverDef drive{.command = "run", .frames = 300, .progress = true, .announce = true};
    std::string obj_dir;
    std::optional<long long> obj_every;  ///< --obj-every; unset = every frame
    ExportOptions exp;                   ///< --export DIR --format ... --every N --range A:B
};

constexpr long long kMaxFrames = 100'000'000;
constexpr long long kMaxObjEvery = 1'000'000'000;

/// The first bad option (one line naming it and the range), or empty.
std::string option_error(const RunOptions& o) {
    if (auto e = range_error("--frames", o.drive.frames, 1, kMaxFrames); !e.empty()) return e;
    if (auto e = dt_error(o.drive.dt); !e.empty()) return e;
    if (o.obj_every && o.obj_dir.empty()) return "--obj-every: needs --obj-dir (the folder to write to)";
    if (o.obj_every)
        if (auto e = range_error("--obj-every", *o.obj_every, 1, kMaxObjEvery); !e.empty()) return e;
    return range_error("--report-every", o.drive.report_every, 0, kMaxObjEvery);
}

/// --obj-dir: the folder (created if missing) with terrain.obj, then surface_NNNNN.obj
/// every `every` frames and at the last; every file goes into the driver's outputs, so a
/// failure takes them back.
class ObjSequence {
public:
    ObjSequence(std::string dir, long long every, long long frames)
        : dir_(std::move(dir)), every_(every), frames_(frames),
          digits_(std::max(5, static_cast<int>(std::to_string(frames - 1).size()))) {}

    bool on() const { return !dir_.empty(); }
    /// The folder and the terrain; exit 2 on failure.
    bool begin(Driver& d) {
        if (!on()) return true;
        if (auto s = d.outputs().make_folder("--obj-dir", dir_); !s) return d.stop(kExitBadInput, s.error().message);
        const std::string terrain_path = (fs::path(dir_) / "terrain.obj").string();
        if (auto s = write_terrain_obj(terrain_path, d.sim().terrain()); !s)
            return d.stop(kExitBadInput, "--obj-dir: " + s.error().message);
        d.outputs().add_file(terrain_path);
        ++written_;
        return true;
    }
    /// Frame `f`'s surface when due; exit 1 on failure.
    bool frame(Driver& d, long long f) {
        if (!on() || (f % every_ != 0 && f != frames_ - 1)) return true;
        const std::string path = (fs::path(dir_) / fmt::format("surface_{:0{}}.obj", f, digits_)).string();
        const std::string comment = fmt::format("metariver water surface, frame {}", f);
        if (auto s = write_surface_obj(path, d.sim().surface(), comment); !s)
            return d.stop(kExitFailure, s.error().message);
        d.outputs().add_file(path);
        ++written_;
        return true;
    }
    /// Files written (the terrain and the surfaces).
    long long written() const { return written_; }

private:
    std::string dir_;
    long long every_, frames_;
    int digits_;
    long long written_ = 0;
};

int run(const RunOptions& o) {
    Driver d(o.drive);
    if (auto e = option_error(o); !e.empty()) return d.fail(kExitBadInput, e);
    if (!d.resolve(o.scene) || !d.resolve_export(o.exp) || !d.create()) return d.exit_code();
    ObjSequence objs(o.obj_dir, o.obj_every.value_or(1), o.drive.frames);
    // The stats path is checked after the OBJ folder, which may hold it; the export's
    // folder and terrain then.
    if (!objs.begin(d) || !d.check_stats() || !d.begin_export()) return d.exit_code();
    RiverMeter meter(d.sim(), o.drive.frames);
    const bool looped = d.loop([&](long long f) {
        meter.record(d.sim(), f, d.time_s(f));
        return objs.frame(d, f);
    });
    const auto stats = [&] { return run_stats_json(d.sim(), meter, d.stage_ms(), o.drive.frames, o.drive.dt); };
    if (!looped || !d.finish(stats))
        return d.exit_code();
    const Simulation& sim = d.sim();
    fmt::print("{}\n", run_summary(sim, meter, d.stage_ms(), o.drive.frames));
    if (sim.field_overflows() > 0)
        fmt::print(stderr, "metariver run: warning: field: no surface on {} of {} frames: {}; lower field.resolution\n",
                   sim.field_overflows(), o.drive.frames, sim.field_overflow_message());
    if (sim.field_windows() > 0)
        fmt::print(stderr, "metariver run: warning: field: the particles spread wider than the field's cap ({} samples) "
                           "on {} of {} frames; it was built around the most of them, up to {} particles not drawn "
                           "(docs/waterfalls.md)\n",
                   kMaxSparseFieldSamples, sim.field_windows(), o.drive.frames, sim.field_left_out());
    if (objs.on()) fmt::print("wrote {} OBJ files to {}\n", objs.written(), o.obj_dir);
    d.print_written();
    return kExitOk;
}

}  // namespace

void register_run(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<RunOptions>();
    CLI::App* cmd = app.add_subcommand("run", "simulate a scene headless; deterministic for a seed");
    opts->scene.add_to(*cmd);
    cmd->add_option("--frames", opts->drive.frames, "frames to simulate (default 300)");
    cmd->add_option("--dt", opts->drive.dt, "frame time in seconds (default 1/60)");
    cmd->add_option("--stats", opts->drive.stats, "write run statistics as JSON to this file");
    cmd->add_option("--obj-dir", opts->obj_dir, "write the water surface (and the terrain) as OBJ to this folder");
    cmd->add_option("--obj-every", opts->obj_every,
                    "with --obj-dir: write every N-th frame's surface (0, N, 2N, ... and the last), [1, 1e9]; default 1");
    opts->exp.add_to(*cmd);
    cmd->add_flag("!--no-progress", opts->drive.progress, "no progress bar (it is shown on a terminal only)");
    cmd->add_option("--report-every", opts->drive.report_every,
                    "print a report line (resident memory, particle counters, non-finite values) every N frames; "
                    "scripts/soak.sh reads them");
    cmd->callback([opts, &action] { action = [opts] { return run(*opts); }; });
}

}  // namespace mr::app
