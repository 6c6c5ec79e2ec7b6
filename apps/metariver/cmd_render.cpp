// `metariver render`: headless rendering of a scene to a numbered PNG sequence or an
// MP4 (raw RGB frames piped to the ffmpeg program). OpenGL 4.5 core on EGL's
// surfaceless platform (no display), the same renderer as the viewer; --export writes the
// rendered frames' water and particles too (docs/export.md). Every option is checked
// before anything is written; a failure part-way removes what this run wrote. The
// lifecycle is the Driver's (driver.h); the renderer and the frames or video are render's.
#include "commands.h"
#include "driver.h"
#include "export_options.h"
#include "run_stats.h"

#include <metariver/checkpoints.h>
#include <metariver/gl_context.h>
#include <metariver/io.h>
#include <metariver/render.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <regex>
#include <unistd.h>
#include <vector>

namespace mr::app {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct RenderOptions {
    SceneOptions scene;
    /// --frames: images (default 60), --steps: simulation frames per image, --warmup:
    /// simulation frames before the first, --dt, --stats, --no-progress, --report-every.
    DriverDef drive{.command = "render", .frames = 60, .progress = true};
    std::string size = "1280x720";
    std::string out = "out/render";
    std::string camera;
    double orbit_deg = 0.0;
    int fps = 30;
    std::string water = "realistic";
    bool particles = false;
    bool foam = true;  ///< draw the diffuse particles ([foam])
    bool flow = true;  ///< realistic water: the flow detail, when the scene's [render] asks for it
    std::optional<int> bvh_level;
    std::string texture;
    ExportOptions exp;  ///< --export DIR --format ... --every N --range A:B (image numbers)
};

constexpr long long kMaxFrames = 1'000'000;
constexpr int kMinSide = 16, kMaxSide = 8192;

bool ends_with_mp4(const std::string& s) {
    if (s.size() < 4) return false;
    std::string tail = s.substr(s.size() - 4);
    std::transform(tail.begin(), tail.end(), tail.begin(), [](unsigned char c) { return std::tolower(c); });
    return tail == ".mp4";
}

/// The ffmpeg program on PATH, or empty.
std::string find_program(const std::string& name) {
    const char* path = std::getenv("PATH");
    if (!path) return {};
    std::string p = path;
    size_t start = 0;
    while (start <= p.size()) {
        const size_t end = std::min(p.find(':', start), p.size());
        const std::string dir = p.substr(start, end - start);
        if (!dir.empty()) {
            const std::string candidate = dir + "/" + name;
            if (access(candidate.c_str(), X_OK) == 0 && !fs::is_directory(candidate)) return candidate;
        }
        start = end + 1;
    }
    return {};
}

std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// True when a file can be created in `dir` (probed by creating one: permission bits
/// say nothing for root, or on a read-only mount).
bool folder_writable(const fs::path& dir) {
    const fs::path probe = dir / fmt::format(".metariver-probe-{}", getpid());
    FILE* f = std::fopen(probe.c_str(), "wb");
    if (!f) return false;
    std::fclose(f);
    std::error_code ec;
    fs::remove(probe, ec);
    return true;
}

/// What the options say beyond the scene, checked: the image size, the shading, the
/// texture.
struct RenderSetup {
    int width = 0, height = 0;
    render::WaterShading shading = render::WaterShading::Realistic;
    std::optional<Image> texture;
};

/// The first bad option among the numbers (one line naming it and the range), or empty.
std::string number_error(const RenderOptions& o) {
    for (const std::string& e : {range_error("--frames", o.drive.frames, 1, kMaxFrames),
                                 range_error("--warmup", o.drive.warmup, 0, kMaxFrames),
                                 range_error("--steps", o.drive.steps, 1, 1000), dt_error(o.drive.dt),
                                 range_error("--report-every", o.drive.report_every, 0, kMaxFrames),
                                 range_error("--fps", o.fps, 1, 240)})
        if (!e.empty()) return e;
    if (!std::isfinite(o.orbit_deg) || std::abs(o.orbit_deg) > 36000.0)
        return fmt::format("--orbit: must be in [-36000, 36000] degrees (got {})", o.orbit_deg);
    return {};
}

/// Every option but the scene's, the export's and the outputs', checked into `setup`.
Status check_options(const RenderOptions& o, RenderSetup& setup) {
    if (auto e = number_error(o); !e.empty()) return Error{e};
    std::smatch m;
    if (!std::regex_match(o.size, m, std::regex("([0-9]{1,6})x([0-9]{1,6})")))
        return Error{fmt::format("--size: expected WIDTHxHEIGHT, e.g. 1280x720 (got '{}')", o.size)};
    setup.width = std::stoi(m[1].str());
    setup.height = std::stoi(m[2].str());
    if (setup.width < kMinSide || setup.width > kMaxSide || setup.height < kMinSide || setup.height > kMaxSide)
        return Error{fmt::format("--size: width and height must be in [{}, {}] pixels (got '{}')", kMinSide, kMaxSide,
                                 o.size)};
    if (o.water == "gouraud") setup.shading = render::WaterShading::Gouraud;
    else if (o.water != "realistic")
        return Error{fmt::format("--water: must be realistic or gouraud (got '{}')", o.water)};
    if (!o.camera.empty() && o.camera != "top") {
        render::Camera probe;
        if (auto s = render::parse_camera(o.camera, probe); !s) return Error{s.error().message + ", or top"};
    }
    if (!o.texture.empty()) {
        auto img = load_image(o.texture, 4);
        if (!img) return Error{"--texture " + img.error().message};
        setup.texture = std::move(img.value());
    }
    return Ok{};
}

/// Where the images go (--out): numbered PNG files in a folder, or an MP4 encoded by the
/// ffmpeg program from raw RGB frames on a pipe, written to a temporary file beside the
/// target and moved into place at the end. Everything goes into the driver's outputs.
class FrameSink {
public:
    explicit FrameSink(const RenderOptions& o)
        : out_(o.out), fps_(o.fps), mp4_(ends_with_mp4(o.out)),
          digits_(std::max(5, static_cast<int>(std::to_string(o.drive.frames - 1).size()))) {}
    FrameSink(const FrameSink&) = delete;
    FrameSink& operator=(const FrameSink&) = delete;
    ~FrameSink() { close_pipe(); }

