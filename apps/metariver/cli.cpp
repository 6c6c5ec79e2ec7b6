// The metariver command line: every subcommand registered on one CLI11 app, parsed
// into the action to run. main() runs it; fuzz/cli_fuzz.cpp fuzzes the parsing.
#include "commands.h"

#include <build_info.h>

#include <fmt/format.h>

#include <cstdio>
#include <string_view>

namespace mr::app {

std::string version_text() {
    return fmt::format("metariver {}\nbuild: commit {} (at configure time), {}, {}", METARIVER_VERSION,
                       METARIVER_GIT_COMMIT, METARIVER_BUILD_TYPE[0] ? METARIVER_BUILD_TYPE : "no build type",
                       METARIVER_COMPILER);
}

CommandLine parse_command_line(int argc, const char* const* argv) {
    CLI::App app{"metariver: real-time river simulation with metaballs"};
    app.require_subcommand(1);
    app.set_version_flag("--version", version_text(), "print the version and the build, then exit");
    CommandLine result;
    register_run(app, result.action);
    register_view(app, result.action);
    register_render(app, result.action);
    register_scene(app, result.action);
    register_bench(app, result.action);
    if (argc > 1 && argv[1][0] != '-') {
        std::string known;
        bool found = false;
        for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
            known += (known.empty() ? "" : ", ") + sub->get_name();
            found |= sub->get_name() == argv[1];
        }
        if (!found) {
            fmt::print(stderr, "metariver: unknown command '{}' (known: {})\n", argv[1], known);
            return {{}, kExitBadInput};
        }
    }
    // CLI11 reads "--version=" (empty value) as the flag itself and "--version=x" as a
    // conversion error about "--version = x"; neither says that the flag takes no value.
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        for (std::string_view flag : {"--version", "--help"}) {
            if (a.size() > flag.size() && a.substr(0, flag.size()) == flag && a[flag.size()] == '=') {
                fmt::print(stderr, "metariver: {} takes no value (got '{}')\n", flag, a);
                return {{}, kExitBadInput};
            }
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForVersion& e) {
        return {{}, app.exit(e)};
    } catch (const CLI::CallForHelp& e) {
        return {{}, app.exit(e)};
    } catch (const CLI::CallForAllHelp& e) {
        return {{}, app.exit(e)};
    } catch (const CLI::ParseError& e) {
        fmt::print(stderr, "metariver: {}\n", e.what());
        return {{}, kExitBadInput};
    }
    if (!result.action) result.exit_code = kExitBadInput;
    return result;
}

}  // namespace mr::app
