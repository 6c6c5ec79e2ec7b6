// The heightmap sidecar reader behind `--real-scale` (apps/metariver/sidecar.h): the
// scales it derives and its one-line errors naming the file and the key.
#include <gtest/gtest.h>
#include "png_test_util.h"
#include "sidecar.h"

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include "require.h"

namespace {

using mr::app::parse_sidecar_scale;
using mr::app::read_sidecar_scale;
using mr::app::sidecar_path;

// alps.json of ../shared/heightmaps/real.
constexpr const char* kAlps = R"({"source": "ETOPO5", "lat": [43.5, 48.5], "lon": [5.0, 14.0],
 "width": 108, "height": 61, "metres_min": -2527.0, "metres_max": 3902.0})";

/// The error of parsing `text` as "t.json" (empty when it parses).
std::string error_of(const std::string& text) {
    auto s = parse_sidecar_scale(text, "t.json");
    return s ? std::string() : s.error().message;
}

TEST(Sidecar, PathIsTheHeightmapsWithJson) {
    EXPECT_EQ(sidecar_path("../shared/heightmaps/real/alps.png"), "../shared/heightmaps/real/alps.json");
    EXPECT_EQ(sidecar_path("maps/h.PNG"), "maps/h.json");
    EXPECT_EQ(sidecar_path("maps/h"), "maps/h.json");
}

TEST(Sidecar, ScalesFromTheLatitudeLongitudeBox) {
    auto s = parse_sidecar_scale(kAlps, "alps.json");
    ASSERT_TRUE(s) << s.error().message;
    const double dz = 5.0 * 111320.0 / 60.0;                                       // 9276.7 m
    const double dx = 9.0 * 111320.0 * std::cos(46.0 * std::numbers::pi / 180.0) / 107.0;  // 6504.3 m
    EXPECT_NEAR(s->area_scale, 0.5 * (dx + dz), 1e-6);
    EXPECT_NEAR(s->area_scale, 7890.5, 0.1);
    EXPECT_DOUBLE_EQ(s->height_scale, 3902.0 + 2527.0);
    EXPECT_EQ(s->width, 108);
    EXPECT_EQ(s->height, 61);
}

TEST(Sidecar, SampleSpacingWinsOverTheBox) {
    auto s = parse_sidecar_scale(R"({"metres_min": 10, "metres_max": 70, "sample_spacing_m": 2.5,
                                     "lat": [0, 1], "lon": [0, 1], "width": 9, "height": 7})",
                                 "s.json");
    ASSERT_TRUE(s) << s.error().message;
    EXPECT_DOUBLE_EQ(s->area_scale, 2.5);
    EXPECT_DOUBLE_EQ(s->height_scale, 60.0);
    EXPECT_EQ(s->width, 9);
    // Without a box or a size: the size is unknown (0), not an error.
    auto bare = parse_sidecar_scale(R"({"metres_min": 0, "metres_max": 5, "sample_spacing_m": 1})", "b.json");
    ASSERT_TRUE(bare) << bare.error().message;
    EXPECT_EQ(bare->width, 0);
    EXPECT_EQ(bare->height, 0);
}

TEST(Sidecar, TheRealMapsOfTheRepository) {
    const std::filesystem::path real = std::filesystem::path(METARIVER_SOURCE_DIR) / "assets/heightmaps/real";
    // The table of docs/scene-format.md, "Heightmap scale".
    const struct {
        const char* name;
        double area, height;
    } want[] = {{"alps", 7890.5, 6429}, {"andes_peru", 9238.3, 10797}, {"colorado_rockies", 8304.1, 2544},
                {"pyrenees", 8110.7, 3958}, {"western_usa", 8308.7, 8546}};
    for (const auto& w : want) {
        auto s = read_sidecar_scale((real / (std::string(w.name) + ".json")).string());
        ASSERT_TRUE(s) << s.error().message;
        EXPECT_NEAR(s->area_scale, w.area, 0.05) << w.name;
        EXPECT_DOUBLE_EQ(s->height_scale, w.height) << w.name;
    }
}