    /// --out checked before anything is written (bad input).
    Status check() {
        std::error_code ec;
        if (!mp4_) {
            if (fs::exists(out_, ec) && !fs::is_directory(out_, ec))
                return Error{fmt::format("--out {}: exists and is not a folder (give a folder, or a .mp4 file)", out_)};
            return Ok{};
        }
        ffmpeg_ = find_program("ffmpeg");
        if (ffmpeg_.empty())
            return Error{fmt::format("--out {}: writing MP4 needs the ffmpeg program, which is not on PATH "
                                     "(install it: apt-get install ffmpeg; or give a folder for PNG frames)", out_)};
        const fs::path parent = fs::path(out_).parent_path().empty() ? fs::path(".") : fs::path(out_).parent_path();
        if (!fs::is_directory(parent, ec))
            return Error{fmt::format("--out {}: folder '{}' does not exist", out_, parent.string())};
        if (fs::is_directory(out_, ec)) return Error{fmt::format("--out {}: is a folder", out_)};
        if (!folder_writable(parent))
            return Error{fmt::format("--out {}: folder '{}' is not writable", out_, parent.string())};
        return Ok{};
    }

    /// The folder (created when missing), or ffmpeg started on its temporary file, for
    /// images of width x height pixels.
    bool open(Driver& d, int width, int height) {
        width_ = width;
        height_ = height;
        if (!mp4_) {
            if (auto s = d.outputs().make_folder("--out", out_); !s) return d.stop(kExitBadInput, s.error().message);
            if (!folder_writable(out_))
                return d.stop(kExitBadInput, fmt::format("--out {}: folder is not writable", out_));
            return true;
        }
        const fs::path out(out_);
        mp4_tmp_ = (out.parent_path() / fmt::format(".{}.partial-{}.mp4", out.filename().string(), getpid())).string();
        // Odd sizes are padded to even ones (yuv420p needs them); -nostdin keeps ffmpeg
        // off the terminal; its errors go to our stderr.
        const std::string cmd = fmt::format(
            "{} -nostdin -hide_banner -loglevel error -y -f rawvideo -pix_fmt rgb24 -s {}x{} -r {} -i - "
            "-vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -c:v libx264 -preset veryfast -crf 20 -pix_fmt yuv420p -f mp4 {}",
            shell_quote(ffmpeg_), width_, height_, fps_, shell_quote(mp4_tmp_));
        std::signal(SIGPIPE, SIG_IGN);  // a dying ffmpeg is reported by fwrite/pclose, not a signal
        pipe_ = popen(cmd.c_str(), "w");
        if (!pipe_) return d.stop(kExitFailure, fmt::format("--out {}: cannot start ffmpeg", out_));
        d.outputs().on_discard([this] { close_pipe(); });  // ffmpeg ends before its file goes
        d.outputs().add_file(mp4_tmp_);
        return true;
    }

