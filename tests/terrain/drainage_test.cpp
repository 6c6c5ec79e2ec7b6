// The drainage network (drainage.h): the channel head, paths and outlets against their
// definitions on a ramp and a valley, and an update after sculpt strokes against the
// network built from scratch.
#include <metariver/drainage.h>
#include <metariver/terrain.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>
#include "require.h"

namespace mr {
namespace {

Terrain ramp_terrain() {
    // Heights fall along +x: image column c has 1 - c / (w - 1); 33 x 17 samples.
    Heightmap m = flat_heightmap(33, 17);
    for (int r = 0; r < 17; ++r)
        for (int c = 0; c < 33; ++c) m.samples[size_t(r) * 33 + c] = 1.0f - float(c) / 32.0f;
    auto t = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 8.0f});
    EXPECT_TRUE(t.ok());
    return std::move(t.value());
}

TEST(ChannelMap, ValleyChannelHeadIsAtTheUpstreamEndAndRampDrainsDownhill) {
    auto t = Terrain::build(procedural_valley(65, 97, 7), TerrainDef{.area_scale = 1.0f, .height_scale = 24.0f});
    const ChannelMap m = ChannelMap::build(t.value());
    const auto [i, j] = m.main_head();
    EXPECT_GT(i, int(0.8 * 96)) << "the valley runs from high z (its head) to low z";
    EXPECT_TRUE(m.is_channel(i, j));
    const ChannelMap r = ChannelMap::build(ramp_terrain());
    EXPECT_GT(r.flow_direction(8, 10).x, 0.9f) << "downhill is +x";
}

bool neighbours(std::pair<int, int> a, std::pair<int, int> b) {
    return a != b && std::abs(a.first - b.first) <= 1 && std::abs(a.second - b.second) <= 1;
}

TEST(ChannelMap, RampPathFromTheTopEndsOnTheLowEdge) {
    const ChannelMap m = ChannelMap::build(ramp_terrain());  // 33 columns (x) x 17 rows (z), falling along +x
    const auto path = m.path_from(8, 1);
    ASSERT_EQ(path.size(), 32u) << "straight down the ramp: columns 1 .. 32";
    for (size_t k = 0; k < path.size(); ++k) EXPECT_EQ(path[k], std::pair(8, int(k) + 1));
    EXPECT_EQ(m.outlet_of(8, 1), std::pair(8, 32));
    EXPECT_EQ(m.outlet_of(3, 32), std::pair(3, 32)) << "an outlet cell is its own path";
    EXPECT_EQ(m.nearest_channel_cell(8, 1), std::pair(8, 15)) << "accumulation 16 = threshold from column 15 on";
    // Outlets: the whole low edge (every row drains straight out), 33 cells each.
    ASSERT_EQ(m.outlets().size(), 17u);
    for (const ChannelMap::Outlet& o : m.outlets()) {
        EXPECT_EQ(o.column, 32);
        EXPECT_EQ(o.accumulation, 33u);
    }
}

TEST(ChannelMap, ValleyMainPathRunsDownTheChannelToTheLargestOutlet) {
    auto t = Terrain::build(procedural_valley(65, 97, 7), TerrainDef{.area_scale = 1.0f, .height_scale = 24.0f});
    const ChannelMap m = ChannelMap::build(t.value());
    const auto [hi, hj] = m.main_head();
    const auto path = m.path_from(hi, hj);
    ASSERT_GT(path.size(), 48u) << "the channel runs most of the valley's 97 rows";
    EXPECT_EQ(path.front(), m.main_head());
    for (size_t k = 1; k < path.size(); ++k) {
        EXPECT_TRUE(neighbours(path[k - 1], path[k])) << k;
        EXPECT_GT(m.accumulation(path[k].first, path[k].second), m.accumulation(path[k - 1].first, path[k - 1].second));
        EXPECT_TRUE(m.is_channel(path[k].first, path[k].second)) << k;
    }
    const auto [oi, oj] = path.back();
    EXPECT_TRUE(oi == 0 || oj == 0 || oi == 96 || oj == 64) << "it leaves over the border";
    EXPECT_LT(oi, 10) << "at the valley's low end";
    // Outlets against their definition: border channel cells whose path is themselves.
    std::vector<std::pair<int, int>> want;
    for (int i = 0; i < 97; ++i)
        for (int j = 0; j < 65; ++j)
            if ((i == 0 || j == 0 || i == 96 || j == 64) && m.is_channel(i, j) && m.path_from(i, j).size() == 1)
                want.emplace_back(i, j);
    std::vector<std::pair<int, int>> got;
    for (const ChannelMap::Outlet& o : m.outlets()) got.emplace_back(o.row, o.column);
    for (size_t k = 1; k < m.outlets().size(); ++k)
        EXPECT_GE(m.outlets()[k - 1].accumulation, m.outlets()[k].accumulation);
    ASSERT_FALSE(got.empty());
    EXPECT_EQ(got.front(), path.back()) << "the main channel drains the most";
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, want);
}

