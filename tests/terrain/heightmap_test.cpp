// Heightmap loading (PNG, 8/16-bit, every colour type), its errors, and the
// procedural generators.
#include <metariver/terrain.h>

#include <gtest/gtest.h>
#include <png_test_util.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include "require.h"

namespace mr {
namespace {

const std::string kPaperDir = METARIVER_SHARED_DIR "/heightmaps/metawater/";

#define SKIP_WITHOUT_PAPER_MAPS()                                                      \
    do {                                                                               \
        if (!std::filesystem::is_directory(kPaperDir)) MR_SKIP_OR_FAIL("no " << kPaperDir); \
    } while (0)

std::vector<uint8_t> read_file(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

/// Asserts that r failed and that its one-line message names `name` and contains `what`.
void expect_error(const Result<Heightmap>& r, const std::string& name, const std::string& what) {
    ASSERT_FALSE(r.ok()) << "expected an error for " << name;
    const std::string& m = r.error().message;
    EXPECT_NE(m.find(name), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
}

// --- the paper's heightmaps -------------------------------------------------------

TEST(PaperHeightmaps, SizesAndKnownValues) {
    SKIP_WITHOUT_PAPER_MAPS();
    struct Expect {
        const char* file;
        int size;
    };
    for (const Expect e : {Expect{"strict17.png", 17}, Expect{"strict.png", 33}, Expect{"nile.png", 33},
                           Expect{"bowl.png", 33}, Expect{"small.png", 33}, Expect{"flat0.png", 33}}) {
        SCOPED_TRACE(e.file);
        auto map = load_heightmap_png(kPaperDir + e.file);
        ASSERT_TRUE(map.ok()) << map.error().message;
        EXPECT_EQ(map->width, e.size);
        EXPECT_EQ(map->height, e.size);
        EXPECT_EQ(map->bit_depth, 8);
        ASSERT_EQ(map->samples.size(), static_cast<size_t>(e.size * e.size));
        for (float v : map->samples) {
            ASSERT_GE(v, 0.0f);
            ASSERT_LE(v, 1.0f);
        }
    }
    auto flat = load_heightmap_png(kPaperDir + "flat0.png");
    ASSERT_TRUE(flat.ok());
    EXPECT_TRUE(std::all_of(flat->samples.begin(), flat->samples.end(), [](float v) { return v == 0.0f; }));

    // Red-channel values read from the files with an independent decoder.
    auto strict17 = load_heightmap_png(kPaperDir + "strict17.png");
    ASSERT_TRUE(strict17.ok());
    EXPECT_EQ(strict17->at(0, 0), 252.0f / 255.0f);
    EXPECT_EQ(strict17->at(0, 7), 232.0f / 255.0f);  // the darker middle strip
    EXPECT_EQ(strict17->at(16, 0), 36.0f / 255.0f);
    EXPECT_EQ(strict17->at(16, 16), 37.0f / 255.0f);

    auto bowl = load_heightmap_png(kPaperDir + "bowl.png");
    ASSERT_TRUE(bowl.ok());
    EXPECT_EQ(bowl->at(15, 15), 5.0f / 255.0f);
    EXPECT_EQ(bowl->at(0, 0), 1.0f);

    auto small = load_heightmap_png(kPaperDir + "small.png");  // gray
    ASSERT_TRUE(small.ok());
    EXPECT_EQ(small->at(0, 0), 126.0f / 255.0f);
    EXPECT_EQ(small->at(0, 32), 119.0f / 255.0f);

    auto nile = load_heightmap_png(kPaperDir + "nile.png");  // RGBA, not gray: red is used
    ASSERT_TRUE(nile.ok());
    EXPECT_EQ(nile->at(0, 0), 180.0f / 255.0f);
    EXPECT_EQ(nile->at(32, 19), 0.0f);
}

TEST(PaperHeightmaps, MemoryAndFileLoadersAgree) {
    SKIP_WITHOUT_PAPER_MAPS();
    const std::string path = kPaperDir + "nile.png";
    auto a = load_heightmap_png(path);
    auto b = load_heightmap_png_memory(read_file(path), "nile.png");
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->samples, b->samples);
}

TEST(PaperHeightmaps, EveryPrefixIsAnError) {
    SKIP_WITHOUT_PAPER_MAPS();
    const std::vector<uint8_t> bytes = read_file(kPaperDir + "strict17.png");
    ASSERT_GT(bytes.size(), 100u);
    for (size_t n = 0; n < bytes.size(); ++n) {
        auto r = load_heightmap_png_memory(std::span(bytes.data(), n), "cut.png");
        ASSERT_FALSE(r.ok()) << "prefix of " << n << " bytes loaded";
        ASSERT_EQ(r.error().message.rfind("cut.png: ", 0), 0u) << r.error().message;
    }
    EXPECT_TRUE(load_heightmap_png_memory(bytes, "whole.png").ok());
}

// --- written PNGs -------------------------------------------------------------------

TEST(HeightmapPng, EightBitColourTypesUseRedOrGray) {
    test::TempDir dir;
    const int w = 5, h = 3;  // non-square on purpose
    for (int channels = 1; channels <= 4; ++channels) {
        SCOPED_TRACE(channels);
        std::vector<uint8_t> px(static_cast<size_t>(w * h * channels));
        for (int r = 0; r < h; ++r) {
            for (int c = 0; c < w; ++c) {
                uint8_t* p = &px[static_cast<size_t>((r * w + c) * channels)];
                p[0] = static_cast<uint8_t>(r * 80 + c * 17);  // the height
                for (int k = 1; k < channels; ++k) p[k] = static_cast<uint8_t>(255 - p[0] / k);  // distractors
            }
        }
        const std::string path = dir.write("c" + std::to_string(channels) + ".png", test::encode_png8(w, h, channels, px));
        auto map = load_heightmap_png(path);
        ASSERT_TRUE(map.ok()) << map.error().message;
        EXPECT_EQ(map->width, w);
        EXPECT_EQ(map->height, h);
        EXPECT_EQ(map->bit_depth, 8);
        for (int r = 0; r < h; ++r) {
            for (int c = 0; c < w; ++c) {
                EXPECT_EQ(map->at(r, c), static_cast<float>(r * 80 + c * 17) / 255.0f) << r << "," << c;
            }
        }
    }
}

TEST(HeightmapPng, SixteenBitKeepsFullPrecision) {
    const int w = 4, h = 2;
    const std::vector<uint16_t> gray = {0, 1, 32768, 65535, 257, 65534, 12345, 2};
    for (int channels = 1; channels <= 4; ++channels) {
        SCOPED_TRACE(channels);
        std::vector<uint16_t> px(static_cast<size_t>(w * h * channels));
        for (size_t k = 0; k < gray.size(); ++k) {
            px[k * channels] = gray[k];
            for (int c = 1; c < channels; ++c) px[k * channels + c] = static_cast<uint16_t>(65535 - gray[k] / 3);
        }
        auto map = load_heightmap_png_memory(test::encode_png_raw(w, h, channels, 16, px), "deep.png");
        ASSERT_TRUE(map.ok()) << map.error().message;
        EXPECT_EQ(map->bit_depth, 16);
        ASSERT_EQ(map->width, w);
        ASSERT_EQ(map->height, h);
        for (size_t k = 0; k < gray.size(); ++k) {
            EXPECT_EQ(map->samples[k], static_cast<float>(gray[k]) / 65535.0f) << k;
        }
        // 1/65535 is below 8-bit resolution: it must not collapse to 0.
        EXPECT_GT(map->samples[1], 0.0f);
        EXPECT_LT(map->samples[1], 1.0f / 255.0f);
    }
}

TEST(HeightmapPng, HandEncoderEightBitMatchesStb) {
    // The hand-written encoder is also used for malformed files below; check it on 8 bit.
    const std::vector<uint16_t> px = {0, 10, 20, 30, 40, 50};
    auto map = load_heightmap_png_memory(test::encode_png_raw(3, 2, 1, 8, px), "hand.png");
    ASSERT_TRUE(map.ok()) << map.error().message;
    EXPECT_EQ(map->width, 3);
    EXPECT_EQ(map->height, 2);
    EXPECT_EQ(map->at(1, 2), 50.0f / 255.0f);
}

TEST(HeightmapPng, LargeSixteenBitImage) {
    // More than one stored deflate block (> 65535 bytes of scanlines).
    const int w = 300, h = 200;
    std::vector<uint16_t> px(static_cast<size_t>(w * h));
    for (size_t k = 0; k < px.size(); ++k) px[k] = static_cast<uint16_t>(k * 7919u);
    auto map = load_heightmap_png_memory(test::encode_png_raw(w, h, 1, 16, px), "big.png");
    ASSERT_TRUE(map.ok()) << map.error().message;
    for (size_t k = 0; k < px.size(); k += 97) EXPECT_EQ(map->samples[k], px[k] / 65535.0f);
}

// --- errors ---------------------------------------------------------------------------

TEST(HeightmapErrors, MissingFile) {
    test::TempDir dir;
    const std::string path = dir.file("nope.png");
    expect_error(load_heightmap_png(path), path, "no such file");
}

TEST(HeightmapErrors, EmptyFile) {
    test::TempDir dir;
    const std::string path = dir.write("empty.png", {});
    expect_error(load_heightmap_png(path), path, "empty");
}

TEST(HeightmapErrors, TextFile) {
    test::TempDir dir;
    const std::string text = "height,width\n1,2\n";
    const std::string path = dir.write("notes.png", std::vector<uint8_t>(text.begin(), text.end()));
    expect_error(load_heightmap_png(path), path, "not a PNG");
}

TEST(HeightmapErrors, Directory) {
    test::TempDir dir;
    std::filesystem::create_directories(dir.file("folder.png"));
    expect_error(load_heightmap_png(dir.file("folder.png")), "folder.png", "directory");
}

TEST(HeightmapErrors, TruncatedFile) {
    test::TempDir dir;
    const auto bytes = test::encode_png8(4, 4, 1, std::vector<uint8_t>(16, 7));
    for (size_t n : {size_t{8}, size_t{20}, bytes.size() / 2, bytes.size() - 1}) {
        const std::string path = dir.write("cut" + std::to_string(n) + ".png", {bytes.begin(), bytes.begin() + n});
        expect_error(load_heightmap_png(path), path, "truncated");
    }
}

TEST(HeightmapErrors, TooSmall) {
    test::TempDir dir;
    const std::string path = dir.write("dot.png", test::encode_png8(1, 1, 1, {9}));
    expect_error(load_heightmap_png(path), path, "1 x 1");
    expect_error(load_heightmap_png(path), path, "minimum is 2 x 2");
    expect_error(load_heightmap_png_memory(test::encode_png8(7, 1, 3, std::vector<uint8_t>(21, 1)), "row.png"),
                 "row.png", "7 x 1");
}

TEST(HeightmapErrors, TooLarge) {
    // Only IHDR claims the size; rejected before decoding anything.
    const int side = kMaxHeightmapSide + 1;
    auto bytes = test::encode_png_raw(2, 2, 1, 8, {1, 2, 3, 4}, side, 2);
    expect_error(load_heightmap_png_memory(bytes, "huge.png"), "huge.png", "maximum");
    expect_error(load_heightmap_png_memory(test::encode_png_raw(2, 2, 1, 8, {1, 2, 3, 4}, 2, 0x7fffffff), "tall.png"),
                 "tall.png", "maximum");
}

TEST(HeightmapErrors, CorruptCrcAndData) {
    auto bytes = test::encode_png_raw(3, 3, 1, 8, std::vector<uint16_t>(9, 5));
    auto bad_crc = bytes;
    bad_crc[29] ^= 0x01u;  // last byte of IHDR's CRC (8 signature + 8 header + 13 data)
    expect_error(load_heightmap_png_memory(bad_crc, "crc.png"), "crc.png", "CRC");

    // IHDR says 3 x 3 but IDAT holds 2 x 2 worth of scanlines: stb must report it.
    auto short_data = test::encode_png_raw(2, 2, 1, 8, {1, 2, 3, 4}, 3, 3);
    expect_error(load_heightmap_png_memory(short_data, "short.png"), "short.png", "short.png: ");
}

TEST(HeightmapErrors, AnEmptyIdatBeforeTheImageDataIsRefusedBeforeStbReadsIt) {
    // stb_image memcpy'd a first, empty IDAT chunk to its null buffer (undefined
    // behaviour; UBSan in the png_heightmap fuzzer). An empty IDAT after the data is fine.
    const auto good = test::encode_png_raw(3, 3, 1, 8, std::vector<uint16_t>(9, 5));
    const std::vector<uint8_t> empty_idat{0, 0, 0, 0, 'I', 'D', 'A', 'T', 0x35, 0xaf, 0x06, 0x1e};
    auto before = good;
    before.insert(before.begin() + 33, empty_idat.begin(), empty_idat.end());  // after IHDR (8 + 25)
    expect_error(load_heightmap_png_memory(before, "empty_idat.png"), "empty_idat.png", "empty IDAT");
    auto after = good;
    after.insert(after.end() - 12, empty_idat.begin(), empty_idat.end());  // before IEND
    EXPECT_TRUE(load_heightmap_png_memory(after, "late_empty_idat.png").ok());
}

TEST(HeightmapErrors, RandomCorruptionNeverCrashes) {
    // Flip random bytes of a valid file; the loader must return (ok or a named error).
    const auto base = test::encode_png8(6, 5, 4, std::vector<uint8_t>(120, 99));
    Lcg rng(7);
    int errors = 0;
    for (int round = 0; round < 3000; ++round) {
        auto bytes = base;
        const int flips = 1 + static_cast<int>(rng.next_u32() % 4);
        for (int k = 0; k < flips; ++k) bytes[rng.next_u32() % bytes.size()] = static_cast<uint8_t>(rng.next_u32());
        auto r = load_heightmap_png_memory(bytes, "fuzz.png");
        if (!r.ok()) {
            ++errors;
            ASSERT_EQ(r.error().message.rfind("fuzz.png: ", 0), 0u) << r.error().message;
        } else {
            ASSERT_EQ(r->samples.size(), static_cast<size_t>(r->width) * r->height);
        }
    }
    EXPECT_GT(errors, 0);
    // Random garbage with a valid signature.
    for (int round = 0; round < 500; ++round) {
        std::vector<uint8_t> bytes = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
        const size_t n = rng.next_u32() % 200;
        for (size_t k = 0; k < n; ++k) bytes.push_back(static_cast<uint8_t>(rng.next_u32()));
        auto r = load_heightmap_png_memory(bytes, "noise.png");
        ASSERT_FALSE(r.ok());
    }
}

// --- procedural -------------------------------------------------------------------------

void expect_normalised(const Heightmap& m, int w, int h) {
    EXPECT_EQ(m.width, w);
    EXPECT_EQ(m.height, h);
    EXPECT_EQ(m.bit_depth, 32);
    ASSERT_EQ(m.samples.size(), static_cast<size_t>(w) * h);
    for (float v : m.samples) {
        ASSERT_TRUE(std::isfinite(v));
        ASSERT_GE(v, 0.0f);
        ASSERT_LE(v, 1.0f);
    }
}

TEST(Procedural, AllSizesNormalised) {
    for (auto [w, h] : {std::pair{2, 2}, std::pair{3, 7}, std::pair{17, 17}, std::pair{129, 129}, std::pair{50, 31}}) {
        SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
        expect_normalised(procedural_valley(w, h, 1), w, h);
        expect_normalised(procedural_strict(w, h), w, h);
        expect_normalised(procedural_bowl(w, h), w, h);
    }
}

TEST(Procedural, ValleyIsDeterministicPerSeed) {
    EXPECT_EQ(procedural_valley(65, 40, 3).samples, procedural_valley(65, 40, 3).samples);
    EXPECT_NE(procedural_valley(65, 40, 3).samples, procedural_valley(65, 40, 4).samples);
}

TEST(Procedural, ValleyChannelRunsDownhillAndIsDeep) {
    for (uint32_t seed : {1u, 2u, 99u}) {
        SCOPED_TRACE(seed);
        const int w = 129, h = 129;
        const Heightmap m = procedural_valley(w, h, seed);
        std::vector<float> row_min(h);
        std::vector<int> row_argmin(h);
        for (int r = 0; r < h; ++r) {
            const auto begin = m.samples.begin() + static_cast<std::ptrdiff_t>(r) * w;
            const auto it = std::min_element(begin, begin + w);
            row_min[r] = *it;
            row_argmin[r] = static_cast<int>(it - begin);
        }
        // The bed falls from image row 0 (high) to the last row (low) ...
        EXPECT_GT(row_min.front() - row_min.back(), 0.3f);
        for (int r = 1; r < h; ++r) {
            // ... nearly monotonically: sampling the channel's Gaussian cross-section at
            // a varying offset from its centre moves the row minimum by < 0.02.
            EXPECT_LT(row_min[r] - row_min[r - 1], 0.02f) << "row " << r;
        }
        // It meanders: the channel's column moves by several samples.
        const auto [lo, hi] = std::minmax_element(row_argmin.begin(), row_argmin.end());
        EXPECT_GT(*hi - *lo, 10);
        // Valley walls: the outer columns are higher than the channel on every row.
        // The channel is well below its banks 8 samples to each side.
        for (int r = 0; r < h; r += 8) {
            const int c = row_argmin[r];
            EXPECT_GT(m.at(r, 0), row_min[r] + 0.2f);
            EXPECT_GT(m.at(r, w - 1), row_min[r] + 0.2f);
            EXPECT_GT(m.at(r, std::max(c - 8, 0)), row_min[r] + 0.05f) << "row " << r;
            EXPECT_GT(m.at(r, std::min(c + 8, w - 1)), row_min[r] + 0.05f) << "row " << r;
        }
    }
}

TEST(Procedural, StrictMatchesPaperImage) {
    SKIP_WITHOUT_PAPER_MAPS();
    for (const char* file : {"strict17.png", "strict.png"}) {
        SCOPED_TRACE(file);
        auto paper = load_heightmap_png(kPaperDir + file);
        ASSERT_TRUE(paper.ok());
        const Heightmap m = procedural_strict(paper->width, paper->height);
        float worst = 0.0f;
        for (size_t k = 0; k < m.samples.size(); ++k) worst = std::max(worst, std::abs(m.samples[k] - paper->samples[k]));
        // The paper's image is hand-made: slightly noisy, its strip one column off-centre
        // at 33 wide; 0.09 bounds that (the strip is only 0.08 deep).
        EXPECT_LT(worst, 0.09f);
        // Strip darker than its neighbours, top brighter than bottom.
        const int mid = m.width / 2;
        EXPECT_LT(m.at(0, mid), m.at(0, 0));
        EXPECT_GT(m.at(0, 0), m.at(m.height - 1, 0) + 0.7f);
    }
}

TEST(Procedural, BowlMatchesPaperImage) {
    SKIP_WITHOUT_PAPER_MAPS();
    auto paper = load_heightmap_png(kPaperDir + "bowl.png");
    ASSERT_TRUE(paper.ok());
    const Heightmap m = procedural_bowl(33, 33);
    double sum = 0.0;
    for (size_t k = 0; k < m.samples.size(); ++k) sum += std::abs(m.samples[k] - paper->samples[k]);
    // Same radial profile; the paper's centre is half a sample off (15.5, 15.5).
    EXPECT_LT(sum / static_cast<double>(m.samples.size()), 0.03);
    // Lowest at the centre, highest in the corners.
    const auto lowest = std::min_element(m.samples.begin(), m.samples.end()) - m.samples.begin();
    EXPECT_EQ(lowest, 16 * 33 + 16);
    EXPECT_GT(m.at(0, 0), 0.99f);
}

}  // namespace
}  // namespace mr
