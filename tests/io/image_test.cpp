// The image loader behind --texture and the golden images (issue 13): PNG and JPEG
// only, the size read from the header and checked before anything is decoded, and the
// same PNG writer/reader round trip the frames use.
#include <metariver/io.h>

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

using mr::load_image;
using mr::load_image_memory;

std::vector<uint8_t> gradient_png(int w, int h) {
    std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3);
    for (size_t k = 0; k < rgb.size(); ++k) rgb[k] = static_cast<uint8_t>(k * 7);
    return mr::encode_png(rgb, w, h, 3);
}

/// The PNG with its IHDR width replaced (and the CRC made to match): the size check must
/// come before any decoding.
uint32_t png_crc(const uint8_t* data, size_t n) {
    uint32_t crc = 0xffffffffu;
    for (size_t i = 0; i < n; ++i) {
        crc ^= data[i];
        for (int k = 0; k < 8; ++k) crc = (crc & 1u) ? 0xedb88320u ^ (crc >> 1) : crc >> 1;
    }
    return crc ^ 0xffffffffu;
}

std::vector<uint8_t> with_width(std::vector<uint8_t> png, uint32_t width) {
    png[16] = uint8_t(width >> 24);
    png[17] = uint8_t(width >> 16);
    png[18] = uint8_t(width >> 8);
    png[19] = uint8_t(width);
    // The IHDR's CRC again (bytes 12..28 are its type and data): a header that only
    // lies about the size, not a corrupt file.
    const uint32_t crc = png_crc(png.data() + 12, 17);
    for (int b = 0; b < 4; ++b) png[29 + b] = uint8_t(crc >> (24 - 8 * b));
    return png;
}

TEST(ImageLoader, PngRoundTripsInEveryChannelCount) {
    const std::vector<uint8_t> png = gradient_png(5, 3);
    for (int channels = 1; channels <= 4; ++channels) {
        auto img = load_image_memory(png, "g.png", channels);
        ASSERT_TRUE(img.ok()) << img.error().message;
        EXPECT_EQ(img->width, 5);
        EXPECT_EQ(img->height, 3);
        EXPECT_EQ(img->channels, channels);
        EXPECT_EQ(img->pixels.size(), size_t(5 * 3 * channels));
    }
    auto rgb = load_image_memory(png, "g.png", 3);
    ASSERT_TRUE(rgb.ok());
    for (size_t k = 0; k < rgb->pixels.size(); ++k) ASSERT_EQ(rgb->pixels[k], uint8_t(k * 7)) << k;
}

TEST(ImageLoader, OnlyPngAndJpegAreRead) {
    // A valid 1x1 BMP and GIF header: stb_image would decode them; the loader refuses
    // every format but the two the docs name.
    const std::vector<uint8_t> bmp = {'B', 'M', 58, 0, 0, 0, 0, 0, 0, 0, 54, 0, 0, 0, 40, 0, 0, 0, 1, 0, 0, 0, 1, 0,
                                      0, 0, 1, 0, 24, 0, 0, 0, 0, 0, 4, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                                      0, 0, 0, 0, 255, 0, 0, 0};
    const std::vector<uint8_t> gif = {'G', 'I', 'F', '8', '9', 'a', 1, 0, 1, 0, 0, 0, 0, ',', 0, 0, 0, 0,
                                      1, 0, 1, 0, 0, 2, 2, 'D', 1, 0, ';'};
    for (const auto& bytes : {bmp, gif, std::vector<uint8_t>{}, std::vector<uint8_t>{0xff, 0xd8}}) {
        auto img = load_image_memory(bytes, "t.img", 4);
        ASSERT_FALSE(img.ok());
        EXPECT_EQ(img.error().message, "t.img: not a PNG or JPEG image");
    }
}

TEST(ImageLoader, TheSizeIsCheckedBeforeDecoding) {
    const std::vector<uint8_t> png = gradient_png(4, 4);
    auto wide = load_image_memory(with_width(png, 20000), "wide.png", 4);
    ASSERT_FALSE(wide.ok());
    EXPECT_NE(wide.error().message.find("wide.png: image is 20000 x 4"), std::string::npos) << wide.error().message;
    // A pixel budget below the image's: refused, naming it.
    auto big = load_image_memory(gradient_png(100, 100), "big.png", 4, 5000);
    ASSERT_FALSE(big.ok());
    EXPECT_NE(big.error().message.find("5000 pixels in all"), std::string::npos) << big.error().message;
    EXPECT_TRUE(load_image_memory(gradient_png(100, 50), "ok.png", 4, 5000).ok());
}