    /// Image `f`; exit 1 on failure.
    bool write(Driver& d, long long f, const std::vector<uint8_t>& rgb) {
        if (mp4_) {
            if (std::fwrite(rgb.data(), 1, rgb.size(), pipe_) != rgb.size())
                return d.stop(kExitFailure, fmt::format("--out {}: ffmpeg stopped accepting frames", out_));
            return true;
        }
        const std::string path = (fs::path(out_) / fmt::format("frame_{:0{}}.png", f, digits_)).string();
        if (auto s = write_png(path, rgb, width_, height_, 3); !s) return d.stop(kExitFailure, s.error().message);
        d.outputs().add_file(path);
        ++pngs_;
        return true;
    }

    /// The video finished and moved into place (it stays in the outputs: a later failure
    /// takes it back); nothing to do for PNG frames.
    bool close(Driver& d) {
        if (!mp4_) return true;
        const int status = close_pipe();
        std::error_code ec;
        if (status != 0 || !fs::exists(mp4_tmp_, ec))
            return d.stop(kExitFailure, fmt::format("--out {}: ffmpeg failed (exit status {})", out_, status));
        fs::rename(mp4_tmp_, out_, ec);
        if (ec)
            return d.stop(kExitFailure,
                          fmt::format("--out {}: cannot move the video into place: {}", out_, ec.message()));
        d.outputs().add_file(out_);
        return true;
    }

    void print_written(long long frames) const {
        if (mp4_) fmt::print("wrote {}\n", out_);
        else fmt::print("wrote {} PNG frames to {} (frame_{:0{}}.png .. frame_{:0{}}.png)\n", pngs_, out_, 0, digits_,
                        frames - 1, digits_);
    }

private:
    int close_pipe() {
        if (!pipe_) return 0;
        const int status = pclose(pipe_);
        pipe_ = nullptr;
        return status;
    }

