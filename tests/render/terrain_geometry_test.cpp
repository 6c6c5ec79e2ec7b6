// The renderer's terrain mesh on the CPU (src/render/terrain_geometry.h): updating the
// rows around a sculpt stroke gives the mesh a whole build gives, bit for bit (the fast
// path and its obviously-right twin), for strokes inside, over a corner, along an edge,
// and lowering the lowest point (the skirts' bottom moves: the update refuses).
#include <metariver/terrain.h>

#include "terrain_geometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace mr::render {
namespace {

Heightmap bumpy(int w, int h) {
    Heightmap m = flat_heightmap(w, h);
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c)
            m.samples[size_t(r) * w + c] = 0.5f + 0.3f * std::sin(0.7f * float(c)) * std::cos(0.45f * float(r));
    m.samples[size_t(1) * w + 3] = 0.0f;  // the lowest point, away from the strokes: the skirts' bottom stays
    return m;
}

void expect_same(const TerrainGeometry& a, const TerrainGeometry& b) {
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    size_t differing = 0;
    for (size_t v = 0; v < a.vertices.size(); ++v)
        differing += std::memcmp(&a.vertices[v], &b.vertices[v], sizeof(TerrainVertex)) != 0;
    EXPECT_EQ(differing, 0u) << "vertices differ from a whole build";
    EXPECT_EQ(a.indices, b.indices);
    EXPECT_EQ(a.bounds.min, b.bounds.min);
    EXPECT_EQ(a.bounds.max, b.bounds.max);
}

TEST(TerrainGeometry, UpdatingAroundAStrokeEqualsAWholeBuild) {
    auto t = Terrain::build(bumpy(23, 17), TerrainDef{.area_scale = 1.0f, .height_scale = 6.0f});
    ASSERT_TRUE(t.ok()) << t.error().message;
    Terrain& terrain = t.value();
    TerrainGeometry g;
    build_terrain_geometry(terrain, false, g);
    const Brush strokes[] = {
        {.x = 11.0f, .z = 8.0f, .radius = 3.0f, .strength = 1.5f},                            // inside
        {.x = 0.0f, .z = 0.0f, .radius = 4.0f, .strength = 1.0f},                             // a corner
        {.x = 22.0f, .z = 9.0f, .radius = 2.5f, .strength = 0.7f, .mode = BrushMode::Smooth},  // an edge
    };
    for (const Brush& b : strokes) {
        auto e = terrain.sculpt(b);
        ASSERT_TRUE(e.ok()) << e.error().message;
        ASSERT_FALSE(e->empty());
        TerrainEdit rows;
        ASSERT_TRUE(update_terrain_geometry(terrain, e.value(), g, rows));
        EXPECT_LE(rows.i0, e->i0);
        EXPECT_GE(rows.i1, e->i1);
        TerrainGeometry whole;
        build_terrain_geometry(terrain, false, whole);
        expect_same(g, whole);
    }
    // Lowering below the lowest sample moves the skirts' bottom: the update refuses and
    // leaves the geometry for a whole build.
    const Vec3 lo = terrain.bounds().min;
    auto e = terrain.sculpt({.x = 5.0f, .z = 5.0f, .radius = 3.0f, .strength = 50.0f, .mode = BrushMode::Lower});
    ASSERT_TRUE(e.ok());
    ASSERT_LT(terrain.bounds().min.y, lo.y);
    TerrainEdit rows;
    EXPECT_FALSE(update_terrain_geometry(terrain, e.value(), g, rows));
}

// The tree boxes after a refit, updated in place, equal a whole build; the spans say
// where they moved (a raise above the highest sample moves every box's top).
TEST(TerrainGeometry, RefittedTreeBoxesEqualAWholeBuildAndTheirSpansCoverEveryMove) {
    auto t = Terrain::build(bumpy(23, 17), TerrainDef{.area_scale = 1.0f, .height_scale = 6.0f});
    ASSERT_TRUE(t.ok()) << t.error().message;
    Terrain& terrain = t.value();
    auto bvh = Bvh::build(terrain, BvhDef{});
    ASSERT_TRUE(bvh.ok()) << bvh.error().message;
    TreeBoxes boxes;
    build_tree_boxes(bvh.value(), boxes);
    const std::vector<BoxInstance> before = boxes.boxes;
    auto e = terrain.sculpt({.x = 11.0f, .z = 8.0f, .radius = 3.0f, .strength = 20.0f});
    ASSERT_TRUE(e.ok()) << e.error().message;
    bvh.value().refit_heights(terrain);
    std::vector<std::pair<uint32_t, uint32_t>> spans;
    ASSERT_TRUE(refit_tree_boxes(bvh.value(), boxes, spans));
    TreeBoxes whole;
    build_tree_boxes(bvh.value(), whole);
    ASSERT_EQ(boxes.boxes.size(), whole.boxes.size());
    EXPECT_EQ(std::memcmp(boxes.boxes.data(), whole.boxes.data(), whole.boxes.size() * sizeof(BoxInstance)), 0);
    size_t moved = 0;
    for (uint32_t k = 0; k < whole.boxes.size(); ++k) {
        if (std::memcmp(&before[k], &whole.boxes[k], sizeof(BoxInstance)) == 0) continue;
        ++moved;
        bool covered = false;
        for (const auto& [lo, hi] : spans) covered |= k >= lo && k < hi;
        EXPECT_TRUE(covered) << "box " << k << " moved outside every span";
    }
    EXPECT_GT(moved, 0u) << "the stroke moved no box: the test checks nothing";
    // Another tree (another node count) is refused, for a whole build.
    TreeBoxes other = boxes;
    other.nodes += 1;
    EXPECT_FALSE(refit_tree_boxes(bvh.value(), other, spans));
}

}  // namespace
}  // namespace mr::render
