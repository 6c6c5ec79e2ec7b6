// PNG heightmap loading (the paper's section 2.2: "the terrain is generated from a
// heightmap"; height = red channel / 255 in its code).
//
// Decoding is stb_image's (libstb). Before stb sees the bytes we check the PNG
// signature and walk the chunk list (length, type, data, CRC) up to IEND, so that a
// truncated or corrupt file is reported as such (stb alone accepts a file cut inside
// IEND's CRC), and we read the size from IHDR first, so that an oversized image is
// rejected before anything is allocated for it.
#include <metariver/terrain.h>

#include <stb_image.h>

#include <fmt/format.h>

#include <array>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

namespace mr {
namespace {

constexpr std::array<uint8_t, 8> kPngSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

uint32_t read_be32(const uint8_t* p) {
    return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}


std::string chunk_name(const uint8_t* type) {
    std::string s;
    for (int k = 0; k < 4; ++k) {
        const char ch = static_cast<char>(type[k]);
        s += (ch >= 33 && ch <= 126) ? ch : '?';
    }
    return s;
}

Error fail(const std::string& name, const std::string& what) { return Error{name + ": " + what}; }

}  // namespace

// Table driven.
uint32_t png_crc32(const uint8_t* data, size_t n) {
    static const std::array<uint32_t, 256> table = [] {
        std::array<uint32_t, 256> t{};
        for (uint32_t i = 0; i < 256; ++i) {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xedb88320u ^ (c >> 1) : c >> 1;
            t[i] = c;
        }
        return t;
    }();
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; ++i) c = table[(c ^ data[i]) & 0xffu] ^ (c >> 8);
    return c ^ 0xffffffffu;
}

Result<std::array<uint32_t, 2>> check_png_structure(std::span<const uint8_t> bytes, const std::string& name) {
    if (bytes.size() < kPngSignature.size() ||
        std::memcmp(bytes.data(), kPngSignature.data(), kPngSignature.size()) != 0) {
        return fail(name, "not a PNG image (bad signature)");
    }
    size_t pos = kPngSignature.size();
    bool first = true, image_data = false;
    std::array<uint32_t, 2> size{0, 0};
    for (;;) {
        if (bytes.size() - pos < 12) {
            return fail(name, "truncated PNG (ends before the IEND chunk)");
        }
        const uint32_t length = read_be32(bytes.data() + pos);
        const uint8_t* type = bytes.data() + pos + 4;
        if (length > 0x7fffffffu) {
            return fail(name, fmt::format("corrupt PNG (chunk length {} out of range)", length));
        }
        if (bytes.size() - pos - 12 < length) {
            return fail(name, fmt::format("truncated PNG (chunk {} is cut short)", chunk_name(type)));
        }
        const std::string type_name = chunk_name(type);
        const bool critical = (type[0] & 0x20u) == 0;
        if (critical) {
            // libpng's default: a CRC error in a critical chunk is fatal.
            const uint32_t stored = read_be32(type + 4 + length);
            if (png_crc32(type, length + 4u) != stored) {
                return fail(name, fmt::format("corrupt PNG (CRC mismatch in chunk {})", type_name));
            }
        }
        if (first) {
            if (type_name != "IHDR" || length != 13) {
                return fail(name, "corrupt PNG (first chunk is not IHDR)");
            }
            size = {read_be32(type + 4), read_be32(type + 8)};
            first = false;
        }
        if (type_name == "IDAT") {
            // stb_image copies an IDAT chunk into its buffer before it has one when the
            // first is empty (memcpy to a null pointer: undefined; found by fuzzing).
            if (length == 0 && !image_data)
                return fail(name, "unsupported PNG (an empty IDAT chunk before the image data)");
            image_data = true;
        }
        pos += 12u + length;
        if (type_name == "IEND") break;
    }
    return size;
}

