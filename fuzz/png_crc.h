// For the PNG fuzz targets: the input with the CRC of every complete chunk recomputed,
// so that mutations get past the loaders' CRC check into the decoder.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mr::fuzz {

inline uint32_t crc32_png(const uint8_t* p, size_t n) {
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; ++i) {
        c ^= p[i];
        for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xedb88320u ^ (c >> 1) : c >> 1;
    }
    return c ^ 0xffffffffu;
}

/// The bytes with every complete chunk's CRC (after the 8-byte signature) recomputed.
inline std::vector<uint8_t> with_fixed_crcs(const uint8_t* data, size_t size) {
    std::vector<uint8_t> b(data, data + size);
    size_t pos = 8;
    while (pos + 12 <= b.size()) {
        const size_t len = (size_t{b[pos]} << 24) | (size_t{b[pos + 1]} << 16) | (size_t{b[pos + 2]} << 8) | b[pos + 3];
        if (len > b.size() - pos - 12) break;
        const uint32_t crc = crc32_png(b.data() + pos + 4, len + 4);
        uint8_t* out = b.data() + pos + 8 + len;
        out[0] = uint8_t(crc >> 24);
        out[1] = uint8_t(crc >> 16);
        out[2] = uint8_t(crc >> 8);
        out[3] = uint8_t(crc);
        pos += 12 + len;
    }
    return b;
}

}  // namespace mr::fuzz
