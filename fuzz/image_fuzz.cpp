// libFuzzer target: the image loader (mr::load_image_memory) behind `--texture`
// and the golden-image tests: PNG or JPEG, everything else refused.
//
// The first byte picks the channel count (1 to 4, as load_image's callers ask 3 or 4);
// the rest is the file, loaded as it is and, when its chunk CRCs were wrong, with them
// recomputed (png_crc.h), so mutations of a PNG reach the decoder. The pixel limit is 2^20 here instead of kMaxImagePixels, so the
// fuzzer spends its time in the decoders rather than on decoding a few huge (accepted)
// images; the limit itself is tested in tests/io/image_test.cpp. A decoded image
// must be at least 1 x 1, within the limits, and hold width x height x channels bytes.
#include <metariver/io.h>

#include "png_crc.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

namespace {

constexpr int64_t kFuzzMaxPixels = int64_t{1} << 20;

void check(std::span<const uint8_t> bytes, int channels) {
    auto img = mr::load_image_memory(bytes, "fuzz.img", channels, kFuzzMaxPixels);
    if (!img) {
        if (img.error().message.empty()) std::abort();
        return;
    }
    const mr::Image& m = img.value();
    if (m.width < 1 || m.height < 1 || int64_t{m.width} * m.height > kFuzzMaxPixels) std::abort();
    if (m.channels != channels) std::abort();
    if (m.pixels.size() != static_cast<size_t>(m.width) * static_cast<size_t>(m.height) * static_cast<size_t>(channels))
        std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    const int channels = 1 + data[0] % 4;
    check({data + 1, size - 1}, channels);
    const std::vector<uint8_t> fixed = mr::fuzz::with_fixed_crcs(data + 1, size - 1);
    if (!std::equal(fixed.begin(), fixed.end(), data + 1)) check(fixed, channels);
    return 0;
}