Result<Heightmap> load_heightmap_png_memory(std::span<const uint8_t> bytes, const std::string& name) {
    if (bytes.empty()) return fail(name, "empty file");
    if (bytes.size() > static_cast<size_t>(INT_MAX)) return fail(name, "file too large for a PNG heightmap");

    auto structure = check_png_structure(bytes, name);
    if (!structure) return structure.error();
    const uint32_t w = structure.value()[0], h = structure.value()[1];
    if (w < 2 || h < 2) {
        return fail(name, fmt::format("image is {} x {}; the minimum is 2 x 2", w, h));
    }
    if (w > static_cast<uint32_t>(kMaxHeightmapSide) || h > static_cast<uint32_t>(kMaxHeightmapSide)) {
        return fail(name, fmt::format("image is {} x {}; the maximum is {} x {}", w, h, kMaxHeightmapSide,
                                      kMaxHeightmapSide));
    }

    const int len = static_cast<int>(bytes.size());
    const bool is16 = stbi_is_16_bit_from_memory(bytes.data(), len) != 0;
    int width = 0, height = 0, channels = 0;
    Heightmap map;
    if (is16) {
        std::unique_ptr<stbi_us, void (*)(void*)> data(
            stbi_load_16_from_memory(bytes.data(), len, &width, &height, &channels, 0), stbi_image_free);
        if (!data) {
            return fail(name, fmt::format("not a valid PNG image ({})", stbi_failure_reason()));
        }
        if (width != static_cast<int>(w) || height != static_cast<int>(h) || channels < 1) {
            return fail(name, "corrupt PNG (decoded size differs from IHDR)");
        }
        map.bit_depth = 16;
        map.samples.resize(static_cast<size_t>(width) * height);
        for (size_t k = 0; k < map.samples.size(); ++k) {
            map.samples[k] = static_cast<float>(data.get()[k * channels]) / 65535.0f;
        }
    } else {
        std::unique_ptr<stbi_uc, void (*)(void*)> data(
            stbi_load_from_memory(bytes.data(), len, &width, &height, &channels, 0), stbi_image_free);
        if (!data) {
            return fail(name, fmt::format("not a valid PNG image ({})", stbi_failure_reason()));
        }
        if (width != static_cast<int>(w) || height != static_cast<int>(h) || channels < 1) {
            return fail(name, "corrupt PNG (decoded size differs from IHDR)");
        }
        map.bit_depth = 8;
        map.samples.resize(static_cast<size_t>(width) * height);
        for (size_t k = 0; k < map.samples.size(); ++k) {
            map.samples[k] = static_cast<float>(data.get()[k * channels]) / 255.0f;
        }
    }
    map.width = width;
    map.height = height;
    return map;
}

Result<Heightmap> load_heightmap_png(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return fail(path, "no such file");
    if (std::filesystem::is_directory(path, ec)) return fail(path, "is a directory, not a PNG file");
    // Only regular files: a FIFO or a device would block or never end.
    if (!std::filesystem::is_regular_file(path, ec)) return fail(path, "not a regular file");
    constexpr uintmax_t kMaxPngBytes = uintmax_t{512} << 20;
    if (const uintmax_t size = std::filesystem::file_size(path, ec); !ec && size > kMaxPngBytes)
        return fail(path, fmt::format("file is {} bytes; a heightmap PNG may have at most {}", size, kMaxPngBytes));

    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), std::fclose);
    if (!file) return fail(path, fmt::format("cannot open ({})", std::strerror(errno)));

    std::vector<uint8_t> bytes;
    std::array<uint8_t, 65536> chunk{};
    for (;;) {
        const size_t n = std::fread(chunk.data(), 1, chunk.size(), file.get());
        bytes.insert(bytes.end(), chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(n));
        if (n < chunk.size()) break;
        if (bytes.size() > static_cast<size_t>(INT_MAX)) return fail(path, "file too large for a PNG heightmap");
    }
    if (std::ferror(file.get())) return fail(path, "read error");
    return load_heightmap_png_memory(bytes, path);
}

}  // namespace mr