    std::string out_;
    int fps_, width_ = 0, height_ = 0;
    bool mp4_;
    int digits_;
    std::string ffmpeg_, mp4_tmp_;
    FILE* pipe_ = nullptr;
    long long pngs_ = 0;
};

/// The renderer's part of a frame: the camera turned, the scene drawn and read back.
struct Shot {
    render::Renderer& renderer;
    render::Camera camera;
    render::RenderSettings settings;
    float yaw0 = 0.0f;
    std::vector<uint8_t> rgb;
};

Shot make_shot(render::Renderer& renderer, const RenderOptions& o, const RenderSetup& setup, const Simulation& sim) {
    Shot shot{.renderer = renderer, .camera = render::frame_terrain(sim.terrain()), .settings = {}};
    if (o.camera == "top")
        shot.camera = render::frame_terrain_from_above(sim.terrain(), float(setup.width) / float(setup.height));
    else if (!o.camera.empty()) (void)render::parse_camera(o.camera, shot.camera);  // checked before
    shot.yaw0 = shot.camera.yaw_deg;
    render::RenderSettings& s = shot.settings;
    s.shading = setup.shading;
    s.particles = o.particles;
    s.foam = o.foam;
    s.flow_detail = o.flow && sim.def().render.flow_detail;
    if (o.bvh_level) {
        s.bvh = true;
        s.bvh_level = *o.bvh_level;
    }
    return shot;
}

/// Per frame (the records `times` and the driver's stage times keep): the image's write
/// and the export's frame.
std::vector<double> write_ms(const Driver& d, const Checkpoints& times) {
    std::vector<double> write = times.column(1);
    const std::vector<double> exported = d.stage_ms().column(kStageExport);
    for (size_t k = 0; k < write.size() && k < exported.size(); ++k) write[k] += exported[k];
    return write;
}

/// What render --stats writes: the GL, the renderer's counts, the stage times and, for
/// a shallow-water grid (swe, hybrid), run --stats' swe and hybrid blocks (null otherwise).
/// `times`: render and the image's write per frame.
nlohmann::json render_stats_json(const Driver& d, const render::Renderer& renderer, const RenderSetup& setup,
                                 const Checkpoints& times, const RiverMeter& meter, double total_s) {
    nlohmann::json j;
    j["scene"] = d.scene().name;
    j["frames"] = d.def().frames;
    j["size"] = {setup.width, setup.height};
    j["gl"] = renderer.gl_description();
    j["water_triangles"] = renderer.stats().water_triangles;
    j["terrain_triangles"] = renderer.stats().terrain_triangles;
    j["gl_objects_created"] = renderer.stats().gl_objects_created;
    j["buffer_reallocations"] = renderer.stats().buffer_reallocations;
    j["stage_ms"] = {{"simulate", stage_json(d.stage_ms().column(kStageStepWall))},
                     {"render", stage_json(times.column(0))},
                     {"write", stage_json(write_ms(d, times))}};
    j["total_s"] = total_s;
    j["swe"] = swe_stats_json(d.sim(), meter, d.def().frames);
    j["hybrid"] = hybrid_stats_json(d.sim(), d.def().frames, d.def().dt);
    return j;
}

/// After the warm-up: every image rendered, written and timed (render, write).
bool render_frames(Driver& d, Shot& shot, FrameSink& sink, const RenderOptions& o, const RenderSetup& setup,
                   Checkpoints& times, RiverMeter& meter) {
    shot.renderer.set_scene(d.sim().view());
    return d.loop([&](long long f) {
        meter.record(d.sim(), f, d.time_s(f));  // before the clock: not the render's time
        auto t0 = Clock::now();
        shot.camera.yaw_deg =
            shot.yaw0 + static_cast<float>(o.orbit_deg * static_cast<double>(f) / static_cast<double>(o.drive.frames));
        render::fit_clip_planes(shot.camera, d.sim().terrain());
        shot.renderer.update(d.sim().view());
        shot.settings.time_s = static_cast<float>(d.time_s(f));
        shot.renderer.draw(shot.camera, setup.width, setup.height, shot.settings);
        shot.renderer.read_rgb(shot.rgb);  // waits for the GPU: the time covers the whole frame
        const double render_ms = ms_since(t0);
        t0 = Clock::now();
        if (!sink.write(d, f, shot.rgb)) return false;
        const double record[2] = {render_ms, ms_since(t0)};
        times.push(record);
        return true;
    });
}

int render(const RenderOptions& o) {
    FrameSink sink(o);  // before the driver: the driver's outputs close its pipe
    Driver d(o.drive);
    // ---- every input is checked before anything is written ----
    RenderSetup setup;
    if (auto s = check_options(o, setup); !s) return d.fail(kExitBadInput, s.error().message);
    // Exported frames are the images: water_00042 is frame_00042.png's.
    if (!d.resolve(o.scene) || !d.resolve_export(o.exp)) return d.exit_code();
    if (auto s = sink.check(); !s) return d.fail(kExitBadInput, s.error().message);
    if (!d.check_stats() || !d.create()) return d.exit_code();
    auto context = gl::HeadlessContext::create();
    if (!context) return d.fail(kExitFailure, context.error().message);
    auto renderer = render::Renderer::create();
    if (!renderer) return d.fail(kExitFailure, renderer.error().message);

    // ---- outputs: created now; a failure takes them back ----
    if (!sink.open(d, setup.width, setup.height) || !d.begin_export()) return d.exit_code();
    if (setup.texture) {
        const Image& t = *setup.texture;
        if (auto s = renderer.value()->set_terrain_texture(t.pixels, t.width, t.height); !s)
            return d.fail(kExitBadInput, fmt::format("--texture {}: {}", o.texture, s.error().message));
    }
    Shot shot = make_shot(*renderer.value(), o, setup, d.sim());
    d.warm_up();
    Checkpoints times(kTimingSamples, 2);  // render, write: constant memory however many frames
    RiverMeter meter(d.sim(), o.drive.frames);
    if (!render_frames(d, shot, sink, o, setup, times, meter) || !sink.close(d)) return d.exit_code();
    const double total_s = d.elapsed_s();
    const render::Renderer& r = shot.renderer;
    if (!d.finish([&] { return render_stats_json(d, r, setup, times, meter, total_s); })) return d.exit_code();
    fmt::print("{}: {} frames {}x{} in {:.1f} s; per frame median: render {:.2f} ms (draw + read back), "
               "simulate {:.2f} ms, write {:.2f} ms; water {} triangles (surface velocities {:.2f} ms, last frame); {}\n",
               d.scene().name, o.drive.frames, setup.width, setup.height, total_s, percentiles(times.column(0)).median,
               percentiles(d.stage_ms().column(kStageStepWall)).median, percentiles(write_ms(d, times)).median,
               r.stats().water_triangles, r.stats().flow_ms, r.gl_description());
    sink.print_written(o.drive.frames);
    d.print_written();
    return kExitOk;
}

}  // namespace

