// The real scale of a PNG heightmap from the JSON "sidecar" beside it (`--real-scale`):
// FILE.png -> FILE.json with metres_min and metres_max (the real range of the
// normalised heights 0..1) and either sample_spacing_m or the latitude/longitude box
// (lat [south, north], lon [west, east], degrees) with the grid's width and height.
// ../shared/heightmaps/real/*.json are such files; docs/scene-format.md, "Heightmap scale".
#pragma once

#include <metariver/core.h>

#include <string>
#include <string_view>

namespace mr::app {

/// The ranges of terrain.area_scale and terrain.height_scale (metres; scene_def.cpp, validate).
inline constexpr double kMaxAreaScale = 1e4;
inline constexpr double kMaxHeightScale = 1e5;

/// Largest sidecar read, in bytes: a sidecar is a few keys, anything larger is not one.
inline constexpr size_t kMaxSidecarBytes = 1u << 20;

struct SidecarScale {
    double area_scale = 0.0;    ///< metres between samples (terrain.area_scale)
    double height_scale = 0.0;  ///< metres_max - metres_min (terrain.height_scale)
    int width = 0;              ///< the grid the sidecar describes; 0 when it does not say
    int height = 0;
};

/// The sidecar's path for a heightmap: the same path with the extension ".json".
std::string sidecar_path(const std::string& heightmap);

/// The scale a sidecar's text gives. The area scale is sample_spacing_m when the key is
/// there, else the mean of the spacings along z, (lat1 - lat0) * 111320 / (height - 1),
/// and along x, (lon1 - lon0) * 111320 * cos(mean latitude) / (width - 1), in metres.
/// Errors are one line, "NAME: KEY: what is wrong"; the scales must be within
/// terrain.area_scale's (0, 1e4] and terrain.height_scale's (0, 1e5].
Result<SidecarScale> parse_sidecar_scale(std::string_view text, const std::string& name);

/// The same read from a file (a regular file of at most kMaxSidecarBytes); errors name it.
Result<SidecarScale> read_sidecar_scale(const std::string& path);

}  // namespace mr::app
