// `metariver render`: headless rendering of a scene to a numbered PNG sequence or an
// MP4 (raw RGB frames piped to the ffmpeg program). OpenGL 4.5 core on EGL's
// surfaceless platform (no display), the same renderer as the viewer; --export writes the
// rendered frames' water and particles too (docs/export.md). Every option is checked
// before anything is written; a failure part-way removes what this run wrote.
#include "commands.h"
#include "export_options.h"
#include "progress.h"
#include "report.h"

#include <metariver/export.h>
#include <metariver/checkpoints.h>
#include <metariver/gl_context.h>
#include <metariver/io.h>
#include <metariver/render.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <regex>
#include <unistd.h>
#include <vector>

namespace mr::app {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct RenderOptions {
    SceneOptions scene;
    long long frames = 60;
    std::string size = "1280x720";
    std::string out = "out/render";
    std::string camera;
    double orbit_deg = 0.0;
    long long warmup = 0;
    long long steps = 1;
    double dt = 1.0 / 60.0;
    int fps = 30;
    std::string water = "realistic";
    bool particles = false;
    bool foam = true;  ///< draw the diffuse particles ([foam])
    bool flow = true;  ///< realistic water: the flow detail, when the scene's [render] asks for it
    std::optional<int> bvh_level;
    std::string texture;
    std::string stats;
    bool progress = true;
    ExportOptions exp;  ///< --export DIR --format ... --every N --range A:B (image numbers)
    long long report_every = 0;  ///< --report-every: a report line every N frames (0: none)
};

constexpr long long kMaxFrames = 1'000'000;
constexpr int kMinSide = 16, kMaxSide = 8192;

int fail(int code, const std::string& message) {
    fmt::print(stderr, "metariver render: {}\n", message);
    return code;
}

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

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

int render(const RenderOptions& o) {
    // ---- every input is checked before anything is written ----
    if (o.frames < 1 || o.frames > kMaxFrames)
        return fail(kExitBadInput, fmt::format("--frames: must be in [1, {}] (got {})", kMaxFrames, o.frames));
    if (o.warmup < 0 || o.warmup > kMaxFrames)
        return fail(kExitBadInput, fmt::format("--warmup: must be in [0, {}] (got {})", kMaxFrames, o.warmup));
    if (o.steps < 1 || o.steps > 1000)
        return fail(kExitBadInput, fmt::format("--steps: must be in [1, 1000] (got {})", o.steps));
    if (!std::isfinite(o.dt) || o.dt <= 0.0 || o.dt > 1.0)
        return fail(kExitBadInput, fmt::format("--dt: must be in (0, 1] seconds (got {})", o.dt));
    if (o.report_every < 0 || o.report_every > kMaxFrames)
        return fail(kExitBadInput, fmt::format("--report-every: must be in [0, {}] (got {})", kMaxFrames, o.report_every));
    if (o.fps < 1 || o.fps > 240) return fail(kExitBadInput, fmt::format("--fps: must be in [1, 240] (got {})", o.fps));
    if (!std::isfinite(o.orbit_deg) || std::abs(o.orbit_deg) > 36000.0)
        return fail(kExitBadInput, fmt::format("--orbit: must be in [-36000, 36000] degrees (got {})", o.orbit_deg));
    int width = 0, height = 0;
    {
        std::smatch m;
        if (!std::regex_match(o.size, m, std::regex("([0-9]{1,6})x([0-9]{1,6})")))
            return fail(kExitBadInput, fmt::format("--size: expected WIDTHxHEIGHT, e.g. 1280x720 (got '{}')", o.size));
        width = std::stoi(m[1].str());
        height = std::stoi(m[2].str());
        if (width < kMinSide || width > kMaxSide || height < kMinSide || height > kMaxSide)
            return fail(kExitBadInput, fmt::format("--size: width and height must be in [{}, {}] pixels (got '{}')",
                                                   kMinSide, kMaxSide, o.size));
    }
    render::WaterShading shading = render::WaterShading::Realistic;
    if (o.water == "gouraud") shading = render::WaterShading::Gouraud;
    else if (o.water != "realistic")
        return fail(kExitBadInput, fmt::format("--water: must be realistic or gouraud (got '{}')", o.water));
    if (!o.camera.empty() && o.camera != "top") {
        render::Camera probe;
        if (auto s = render::parse_camera(o.camera, probe); !s)
            return fail(kExitBadInput, s.error().message + ", or top");
    }
    std::optional<Image> texture;
    if (!o.texture.empty()) {
        auto img = load_image(o.texture, 4);
        if (!img) return fail(kExitBadInput, "--texture " + img.error().message);
        texture = std::move(img.value());
    }
    auto def = o.scene.resolve();
    if (!def) return fail(kExitBadInput, def.error().message);
    std::optional<ExportDef> export_def;
    if (o.exp.given()) {  // exported frames are the images: water_00042 is frame_00042.png's
        auto e = o.exp.resolve(o.frames, def.value());
        if (!e) return fail(kExitBadInput, e.error().message);
        export_def = std::move(e.value());
        export_def->frame_rate = 1.0 / (o.dt * double(o.steps));
        export_def->solver_dt = o.dt;
    }

    const bool mp4 = ends_with_mp4(o.out);
    std::string ffmpeg;
    if (mp4) {
        ffmpeg = find_program("ffmpeg");
        if (ffmpeg.empty())
            return fail(kExitBadInput, fmt::format("--out {}: writing MP4 needs the ffmpeg program, which is not on PATH "
                                                   "(install it: apt-get install ffmpeg; or give a folder for PNG frames)", o.out));
        const fs::path parent = fs::path(o.out).parent_path().empty() ? fs::path(".") : fs::path(o.out).parent_path();
        std::error_code ec;
        if (!fs::is_directory(parent, ec))
            return fail(kExitBadInput, fmt::format("--out {}: folder '{}' does not exist", o.out, parent.string()));
        if (fs::is_directory(o.out, ec)) return fail(kExitBadInput, fmt::format("--out {}: is a folder", o.out));
        if (!folder_writable(parent))
            return fail(kExitBadInput, fmt::format("--out {}: folder '{}' is not writable", o.out, parent.string()));
    } else {
        std::error_code ec;
        if (fs::exists(o.out, ec) && !fs::is_directory(o.out, ec))
            return fail(kExitBadInput, fmt::format("--out {}: exists and is not a folder (give a folder, or a .mp4 file)", o.out));
    }
    if (!o.stats.empty()) {
        const fs::path parent = fs::path(o.stats).parent_path().empty() ? fs::path(".") : fs::path(o.stats).parent_path();
        std::error_code ec;
        if (!fs::is_directory(parent, ec))
            return fail(kExitBadInput, fmt::format("--stats {}: folder '{}' does not exist", o.stats, parent.string()));
    }

    auto sim_result = Simulation::create(def.value());
    if (!sim_result) return fail(kExitBadInput, sim_result.error().message);
    std::unique_ptr<Simulation> sim = std::move(sim_result.value());

    auto context = gl::HeadlessContext::create();
    if (!context) return fail(kExitFailure, context.error().message);
    auto renderer_result = render::Renderer::create();
    if (!renderer_result) return fail(kExitFailure, renderer_result.error().message);
    render::Renderer& renderer = *renderer_result.value();

    // ---- outputs: created now; everything is recorded so a failure can take it back ----
    bool created_dir = false;
    std::vector<std::string> written;
    std::string mp4_tmp;
    FILE* pipe = nullptr;
    auto cleanup = [&] {
        std::error_code ec;
        if (pipe) {
            pclose(pipe);
            pipe = nullptr;
        }
        for (const auto& f : written) fs::remove(f, ec);
        if (!mp4_tmp.empty()) fs::remove(mp4_tmp, ec);
        if (created_dir) fs::remove_all(o.out, ec);
    };
    if (mp4) {
        const fs::path out(o.out);
        mp4_tmp = (out.parent_path() / fmt::format(".{}.partial-{}.mp4", out.filename().string(), getpid())).string();
        // Odd sizes are padded to even ones (yuv420p needs them); -nostdin keeps ffmpeg
        // off the terminal; its errors go to our stderr.
        const std::string cmd = fmt::format(
            "{} -nostdin -hide_banner -loglevel error -y -f rawvideo -pix_fmt rgb24 -s {}x{} -r {} -i - "
            "-vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -c:v libx264 -preset veryfast -crf 20 -pix_fmt yuv420p -f mp4 {}",
            shell_quote(ffmpeg), width, height, o.fps, shell_quote(mp4_tmp));
        std::signal(SIGPIPE, SIG_IGN);  // a dying ffmpeg is reported by fwrite/pclose, not a signal
        pipe = popen(cmd.c_str(), "w");
        if (!pipe) return fail(kExitFailure, fmt::format("--out {}: cannot start ffmpeg", o.out));
    } else {
        std::error_code ec;
        if (!fs::exists(o.out, ec)) {
            if (!fs::create_directories(o.out, ec) || ec)
                return fail(kExitBadInput, fmt::format("--out {}: cannot create folder: {}", o.out, ec ? ec.message() : "unknown error"));
            created_dir = true;
        }
        if (!folder_writable(o.out)) {
            cleanup();
            return fail(kExitBadInput, fmt::format("--out {}: folder is not writable", o.out));
        }
    }

    std::unique_ptr<Exporter> exporter;  // removes its files unless finish() succeeds
    if (export_def) {
        std::signal(SIGXFSZ, SIG_IGN);  // a file size limit: an error from write(), not a kill
        auto e = Exporter::begin(*export_def);
        if (!e) {
            cleanup();
            return fail(kExitBadInput, e.error().message);
        }
        exporter = std::move(e.value());
        if (auto s = exporter->write_terrain(sim->terrain()); !s) {
            cleanup();
            return fail(kExitFailure, s.error().message);
        }
    }

    if (texture) {
        if (auto s = renderer.set_terrain_texture(texture->pixels, texture->width, texture->height); !s) {
            cleanup();
            return fail(kExitBadInput, fmt::format("--texture {}: {}", o.texture, s.error().message));
        }
    }
    render::Camera camera = render::frame_terrain(sim->terrain());
    if (o.camera == "top") camera = render::frame_terrain_from_above(sim->terrain(), float(width) / float(height));
    else if (!o.camera.empty()) (void)render::parse_camera(o.camera, camera);  // checked above
    render::RenderSettings settings;
    settings.shading = shading;
    settings.particles = o.particles;
    settings.foam = o.foam;
    settings.flow_detail = o.flow && sim->def().render.flow_detail;
    if (o.bvh_level) {
        settings.bvh = true;
        settings.bvh_level = *o.bvh_level;
    }

    const float dt = static_cast<float>(o.dt);
    for (long long i = 0; i < o.warmup; ++i) sim->step(dt);
    renderer.set_scene(sim->view());

    const bool show_progress = progress_wanted(o.progress, o.frames);
    const int digits = std::max(5, static_cast<int>(std::to_string(o.frames - 1).size()));
    // Per-frame times (simulate, render, write): constant memory however many frames.
    Checkpoints frame_ms(size_t{1} << 13, 3);
    std::vector<uint8_t> rgb;
    const float yaw0 = camera.yaw_deg;
    const auto t_start = Clock::now();
    for (long long f = 0; f < o.frames; ++f) {
        auto t0 = Clock::now();
        for (long long s = 0; s < o.steps; ++s) sim->step(dt);
        const double sim_t = ms_since(t0);

        t0 = Clock::now();
        camera.yaw_deg = yaw0 + static_cast<float>(o.orbit_deg * static_cast<double>(f) / static_cast<double>(o.frames));
        render::fit_clip_planes(camera, sim->terrain());
        renderer.update(sim->view());
        settings.time_s = static_cast<float>(double(o.warmup + (f + 1) * o.steps) * o.dt);
        renderer.draw(camera, width, height, settings);
        renderer.read_rgb(rgb);  // waits for the GPU: the time covers the whole frame
        const double render_t = ms_since(t0);

        t0 = Clock::now();
        if (mp4) {
            if (std::fwrite(rgb.data(), 1, rgb.size(), pipe) != rgb.size()) {
                cleanup();
                if (show_progress) end_progress();
                return fail(kExitFailure, fmt::format("--out {}: ffmpeg stopped accepting frames", o.out));
            }
        } else {
            const std::string path = (fs::path(o.out) / fmt::format("frame_{:0{}}.png", f, digits)).string();
            if (auto s = write_png(path, rgb, width, height, 3); !s) {
                cleanup();
                if (show_progress) end_progress();
                return fail(kExitFailure, s.error().message);
            }
            written.push_back(path);
        }
        if (exporter && exporter->due(f)) {
            const double time_s = double(o.warmup + (f + 1) * o.steps) * o.dt;
            if (auto s = exporter->write_frame(f, time_s, sim->surface(), sim->particles(), sim->frame(),
                                                 sim->foam() ? &sim->foam()->particles() : nullptr); !s) {
                cleanup();
                if (show_progress) end_progress();
                return fail(kExitFailure, s.error().message);
            }
        }
        const double frame_t[3] = {sim_t, render_t, ms_since(t0)};
        frame_ms.push(frame_t);
        if (o.report_every > 0 && (f + 1) % o.report_every == 0) {
            fmt::print("{}\n", report_line(*sim, o.warmup + (f + 1) * o.steps));
            std::fflush(stdout);
        }
        if (show_progress) print_progress(f + 1, o.frames, ms_since(t_start) / 1000.0);
    }
    if (show_progress) end_progress();
    if (mp4) {
        const int status = pclose(pipe);
        pipe = nullptr;
        std::error_code ec;
        if (status != 0 || !fs::exists(mp4_tmp, ec)) {
            cleanup();
            return fail(kExitFailure, fmt::format("--out {}: ffmpeg failed (exit status {})", o.out, status));
        }
        fs::rename(mp4_tmp, o.out, ec);
        if (ec) {
            cleanup();
            return fail(kExitFailure, fmt::format("--out {}: cannot move the video into place: {}", o.out, ec.message()));
        }
        mp4_tmp.clear();
    }
    const double total_s = ms_since(t_start) / 1000.0;
    const Percentiles pr = percentiles(frame_ms.column(1)), ps = percentiles(frame_ms.column(0)),
                      pw = percentiles(frame_ms.column(2));
    if (!o.stats.empty()) {
        auto stage = [](const Percentiles& p) {
            return nlohmann::json{{"median", p.median}, {"p95", p.p95}, {"mean", p.mean}, {"max", p.max}};
        };
        nlohmann::json j;
        j["scene"] = sim->def().name;
        j["frames"] = o.frames;
        j["size"] = {width, height};
        j["gl"] = renderer.gl_description();
        j["water_triangles"] = renderer.stats().water_triangles;
        j["terrain_triangles"] = renderer.stats().terrain_triangles;
        j["gl_objects_created"] = renderer.stats().gl_objects_created;
        j["buffer_reallocations"] = renderer.stats().buffer_reallocations;
        j["stage_ms"] = {{"simulate", stage(ps)}, {"render", stage(pr)}, {"write", stage(pw)}};
        j["total_s"] = total_s;
        if (auto s = write_file_atomic(o.stats, j.dump(2) + "\n"); !s) {
            cleanup();
            return fail(kExitFailure, s.error().message);
        }
    }
    if (exporter) {  // the manifest last: once it is there, the export is complete
        if (auto s = exporter->finish(); !s) {
            cleanup();
            std::error_code ec;
            if (mp4) fs::remove(o.out, ec);
            if (!o.stats.empty()) fs::remove(o.stats, ec);
            return fail(kExitFailure, s.error().message);
        }
    }
    fmt::print("{}: {} frames {}x{} in {:.1f} s; per frame median: render {:.2f} ms (draw + read back), "
               "simulate {:.2f} ms, write {:.2f} ms; water {} triangles (surface velocities {:.2f} ms, last frame); {}\n",
               sim->def().name, o.frames, width, height, total_s, pr.median, ps.median, pw.median,
               renderer.stats().water_triangles, renderer.stats().flow_ms, renderer.gl_description());
    if (mp4) fmt::print("wrote {}\n", o.out);
    else fmt::print("wrote {} PNG frames to {} (frame_{:0{}}.png .. frame_{:0{}}.png)\n", written.size(), o.out, 0, digits,
                    o.frames - 1, digits);
    if (exporter) print_export_summary(*exporter);
    if (!o.stats.empty()) fmt::print("wrote stats to {}\n", o.stats);
    return kExitOk;
}

}  // namespace

