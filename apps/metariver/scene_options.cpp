#include "commands.h"

#include <fmt/format.h>

namespace mr::app {

void SceneOptions::add_to(CLI::App& cmd) {
    std::string presets;
    for (const auto& n : preset_names()) presets += (presets.empty() ? "" : ", ") + n;
    auto* p = cmd.add_option("--preset", preset, "built-in scene: " + presets + " (default: default)");
    auto* s = cmd.add_option("--scene", scene_file, "scene file (TOML, see docs/scene-format.md)");
    p->excludes(s);
    cmd.add_option("--heightmap", heightmap, "PNG heightmap (8/16-bit); replaces the scene's terrain");
    cmd.add_option("--seed", seed, "particle spawn seed (overrides the scene's)");
    cmd.add_option("--collision", collision, "override collision mode: paper, robust or none");
}

Result<SceneDef> SceneOptions::resolve() const {
    SceneDef def;
    if (!scene_file.empty()) {
        auto loaded = load_scene_file(scene_file);
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
    if (seed) def.seed = *seed;
    if (!collision.empty()) {
        if (collision == "paper") def.collision.mode = CollisionMode::Paper;
        else if (collision == "robust") def.collision.mode = CollisionMode::Robust;
        else if (collision == "none") def.collision.mode = CollisionMode::None;
        else return Error{fmt::format("--collision: must be one of paper, robust, none (got '{}')", collision)};
    }
    if (def.source.kind == TerrainSource::File && def.source.heightmap.empty())
        return Error{fmt::format("scene '{}' uses the paper's heightmap file: give it with --heightmap FILE", def.name)};
    if (auto v = validate(def); !v) return v.error();
    return def;
}

}  // namespace mr::app
