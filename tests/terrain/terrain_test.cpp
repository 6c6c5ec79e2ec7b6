// The terrain mesh (the paper's figure 2) and its height/normal queries.
#include <metariver/terrain.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <filesystem>
#include "require.h"

namespace mr {
namespace {

Heightmap random_map(int w, int h, uint32_t seed) {
    Heightmap m = flat_heightmap(w, h);
    Lcg rng(seed);
    for (float& v : m.samples) v = static_cast<float>(rng.next());
    return m;
}

Terrain build_ok(const Heightmap& m, const TerrainDef& def = {}) {
    auto t = Terrain::build(m, def);
    EXPECT_TRUE(t.ok()) << (t.ok() ? "" : t.error().message);
    return std::move(t).value();
}

TEST(Terrain, VertexLayoutPaperOrientation) {
    const Heightmap m = random_map(5, 3, 1);
    const TerrainDef def{0.5f, 7.0f, true};
    const Terrain t = build_ok(m, def);
    EXPECT_EQ(t.columns(), 5);
    EXPECT_EQ(t.rows(), 3);
    ASSERT_EQ(t.vertices().size(), 15u);
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 5; ++j) {
            const Vec3 v = t.vertices()[static_cast<size_t>(i * 5 + j)];
            EXPECT_EQ(v.x, j * 0.5f);
            EXPECT_EQ(v.z, i * 0.5f);
            // Grid row i counts from the bottom of the image: image row 2 - i.
            EXPECT_EQ(v.y, m.at(2 - i, j) * 7.0f);
            EXPECT_EQ(t.sample(i, j), v.y);
        }
    }
}

TEST(Terrain, VertexLayoutImageOrientation) {
    const Heightmap m = random_map(4, 6, 2);
    const Terrain t = build_ok(m, TerrainDef{1.0f, 2.0f, false});
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 4; ++j) EXPECT_EQ(t.vertices()[static_cast<size_t>(i * 4 + j)].y, m.at(i, j) * 2.0f);
    }
}

TEST(Terrain, ImageRowZeroIsHighestZ) {
    // strict: image row 0 is white; under the paper orientation it lies at the largest z.
    const Terrain t = build_ok(procedural_strict(17, 17));
    const float zmax = 16.0f;
    for (int j = 0; j < 17; ++j) {
        EXPECT_EQ(t.vertices()[static_cast<size_t>(16 * 17 + j)].z, zmax);
        EXPECT_GT(t.sample(16, j), t.sample(0, j));
    }
    EXPECT_GT(t.height_mesh(0.0f, zmax), t.height_mesh(0.0f, 0.0f));
}

TEST(Terrain, PaperNileSpawnLiesOnTheChannel) {
    // README: with the paper orientation the Nile spawn volume (27, 4.6, 31) lands on
    // the river channel at the top right of the image.
    const std::string path = METARIVER_SHARED_DIR "/heightmaps/metawater/nile.png";
    if (!std::filesystem::exists(path)) MR_SKIP_OR_FAIL("no " << path);
    auto map = load_heightmap_png(path);
    ASSERT_TRUE(map.ok());
    const Terrain t = build_ok(*map, TerrainDef{1.0f, 7.0f, true});
    // The channel (about 0.54 * 7 = 3.8 m) is below the spawn height, its banks above it.
    EXPECT_LT(t.height_mesh(27.0f, 31.0f), 4.6f);
    EXPECT_GT(t.height_mesh(31.0f, 31.0f), 4.6f);
}

