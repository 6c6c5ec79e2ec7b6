// libFuzzer target: the command line of the metariver program. The input is the
// argument list, one argument per line (argv[0] is added). It is parsed exactly as
// main() parses it (mr::app::parse_command_line: every command's options, CLI11's
// conversions); nothing is run. Then what the commands check before they run, where
// it reads no file: the scene options (--preset, --collision, --area-scale,
// --height-scale, --seed) resolved to a validated scene, and --camera.
//
// Run it in an empty folder (scripts/fuzz.sh does): a --scene or --heightmap argument
// names a path relative to it.
#include "commands.h"

#include <metariver/render.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

/// SceneOptions::resolve for arguments that name no file (reading files is the other
/// targets' job, and a fuzzed path could name anything on the machine).
void resolve_scene_options(const std::vector<const char*>& argv) {
    for (const char* a : argv) {
        const std::string s = a;
        if (s.rfind("--scene", 0) == 0 || s.rfind("--heightmap", 0) == 0 || s.rfind("--real-scale", 0) == 0) return;
    }
    CLI::App app{"fuzz"};
    mr::app::SceneOptions opts;
    CLI::App* cmd = app.add_subcommand("scene");
    opts.add_to(*cmd);
    cmd->allow_extras();
    std::vector<const char*> args = {"metariver", "scene"};
    args.insert(args.end(), argv.begin() + 2, argv.end());
    try {
        app.parse(static_cast<int>(args.size()), args.data());
    } catch (const CLI::ParseError&) {
        return;
    }
    auto def = opts.resolve();
    if (def && !mr::validate(def.value())) std::abort();  // resolve returns only valid scenes
    if (!def && def.error().message.find('\n') != std::string::npos) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    // Help and usage text go to stdout: not the fuzzer's business.
    if (!std::freopen("/dev/null", "w", stdout)) std::abort();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    // An argument ends at its first NUL byte, as argv's C strings do: the checks below
    // must see what CLI11 sees ("--version\0..." is --version; found by CI's fuzz run).
    std::vector<std::string> args = {"metariver"};
    std::string cur;
    for (size_t i = 0; i < size; ++i) {
        if (data[i] == '\n') {
            args.emplace_back(cur.c_str());
            cur.clear();
        } else {
            cur += static_cast<char>(data[i]);
        }
    }
    if (!cur.empty()) args.emplace_back(cur.c_str());
    if (args.size() > 64) return 0;  // no command takes more
    std::vector<const char*> argv;
    for (const auto& a : args) argv.push_back(a.c_str());

    mr::app::CommandLine cl = mr::app::parse_command_line(static_cast<int>(argv.size()), argv.data());
    if (!cl.action && cl.exit_code == mr::app::kExitOk && argv.size() > 1) {
        // exit 0 without an action only for help or the version: --help, --help-all, -h
        // alone or in a group of short flags ("-help" is -h -e -l -p to CLI11), --version
        bool help = false;
        for (const auto& a : args)
            help |= a.rfind("--help", 0) == 0 || a == "--version" ||
                    (a.size() > 1 && a[0] == '-' && a[1] != '-' && a.find('h') != std::string::npos);
        if (!help) std::abort();
    }
    if (!cl.action) return 0;
    resolve_scene_options(argv);
    for (size_t i = 1; i + 1 < args.size(); ++i) {
        if (args[i] == "--camera") {
            mr::render::Camera camera;
            (void)mr::render::parse_camera(args[i + 1], camera);
        }
    }
    return 0;
}
