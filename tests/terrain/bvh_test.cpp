// The paper's AABB tree: structure, point query, and both segment queries checked
// against brute force.
#include <metariver/terrain.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include "require.h"

namespace mr {
namespace {

Terrain random_terrain(int w, int h, uint32_t seed, float s = 1.0f, float hs = 7.0f) {
    Heightmap m;
    m.width = w;
    m.height = h;
    Lcg rng(seed);
    m.samples.resize(static_cast<size_t>(w) * h);
    for (float& v : m.samples) v = static_cast<float>(rng.next());
    auto t = Terrain::build(m, TerrainDef{s, hs, true});
    EXPECT_TRUE(t.ok());
    return std::move(t).value();
}

Bvh build_bvh(const Terrain& t, int leaf) {
    auto b = Bvh::build(t, BvhDef{leaf});
    EXPECT_TRUE(b.ok()) << (b.ok() ? "" : b.error().message);
    return std::move(b).value();
}

/// The terrains the queries are checked on: the paper's maps (when present) and
/// random ones of awkward sizes.
std::vector<std::pair<std::string, Terrain>> test_terrains() {
    std::vector<std::pair<std::string, Terrain>> out;
    for (const char* f : {"strict17.png", "nile.png", "bowl.png", "small.png"}) {
        if (!test::have_file(test::paper_map(f))) continue;
        auto m = load_heightmap_png(test::paper_map(f));
        EXPECT_TRUE(m.ok());
        auto t = Terrain::build(*m, TerrainDef{1.0f, 7.0f, true});
        EXPECT_TRUE(t.ok());
        out.emplace_back(f, std::move(t).value());
    }
    uint32_t seed = 100;
    for (auto [w, h] : {std::pair{2, 2}, std::pair{3, 7}, std::pair{17, 17}, std::pair{33, 33}, std::pair{50, 31},
                        std::pair{129, 65}}) {
        out.emplace_back(std::to_string(w) + "x" + std::to_string(h), random_terrain(w, h, seed++, 0.8f, 5.0f));
    }
    return out;
}

bool overlap_xz(const Aabb& a, const Aabb& b) {
    return a.min.x < b.max.x && b.min.x < a.max.x && a.min.z < b.max.z && b.min.z < a.max.z;
}

std::vector<int> leaves_of(const Bvh& b) {
    std::vector<int> leaves;
    for (size_t k = 0; k < b.nodes().size(); ++k) {
        if (b.nodes()[k].count > 0) leaves.push_back(static_cast<int>(k));
    }
    return leaves;
}

TEST(Bvh, RejectsBadLeafSize) {
    const Terrain t = random_terrain(5, 5, 1);
    for (int leaf : {1, 0, -3, 4097}) {
        auto b = Bvh::build(t, BvhDef{leaf});
        ASSERT_FALSE(b.ok());
        EXPECT_NE(b.error().message.find("collision.bvh_leaf_triangles"), std::string::npos) << b.error().message;
        EXPECT_NE(b.error().message.find(std::to_string(leaf)), std::string::npos) << b.error().message;
    }
    EXPECT_TRUE(Bvh::build(t, BvhDef{2}).ok());
    EXPECT_TRUE(Bvh::build(t, BvhDef{4096}).ok());
    EXPECT_FALSE(Bvh::build(Terrain{}, BvhDef{8}).ok());
}

TEST(Bvh, Structure) {
    for (const auto& [name, t] : test_terrains()) {
        for (int leaf : {2, 3, 8, 64}) {
            SCOPED_TRACE(name + " leaf " + std::to_string(leaf));
            const Bvh b = build_bvh(t, leaf);
            const auto nodes = b.nodes();
            const auto ids = b.leaf_triangle_ids();
            const size_t ntri = t.triangle_count();
            ASSERT_EQ(ids.size(), ntri);
            const BvhStats st = b.stats();
            EXPECT_EQ(st.nodes, nodes.size());
            EXPECT_LE(st.max_leaf_triangles, static_cast<size_t>(leaf));
            EXPECT_EQ(st.leaves, (nodes.size() + 1) / 2);  // a full binary tree
            EXPECT_LE(st.depth, static_cast<int>(std::ceil(std::log2(static_cast<double>(ntri)))) + 2);

            std::vector<int> seen(ntri, 0);
            const auto v = t.vertices();
            const auto idx = t.indices();
            for (size_t k = 0; k < nodes.size(); ++k) {
                const BvhNode& n = nodes[k];
                // Every box spans the terrain's full height.
                EXPECT_EQ(n.box.min.y, t.bounds().min.y);
                EXPECT_EQ(n.box.max.y, t.bounds().max.y);
                if (n.count == 0) {
                    ASSERT_LT(n.left, nodes.size());
                    ASSERT_LT(n.right, nodes.size());
                    for (uint32_t c : {n.left, n.right}) {
                        EXPECT_GE(nodes[c].box.min.x, n.box.min.x);
                        EXPECT_GE(nodes[c].box.min.z, n.box.min.z);
                        EXPECT_LE(nodes[c].box.max.x, n.box.max.x);
                        EXPECT_LE(nodes[c].box.max.z, n.box.max.z);
                    }
                    EXPECT_FALSE(overlap_xz(nodes[n.left].box, nodes[n.right].box));
                    continue;
                }
                EXPECT_LE(n.count, static_cast<uint32_t>(leaf));
                ASSERT_LE(n.first + n.count, ids.size());
                Aabb tight;
                for (uint32_t tri : b.leaf_triangles(static_cast<int>(k))) {
                    ASSERT_LT(tri, ntri);
                    ++seen[tri];
                    for (int c = 0; c < 3; ++c) {
                        const Vec3 p = v[idx[3 * size_t{tri} + c]];
                        EXPECT_TRUE(n.box.contains(p));
                        tight.grow(p);
                    }
                }
                // x/z exactly from the range's vertices.
                EXPECT_EQ(n.box.min.x, tight.min.x);
                EXPECT_EQ(n.box.max.x, tight.max.x);
                EXPECT_EQ(n.box.min.z, tight.min.z);
                EXPECT_EQ(n.box.max.z, tight.max.z);
            }
            for (size_t tri = 0; tri < ntri; ++tri) ASSERT_EQ(seen[tri], 1) << "triangle " << tri;

            // Leaves tile the root rectangle: pairwise disjoint interiors, areas add up.
            const auto leaves = leaves_of(b);
            double area = 0.0;
            for (int l : leaves) area += double(nodes[l].box.extent().x) * nodes[l].box.extent().z;
            const double root = double(nodes[0].box.extent().x) * nodes[0].box.extent().z;
            EXPECT_NEAR(area, root, 1e-4 * root);  // float box corners summed in double
            if (leaves.size() <= 800) {
                for (size_t a = 0; a < leaves.size(); ++a) {
                    for (size_t c = a + 1; c < leaves.size(); ++c) {
                        ASSERT_FALSE(overlap_xz(nodes[leaves[a]].box, nodes[leaves[c]].box));
                    }
                }
            }
        }
    }
}

TEST(Bvh, PaperListHalvingOnPowerOfTwoPlusOne) {
    // 17 x 17, 8 per leaf (the paper's FullVersion scene): 512 triangles in 64 leaves
    // of 8 consecutive triangles of the paper's list, in list order.
    const Terrain t = random_terrain(17, 17, 5);
    const Bvh b = build_bvh(t, 8);
    const auto ids = b.leaf_triangle_ids();
    for (size_t k = 0; k < ids.size(); ++k) ASSERT_EQ(ids[k], k);
    const BvhStats st = b.stats();
    EXPECT_EQ(st.leaves, 64u);
    EXPECT_EQ(st.depth, 7);
    EXPECT_EQ(st.max_leaf_triangles, 8u);
}

TEST(Bvh, LeafContainingMatchesBruteForce) {
    for (const auto& [name, t] : test_terrains()) {
        SCOPED_TRACE(name);
        const Bvh b = build_bvh(t, 8);
        const auto nodes = b.nodes();
        const auto leaves = leaves_of(b);
        const Aabb root = nodes[0].box;
        Lcg rng(3);
        for (int k = 0; k < 2000; ++k) {
            Vec3 p(rng.uniform(root.min.x - 1, root.max.x + 1), rng.uniform(root.min.y - 1, root.max.y + 1),
                   rng.uniform(root.min.z - 1, root.max.z + 1));
            if (k % 4 == 0) {  // exactly on grid lines: shared leaf boundaries
                p.x = t.vertices()[rng.next_u32() % t.vertices().size()].x;
                p.z = t.vertices()[rng.next_u32() % t.vertices().size()].z;
            }
            std::vector<int> holders;
            for (int l : leaves) {
                if (nodes[l].box.contains(p)) holders.push_back(l);
            }
            const int got = b.leaf_containing(p);
            if (holders.empty()) {
                EXPECT_EQ(got, -1);
            } else {
                ASSERT_NE(got, -1);
                EXPECT_NE(std::find(holders.begin(), holders.end(), got), holders.end());
                if (holders.size() == 1) {
                    EXPECT_EQ(got, holders[0]);
                }
            }
        }
    }
}

/// Nearest watertight hit over every triangle.
std::optional<std::pair<float, uint32_t>> brute_nearest(const Terrain& t, const Vec3& from, const Vec3& to) {
    const auto v = t.vertices();
    const auto idx = t.indices();
    std::optional<std::pair<float, uint32_t>> best;
    for (uint32_t tri = 0; tri < t.triangle_count(); ++tri) {
        const auto h = ray_triangle_watertight(from, to - from, v[idx[3 * tri]], v[idx[3 * tri + 1]], v[idx[3 * tri + 2]]);
        if (h && (!best || *h < best->first)) best = std::pair{*h, tri};
    }
    return best;
}

/// Random segments: long and short, any direction, vertical and horizontal ones, some
/// through grid vertices.
std::pair<Vec3, Vec3> random_segment(const Terrain& t, Lcg& rng) {
    const Aabb& bb = t.bounds();
    auto point = [&](float grow) {
        return Vec3(rng.uniform(bb.min.x - grow, bb.max.x + grow), rng.uniform(bb.min.y - grow, bb.max.y + grow),
                    rng.uniform(bb.min.z - grow, bb.max.z + grow));
    };
    const uint32_t kind = rng.next_u32() % 5;
    Vec3 a = point(2.0f);
    Vec3 b;
    switch (kind) {
        case 0: b = point(2.0f); break;                                              // anywhere
        case 1: b = a + Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)); break;  // short
        case 2: b = Vec3(a.x, bb.min.y - 1.0f, a.z); a.y = bb.max.y + 1.0f; break;  // vertical through
        case 3: b = Vec3(rng.uniform(bb.min.x, bb.max.x), a.y, rng.uniform(bb.min.z, bb.max.z)); break;  // horizontal
        default: {  // vertical through a grid vertex
            const Vec3 p = t.vertices()[rng.next_u32() % t.vertices().size()];
            a = Vec3(p.x, bb.max.y, p.z);
            b = Vec3(p.x, bb.min.y, p.z);
        }
    }
    return {a, b};
}