TEST(Terrain, IndicesFollowThePaper) {
    const int W = 4, H = 3;
    const Terrain t = build_ok(random_map(W, H, 3));
    ASSERT_EQ(t.triangle_count(), static_cast<size_t>(2 * (W - 1) * (H - 1)));
    const auto idx = t.indices();
    for (int i = 0; i + 1 < H; ++i) {
        for (int j = 0; j + 1 < W; ++j) {
            const uint32_t c = static_cast<uint32_t>(i * W + j);
            const size_t tri = 2 * static_cast<size_t>(i * (W - 1) + j);
            EXPECT_EQ(idx[3 * tri + 0], c);
            EXPECT_EQ(idx[3 * tri + 1], c + W);
            EXPECT_EQ(idx[3 * tri + 2], c + 1);
            EXPECT_EQ(idx[3 * tri + 3], c + 1);
            EXPECT_EQ(idx[3 * tri + 4], c + W);
            EXPECT_EQ(idx[3 * tri + 5], c + W + 1);
        }
    }
}

TEST(Terrain, TriangleCountsAndUpNormals) {
    for (auto [w, h] : {std::pair{2, 2}, std::pair{3, 7}, std::pair{17, 17}, std::pair{50, 31}}) {
        const Terrain t = build_ok(random_map(w, h, 4), TerrainDef{0.3f, 5.0f, true});
        ASSERT_EQ(t.triangle_count(), static_cast<size_t>(2 * (w - 1) * (h - 1)));
        const auto v = t.vertices();
        const auto idx = t.indices();
        for (uint32_t tri = 0; tri < t.triangle_count(); ++tri) {
            const Vec3 a = v[idx[3 * tri]], b = v[idx[3 * tri + 1]], c = v[idx[3 * tri + 2]];
            // Winding as stored: (b - a) x (c - a) points up.
            EXPECT_GT(glm::cross(b - a, c - a).y, 0.0f);
            const Vec3 n = t.triangle_normal(tri);
            EXPECT_NEAR(glm::length(n), 1.0f, 1e-6f);  // float normalisation rounding
            EXPECT_GT(n.y, 0.0f);
            EXPECT_NEAR(glm::dot(n, b - a), 0.0f, 1e-5f);  // float rounding, edges ~1 m
            EXPECT_NEAR(glm::dot(n, c - a), 0.0f, 1e-5f);  // float rounding, edges ~1 m
        }
    }
}

TEST(Terrain, Bounds) {
    const Heightmap m = random_map(9, 5, 5);
    const Terrain t = build_ok(m, TerrainDef{2.0f, 3.0f, true});
    float lo = 1e9f, hi = -1e9f;
    for (float s : m.samples) {
        lo = std::min(lo, s * 3.0f);
        hi = std::max(hi, s * 3.0f);
    }
    EXPECT_EQ(t.bounds().min, Vec3(0.0f, lo - 1.0f, 0.0f));
    EXPECT_EQ(t.bounds().max, Vec3(16.0f, hi + 1.0f, 8.0f));
    EXPECT_TRUE(t.contains_xz(0.0f, 0.0f));
    EXPECT_TRUE(t.contains_xz(16.0f, 8.0f));
    EXPECT_FALSE(t.contains_xz(16.01f, 4.0f));
    EXPECT_FALSE(t.contains_xz(4.0f, -0.01f));
    EXPECT_FALSE(t.contains_xz(NAN, 1.0f));
}

TEST(Terrain, HeightsAtGridPointsAndMidpoints) {
    const float s = 0.75f;
    const Terrain t = build_ok(random_map(7, 6, 6), TerrainDef{s, 4.0f, true});
    for (int i = 0; i < t.rows(); ++i) {
        for (int j = 0; j < t.columns(); ++j) {
            const float x = j * s, z = i * s;
            EXPECT_EQ(t.height_bilinear(x, z), t.sample(i, j));
            // (j*s)/s need not round back to j: the point may land a hair inside the
            // neighbouring triangle, whose plane passes through the same vertex.
            EXPECT_NEAR(t.height_mesh(x, z), t.sample(i, j), 1e-5f);
        }
    }
    for (int i = 0; i + 1 < t.rows(); ++i) {
        for (int j = 0; j + 1 < t.columns(); ++j) {
            const float avg = 0.25f * (t.sample(i, j) + t.sample(i, j + 1) + t.sample(i + 1, j) + t.sample(i + 1, j + 1));
            // float rounding of the bilinear weights
            EXPECT_NEAR(t.height_bilinear((j + 0.5f) * s, (i + 0.5f) * s), avg, 1e-5f);
            // The cell centre lies on the diagonal (i+1, j)-(i, j+1): the mesh is their mean there.
            EXPECT_NEAR(t.height_mesh((j + 0.5f) * s, (i + 0.5f) * s), 0.5f * (t.sample(i + 1, j) + t.sample(i, j + 1)),
                        1e-5f);  // float rounding
        }
    }
}