TEST(ImageLoader, APngChunkLongerThanTheFileIsRefusedBeforeDecoding) {
    // Found by fuzz/image_fuzz.cpp: stb_image grew its buffer to what an IDAT chunk's
    // length field claimed (2 GiB for a 150-byte file) before reading the chunk. The
    // loader checks the chunk structure first, as the heightmap loader does.
    std::vector<uint8_t> png = gradient_png(4, 4);
    const size_t idat = 33;  // after the signature (8) and IHDR (25)
    ASSERT_EQ(std::string(png.begin() + idat + 4, png.begin() + idat + 8), "IDAT");
    png[idat] = 0x7f;
    png[idat + 1] = 0xff;
    png[idat + 2] = 0xff;
    png[idat + 3] = 0xf0;
    auto img = load_image_memory(png, "long.png", 4);
    ASSERT_FALSE(img.ok());
    EXPECT_EQ(img.error().message, "long.png: truncated PNG (chunk IDAT is cut short)");
}

TEST(ImageLoader, TruncatedFilesAreErrorsNamingTheFile) {
    const std::vector<uint8_t> png = gradient_png(16, 16);
    for (size_t n : {size_t(8), size_t(20), size_t(33), png.size() / 2, png.size() - 13}) {
        const std::vector<uint8_t> cut(png.begin(), png.begin() + static_cast<std::ptrdiff_t>(n));
        auto img = load_image_memory(cut, "cut.png", 3);
        ASSERT_FALSE(img.ok()) << n << " bytes";
        EXPECT_EQ(img.error().message.rfind("cut.png: ", 0), 0u) << img.error().message;
    }
}

std::vector<uint8_t> corpus_file(const char* name) {
    // The fuzz seed corpus (fuzz/corpus/image/): the first byte picks the fuzzer's channel
    // count, the rest is the file.
    std::ifstream in(std::string(METARIVER_SOURCE_DIR) + "/fuzz/corpus/image/" + name, std::ios::binary);
    std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!b.empty()) b.erase(b.begin());
    return b;
}

// JPEGs are decoded by libjpeg-turbo (src/render/image.cpp, decode_jpeg): Debian 12's
// stb_image JPEG decoder is not compiled in (src/io/stb_impl.cpp, STBI_ONLY_PNG) after the
// fuzzer found three bugs in it. The inputs of those bugs stay here as tests.

TEST(ImageLoader, AJpegHuffmanTableWithMoreThan256CodesIsAnErrorNamingTheFile) {
    // Found by fuzz/image_fuzz.cpp in stb_image: writes past its Huffman arrays (UBSan:
    // index 257 out of bounds for stbi_uc[257]) for a DHT table whose 16 code counts add up
    // to more than 256. A real JPEG (ffmpeg's, from the fuzz corpus) still loads.
    const std::vector<uint8_t> good = corpus_file("color_8x8.jpg");
    ASSERT_GT(good.size(), 100u);
    auto ok = load_image_memory(good, "good.jpg", 3);
    ASSERT_TRUE(ok.ok()) << ok.error().message;
    EXPECT_EQ(ok->width, 8);
    // SOI, then a DHT segment: class 0 table 0, counts 16 x 255 (4080 codes).
    std::vector<uint8_t> bad = {0xff, 0xd8, 0xff, 0xc4, 0x00, 0x13, 0x00};
    for (int i = 0; i < 16; ++i) bad.push_back(0xff);
    auto img = load_image_memory(bad, "bad.jpg", 3);
    ASSERT_FALSE(img.ok());
    EXPECT_EQ(img.error().message, "bad.jpg: cannot read image (corrupt JPEG: Bogus Huffman table definition)");
    // The same table after a valid one, and inside a JPEG that is otherwise fine: the
    // fuzzer's input was a real file with its second table's counts changed.
    std::vector<uint8_t> spliced = good;
    bool found = false;
    for (size_t i = 2; i + 4 < spliced.size() && !found; ++i)
        if (spliced[i] == 0xff && spliced[i + 1] == 0xc4) {
            for (size_t k = 0; k < 16; ++k) spliced[i + 5 + k] = 0x40;  // 16 x 64 = 1024 codes
            found = true;
        }
    ASSERT_TRUE(found);
    auto spliced_img = load_image_memory(spliced, "spliced.jpg", 3);
    ASSERT_FALSE(spliced_img.ok());
    EXPECT_EQ(spliced_img.error().message,
              "spliced.jpg: cannot read image (corrupt JPEG: Bogus Huffman table definition)");
}

