#include "export_options.h"

#include <metariver/io.h>

#include <fmt/format.h>

#include <charconv>
#include <cmath>

namespace mr::app {

namespace {

/// A whole decimal number with nothing around it.
std::optional<long long> parse_frame(std::string_view s) {
    long long v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc{} || end != s.data() + s.size()) return std::nullopt;
    return v;
}

}  // namespace

void ExportOptions::add_to(CLI::App& cmd) {
    cmd.add_option("--export", dir,
                   "write the water, the particles and the terrain to this folder, one file per frame and format, "
                   "with a manifest export.json (docs/export.md)");
    cmd.add_option("--format", format, "with --export: obj, ply, glb, vdb or npy (a heightfield solver's grid), several separated by commas (default obj)");
    cmd.add_option("--every", every, "with --export: write every N-th frame of the range, [1, 1e9] (default 1)");
    cmd.add_option("--range", range,
                   "with --export: frames FIRST:LAST to write, inclusive, 0-based (LAST may be left out: to the end)");
    cmd.add_option("--voxel-size", voxel_size, "with --export --format vdb: voxel edge in metres, (0, 100] "
                                               "(default: the field's cell, 1 / field.resolution)");
    cmd.add_flag("--no-particles", no_particles, "with --export: the water only, no particles_NNNNN files");
}

Result<ExportDef> ExportOptions::resolve(long long frames, const SceneDef& scene) const {
    if (!enabled()) {
        const char* stray = format ? "--format" : every ? "--every" : range ? "--range" : voxel_size ? "--voxel-size"
                                                                                                    : no_particles ? "--no-particles" : nullptr;
        if (stray) return Error{fmt::format("{}: needs --export (the folder to write to)", stray)};
        return Error{"--export: no folder given"};
    }
    ExportDef d;
    d.dir = dir;
    d.scene = scene.name;
    d.particles = !no_particles;
    if (format) {
        auto f = parse_export_formats(*format, "--format");
        if (!f) return f.error();
        d.formats = std::move(f.value());
    }
    if (every) {
        if (*every < 1 || *every > kMaxExportEvery)
            return Error{fmt::format("--every: must be in [1, {}] (got {})", kMaxExportEvery, *every)};
        d.every = *every;
    }
    d.first = 0;
    d.last = frames - 1;
    if (range) {
        const std::string& r = *range;
        const size_t colon = r.find(':');
        const auto bad = [&] {
            return Error{fmt::format("--range: expected FIRST:LAST frame numbers with 0 <= FIRST <= LAST <= {} (the "
                                     "last of --frames {}), LAST optional (got '{}')",
                                     frames - 1, frames, r)};
        };
        if (colon == std::string::npos) return bad();
        const auto first = parse_frame(std::string_view(r).substr(0, colon));
        const std::string_view last_text = std::string_view(r).substr(colon + 1);
        const auto last = last_text.empty() ? std::optional<long long>(frames - 1) : parse_frame(last_text);
        if (!first || !last || *first < 0 || *first > *last || *last > frames - 1) return bad();
        d.first = *first;
        d.last = *last;
    }
    const double voxel = voxel_size ? *voxel_size : 1.0 / static_cast<double>(scene.field.resolution);
    if (!std::isfinite(voxel) || static_cast<float>(voxel) <= 0.0f || voxel > 100.0)
        return Error{fmt::format("--voxel-size: must be in (0, 100] metres (got {})", voxel)};
    d.voxel_size = static_cast<float>(voxel);
    const int digits = static_cast<int>(std::to_string(std::max(frames - 1, 0LL)).size());
    d.digits = std::max(5, digits);
    return d;
}

void print_export_summary(const Exporter& e) {
    std::string per_format;
    const double frames = static_cast<double>(std::max<size_t>(e.frames().size(), 1));
    for (const ExportFormatStats& st : e.stats())
        per_format += fmt::format("{}{} {:.2f} MB/frame {:.1f} ms/frame", per_format.empty() ? "" : ", ",
                                  to_string(st.format), static_cast<double>(st.bytes) / frames / 1e6,
                                  percentiles(st.ms).median);
    fmt::print("exported {} frames ({} files and {}) to {}: {}\n", e.frames().size(), e.written().size(), "export.json",
               e.def().dir, per_format);
}

}  // namespace mr::app
