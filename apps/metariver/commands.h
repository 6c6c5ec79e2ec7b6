// The metariver command-line tool: each subcommand registers its options on the
// CLI11 app and runs after parsing. Exit codes: 0 success, 2 bad input (one-line
// message naming the file/option/key and the allowed range), 1 an unexpected failure.
#pragma once

#include <CLI/CLI.hpp>

#include <metariver/scene.h>

#include <functional>
#include <optional>
#include <string>

namespace mr::app {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitBadInput = 2;

/// The options every command that builds a scene shares.
struct SceneOptions {
    std::string preset;
    std::string scene_file;
    std::string heightmap;
    std::optional<uint32_t> seed;
    std::string collision;
    std::optional<double> area_scale;    ///< --area-scale: terrain.area_scale, wins over --real-scale
    std::optional<double> height_scale;  ///< --height-scale: terrain.height_scale, wins over --real-scale
    bool real_scale = false;             ///< --real-scale: both scales from the heightmap's JSON sidecar

    void add_to(CLI::App& cmd);
    /// The scene the options describe; errors are one line, naming the option or file.
    /// need_heightmap = false: a preset whose paper scene used a PNG may stay without one
    /// (`metariver scene` prints it with an empty terrain.heightmap to fill in).
    Result<SceneDef> resolve(bool need_heightmap = true) const;
};

/// Registers `run`; `action` is set to the function to call after parsing.
void register_run(CLI::App& app, std::function<int()>& action);
/// Registers `view` (the interactive viewer; apps/metariver/cmd_view.cpp).
void register_view(CLI::App& app, std::function<int()>& action);
/// Registers `render` (headless PNG/MP4 rendering; apps/metariver/cmd_render.cpp).
void register_render(CLI::App& app, std::function<int()>& action);
/// Registers `scene` (a scene as a commented TOML file; the key reference; cmd_scene.cpp).
void register_scene(CLI::App& app, std::function<int()>& action);
/// Registers `bench`.
void register_bench(CLI::App& app, std::function<int()>& action);

/// A parsed command line: `action` runs the chosen command (checking its options first);
/// without one, `exit_code` is the result (help printed, or the one-line parse error
/// already on stderr).
struct CommandLine {
    std::function<int()> action;
    int exit_code = kExitOk;
};
/// What `metariver --version` prints: the version, the git commit at configure time, the
/// build type and the compiler.
std::string version_text();
/// Parses `argv` (argv[0] is the program) for every command; runs nothing.
CommandLine parse_command_line(int argc, const char* const* argv);

}  // namespace mr::app