TEST(Terrain, MeshHeightIsTheTrianglePlane) {
    const Terrain t = build_ok(random_map(11, 8, 7), TerrainDef{1.3f, 6.0f, true});
    const auto v = t.vertices();
    const auto idx = t.indices();
    Lcg rng(8);
    for (int k = 0; k < 5000; ++k) {
        const float x = rng.uniform(0.0f, 13.0f), z = rng.uniform(0.0f, 9.1f);
        const uint32_t tri = t.triangle_at(x, z);
        ASSERT_LT(tri, t.triangle_count());
        const Vec3 a = v[idx[3 * tri]], b = v[idx[3 * tri + 1]], c = v[idx[3 * tri + 2]];
        // (x, z) is inside the triangle's xz projection (barycentrics in double).
        const double det = double(b.x - a.x) * (c.z - a.z) - double(c.x - a.x) * (b.z - a.z);
        const double l1 = (double(x - a.x) * (c.z - a.z) - double(c.x - a.x) * (z - a.z)) / det;
        const double l2 = (double(b.x - a.x) * (z - a.z) - double(x - a.x) * (b.z - a.z)) / det;
        EXPECT_GE(l1, -1e-6);  // float rounding of x, z
        EXPECT_GE(l2, -1e-6);  // float rounding of x, z
        EXPECT_LE(l1 + l2, 1.0 + 1e-6);  // float rounding of x, z
        const double plane = a.y + l1 * (b.y - a.y) + l2 * (c.y - a.y);
        EXPECT_NEAR(t.height_mesh(x, z), plane, 2e-5);  // float arithmetic, heights <= 6 m
        EXPECT_EQ(t.normal_mesh(x, z), t.triangle_normal(tri));
        // The bilinear normal is unit length and up.
        const Vec3 nb = t.normal_bilinear(x, z);
        EXPECT_NEAR(glm::length(nb), 1.0f, 1e-6f);  // float normalisation rounding
        EXPECT_GT(nb.y, 0.0f);
    }
}

TEST(Terrain, TriangleAtPicksTheCellHalves) {
    const Terrain t = build_ok(random_map(4, 4, 9));
    // Cell (i=1, j=2) is triangles 2*(1*3+2) = 10 (below the diagonal) and 11.
    EXPECT_EQ(t.triangle_at(2.2f, 1.2f), 10u);
    EXPECT_EQ(t.triangle_at(2.8f, 1.8f), 11u);
    // Clamped into the rectangle.
    EXPECT_EQ(t.triangle_at(-5.0f, -5.0f), 0u);
    EXPECT_EQ(t.triangle_at(50.0f, 50.0f), t.triangle_count() - 1);
}