TEST(Bvh, IntersectSegmentMatchesBruteForce) {
    for (const auto& [name, t] : test_terrains()) {
        SCOPED_TRACE(name);
        for (int leaf : {2, 8, 64}) {
            const Bvh b = build_bvh(t, leaf);
            Lcg rng(11 + static_cast<uint32_t>(leaf));
            const int n = t.triangle_count() > 5000 ? 300 : 1000;  // keep brute force cheap
            int hits = 0;
            for (int k = 0; k < n; ++k) {
                const auto [from, to] = random_segment(t, rng);
                const auto got = b.intersect_segment(t, from, to);
                const auto want = brute_nearest(t, from, to);
                ASSERT_EQ(got.has_value(), want.has_value()) << "segment " << k;
                if (!got) continue;
                ++hits;
                // Same test, same triangle: same t; a different triangle sharing the hit
                // point (edge/vertex, equal t) computes t with its own rounding.
                EXPECT_NEAR(got->t, want->first, 1e-5f);
                if (got->triangle == want->second) {
                    EXPECT_EQ(got->t, want->first);
                }
                const Vec3 p = from + got->t * (to - from);
                EXPECT_NEAR(glm::length(got->point - p), 0.0f, 1e-4f);  // float rounding, coordinates ~100 m
                EXPECT_EQ(got->normal, t.triangle_normal(got->triangle));
                EXPECT_GT(got->normal.y, 0.0f);
            }
            EXPECT_GT(hits, n / 10);
        }
    }
}

