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

// Images (src/io/image.cpp): PNG encoding (stb_image_write) for frames and screenshots,
// PNG/JPEG loading for terrain textures and golden images.
/// Encodes RGB8 (channels 3) or RGBA8 (4) pixels, top row first, as PNG bytes.
std::vector<uint8_t> encode_png(std::span<const uint8_t> pixels, int width, int height, int channels);
/// Writes a PNG atomically (temporary sibling, then rename).
Status write_png(const std::string& path, std::span<const uint8_t> pixels, int width, int height,
                 int channels);
/// A decoded PNG/JPEG (terrain textures, golden images), top row first.
struct Image {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<uint8_t> pixels;
};
/// Largest side and pixel count load_image accepts: 16384 is the largest texture side
/// of common GL drivers (llvmpipe's included); 2^28 pixels are 1 GiB as RGBA8.
inline constexpr int kMaxImageSide = 16384;
inline constexpr int64_t kMaxImagePixels = int64_t{1} << 28;
/// Only regular files of at most 512 MiB; see load_image_memory.
Result<Image> load_image(const std::string& path, int channels);
/// Decodes a PNG or JPEG (other formats are refused) to `channels` (1 to 4) per pixel.
/// The size is read from the header first: more than kMaxImageSide a side or
/// `max_pixels` in all is an error before anything is decoded. `name` names the image
/// in messages.
Result<Image> load_image_memory(std::span<const uint8_t> bytes, const std::string& name, int channels,
                                int64_t max_pixels = kMaxImagePixels);


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