TEST(ImageLoader, AScanWithoutHuffmanTablesUsesTheStandardOnesAndProgressiveJpegsStillLoad) {
    // Found by fuzz/image_fuzz.cpp in stb_image: a scan using a Huffman table no DHT segment
    // defined made stb decode with uninitialised memory (an index of 1061349242 into a
    // 256-entry table). libjpeg-turbo decodes such a scan with the standard tables of the
    // JPEG specification (Annex K), as Motion-JPEG frames need. Progressive files define
    // their tables scan by scan; they must load.
    for (const char* name : {"progressive_color_16x9.jpg", "progressive_gray_7x5.jpg", "color_16x9.jpg"}) {
        const std::vector<uint8_t> good = corpus_file(name);
        ASSERT_GT(good.size(), 100u) << name;
        auto img = load_image_memory(good, name, 4);
        ASSERT_TRUE(img.ok()) << img.error().message;
        EXPECT_GT(img->width, 1) << name;
    }
    // The sequential file with its DHT markers renamed to COM (skipped): no table defined.
    std::vector<uint8_t> bad = corpus_file("color_16x9.jpg");
    size_t renamed = 0;
    for (size_t i = 2; i + 1 < bad.size(); ++i)
        if (bad[i] == 0xff && bad[i + 1] == 0xc4) {
            bad[i + 1] = 0xfe;
            ++renamed;
        }
    ASSERT_GT(renamed, 0u);
    auto img = load_image_memory(bad, "bad.jpg", 3);
    ASSERT_TRUE(img.ok()) << img.error().message;
    EXPECT_EQ(img->width, 16);
    EXPECT_EQ(img->height, 9);
    EXPECT_EQ(img->pixels.size(), 16u * 9u * 3u);
}

TEST(ImageLoader, MarkersAndCutsInsideTheScanDataGiveAnImageOrAnErrorNamingTheFile) {
    // Found by fuzz/image_fuzz.cpp in stb_image (CI, stop 22): a marker cutting the
    // entropy-coded data short left its bit count negative, and the next read shifted an
    // unsigned int by 32 (UBSan, stb_image.h:2065). Every such file here: a marker (restart,
    // end of image, DHT, comment, APP1) written over each byte after the first scan header of
    // the corpus's five JPEGs, and each file cut at each of those bytes (7,734 files). libjpeg-turbo
    // reports most as warnings and keeps what it decoded (an image of the full size) or
    // refuses them; the sanitizer build checks that nothing reads out of bounds.
    size_t images = 0, errors = 0;
    for (const char* name : {"color_16x9.jpg", "color_8x8.jpg", "gray_7x5.jpg", "progressive_color_16x9.jpg",
                             "progressive_gray_7x5.jpg"}) {
        const std::vector<uint8_t> good = corpus_file(name);
        ASSERT_GT(good.size(), 100u) << name;
        auto reference = load_image_memory(good, name, 3);
        ASSERT_TRUE(reference.ok()) << reference.error().message;
        size_t scan = 0;
        for (size_t i = 2; i + 3 < good.size() && scan == 0; ++i)
            if (good[i] == 0xff && good[i + 1] == 0xda) scan = i + 2 + size_t((good[i + 2] << 8) | good[i + 3]);
        ASSERT_GT(scan, 0u) << name;
        auto check = [&](const std::vector<uint8_t>& bytes, size_t at) {
            auto img = load_image_memory(bytes, "mutant.jpg", 3);
            if (img.ok()) {
                ++images;
                EXPECT_EQ(img->width, reference->width) << name << " at " << at;
                EXPECT_EQ(img->height, reference->height) << name << " at " << at;
                EXPECT_EQ(img->pixels.size(), reference->pixels.size()) << name << " at " << at;
            } else {
                ++errors;
                EXPECT_EQ(img.error().message.rfind("mutant.jpg: ", 0), 0u) << img.error().message;
            }
        };
        for (size_t p = scan; p + 2 < good.size(); ++p) {
            for (uint8_t marker : {uint8_t{0xd0}, uint8_t{0xd9}, uint8_t{0xc4}, uint8_t{0xfe}, uint8_t{0xe1}}) {
                std::vector<uint8_t> bytes = good;
                bytes[p] = 0xff;
                bytes[p + 1] = marker;
                check(bytes, p);
            }
            check(std::vector<uint8_t>(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(p)), p);
        }
    }
    EXPECT_GT(images, 0u);  // damaged files that still decode are kept, as viewers keep them
    EXPECT_GT(errors, 0u);
}

TEST(ImageLoader, FilesGoThroughTheSameChecks) {
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("metariver_image_test_" + std::to_string(::getpid()) + ".bmp")).string();
    std::ofstream(path, std::ios::binary) << "BM not really";
    auto img = load_image(path, 4);
    ASSERT_FALSE(img.ok());
    EXPECT_EQ(img.error().message, path + ": not a PNG or JPEG image");
    std::filesystem::remove(path);
    auto dir = load_image(std::filesystem::temp_directory_path().string(), 4);
    ASSERT_FALSE(dir.ok());
    EXPECT_NE(dir.error().message.find("not a regular file"), std::string::npos);
}

}  // namespace