TEST(Terrain, BilinearNormalMatchesGradient) {
    const Terrain t = build_ok(random_map(6, 6, 10), TerrainDef{1.0f, 2.0f, true});
    Lcg rng(11);
    for (int k = 0; k < 200; ++k) {
        const float x = rng.uniform(0.1f, 4.9f), z = rng.uniform(0.1f, 4.9f);
        const float e = 1e-2f;
        // Stay within one cell so the central difference sees one bilinear patch.
        if (std::floor(x - e) != std::floor(x + e) || std::floor(z - e) != std::floor(z + e)) continue;
        const float gx = (t.height_bilinear(x + e, z) - t.height_bilinear(x - e, z)) / (2 * e);
        const float gz = (t.height_bilinear(x, z + e) - t.height_bilinear(x, z - e)) / (2 * e);
        const Vec3 expect = glm::normalize(Vec3(-gx, 1.0f, -gz));
        const Vec3 n = t.normal_bilinear(x, z);
        // Bilinear is linear along x and z: central differences are exact up to float
        // cancellation (~1e-7 / 1e-2).
        EXPECT_NEAR(n.x, expect.x, 1e-3f);
        EXPECT_NEAR(n.y, expect.y, 1e-3f);  // same reason
        EXPECT_NEAR(n.z, expect.z, 1e-3f);  // same reason
    }
}

TEST(Terrain, QueriesClampOutside) {
    const Terrain t = build_ok(random_map(5, 5, 12));
    EXPECT_EQ(t.height_bilinear(-3.0f, 2.0f), t.height_bilinear(0.0f, 2.0f));
    EXPECT_EQ(t.height_mesh(9.0f, 9.0f), t.sample(4, 4));
    EXPECT_EQ(t.height_mesh(-1.0f, -1.0f), t.sample(0, 0));
    EXPECT_TRUE(std::isfinite(t.height_mesh(NAN, INFINITY)));
    EXPECT_TRUE(std::isfinite(t.height_bilinear(-INFINITY, NAN)));
}

TEST(Terrain, BuildErrorsNameTheField) {
    const Heightmap good = random_map(3, 3, 13);
    auto expect_error = [](const Result<Terrain>& r, const std::string& text) {
        ASSERT_FALSE(r.ok());
        EXPECT_NE(r.error().message.find(text), std::string::npos) << r.error().message;
    };
    expect_error(Terrain::build(good, TerrainDef{-1.0f, 7.0f, true}), "terrain.area_scale: must be finite and > 0 (got -1)");
    expect_error(Terrain::build(good, TerrainDef{0.0f, 7.0f, true}), "terrain.area_scale");
    expect_error(Terrain::build(good, TerrainDef{NAN, 7.0f, true}), "terrain.area_scale");
    expect_error(Terrain::build(good, TerrainDef{1.0f, INFINITY, true}), "terrain.height_scale: must be finite and > 0");
    expect_error(Terrain::build(good, TerrainDef{1.0f, -2.0f, true}), "terrain.height_scale");

    Heightmap thin = random_map(1, 5, 14);
    expect_error(Terrain::build(thin, {}), "at least 2 x 2");
    Heightmap wrong = good;
    wrong.samples.pop_back();
    expect_error(Terrain::build(wrong, {}), "samples");
    Heightmap nan = good;
    nan.samples[4] = NAN;
    expect_error(Terrain::build(nan, {}), "row 1, column 1");
    Heightmap inf = good;
    inf.samples[0] = INFINITY;
    expect_error(Terrain::build(inf, {}), "not finite");
}

TEST(Terrain, AutoAreaScaleStretchesASmallMapToKAutoMinSide) {
    TerrainDef d{.area_scale = 1.0f, .height_scale = 24.0f, .auto_area_scale = true};
    EXPECT_FLOAT_EQ(resolved_area_scale(d, 2, 2), kAutoMinSide);          // one cell: 16 m
    EXPECT_FLOAT_EQ(resolved_area_scale(d, 17, 9), kAutoMinSide / 8.0f);  // the shorter side
    EXPECT_FLOAT_EQ(resolved_area_scale(d, 9, 17), kAutoMinSide / 8.0f);
    EXPECT_FLOAT_EQ(resolved_area_scale(d, 65, 97), 1.0f);  // already 64 m: as given
    EXPECT_FLOAT_EQ(resolved_area_scale(d, 17, 17), 1.0f);  // exactly 16 m
    d.area_scale = 3.0f;  // the value is the least
    EXPECT_FLOAT_EQ(resolved_area_scale(d, 2, 2), kAutoMinSide);
    EXPECT_FLOAT_EQ(resolved_area_scale(d, 9, 9), 3.0f);
    d.auto_area_scale = false;  // a number is used as given
    EXPECT_FLOAT_EQ(resolved_area_scale(d, 2, 2), 3.0f);
    // The mesh is built at the resolved scale, and the terrain reports it.
    auto t = Terrain::build(flat_heightmap(2, 2), TerrainDef{.area_scale = 1.0f, .height_scale = 1.0f, .auto_area_scale = true});
    ASSERT_TRUE(t.ok()) << t.error().message;
    EXPECT_FLOAT_EQ(t->area_scale(), kAutoMinSide);
    EXPECT_FLOAT_EQ(t->bounds().extent().x, kAutoMinSide);
    EXPECT_FLOAT_EQ(t->bounds().extent().z, kAutoMinSide);
}

