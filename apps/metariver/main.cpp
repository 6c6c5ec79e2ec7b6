// metariver: real-time river simulation with metaballs. Thin front end: parse,
// call the library, present.
#include "commands.h"

#include <fmt/format.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
    CLI::App app{"metariver: real-time river simulation with metaballs"};
    app.require_subcommand(1);
    std::function<int()> action;
    mr::app::register_run(app, action);
    mr::app::register_view(app, action);
    mr::app::register_render(app, action);
    mr::app::register_bench(app, action);
    if (argc > 1 && argv[1][0] != '-') {
        std::string known;
        bool found = false;
        for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
            known += (known.empty() ? "" : ", ") + sub->get_name();
            found |= sub->get_name() == argv[1];
        }
        if (!found) {
            fmt::print(stderr, "metariver: unknown command '{}' (known: {})\n", argv[1], known);
            return mr::app::kExitBadInput;
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        fmt::print(stderr, "metariver: {}\n", e.what());
        return mr::app::kExitBadInput;
    }
    try {
        return action ? action() : mr::app::kExitBadInput;
    } catch (const std::exception& e) {
        fmt::print(stderr, "metariver: internal error: {}\n", e.what());
        return mr::app::kExitFailure;
    }
}
