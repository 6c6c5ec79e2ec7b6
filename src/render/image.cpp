// PNG encoding (stb_image_write) and image loading (stb_image) for frames, screenshots,
// terrain textures and golden images.
#include <metariver/io.h>
#include <metariver/render.h>
#include <metariver/terrain.h>

#include <fmt/format.h>
#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string_view>

namespace mr::render {

namespace {

/// The Huffman tables of a JPEG, checked before stb_image reads any of it (Debian's
/// stb_image trusts them; both bugs found by fuzz/image_fuzz.cpp, fixed in later stb):
/// - a DHT table whose code counts add up to more than 256 makes stbi__build_huffman write
///   past its fixed arrays (UBSan: index 257 out of bounds for stbi_uc[257]);
/// - a scan that uses a table no DHT defined makes stb decode with the uninitialised
///   table of its freshly allocated decoder (reads far out of bounds).
/// The walk follows the markers as stb does: segments by their length, entropy-coded data
/// byte by byte up to the next marker (FF 00 is a stuffed byte, FF D0-D7 restart markers,
/// FF FF fill), and a DHT table by table while its length lasts, with bytes past the end
/// read as 0 (stb's reader returns 0 there). A scan needs what stb decodes it with:
/// sequential, the DC and AC tables of each component; progressive, the DC table for a
/// first DC scan, the AC table for an AC scan, none for a DC refinement.
Status check_jpeg_huffman_tables(std::span<const uint8_t> b, const std::string& name) {
    auto at = [&](size_t i) -> size_t { return i < b.size() ? b[i] : 0; };
    bool progressive = false;
    bool defined[2][4] = {};  // [DC, AC][table]
    size_t pos = 2;  // after SOI
    while (pos + 1 < b.size()) {
        if (b[pos] != 0xff || b[pos + 1] == 0xff || b[pos + 1] == 0x00 || (b[pos + 1] >= 0xd0 && b[pos + 1] <= 0xd8)) {
            pos += (b[pos] == 0xff && b[pos + 1] != 0xff) ? 2 : 1;
            continue;
        }
        const uint8_t marker = b[pos + 1];
        if (marker == 0xd9) break;  // EOI
        const long length = static_cast<long>((at(pos + 2) << 8) | at(pos + 3));
        if (marker == 0xc2) progressive = true;
        if (marker == 0xc4) {
            size_t p = pos + 4;
            for (long left = length - 2; left > 0;) {
                size_t codes = 0;
                for (size_t i = 1; i <= 16; ++i) codes += at(p + i);
                if (codes > 256)
                    return Error{fmt::format("{}: corrupt JPEG (a Huffman table with {} codes; at most 256)", name, codes)};
                const size_t cls = at(p) >> 4, id = at(p) & 15;
                if (cls <= 1 && id <= 3) defined[cls][id] = true;
                p += 17 + codes;
                left -= static_cast<long>(17 + codes);
            }
        }
        if (marker == 0xda) {
            const size_t n = at(pos + 4);
            const size_t ss = at(pos + 5 + 2 * n), ah = at(pos + 7 + 2 * n) >> 4;
            const bool dc = !progressive || (ss == 0 && ah == 0), ac = !progressive || ss > 0;
            for (size_t c = 0; c < n; ++c) {
                const size_t t = at(pos + 6 + 2 * c), td = t >> 4, ta = t & 15;
                if ((dc && (td > 3 || !defined[0][td])) || (ac && (ta > 3 || !defined[1][ta])))
                    return Error{fmt::format("{}: corrupt JPEG (a scan uses a Huffman table that was never defined)", name)};
            }
        }
        pos += 2 + static_cast<size_t>(std::max(length, 2L));
    }
    return Ok{};
}

}  // namespace

std::vector<uint8_t> encode_png(std::span<const uint8_t> pixels, int width, int height, int channels) {
    std::vector<uint8_t> out;
    out.reserve(static_cast<size_t>(width) * height);
    auto sink = [](void* ctx, void* data, int size) {
        auto* v = static_cast<std::vector<uint8_t>*>(ctx);
        const auto* b = static_cast<const uint8_t*>(data);
        v->insert(v->end(), b, b + size);
    };
    // Level 4 instead of stb's 8: frames are written every frame and level 8 costs
    // about twice the time for a few percent smaller files.
    stbi_write_png_compression_level = 4;
    stbi_write_png_to_func(sink, &out, width, height, channels, pixels.data(), width * channels);
    return out;
}

Status write_png(const std::string& path, std::span<const uint8_t> pixels, int width, int height,
                 int channels) {
    const std::vector<uint8_t> bytes = encode_png(pixels, width, height, channels);
    if (bytes.empty()) return Error{fmt::format("{}: PNG encoding failed", path)};
    return write_file_atomic(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

Result<Image> load_image_memory(std::span<const uint8_t> bytes, const std::string& name, int channels,
                                int64_t max_pixels) {
    if (channels < 1 || channels > 4) return Error{fmt::format("{}: channels must be in [1, 4] (got {})", name, channels)};
    // Only the two formats the docs promise: stb_image would also take BMP, GIF, PSD, TGA,
    // HDR, PIC and PNM, decoders nobody here needs.
    constexpr uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    constexpr uint8_t kJpeg[3] = {0xff, 0xd8, 0xff};
    const bool png = bytes.size() >= sizeof kPng && std::memcmp(bytes.data(), kPng, sizeof kPng) == 0;
    const bool jpeg = bytes.size() >= sizeof kJpeg && std::memcmp(bytes.data(), kJpeg, sizeof kJpeg) == 0;
    if (!png && !jpeg) return Error{fmt::format("{}: not a PNG or JPEG image", name)};
    // The structure first: stb_image reserves what a PNG chunk's length claims before it
    // reads the chunk (2 GiB for a 150-byte file; found by fuzz/image_fuzz.cpp).
    if (png)
        if (auto c = check_png_structure(bytes, name); !c) return c.error();
    if (jpeg)
        if (auto c = check_jpeg_huffman_tables(bytes, name); !c) return c.error();
    if (bytes.size() > static_cast<size_t>(INT_MAX)) return Error{fmt::format("{}: larger than 2 GiB", name)};
    const int len = static_cast<int>(bytes.size());
    // The size from the header first, so an oversized image is refused before stb
    // allocates for it.
    int w = 0, h = 0, n = 0;
    if (!stbi_info_from_memory(bytes.data(), len, &w, &h, &n)) {
        const char* why = stbi_failure_reason();
        return Error{fmt::format("{}: cannot read image ({})", name, why ? why : "unknown error")};
    }
    if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide || int64_t{w} * h > max_pixels)
        return Error{fmt::format("{}: image is {} x {}; at most {} pixels a side and {} pixels in all", name, w, h,
                                 kMaxImageSide, max_pixels)};
    std::unique_ptr<stbi_uc, void (*)(void*)> data(stbi_load_from_memory(bytes.data(), len, &w, &h, &n, channels),
                                                   stbi_image_free);
    if (!data) {
        const char* why = stbi_failure_reason();
        return Error{fmt::format("{}: cannot read image ({})", name, why ? why : "unknown error")};
    }
    Image img;
    img.width = w;
    img.height = h;
    img.channels = channels;
    img.pixels.assign(data.get(), data.get() + static_cast<size_t>(w) * h * channels);
    return img;
}

Result<Image> load_image(const std::string& path, int channels) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))  // a FIFO or a device would block or never end
        return Error{fmt::format("{}: not a regular file", path)};
    if (std::filesystem::file_size(path, ec) > (uintmax_t{512} << 20))
        return Error{fmt::format("{}: larger than 512 MiB", path)};
    std::ifstream in(path, std::ios::binary);
    if (!in) return Error{fmt::format("{}: cannot open", path)};
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) return Error{fmt::format("{}: read error", path)};
    return load_image_memory(bytes, path, channels);
}

}  // namespace mr::render