TEST(Terrain, ProceduralMapsBuild) {
    for (const Heightmap& m : {procedural_valley(129, 129, 5), procedural_strict(17, 17), procedural_bowl(33, 33)}) {
        const Terrain t = build_ok(m);
        EXPECT_EQ(t.triangle_count(), static_cast<size_t>(2 * (m.width - 1) * (m.height - 1)));
        EXPECT_LE(t.bounds().max.y, 7.0f + 1.0f);
        EXPECT_GE(t.bounds().min.y, -1.0f);
    }
}

}  // namespace
}  // namespace mr

namespace mr {
namespace {

/// Every interior cell has a strictly lower 8-neighbour: water running downhill from
/// anywhere reaches the edge.
bool drains(const Terrain& t) {
    for (int i = 1; i + 1 < t.rows(); ++i)
        for (int j = 1; j + 1 < t.columns(); ++j) {
            bool lower = false;
            for (int di = -1; di <= 1 && !lower; ++di)
                for (int dj = -1; dj <= 1 && !lower; ++dj)
                    if ((di || dj) && t.sample(i + di, j + dj) < t.sample(i, j)) lower = true;
            if (!lower) return false;
        }
    return true;
}

Heightmap pit_map() {
    // A ramp falling towards column 0 with a 0.3-deep pit in the middle of it.
    Heightmap m = flat_heightmap(21, 17);
    for (int r = 0; r < 17; ++r)
        for (int c = 0; c < 21; ++c) {
            const float d = std::hypot(float(c) - 10.0f, float(r) - 8.0f);
            m.samples[size_t(r) * 21 + c] = 0.5f + 0.02f * float(c) - (d < 4.0f ? 0.3f * (1.0f - d / 4.0f) : 0.0f);
        }
    return m;
}

TEST(TerrainCondition, FillAndBreachMakeEveryCellDrainAndReportWhatChanged) {
    const Heightmap m = pit_map();
    auto none = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 10.0f});
    ASSERT_TRUE(none.ok());
    EXPECT_FALSE(drains(none.value())) << "the pit holds water";
    EXPECT_EQ(none->condition_report().cells_raised + none->condition_report().cells_lowered, 0u);

    auto fill = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 10.0f, .condition = TerrainCondition::Fill});
    ASSERT_TRUE(fill.ok());
    EXPECT_TRUE(drains(fill.value()));
    const ConditionReport& f = fill->condition_report();
    EXPECT_GT(f.cells_raised, 10u);
    EXPECT_EQ(f.cells_lowered, 0u);
    // Bottom 0.7 - 0.3 = 0.4; it spills over its downhill rim (column 6: 0.62): 2.2 m.
    EXPECT_NEAR(f.max_change_m, 2.2f, 0.15f);
    EXPECT_GT(f.volume_m3, 10.0);

    auto breach = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 10.0f, .condition = TerrainCondition::Breach});
    ASSERT_TRUE(breach.ok());
    EXPECT_TRUE(drains(breach.value()));
    const ConditionReport& b = breach->condition_report();
    EXPECT_GT(b.cells_lowered, 0u);
    EXPECT_EQ(b.cells_raised, 0u);
    EXPECT_LT(b.cells_lowered, f.cells_raised) << "a channel through the rim, not the whole pit";
    // Nothing outside the pit and its breach channel moved: the far corner is untouched.
    EXPECT_FLOAT_EQ(breach->sample(16, 20), none->sample(16, 20));
    EXPECT_FLOAT_EQ(fill->sample(16, 20), none->sample(16, 20));
}