/// Every public output of two maps equal, cell for cell (receivers through path_from's
/// second cell). Returns the first difference, "" when none.
std::string network_difference(const ChannelMap& a, const ChannelMap& b) {
    if (a.rows() != b.rows() || a.columns() != b.columns()) return "size";
    for (int i = 0; i < a.rows(); ++i)
        for (int j = 0; j < a.columns(); ++j) {
            const std::string at = " at (" + std::to_string(i) + ", " + std::to_string(j) + ")";
            if (a.accumulation(i, j) != b.accumulation(i, j))
                return "accumulation " + std::to_string(a.accumulation(i, j)) + " != " + std::to_string(b.accumulation(i, j)) + at;
            if (a.distance_to_channel(i, j) != b.distance_to_channel(i, j)) return "distance" + at;
            const auto pa = a.path_from(i, j), pb = b.path_from(i, j);
            if ((pa.size() > 1) != (pb.size() > 1) || (pa.size() > 1 && pa[1] != pb[1])) return "receiver" + at;
        }
    if (a.main_head() != b.main_head()) return "head";
    if (a.outlets().size() != b.outlets().size()) return "outlet count";
    for (size_t k = 0; k < a.outlets().size(); ++k) {
        const auto &x = a.outlets()[k], &y = b.outlets()[k];
        if (x.row != y.row || x.column != y.column || x.accumulation != y.accumulation) return "outlet " + std::to_string(k);
    }
    return "";
}

/// Rough random heights (many pits for the fill, several outlets), w x h samples.
Heightmap rough_heightmap(int w, int h, uint32_t seed) {
    Heightmap m = flat_heightmap(w, h);
    uint32_t s = seed;
    const auto next = [&] {
        s = s * 1664525u + 1013904223u;
        return float(s >> 8) / float(1u << 24);
    };
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c)
            m.samples[size_t(r) * w + c] = 0.2f + 0.4f * float(c) / float(w) + 0.3f * next() * next();
    return m;
}

// issue 14: a stroke updates the drainage network where it reaches, and the result is
// the network built from scratch, cell for cell, after every one of 60 random strokes
// (raise, lower, smooth, flatten; dams, cuts; some undone) on the valley, a rough map
// full of pits and a real DEM.
TEST(ChannelMap, AnUpdateAfterStrokesIsTheMapBuiltFromScratch) {
    std::vector<std::pair<std::string, Heightmap>> maps;
    maps.emplace_back("valley 65x97", procedural_valley(65, 97, 1));
    maps.emplace_back("rough 41x29", rough_heightmap(41, 29, 5));
    if (auto real = load_heightmap_png(test::real_dem("pyrenees.png")))
        maps.emplace_back("pyrenees", std::move(real.value()));
    else
        ADD_FAILURE() << real.error().message;
    for (auto& [name, map] : maps) {
        SCOPED_TRACE(name);
        auto built = Terrain::build(map, TerrainDef{.area_scale = 1.0f, .height_scale = 8.0f});
        ASSERT_TRUE(built.ok());
        Terrain t = std::move(built.value());
        ChannelMap m = ChannelMap::build(t);
        uint32_t s = 99;
        const auto next = [&] {
            s = s * 1664525u + 1013904223u;
            return float(s >> 8) / float(1u << 24);
        };
        const Aabb b = t.bounds();
        std::vector<TerrainEdit> undo;
        size_t cells = size_t(t.rows()) * size_t(t.columns()), written = 0, rebuilt = 0;
        for (int k = 0; k < 60; ++k) {
            SCOPED_TRACE(k);
            TerrainEdit e;
            if (k % 7 == 6 && !undo.empty()) {  // undo the newest stroke
                e = std::move(undo.back());
                undo.pop_back();
                t.restore(e);
            } else {
                const BrushMode modes[] = {BrushMode::Raise, BrushMode::Lower, BrushMode::Smooth, BrushMode::Flatten};
                const Brush brush{.x = b.min.x + next() * (b.max.x - b.min.x), .z = b.min.z + next() * (b.max.z - b.min.z),
                                  .radius = 1.0f + 4.0f * next(), .strength = k % 4 < 2 ? 2.0f * next() : next(),
                                  .mode = modes[k % 4], .target = b.min.y + next() * (b.max.y - b.min.y)};
                auto r = t.sculpt(brush);
                ASSERT_TRUE(r.ok()) << r.error().message;
                e = r.value();
                undo.push_back(e);
            }
            if (e.empty()) continue;
            const size_t w = m.update(t, e.i0, e.i1, e.j0, e.j1);
            written += w;
            rebuilt += w == cells;
            const std::string diff = network_difference(m, ChannelMap::build(t));
            ASSERT_EQ(diff, "");
        }
        std::printf("%s: 60 strokes, %zu cells written (%.1f per stroke, of %zu), %zu rebuilt whole\n", name.c_str(),
                    written, double(written) / 60.0, cells, rebuilt);
        EXPECT_LT(rebuilt, 30u) << "most strokes leave the height range alone";
    }
}

}  // namespace
}  // namespace mr