TEST(Bvh, IntersectPaperMatchesBruteForceOverItsLeaf) {
    for (const auto& [name, t] : test_terrains()) {
        SCOPED_TRACE(name);
        const Bvh b = build_bvh(t, 8);
        const auto v = t.vertices();
        const auto idx = t.indices();
        Lcg rng(5);
        int hits = 0;
        for (int k = 0; k < 2000; ++k) {
            const auto [from, to] = random_segment(t, rng);
            const auto got = b.intersect_paper(t, from, to);
            const int leaf = b.leaf_containing(to);
            std::optional<std::pair<float, uint32_t>> want;
            if (leaf >= 0) {
                for (uint32_t tri : b.leaf_triangles(leaf)) {
                    const auto h = ray_triangle_paper(from, to - from, v[idx[3 * tri]], v[idx[3 * tri + 1]], v[idx[3 * tri + 2]]);
                    if (h && (!want || *h < want->first)) want = std::pair{*h, tri};
                }
            }
            ASSERT_EQ(got.has_value(), want.has_value()) << "segment " << k;
            if (!got) continue;
            ++hits;
            EXPECT_EQ(got->t, want->first);
            EXPECT_EQ(got->triangle, want->second);
            EXPECT_EQ(got->normal, t.triangle_normal(got->triangle));
            EXPECT_NEAR(glm::length(got->normal), 1.0f, 1e-6f);  // float normalisation rounding
        }
        EXPECT_GT(hits, 0);
    }
}

