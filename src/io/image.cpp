// PNG encoding (stb_image_write) and image loading (stb_image) for frames, screenshots,
// terrain textures and golden images.
#include <metariver/io.h>
#include <metariver/terrain.h>

#include <fmt/format.h>
#include <stb_image.h>
#include <stb_image_write.h>
#include <turbojpeg.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string_view>

namespace mr {

namespace {

/// JPEGs are decoded by libjpeg-turbo (its TurboJPEG API), not by stb_image: Debian 12's
/// stb_image JPEG decoder trusts the file in ways fuzz/image_fuzz.cpp found three times
/// (Huffman code counts past its arrays, scans using undefined tables, a bit buffer that
/// shifts by 32 once a marker cuts the entropy-coded data short; all fixed only in later
/// stb). libjpeg-turbo validates what it reads and is fuzzed upstream (OSS-Fuzz).
/// TJFLAG_LIMITSCANS refuses progressive files with more than 500 scans, which would
/// otherwise take minutes for a few kilobytes. A warning (corrupt data that still
/// decoded, e.g. a premature end) keeps the image, as image viewers do; an error does not.
Result<Image> decode_jpeg(std::span<const uint8_t> bytes, const std::string& name, int channels,
                          int64_t max_pixels) {
    std::unique_ptr<void, int (*)(tjhandle)> tj(tjInitDecompress(), tjDestroy);
    if (!tj) return Error{fmt::format("{}: cannot start the JPEG decoder", name)};
    const auto fail = [&] {
        return Error{fmt::format("{}: cannot read image (corrupt JPEG: {})", name, tjGetErrorStr2(tj.get()))};
    };
    int w = 0, h = 0, subsampling = 0, colorspace = 0;
    if (tjDecompressHeader3(tj.get(), bytes.data(), static_cast<unsigned long>(bytes.size()), &w, &h, &subsampling,
                            &colorspace) != 0)
        return fail();
    if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide || int64_t{w} * h > max_pixels)
        return Error{fmt::format("{}: image is {} x {}; at most {} pixels a side and {} pixels in all", name, w, h,
                                 kMaxImageSide, max_pixels)};
    // TurboJPEG has no grey + alpha format: two channels decode as grey and gain alpha.
    const int format = channels <= 2 ? TJPF_GRAY : channels == 3 ? TJPF_RGB : TJPF_RGBA;
    const int decoded = channels <= 2 ? 1 : channels;
    std::vector<uint8_t> pixels(static_cast<size_t>(w) * static_cast<size_t>(h) * static_cast<size_t>(decoded));
    if (tjDecompress2(tj.get(), bytes.data(), static_cast<unsigned long>(bytes.size()), pixels.data(), w,
                      w * decoded, h, format, TJFLAG_LIMITSCANS) != 0 &&
        tjGetErrorCode(tj.get()) != TJERR_WARNING)
        return fail();
    Image img;
    img.width = w;
    img.height = h;
    img.channels = channels;
    if (channels == 2) {
        img.pixels.resize(pixels.size() * 2);
        for (size_t i = 0; i < pixels.size(); ++i) {
            img.pixels[2 * i] = pixels[i];
            img.pixels[2 * i + 1] = 255;
        }
    } else {
        img.pixels = std::move(pixels);
    }
    return img;
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
    if (bytes.size() > static_cast<size_t>(INT_MAX)) return Error{fmt::format("{}: larger than 2 GiB", name)};
    if (jpeg) return decode_jpeg(bytes, name, channels, max_pixels);
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

}  // namespace mr