TEST(TerrainCondition, ATerrainThatAlreadyDrainsIsLeftAlone) {
    Heightmap m = flat_heightmap(9, 7);
    for (int r = 0; r < 7; ++r)
        for (int c = 0; c < 9; ++c) m.samples[size_t(r) * 9 + c] = 0.1f * float(c) + 0.01f * float(r % 3);
    for (const TerrainCondition mode : {TerrainCondition::Fill, TerrainCondition::Breach}) {
        auto t = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 10.0f, .condition = mode});
        ASSERT_TRUE(t.ok());
        EXPECT_EQ(t->condition_report().cells_raised + t->condition_report().cells_lowered, 0u) << to_string(mode);
    }
}

TEST(TerrainCondition, RandomMapsOfOddSizesAllDrain) {
    Lcg rng(11);
    for (const auto& [w, h] : {std::pair{2, 2}, std::pair{3, 7}, std::pair{31, 17}, std::pair{64, 65}}) {
        Heightmap m = flat_heightmap(w, h);
        for (float& v : m.samples) v = rng.uniform(0.0f, 1.0f);
        for (const TerrainCondition mode : {TerrainCondition::Fill, TerrainCondition::Breach}) {
            auto t = Terrain::build(m, TerrainDef{.area_scale = 2.0f, .height_scale = 50.0f, .condition = mode});
            ASSERT_TRUE(t.ok());
            EXPECT_TRUE(drains(t.value())) << w << " x " << h << " " << to_string(mode);
        }
    }
}

TEST(TerrainCondition, CarveLaysABedThatDescendsFromSourceToOutletWithBanksAndLevees) {
    // The pit map, breached, then a channel carved along row 8 from column 18 to the
    // edge at column 0: through the pit's rim and its bottom.
    const Heightmap m = pit_map();
    auto given = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 10.0f});
    auto t = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 10.0f, .condition = TerrainCondition::Carve});
    ASSERT_TRUE(given.ok() && t.ok());
    EXPECT_EQ(t->condition_report().mode, TerrainCondition::Carve);
    EXPECT_TRUE(drains(t.value())) << "carve breaches first";
    const float breached_far = t->sample(16, 20);
    std::vector<std::pair<int, int>> path;
    for (int j = 18; j >= 0; --j) path.emplace_back(8, j);
    const CarveDef def{.width_m = 6.0f, .floor_m = 3.0f, .depth_m = 1.0f};
    Terrain carved = t.value();
    carved.carve_channel(path, def);
    // The bed never rises along the path and falls from source to outlet (by at least
    // kConditionSlope per metre), at least depth_m below the ground as given.
    for (size_t k = 0; k < path.size(); ++k) {
        const auto [i, j] = path[k];
        EXPECT_LE(carved.sample(i, j), given->sample(i, j) - def.depth_m + 1e-4f) << "cell " << j;
        if (k > 0) {
            EXPECT_LE(carved.sample(i, j), carved.sample(path[k - 1].first, path[k - 1].second)) << "cell " << j;
        }
    }
    EXPECT_LT(carved.sample(8, 0), carved.sample(8, 18) - kConditionSlope * 17.0f);
    // The floor: the rows beside the path are cut as deep (symmetric, depth_m below the ground).
    for (int j = 2; j <= 16; ++j) {
        EXPECT_FLOAT_EQ(carved.sample(7, j), carved.sample(9, j)) << "column " << j;
        EXPECT_LE(carved.sample(7, j), given->sample(7, j) - 0.5f * def.depth_m) << "column " << j;
    }
    // The banks (3 m out) stand depth_m above the bed, or higher where the ground is.
    EXPECT_GE(carved.sample(5, 12), carved.sample(8, 12) + def.depth_m - 1e-4f);
    EXPECT_GE(carved.sample(11, 12), carved.sample(8, 12) + def.depth_m - 1e-4f);
    // Far from the channel nothing moved; the report counts against the heights as given.
    EXPECT_FLOAT_EQ(carved.sample(16, 20), breached_far);
    const ConditionReport& r = carved.condition_report();
    uint64_t lowered = 0, raised = 0;
    for (int i = 0; i < carved.rows(); ++i)
        for (int j = 0; j < carved.columns(); ++j) {
            lowered += carved.sample(i, j) < given->sample(i, j);
            raised += carved.sample(i, j) > given->sample(i, j);
        }
    EXPECT_EQ(r.cells_lowered, lowered);
    EXPECT_EQ(r.cells_raised, raised);
    EXPECT_GT(r.cells_lowered, 3u * path.size() - 4u) << "at least the floor, three cells wide";
    EXPECT_GE(r.max_change_m, def.depth_m);
    EXPECT_LT(r.max_change_m, 4.5f) << "a channel, not a gorge (the breach, the pit 3 m deep, plus 1 m)";
}