TEST(Bvh, PaperQueryOnlySeesTheLeafOfTheEndPoint) {
    // A long vertical drop ending below the terrain: the paper's query looks in the leaf
    // holding the end point, which is the leaf under it, so it hits; a segment that
    // ends outside the terrain box finds nothing even though it crosses the surface.
    const Terrain t = random_terrain(17, 17, 8);
    const Bvh b = build_bvh(t, 8);
    const float x = 4.3f, z = 9.6f;
    const Vec3 from(x, t.bounds().max.y, z), to(x, t.bounds().min.y, z);
    ASSERT_TRUE(b.intersect_paper(t, from, to).has_value());
    EXPECT_FALSE(b.intersect_paper(t, from, Vec3(x, t.bounds().min.y - 5.0f, z)).has_value());
    EXPECT_TRUE(b.intersect_segment(t, from, Vec3(x, t.bounds().min.y - 5.0f, z)).has_value());
}

TEST(Bvh, VerticalRayHitsTheMeshHeight) {
    for (const auto& [name, t] : test_terrains()) {
        SCOPED_TRACE(name);
        const Bvh b = build_bvh(t, 8);
        Lcg rng(9);
        const Aabb& bb = t.bounds();
        for (int k = 0; k < 1000; ++k) {
            const float x = rng.uniform(bb.min.x, bb.max.x), z = rng.uniform(bb.min.z, bb.max.z);
            const Vec3 from(x, bb.max.y, z), to(x, bb.min.y, z);
            const auto hit = b.intersect_segment(t, from, to);
            ASSERT_TRUE(hit.has_value()) << x << "," << z;
            // float rounding of t over a drop of <= 9 m
            EXPECT_NEAR(hit->point.y, t.height_mesh(x, z), 1e-4f);
            EXPECT_EQ(hit->point.x, x);
            EXPECT_EQ(hit->point.z, z);
        }
    }
}

