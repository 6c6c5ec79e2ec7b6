// The export options `run` and `render` share: --export DIR --format LIST --every N
// --range FIRST:LAST --voxel-size M --no-particles (docs/export.md).
#pragma once

#include <CLI/CLI.hpp>

#include <metariver/export.h>
#include <metariver/scene.h>

#include <optional>
#include <string>

namespace mr::app {

struct ExportOptions {
    std::string dir;                    ///< --export: the folder; empty = no export
    std::optional<std::string> format;  ///< --format: obj, ply, glb, vdb, comma-separated (default obj)
    std::optional<long long> every;     ///< --every: frame stride (default 1)
    std::optional<std::string> range;   ///< --range FIRST:LAST (inclusive; LAST may be left out)
    std::optional<double> voxel_size;   ///< --voxel-size: VDB voxel edge (default: the field's cell)
    bool no_particles = false;          ///< --no-particles

    void add_to(CLI::App& cmd);
    bool enabled() const { return !dir.empty(); }
    /// True when any export option was given (resolve() then checks them all).
    bool given() const { return enabled() || format || every || range || voxel_size || no_particles; }
    /// Checks every export option against a command that produces frames 0 .. frames-1
    /// of `scene`; one-line errors naming the option and the allowed values. Without
    /// --export, any other export option is an error too.
    Result<ExportDef> resolve(long long frames, const SceneDef& scene) const;
};

/// One line after an export: frames and files written, and per format the mean size
/// and the median time (encode + write) per frame.
void print_export_summary(const Exporter& e);

}  // namespace mr::app
