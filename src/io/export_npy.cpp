// Export, the grid format: NumPy's .npy v1.0 written by hand (the format's own description:
// numpy.lib.format): the magic "\x93NUMPY", version 1.0, a little-endian uint16 header
// length, a Python dict literal padded with spaces to a 64-byte boundary and ended by '\n',
// then the values as little-endian float32 in C order (rows, then columns).
#include <metariver/export.h>

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cstring>

namespace mr {

static_assert(std::endian::native == std::endian::little, "the npy encoder copies little-endian floats as is");

std::string encode_npy_f32(std::span<const float> values, int rows, int columns) {
    std::string dict = fmt::format("{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {}), }}", rows, columns);
    constexpr size_t kPrefix = 10;  // magic (6), version (2), header length (2)
    const size_t unpadded = kPrefix + dict.size() + 1;
    dict.append((64 - unpadded % 64) % 64, ' ');
    dict.push_back('\n');
    const auto header_len = static_cast<uint16_t>(dict.size());
    std::string out("\x93NUMPY\x01\x00", 8);
    out.push_back(static_cast<char>(header_len & 0xff));
    out.push_back(static_cast<char>(header_len >> 8));
    out += dict;
    // rows x columns values whatever `values` holds (zeros past its end): the file is
    // always what its header says.
    const size_t cells = static_cast<size_t>(std::max(rows, 0)) * static_cast<size_t>(std::max(columns, 0));
    const size_t n = std::min(values.size(), cells);
    const size_t at = out.size();
    out.resize(at + cells * sizeof(float), '\0');
    if (n) std::memcpy(out.data() + at, values.data(), n * sizeof(float));
    return out;
}

}  // namespace mr
