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

}  // namespace mr
