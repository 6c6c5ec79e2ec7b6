// PNG encoding (stb_image_write) and image loading (stb_image) for frames, screenshots,
// terrain textures and golden images.
#include <metariver/io.h>
#include <metariver/render.h>

#include <fmt/format.h>
#include <stb_image.h>
#include <stb_image_write.h>

#include <cstring>
#include <filesystem>
#include <string_view>

namespace mr::render {

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

Result<Image> load_image(const std::string& path, int channels) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))  // a FIFO or a device would block or never end
        return Error{fmt::format("{}: not a regular file", path)};
    if (std::filesystem::file_size(path, ec) > (uintmax_t{512} << 20))
        return Error{fmt::format("{}: larger than 512 MiB", path)};
    int w = 0, h = 0, n = 0;
    stbi_uc* data = stbi_load(path.c_str(), &w, &h, &n, channels);
    if (!data) {
        const char* why = stbi_failure_reason();
        return Error{fmt::format("{}: cannot read image ({})", path, why ? why : "unknown error")};
    }
    Image img;
    img.width = w;
    img.height = h;
    img.channels = channels;
    img.pixels.assign(data, data + static_cast<size_t>(w) * h * channels);
    stbi_image_free(data);
    return img;
}

}  // namespace mr::render