TEST(Sidecar, ErrorsNameTheFileAndTheKey) {
    const struct {
        std::string text, want;
    } cases[] = {
        {"{\"metres_min\": 0,\n \"metres_max\": ,}", "t.json: not valid JSON (line 2, column"},
        {"", "t.json: not valid JSON (line 1, column 1)"},
        {"[1, 2]", "t.json: must be a JSON object (got array)"},
        {R"({"metres_max": 5, "sample_spacing_m": 1})", "t.json: metres_min: missing"},
        {R"({"metres_min": "low", "metres_max": 5, "sample_spacing_m": 1})", "t.json: metres_min: must be a finite number"},
        {R"({"metres_min": 5, "metres_max": 5, "sample_spacing_m": 1})", "t.json: metres_max - metres_min: must be in (0, 100000]"},
        {R"({"metres_min": 9, "metres_max": 5, "sample_spacing_m": 1})", "t.json: metres_max - metres_min: must be in (0, 100000]"},
        {R"({"metres_min": -1e6, "metres_max": 1e6, "sample_spacing_m": 1})", "metres_max - metres_min: must be in (0, 100000]"},
        {R"({"metres_min": 0, "metres_max": 5, "sample_spacing_m": 0})", "t.json: sample_spacing_m: must be in (0, 10000]"},
        {R"({"metres_min": 0, "metres_max": 5, "sample_spacing_m": 2e4})", "t.json: sample_spacing_m: must be in (0, 10000]"},
        {R"({"metres_min": 0, "metres_max": 5, "sample_spacing_m": 1, "width": 1})", "t.json: width: must be an integer in [2, 4097]"},
        {R"({"metres_min": 0, "metres_max": 5, "lon": [0, 1], "width": 9, "height": 7})", "t.json: lat: missing"},
        {R"({"metres_min": 0, "metres_max": 5, "lat": [1, 0], "lon": [0, 1], "width": 9, "height": 7})",
         "t.json: lat: must be [low, high] degrees with -90 <= low < high <= 90"},
        {R"({"metres_min": 0, "metres_max": 5, "lat": [0, 1], "lon": [2], "width": 9, "height": 7})", "t.json: lon: must be [low, high]"},
        {R"({"metres_min": 0, "metres_max": 5, "lat": [0, 1], "lon": [0, 1], "height": 7})", "t.json: width: missing"},
        {R"({"metres_min": 0, "metres_max": 5, "lat": [0, 1], "lon": [0, 1], "width": 9, "height": 7.5})",
         "t.json: height: must be an integer"},
        // Ten degrees over a 3 x 3 grid: 500 km per sample, beyond terrain.area_scale's range.
        {R"({"metres_min": 0, "metres_max": 5, "lat": [0, 10], "lon": [0, 10], "width": 3, "height": 3})",
         "t.json: lat, lon: sample spacing: must be in (0, 10000]"},
    };
    for (const auto& c : cases) {
        const std::string e = error_of(c.text);
        EXPECT_NE(e.find(c.want), std::string::npos) << c.text << "\n got: '" << e << "'";
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    }
}

TEST(Sidecar, OnlyRegularFilesAreRead) {
    mr::test::TempDir dir;
    auto missing = read_sidecar_scale(dir.file("missing.json"));
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().message.find("missing.json: no such file"), std::string::npos) << missing.error().message;
    std::filesystem::create_directories(dir.file("folder.json"));
    auto folder = read_sidecar_scale(dir.file("folder.json"));
    ASSERT_FALSE(folder);
    EXPECT_NE(folder.error().message.find("folder.json: not a regular file"), std::string::npos);
    auto huge = read_sidecar_scale(dir.write("huge.json", std::vector<uint8_t>(mr::app::kMaxSidecarBytes + 1, ' ')));
    ASSERT_FALSE(huge);
    EXPECT_NE(huge.error().message.find("huge.json: too large"), std::string::npos);
    auto empty = read_sidecar_scale(dir.write("empty.json", {}));
    ASSERT_FALSE(empty);
    EXPECT_NE(empty.error().message.find("empty.json: not valid JSON"), std::string::npos);
    const std::string alps(kAlps);
    auto good = read_sidecar_scale(dir.write("alps.json", std::vector<uint8_t>(alps.begin(), alps.end())));
    ASSERT_TRUE(good) << good.error().message;
    EXPECT_NEAR(good->area_scale, 7890.5, 0.1);
}

}  // namespace
