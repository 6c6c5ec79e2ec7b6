// Test helpers: PNG encoders for heightmap tests and a scratch directory.
//
// encode_png8 uses stb_image_write (implementation in libstb). encode_png_raw writes
// any bit depth (stb_image_write has no 16-bit PNG): the image data goes into zlib
// "stored" (uncompressed) deflate blocks (RFC 1950/1951), chunks carry CRC-32 (PNG
// spec, ISO 3309), and rows use filter type 0, so the encoder is a few dozen lines.
#pragma once

#include <stb_image_write.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace mr::test {

inline uint32_t crc32(const uint8_t* data, size_t n, uint32_t crc = 0) {
    crc ^= 0xffffffffu;
    for (size_t i = 0; i < n; ++i) {
        crc ^= data[i];
        for (int k = 0; k < 8; ++k) crc = (crc & 1u) ? 0xedb88320u ^ (crc >> 1) : crc >> 1;
    }
    return crc ^ 0xffffffffu;
}

inline uint32_t adler32(const std::vector<uint8_t>& data) {
    uint32_t a = 1, b = 0;
    for (uint8_t byte : data) {
        a = (a + byte) % 65521u;
        b = (b + a) % 65521u;
    }
    return (b << 16) | a;
}

inline void put_be32(std::vector<uint8_t>& out, uint32_t v) {
    out.push_back(static_cast<uint8_t>(v >> 24));
    out.push_back(static_cast<uint8_t>(v >> 16));
    out.push_back(static_cast<uint8_t>(v >> 8));
    out.push_back(static_cast<uint8_t>(v));
}

/// Appends a chunk (length, type, data, CRC over type + data).
inline void put_chunk(std::vector<uint8_t>& out, const char type[4], const std::vector<uint8_t>& data) {
    put_be32(out, static_cast<uint32_t>(data.size()));
    const size_t start = out.size();
    out.insert(out.end(), type, type + 4);
    out.insert(out.end(), data.begin(), data.end());
    put_be32(out, crc32(out.data() + start, out.size() - start));
}

/// PNG colour type for a channel count: 1 gray, 2 gray+alpha, 3 RGB, 4 RGBA.
inline uint8_t color_type(int channels) {
    constexpr std::array<uint8_t, 5> types = {0, 0, 4, 2, 6};
    return types[static_cast<size_t>(channels)];
}

/// Encodes a PNG of the given bit depth (8 or 16) from samples (row-major, channels
/// interleaved; 16-bit values are written big-endian). The IHDR size may be given
/// separately to build deliberately inconsistent files.
inline std::vector<uint8_t> encode_png_raw(int width, int height, int channels, int bit_depth,
                                           const std::vector<uint16_t>& samples, int ihdr_width = -1,
                                           int ihdr_height = -1) {
    std::vector<uint8_t> out = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<uint8_t> ihdr;
    put_be32(ihdr, static_cast<uint32_t>(ihdr_width >= 0 ? ihdr_width : width));
    put_be32(ihdr, static_cast<uint32_t>(ihdr_height >= 0 ? ihdr_height : height));
    ihdr.push_back(static_cast<uint8_t>(bit_depth));
    ihdr.push_back(color_type(channels));
    ihdr.push_back(0);  // deflate
    ihdr.push_back(0);  // adaptive filtering
    ihdr.push_back(0);  // no interlace
    put_chunk(out, "IHDR", ihdr);

    // Raw scanlines, filter type 0 (None).
    std::vector<uint8_t> raw;
    const size_t per_row = static_cast<size_t>(width) * channels;
    for (int r = 0; r < height; ++r) {
        raw.push_back(0);
        for (size_t k = 0; k < per_row; ++k) {
            const uint16_t v = samples[static_cast<size_t>(r) * per_row + k];
            if (bit_depth == 16) raw.push_back(static_cast<uint8_t>(v >> 8));
            raw.push_back(static_cast<uint8_t>(v & 0xffu));
        }
    }
    // zlib stream: header, stored blocks of at most 65535 bytes, Adler-32.
    std::vector<uint8_t> z = {0x78, 0x01};
    size_t pos = 0;
    do {
        const size_t n = std::min<size_t>(65535, raw.size() - pos);
        const bool last = pos + n == raw.size();
        z.push_back(last ? 1 : 0);
        z.push_back(static_cast<uint8_t>(n & 0xffu));
        z.push_back(static_cast<uint8_t>(n >> 8));
        z.push_back(static_cast<uint8_t>(~n & 0xffu));
        z.push_back(static_cast<uint8_t>((~n >> 8) & 0xffu));
        z.insert(z.end(), raw.begin() + static_cast<std::ptrdiff_t>(pos),
                 raw.begin() + static_cast<std::ptrdiff_t>(pos + n));
        pos += n;
    } while (pos < raw.size());
    put_be32(z, adler32(raw));
    put_chunk(out, "IDAT", z);
    put_chunk(out, "IEND", {});
    return out;
}

/// Encodes an 8-bit PNG with stb_image_write.
inline std::vector<uint8_t> encode_png8(int width, int height, int channels, const std::vector<uint8_t>& pixels) {
    std::vector<uint8_t> out;
    stbi_write_png_to_func(
        [](void* ctx, void* data, int size) {
            auto* v = static_cast<std::vector<uint8_t>*>(ctx);
            const auto* p = static_cast<const uint8_t*>(data);
            v->insert(v->end(), p, p + size);
        },
        &out, width, height, channels, pixels.data(), width * channels);
    return out;
}

/// A scratch directory, removed with its contents on destruction.
class TempDir {
public:
    TempDir() {
        path_ = std::filesystem::temp_directory_path() /
                ("metariver_terrain_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter()++));
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    /// Writes bytes to a file in the directory and returns its path.
    std::string write(const std::string& name, const std::vector<uint8_t>& bytes) const {
        const std::string p = (path_ / name).string();
        std::ofstream f(p, std::ios::binary);
        f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
        return p;
    }
    std::string file(const std::string& name) const { return (path_ / name).string(); }

private:
    static int& counter() {
        static int c = 0;
        return c;
    }
    std::filesystem::path path_;
};

}  // namespace mr::test
