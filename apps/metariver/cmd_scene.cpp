// `metariver scene`: a scene as a complete, commented TOML file a user can start from
// (every key with its value, unit, range and help; scene_to_toml), from a preset or a
// scene file with the options of `run` applied; `--doc` prints the key reference of
// docs/scene-format.md and `--update-doc FILE` rewrites it there (a test checks the file
// holds what --doc prints).
#include "commands.h"

#include <metariver/io.h>
#include <metariver/scene_keys.h>

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

namespace mr::app {

namespace {

struct SceneCommandOptions {
    SceneOptions scene;
    bool doc = false;
    std::string update_doc;
};

int fail(const std::string& message) {
    fmt::print(stderr, "metariver scene: {}\n", message);
    return kExitBadInput;
}

/// Replaces the text between the reference markers of `path` with the generated one.
int update_doc(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return fail(fmt::format("{}: cannot open", path));
    std::ostringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    const size_t begin = text.find(kReferenceBegin);
    const size_t end = text.find(kReferenceEnd);
    if (begin == std::string::npos || end == std::string::npos || end < begin)
        return fail(fmt::format("{}: no '{}' ... '{}' section to replace", path, kReferenceBegin, kReferenceEnd));
    std::string out = text.substr(0, begin) + scene_reference_markdown();
    const size_t after = text.find('\n', end);
    out += after == std::string::npos ? std::string() : text.substr(after + 1);
    if (auto s = write_file_atomic(path, out); !s) return fail(s.error().message);
    return kExitOk;
}

int scene_command(const SceneCommandOptions& o) {
    if (!o.update_doc.empty()) return update_doc(o.update_doc);
    if (o.doc) {
        fmt::print("{}", scene_reference_markdown());
        return kExitOk;
    }
    auto def = o.scene.resolve(/*need_heightmap=*/false);
    if (!def) return fail(def.error().message);
    // The file may be saved anywhere: a heightmap path relative to here would be read
    // relative to the file's folder.
    if (!def->source.heightmap.empty())
        def->source.heightmap = std::filesystem::absolute(def->source.heightmap).lexically_normal().string();
    // The file starts from the preset it was printed from (`preset = NAME`), so the keys
    // that preset does not read keep its values; a scene file is written on the default.
    const std::string base = o.scene.scene_file.empty() && !o.scene.preset.empty() ? o.scene.preset : "default";
    fmt::print("{}", scene_to_toml(*def, base));
    return kExitOk;
}

}  // namespace

void register_scene(CLI::App& app, std::function<int()>& action) {
    auto opts = std::make_shared<SceneCommandOptions>();
    CLI::App* cmd = app.add_subcommand(
        "scene", "print a scene (--preset, or --scene with the options applied) as a complete, commented TOML file");
    opts->scene.add_to(*cmd);
    auto* doc = cmd->add_flag("--doc", opts->doc, "print the key reference of docs/scene-format.md instead");
    cmd->add_option("--update-doc", opts->update_doc,
                    "rewrite the key reference between its markers in this file (docs/scene-format.md)")
        ->excludes(doc);
    cmd->callback([opts, &action] { action = [opts] { return scene_command(*opts); }; });
}

}  // namespace mr::app