void register_render(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<RenderOptions>();
    CLI::App* cmd = app.add_subcommand("render", "render a scene headless (EGL, no display) to PNG frames or an MP4");
    // A later option wins (scripts pass defaults, users append overrides: run.sh "$@").
    cmd->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    opts->scene.add_to(*cmd);
    cmd->add_option("--frames", opts->frames, "images to render (default 60)");
    cmd->add_option("--size", opts->size, "image size WIDTHxHEIGHT, each in [16, 8192] (default 1280x720)");
    cmd->add_option("--out", opts->out, "folder for frame_NNNNN.png, or a FILE.mp4 (needs ffmpeg) (default out/render)");
    cmd->add_option("--camera", opts->camera, "orbit camera YAW,PITCH,DISTANCE[,TX,TY,TZ] in degrees and metres, or top: straight above, the whole terrain in view (default: frames the terrain, oblique)");
    cmd->add_option("--orbit", opts->orbit_deg, "degrees the camera turns around the target over the sequence (default 0)");
    cmd->add_option("--warmup", opts->warmup, "simulation frames before the first image (default 0)");
    cmd->add_option("--steps", opts->steps, "simulation frames per image (default 1)");
    cmd->add_option("--dt", opts->dt, "simulation frame time in seconds (default 1/60)");
    cmd->add_option("--fps", opts->fps, "MP4 frame rate (default 30)");
    cmd->add_option("--water", opts->water, "water shading: realistic or gouraud (the paper's look) (default realistic)");
    cmd->add_flag("--particles", opts->particles, "debug: draw the particles as spheres");
    cmd->add_flag("!--no-foam", opts->foam, "do not draw foam and spray (the scene's [foam] still makes them)");
    cmd->add_flag("!--no-flow", opts->flow, "realistic water without the flow detail ([render] flow_detail)");
    cmd->add_option("--bvh", opts->bvh_level, "debug: draw the AABB tree's boxes at this depth (-1: the leaves)");
    cmd->add_option("--texture", opts->texture, "image draped over the terrain (PNG/JPEG)");
    cmd->add_option("--stats", opts->stats, "write render timings as JSON to this file");
    cmd->add_flag("!--no-progress", opts->progress, "no progress bar");
    opts->exp.add_to(*cmd);
    cmd->add_option("--report-every", opts->report_every,
                    "print a report line (resident memory, particle counters, non-finite values) every N frames; "
                    "scripts/soak.sh reads them");
    cmd->callback([opts, &action] { action = [opts] { return render(*opts); }; });
}

}  // namespace mr::app
