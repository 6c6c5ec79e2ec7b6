// metariver io: writers for meshes and run statistics. Every writer produces its file
// completely or not at all (it writes a temporary sibling and renames it into place).
#pragma once

#include <metariver/core.h>
#include <metariver/surface.h>
#include <metariver/terrain.h>

#include <glm/vec2.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace mr {

/// Writes `contents` to `path` atomically (temporary file in the same folder, then rename).
Status write_file_atomic(const std::string& path, std::string_view contents);

/// Wavefront OBJ text of an indexed mesh: positions, normals and texture coordinates
/// (each used when it holds one entry per position; vt v is flipped to OBJ's upward v),
/// 1-based faces ("f a//a b//b c//c", or "f a/a/a ..." with texture coordinates).
std::string obj_text(std::span<const Vec3> positions, std::span<const Vec3> normals,
                     std::span<const uint32_t> indices, std::string_view comment,
                     std::span<const glm::vec2> uvs = {});
Status write_surface_obj(const std::string& path, const SurfaceMesh& mesh, std::string_view comment);
/// The terrain mesh as OBJ, with per-vertex normals of the bilinear surface.
Status write_terrain_obj(const std::string& path, const Terrain& terrain);

/// Median and 95th percentile of a sample (nearest-rank); zeros when empty.
struct Percentiles {
    double median = 0.0;
    double p95 = 0.0;
    double mean = 0.0;
    double max = 0.0;
};
Percentiles percentiles(std::vector<double> samples);

/// A 16-bit grey PNG of `samples` (row-major, width per row), deflate-compressed.
Result<std::string> encode_png_gray16(std::span<const uint16_t> samples, int width, int height);

/// What write_terrain_heightmap wrote.
struct TerrainSaved {
    std::string png, sidecar;   ///< the paths written
    float metres_min = 0.0f;    ///< the height of PNG value 0
    float metres_max = 0.0f;    ///< the height of PNG value 65535
    float area_scale = 1.0f;    ///< metres between samples
};
/// Saves a terrain's current heights (sculpted, carved) as a 16-bit grey PNG spanning
/// its lowest to its highest sample, in image row order (`paper_row_orientation` as the
/// scene that built it), and beside it PATH.json with metres_min, metres_max,
/// sample_spacing_m, width and height: `--heightmap PATH --real-scale` loads it back at
/// its scale (heights shifted by -metres_min). Both files are written atomically; on an
/// error neither is left.
Result<TerrainSaved> write_terrain_heightmap(const std::string& png_path, const Terrain& t, bool paper_row_orientation);

}  // namespace mr
