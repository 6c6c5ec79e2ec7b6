// libFuzzer target: the PNG heightmap loader (mr::load_heightmap_png_memory), the code
// `--heightmap` and terrain.heightmap run on every file.
//
// Each input is loaded twice: as it is, and with every chunk's CRC recomputed, so that
// mutations get past the loader's CRC check into the decoder (stb_image, compiled into
// the fuzz build with the same instrumentation). A loaded map must be 2..kMaxHeightmapSide
// samples a side, hold width x height samples, and every sample must be in [0, 1].
#include <metariver/terrain.h>

#include "png_crc.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

namespace {

void check(std::span<const uint8_t> bytes) {
    auto map = mr::load_heightmap_png_memory(bytes, "fuzz.png");
    if (!map) {
        if (map.error().message.empty()) std::abort();  // every error says what is wrong
        return;
    }
    const mr::Heightmap& m = map.value();
    if (m.width < 2 || m.height < 2 || m.width > mr::kMaxHeightmapSide || m.height > mr::kMaxHeightmapSide) std::abort();
    if (m.samples.size() != static_cast<size_t>(m.width) * static_cast<size_t>(m.height)) std::abort();
    if (m.bit_depth != 8 && m.bit_depth != 16) std::abort();
    for (float v : m.samples)
        if (!(v >= 0.0f && v <= 1.0f)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    check({data, size});
    const std::vector<uint8_t> fixed = mr::fuzz::with_fixed_crcs(data, size);
    if (!std::equal(fixed.begin(), fixed.end(), data)) check(fixed);
    return 0;
}