// Sculpting (issue 14): a stroke changes the samples inside its radius only, by the
// documented amount; undo gives the terrain back bit for bit; the refitted tree answers
// segment queries as brute force does, also above the old highest point.
TEST(Sculpt, ABrushChangesItsDiscByTheDocumentedAmount) {
    Terrain t = random_terrain(40, 30, 5, 1.0f, 5.0f);
    const std::vector<Vec3> v0(t.vertices().begin(), t.vertices().end());
    const Brush raise{.x = 20.0f, .z = 12.0f, .radius = 4.0f, .strength = 2.0f, .mode = BrushMode::Raise};
    auto e = t.sculpt(raise);
    ASSERT_TRUE(e.ok()) << e.error().message;
    EXPECT_EQ(e->i0, 8);
    EXPECT_EQ(e->i1, 16);
    EXPECT_EQ(e->j0, 16);
    EXPECT_EQ(e->j1, 24);
    for (size_t k = 0; k < v0.size(); ++k) {
        const Vec3& a = v0[k];
        const float d2 = ((a.x - 20.0f) * (a.x - 20.0f) + (a.z - 12.0f) * (a.z - 12.0f)) / 16.0f;
        const float want = d2 < 1.0f ? a.y + 2.0f * (1.0f - d2) * (1.0f - d2) : a.y;
        ASSERT_FLOAT_EQ(t.vertices()[k].y, want) << k;
    }
    EXPECT_FLOAT_EQ(t.sample(12, 20), v0[12 * 40 + 20].y + 2.0f);  // the centre: the full strength
    EXPECT_GE(t.bounds().max.y, t.sample(12, 20) + 1.0f);
    // Flatten all the way at the centre; smooth lowers a spike's height.
    auto f = t.sculpt({.x = 5.0f, .z = 5.0f, .radius = 2.0f, .strength = 1.0f, .mode = BrushMode::Flatten, .target = 3.0f});
    ASSERT_TRUE(f.ok());
    EXPECT_FLOAT_EQ(t.sample(5, 5), 3.0f);
    // Smoothing lowers the spread of the heights under the brush.
    const auto spread = [&] {
        double s1 = 0.0, s2 = 0.0;
        for (int i = 10; i <= 14; ++i)
            for (int j = 18; j <= 22; ++j) s1 += t.sample(i, j), s2 += double(t.sample(i, j)) * t.sample(i, j);
        return s2 / 25.0 - (s1 / 25.0) * (s1 / 25.0);
    };
    const double before_smooth = spread();
    ASSERT_TRUE(t.sculpt({.x = 20.0f, .z = 12.0f, .radius = 3.0f, .strength = 1.0f, .mode = BrushMode::Smooth}).ok());
    EXPECT_LT(spread(), 0.7 * before_smooth);
    // Undo, newest first: bit for bit (the smooth stroke lies inside the raise's edit).
    t.restore(f.value());
    t.restore(e.value());
    // The smooth stroke changed samples near (12, 20) that e restored; everything else is back.
    for (size_t k = 0; k < v0.size(); ++k) ASSERT_EQ(t.vertices()[k].y, v0[k].y) << k;
    // A brush off the map changes nothing; bad brushes name the field.
    auto off = t.sculpt({.x = -50.0f, .z = 5.0f, .radius = 2.0f});
    ASSERT_TRUE(off.ok());
    EXPECT_TRUE(off->empty());
    EXPECT_FALSE(t.sculpt({.radius = 0.0f}).ok());
    EXPECT_NE(t.sculpt({.radius = NAN}).error().message.find("brush: radius"), std::string::npos);
    EXPECT_NE(t.sculpt({.strength = 2.0f, .mode = BrushMode::Smooth}).error().message.find("brush: strength"),
              std::string::npos);
    for (size_t k = 0; k < v0.size(); ++k) ASSERT_EQ(t.vertices()[k].y, v0[k].y) << k;
}

TEST(Sculpt, TheRefittedTreeMatchesBruteForce) {
    for (const auto& [name, t0] : test_terrains()) {
        SCOPED_TRACE(name);
        Terrain t = t0;
        Bvh b = build_bvh(t, 8);
        const Vec3 c = t.bounds().center();
        // A hill far above the old highest point and a pit below the lowest.
        ASSERT_TRUE(t.sculpt({.x = c.x, .z = c.z, .radius = 3.0f, .strength = 20.0f}).ok());
        ASSERT_TRUE(t.sculpt({.x = t.bounds().min.x + 1.0f, .z = t.bounds().min.z + 1.0f, .radius = 2.0f,
                              .strength = 15.0f, .mode = BrushMode::Lower})
                        .ok());
        b.refit_heights(t);
        Lcg rng(3);
        for (int k = 0; k < 300; ++k) {
            const auto [from, to] = random_segment(t, rng);
            const auto got = b.intersect_segment(t, from, to);
            const auto want = brute_nearest(t, from, to);
            ASSERT_EQ(got.has_value(), want.has_value()) << "segment " << k;
            if (got) {
                EXPECT_NEAR(got->t, want->first, 1e-5f);
            }
        }
    }
}

}  // namespace
}  // namespace mr