void register_render(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<RenderOptions>();
    CLI::App* cmd = app.add_subcommand("render", "render a scene headless (EGL, no display) to PNG frames or an MP4");
    // A later option wins (scripts pass defaults, users append overrides: run.sh "$@").
    cmd->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    opts->scene.add_to(*cmd);
    cmd->add_option("--frames", opts->drive.frames, "images to render (default 60)");
    cmd->add_option("--size", opts->size, "image size WIDTHxHEIGHT, each in [16, 8192] (default 1280x720)");
    cmd->add_option("--out", opts->out, "folder for frame_NNNNN.png, or a FILE.mp4 (needs ffmpeg) (default out/render)");
    cmd->add_option("--camera", opts->camera, "orbit camera YAW,PITCH,DISTANCE[,TX,TY,TZ] in degrees and metres, or top: straight above, the whole terrain in view (default: frames the terrain, oblique)");
    cmd->add_option("--orbit", opts->orbit_deg, "degrees the camera turns around the target over the sequence (default 0)");
    cmd->add_option("--warmup", opts->drive.warmup, "simulation frames before the first image (default 0)");
    cmd->add_option("--steps", opts->drive.steps, "simulation frames per image (default 1)");
    cmd->add_option("--dt", opts->drive.dt, "simulation frame time in seconds (default 1/60)");
    cmd->add_option("--fps", opts->fps, "MP4 frame rate (default 30)");
    cmd->add_option("--water", opts->water, "water shading: realistic or gouraud (the paper's look) (default realistic)");
    cmd->add_flag("--particles", opts->particles, "debug: draw the particles as spheres");
    cmd->add_flag("!--no-foam", opts->foam, "do not draw foam and spray (the scene's [foam] still makes them)");
    cmd->add_flag("!--no-flow", opts->flow, "realistic water without the flow detail ([render] flow_detail)");
    cmd->add_option("--bvh", opts->bvh_level, "debug: draw the AABB tree's boxes at this depth (-1: the leaves)");
    cmd->add_option("--texture", opts->texture, "image draped over the terrain (PNG/JPEG)");
    cmd->add_option("--stats", opts->drive.stats, "write render timings as JSON to this file");
    cmd->add_flag("!--no-progress", opts->drive.progress, "no progress bar");
    opts->exp.add_to(*cmd);
    cmd->add_option("--report-every", opts->drive.report_every,
                    "print a report line (resident memory, particle counters, non-finite values) every N frames; "
                    "scripts/soak.sh reads them");
    cmd->callback([opts, &action] { action = [opts] { return render(*opts); }; });
}

}  // namespace mr::app