TEST(TerrainCondition, CarveCutsACliffOnThePathIntoARampNoSteeperThanKCarveSteepest) {
    // A ledge 6 m high (columns 12..24), a cliff, a gentle plain down to the edge at
    // column 0 (mean slope well under 1). Water leaving the cliff's edge flew off as
    // spray (paper-nile: a source on a ledge 4 m above its pool; colorado_rockies).
    Heightmap m = flat_heightmap(25, 9);
    for (int i = 0; i < 9; ++i)
        for (int j = 0; j < 25; ++j) m.samples[size_t(i) * 25 + size_t(j)] = (j >= 12 ? 0.7f : 0.1f) + 0.002f * float(j);
    auto t = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 10.0f});
    ASSERT_TRUE(t.ok());
    std::vector<std::pair<int, int>> path;
    for (int j = 24; j >= 0; --j) path.emplace_back(4, j);
    const CarveDef def{.width_m = 3.0f, .floor_m = 1.0f, .depth_m = 0.5f};
    Terrain carved = t.value();
    carved.carve_channel(path, def);
    float steepest = 0.0f;
    for (size_t k = 1; k < path.size(); ++k) {
        const float drop = carved.sample(4, path[k - 1].second) - carved.sample(4, path[k].second);
        EXPECT_GE(drop, 0.0f) << "the bed never rises, column " << path[k].second;
        steepest = std::max(steepest, drop);
    }
    EXPECT_LE(steepest, kCarveSteepest + 1e-4f);
    EXPECT_GT(steepest, 0.9f * kCarveSteepest) << "the ramp is as steep as allowed, no shallower";
    // Upstream of the cliff the ramp ends: the head of the ledge keeps its bed (ground - depth).
    EXPECT_NEAR(carved.sample(4, 24), t->sample(4, 24) - def.depth_m, 1e-4f);
    // Without the limit the bed would drop 6 m in one step.
    EXPECT_GT(t->sample(4, 12) - t->sample(4, 11), 5.0f);
}

