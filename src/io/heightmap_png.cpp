// The terrain as a 16-bit grey PNG plus the JSON sidecar `--real-scale` reads
// (issue 14: save what was sculpted, load it back). stb_image_write has no 16-bit PNG:
// the chunks are written here (their CRC: png_crc32, terrain.h), the deflate stream
// comes from its zlib compressor.
#include <metariver/io.h>
#include <metariver/terrain.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

extern "C" unsigned char* stbi_zlib_compress(unsigned char* data, int data_len, int* out_len, int quality);

namespace mr {
namespace {

void put_be32(std::string& out, uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(char((v >> s) & 0xffu));
}

void put_chunk(std::string& out, const char type[4], std::string_view data) {
    put_be32(out, uint32_t(data.size()));
    const size_t start = out.size();
    out.append(type, 4);
    out.append(data);
    put_be32(out, png_crc32(reinterpret_cast<const uint8_t*>(out.data()) + start, out.size() - start));
}

}  // namespace

Result<std::string> encode_png_gray16(std::span<const uint16_t> samples, int width, int height) {
    if (width <= 0 || height <= 0 || samples.size() != size_t(width) * size_t(height))
        return Error{fmt::format("png: {} samples do not make a {} x {} image", samples.size(), width, height)};
    std::string out("\x89PNG\r\n\x1a\n", 8);
    std::string ihdr;
    put_be32(ihdr, uint32_t(width));
    put_be32(ihdr, uint32_t(height));
    ihdr += std::string("\x10\x00\x00\x00\x00", 5);  // 16 bits, grey, deflate, filter 0, no interlace
    put_chunk(out, "IHDR", ihdr);
    std::string raw;  // scanlines with filter type 0, big-endian samples
    raw.reserve(size_t(height) * (1 + 2 * size_t(width)));
    for (int r = 0; r < height; ++r) {
        raw.push_back(0);
        for (int c = 0; c < width; ++c) {
            const uint16_t v = samples[size_t(r) * width + c];
            raw.push_back(char(v >> 8));
            raw.push_back(char(v & 0xffu));
        }
    }
    if (raw.size() > size_t(1) << 30) return Error{"png: the image is too large to compress"};
    int zlen = 0;
    unsigned char* z = stbi_zlib_compress(reinterpret_cast<unsigned char*>(raw.data()), int(raw.size()), &zlen, 6);
    if (!z) return Error{"png: compression failed (out of memory)"};
    put_chunk(out, "IDAT", std::string_view(reinterpret_cast<const char*>(z), size_t(zlen)));
    std::free(z);
    put_chunk(out, "IEND", {});
    return out;
}

Result<TerrainSaved> write_terrain_heightmap(const std::string& png_path, const Terrain& t, bool paper_row_orientation) {
    const int W = t.columns(), H = t.rows();
    const float lo = t.mesh_bounds().min.y, hi = t.mesh_bounds().max.y;
    const float range = hi > lo ? hi - lo : 1.0f;  // a flat terrain: every sample 0
    std::vector<uint16_t> px(size_t(W) * size_t(H));
    for (int i = 0; i < H; ++i) {
        const int r = paper_row_orientation ? H - 1 - i : i;  // image row of grid row i (Terrain::build)
        for (int j = 0; j < W; ++j)
            px[size_t(r) * W + j] = uint16_t(std::lround(std::clamp((t.sample(i, j) - lo) / range, 0.0f, 1.0f) * 65535.0f));
    }
    auto png = encode_png_gray16(px, W, H);
    if (!png) return Error{fmt::format("{}: {}", png_path, png.error().message)};
    // The sidecar `--real-scale` reads: the same path with ".json" (sidecar_path in the app).
    const TerrainSaved s{.png = png_path,
                         .sidecar = std::filesystem::path(png_path).replace_extension(".json").string(),
                         .metres_min = lo,
                         .metres_max = lo + range,
                         .area_scale = t.area_scale()};
    const std::string json = fmt::format(
        "{{\n \"source\": \"metariver: a terrain saved from a simulation\",\n \"width\": {},\n \"height\": {},\n"
        " \"metres_min\": {},\n \"metres_max\": {},\n \"sample_spacing_m\": {}\n}}\n",
        W, H, s.metres_min, s.metres_max, s.area_scale);
    if (auto w = write_file_atomic(png_path, png.value()); !w) return w.error();
    if (auto w = write_file_atomic(s.sidecar, json); !w) {
        std::remove(png_path.c_str());  // no half-saved terrain
        return w.error();
    }
    return s;
}

}  // namespace mr
