// A sculpted terrain saved as a 16-bit PNG and its sidecar (issue 14) loads back with
// the same heights, to the PNG's 1 / 65535 of the range.
#include <metariver/io.h>
#include <metariver/terrain.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace mr {
namespace {

namespace fs = std::filesystem;

TEST(HeightmapPng, ASculptedTerrainRoundTrips) {
    for (const bool paper : {true, false}) {
        SCOPED_TRACE(paper);
        Heightmap m = flat_heightmap(37, 23);
        for (int r = 0; r < m.height; ++r)
            for (int c = 0; c < m.width; ++c) m.samples[size_t(r) * m.width + c] = 0.5f + 0.4f * std::sin(0.3f * c + 0.7f * r);
        auto built = Terrain::build(m, TerrainDef{.area_scale = 1.5f, .height_scale = 10.0f, .paper_row_orientation = paper});
        ASSERT_TRUE(built.ok());
        Terrain t = std::move(built.value());
        ASSERT_TRUE(t.sculpt({.x = 20.0f, .z = 12.0f, .radius = 6.0f, .strength = 7.0f}).ok());  // above the old top
        ASSERT_TRUE(t.sculpt({.x = 5.0f, .z = 5.0f, .radius = 4.0f, .strength = 6.0f, .mode = BrushMode::Lower}).ok());
        const fs::path dir = fs::path(::testing::TempDir()) / "mr_heightmap_png";
        fs::create_directories(dir);
        const std::string path = (dir / "saved.png").string();
        auto s = write_terrain_heightmap(path, t, paper);
        ASSERT_TRUE(s.ok()) << s.error().message;
        EXPECT_EQ(s->sidecar, (dir / "saved.json").string());
        float lo = t.sample(0, 0), hi = lo;
        for (const Vec3& v : t.vertices()) lo = std::min(lo, v.y), hi = std::max(hi, v.y);
        EXPECT_FLOAT_EQ(s->metres_min, lo);
        EXPECT_FLOAT_EQ(s->metres_max, hi);
        EXPECT_GT(hi, 10.0f);  // the hill rose above the map's 0..10 m
        EXPECT_FLOAT_EQ(s->area_scale, 1.5f);
        std::stringstream json;
        json << std::ifstream(s->sidecar).rdbuf();
        for (const char* key : {"\"metres_min\"", "\"metres_max\"", "\"sample_spacing_m\": 1.5", "\"width\": 37",
                                "\"height\": 23"})
            EXPECT_NE(json.str().find(key), std::string::npos) << key << " in " << json.str();
        // Loaded back at the sidecar's scale: the same heights shifted by -metres_min.
        auto png = load_heightmap_png(path);
        ASSERT_TRUE(png.ok()) << png.error().message;
        const float range = s->metres_max - s->metres_min;
        auto back = Terrain::build(png.value(), TerrainDef{.area_scale = s->area_scale, .height_scale = range,
                                                           .paper_row_orientation = paper});
        ASSERT_TRUE(back.ok());
        ASSERT_EQ(back->rows(), t.rows());
        ASSERT_EQ(back->columns(), t.columns());
        for (int i = 0; i < t.rows(); ++i)
            for (int j = 0; j < t.columns(); ++j)
                ASSERT_NEAR(back->sample(i, j), t.sample(i, j) - s->metres_min, 0.51f * range / 65535.0f + 1e-5f)
                    << i << ", " << j;
        fs::remove_all(dir);
    }
    EXPECT_FALSE(encode_png_gray16(std::vector<uint16_t>(5), 2, 2).ok());
}

}  // namespace
}  // namespace mr
