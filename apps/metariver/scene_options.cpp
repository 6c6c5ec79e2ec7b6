#include "commands.h"
#include "sidecar.h"

#include <metariver/scene_keys.h>
#include <metariver/terrain.h>

#include <fmt/format.h>

#include <cmath>

namespace mr::app {

namespace {

/// An explicit scale option: finite, > 0 (also as a float) and at most `hi` metres.
Status check_scale(const char* option, const std::optional<double>& v, double hi) {
    if (v && !(std::isfinite(*v) && static_cast<float>(*v) > 0.0f && *v <= hi))
        return Error{fmt::format("{}: must be in (0, {}] metres (got {})", option, hi, *v)};
    return Ok{};
}

/// The scales of the heightmap's sidecar (--real-scale), checked against the image's size.
Result<SidecarScale> real_scale_of(const SceneDef& def) {
    if (def.source.kind != TerrainSource::File || def.source.heightmap.empty())
        return Error{"--real-scale: needs a heightmap file (--heightmap FILE, or a scene's terrain.heightmap)"};
    const std::string json_path = sidecar_path(def.source.heightmap);
    auto s = read_sidecar_scale(json_path);
    if (!s || (s->width == 0 && s->height == 0)) return s;
    auto map = load_heightmap_png(def.source.heightmap);
    if (!map) return map.error();
    if ((s->width != 0 && s->width != map->width) || (s->height != 0 && s->height != map->height))
        return Error{fmt::format("{}: width, height: {} x {} does not match the heightmap's {} x {} samples ({})",
                                 json_path, s->width, s->height, map->width, map->height, def.source.heightmap)};
    return s;
}

/// collision.mode of the key table: --collision takes its choices.
const SceneKey& collision_mode_key() { return *find_scene_key("collision.mode"); }

}  // namespace

void SceneOptions::add_to(CLI::App& cmd) {
    std::string presets;
    for (const auto& n : preset_names()) presets += (presets.empty() ? "" : ", ") + n;
    auto* p = cmd.add_option("--preset", preset, "built-in scene: " + presets + " (default: default)");
    auto* s = cmd.add_option("--scene", scene_file, "scene file (TOML, see docs/scene-format.md)");
    p->excludes(s);
    cmd.add_option("--heightmap", heightmap, "PNG heightmap (8/16-bit); replaces the scene's terrain");
    cmd.add_option("--seed", seed, "particle spawn seed (overrides the scene's)");
    std::string modes;
    const auto choices = collision_mode_key().choices;
    for (size_t i = 0; i < choices.size(); ++i)
        modes += fmt::format("{}{}", i == 0 ? "" : (i + 1 == choices.size() ? " or " : ", "), choices[i]);
    cmd.add_option("--collision", collision, "override collision mode: " + modes);
    cmd.add_option("--area-scale", area_scale,
                   "metres between heightmap samples, (0, 10000] (overrides terrain.area_scale and --real-scale)");
    cmd.add_option("--height-scale", height_scale,
                   "metres for a normalised height of 1, (0, 100000] (overrides terrain.height_scale and --real-scale)");
    cmd.add_flag("--real-scale", real_scale,
                 "both scales from the heightmap's JSON sidecar (FILE.json beside FILE.png: metres_min, "
                 "metres_max, lat, lon, width, height or sample_spacing_m; docs/scene-format.md)");
}

Result<SceneDef> SceneOptions::resolve(bool need_heightmap) const {
    SceneDef def;
    if (!scene_file.empty()) {
        auto loaded = load_scene_file(scene_file, heightmap);  // --heightmap replaces its terrain
        if (!loaded) return loaded.error();
        def = std::move(loaded.value());
    } else {
        auto p = mr::preset(preset.empty() ? "default" : preset);
        if (!p) return Error{"--preset: " + p.error().message};
        def = std::move(p.value());
    }
    if (!heightmap.empty()) {
        def.source.kind = TerrainSource::File;
        def.source.heightmap = heightmap;
    }
    if (seed) {
        if (const std::string why = seed_unused(def.solver); !why.empty()) return Error{"--seed: " + why};
        def.seed = *seed;
    }
    if (!collision.empty()) {
        const SceneKey& mode = collision_mode_key();
        if (const std::string e = set_choice(mode, mode.field(def), collision); !e.empty()) return Error{"--collision: " + e};
        if (const std::string why = collision_mode_unused(def.solver, def.collision.mode); !why.empty())
            return Error{"--collision: " + why};
    }
    if (need_heightmap && def.source.kind == TerrainSource::File && def.source.heightmap.empty())
        return Error{fmt::format("scene '{}' uses the paper's heightmap file: give it with --heightmap FILE", def.name)};
    if (auto c = check_scale("--area-scale", area_scale, kMaxAreaScale); !c) return c.error();
    if (auto c = check_scale("--height-scale", height_scale, kMaxHeightScale); !c) return c.error();
    if (real_scale) {
        auto s = real_scale_of(def);
        if (!s) return s.error();
        def.terrain.area_scale = static_cast<float>(s->area_scale);
        def.terrain.auto_area_scale = false;
        def.terrain.height_scale = static_cast<float>(s->height_scale);
    }
    if (area_scale) {
        def.terrain.area_scale = static_cast<float>(*area_scale);
        def.terrain.auto_area_scale = false;
    }
    if (height_scale) def.terrain.height_scale = static_cast<float>(*height_scale);
    if (auto v = validate(def); !v) return v.error();
    return def;
}

}  // namespace mr::app
