// metariver: real-time river simulation with metaballs. Thin front end: parse,
// call the library, present.
#include "commands.h"

#include <fmt/format.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
    mr::app::CommandLine cl = mr::app::parse_command_line(argc, argv);
    if (!cl.action) return cl.exit_code;
    try {
        return cl.action();
    } catch (const std::exception& e) {
        fmt::print(stderr, "metariver: internal error: {}\n", e.what());
        return mr::app::kExitFailure;
    }
}