TEST(TerrainCondition, CarveOnAFlatLaysABedFallingKCarveLeastSlopePerMetre) {
    // A flat map (flat0.png, the procedural flat): the bed must fall so the river runs.
    // With the old rule (half the path's mean slope, at least 0.1 %) it fell 0.1 % and
    // the river on flat0.png stopped (0.002 of inflow at its outlet; 0.989 with 2 %).
    // The path turns a diagonal corner: the step is measured in metres.
    Heightmap m = flat_heightmap(30, 12);
    auto t = Terrain::build(m, TerrainDef{.area_scale = 2.0f, .height_scale = 10.0f});
    ASSERT_TRUE(t.ok());
    std::vector<std::pair<int, int>> path;
    for (int j = 28; j >= 10; --j) path.emplace_back(5, j);
    for (int k = 1; k <= 4; ++k) path.emplace_back(5 + k, 10 - k);
    for (int j = 5; j >= 0; --j) path.emplace_back(9, j);
    const CarveDef def{.width_m = 8.0f, .floor_m = 6.0f, .depth_m = 1.0f};
    Terrain carved = t.value();
    carved.carve_channel(path, def);
    // Each path sample lies at least depth_m + kCarveLeastSlope x (metres along the path
    // from the head) under the flat ground (the next cells' floors may cut it deeper),
    // and the bed never rises.
    float along = 0.0f;
    for (size_t k = 0; k < path.size(); ++k) {
        const auto [i, j] = path[k];
        if (k > 0) {
            const auto [pi, pj] = path[k - 1];
            along += 2.0f * std::hypot(float(i - pi), float(j - pj));
            EXPECT_LE(carved.sample(i, j), carved.sample(pi, pj) + 1e-5f) << "path cell " << k;
        }
        EXPECT_LE(carved.sample(i, j), t->sample(i, j) - def.depth_m - kCarveLeastSlope * along + 1e-4f) << "path cell " << k;
    }
    const auto [oi, oj] = path.back();
    EXPECT_GT(t->sample(oi, oj) - carved.sample(oi, oj), def.depth_m + 0.9f * kCarveLeastSlope * along)
        << "the outlet's bed, " << along << " m down the path";
}

TEST(TerrainCondition, CarveWithAnEmptyPathOrOutsideTheGridChangesNothing) {
    auto t = Terrain::build(pit_map(), TerrainDef{.area_scale = 1.0f, .height_scale = 10.0f});
    ASSERT_TRUE(t.ok());
    Terrain c = t.value();
    c.carve_channel({}, CarveDef{});
    const std::vector<std::pair<int, int>> outside{{-5, -5}, {100, 3}};
    c.carve_channel(outside, CarveDef{});
    for (int i = 0; i < c.rows(); ++i)
        for (int j = 0; j < c.columns(); ++j) ASSERT_EQ(c.sample(i, j), t->sample(i, j));
}

}  // namespace
}  // namespace mr

namespace mr {
namespace {

TEST(HeightfieldQuery, ExplodingCoordinatesNeitherCrashNorHit) {
    // Issue 13: floor(x) was converted to int before clamping (undefined for 1e30; the
    // UBSan build reports it). Segments from far outside, or with inf/NaN ends, must come
    // back without a hit or as too long for the cell walk.
    auto t = Terrain::build(flat_heightmap(9, 9), TerrainDef{.area_scale = 1.0f, .height_scale = 1.0f});
    ASSERT_TRUE(t.ok());
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    for (const auto& [from, to] : {std::pair{Vec3(-1e30f, 5, 2), Vec3(3, 5, 2)}, std::pair{Vec3(2, 5, -1e30f), Vec3(2, 5, 3)},
                                    std::pair{Vec3(-inf, 1, 1), Vec3(1, 1, 1)}, std::pair{Vec3(nan, 1, 1), Vec3(1, -1, 1)},
                                    std::pair{Vec3(1e30f, 1, 1e30f), Vec3(2e30f, -1, 2e30f)}}) {
        const HeightfieldQuery q = intersect_segment_heightfield(t.value(), from, to);
        if (q.hit) {
            EXPECT_TRUE(std::isfinite(q.hit->point.y));
        }
        EXPECT_FALSE(q.hit && !q.too_long && q.hit->point.y < -1.0f);
    }
}

}  // namespace
}  // namespace mr
