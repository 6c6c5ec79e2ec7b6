// append_heightfield_surface: water given as depths over a heightfield becomes a triangle
// grid over the wet cells at bed + depth, wound up, with smooth normals, appended.
#include <metariver/surface.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace mr {
namespace {

/// A rows x columns bed of spacing 1 at height h(i, j), row-major like Terrain::vertices().
template <class H>
std::vector<Vec3> bed(int rows, int columns, H h) {
    std::vector<Vec3> v;
    for (int i = 0; i < rows; ++i)
        for (int j = 0; j < columns; ++j) v.emplace_back(float(j), h(i, j), float(i));
    return v;
}

TEST(HeightfieldSurface, AWetGridIsTwoTrianglesPerCellAtBedPlusDepthWithNormalsUp) {
    const int rows = 4, columns = 5;
    const auto b = bed(rows, columns, [](int i, int j) { return 0.1f * float(i * j); });
    std::vector<float> depth(b.size());
    for (size_t k = 0; k < depth.size(); ++k) depth[k] = 0.5f + 0.01f * float(k);
    SurfaceMesh m;
    append_heightfield_surface(b, depth, rows, columns, m);
    EXPECT_EQ(m.triangle_count(), size_t(2 * (rows - 1) * (columns - 1)));
    ASSERT_EQ(m.vertex_count(), b.size());  // every sample belongs to a wet cell
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (size_t k = 0; k < b.size(); ++k) {  // vertices in sample order
        EXPECT_EQ(m.positions[k], b[k] + Vec3(0.0f, depth[k], 0.0f)) << k;
        EXPECT_NEAR(glm::length(m.normals[k]), 1.0f, 1e-5f) << k;  // float normalisation
        EXPECT_GT(m.normals[k].y, 0.0f) << k;
    }
    // Every triangle faces up (counter-clockwise seen from above).
    for (size_t t = 0; t < m.indices.size(); t += 3) {
        const Vec3 a = m.positions[m.indices[t]], c1 = m.positions[m.indices[t + 1]], c2 = m.positions[m.indices[t + 2]];
        EXPECT_GT(glm::cross(c1 - a, c2 - a).y, 0.0f) << t / 3;
    }
    // Consistently wound: an interior edge is used once in each direction.
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t t = 0; t < m.indices.size(); t += 3)
        for (int e = 0; e < 3; ++e) ++directed[{m.indices[t + e], m.indices[t + (e + 1) % 3]}];
    for (const auto& [edge, count] : directed) EXPECT_EQ(count, 1);
}

TEST(HeightfieldSurface, SmoothNormalsOfAPlaneAreItsNormal) {
    // Water 1 m deep on a plane rising 0.5 m per column: every normal is the plane's.
    const int rows = 3, columns = 3;
    const auto b = bed(rows, columns, [](int, int j) { return 0.5f * float(j); });
    const std::vector<float> depth(b.size(), 1.0f);
    SurfaceMesh m;
    append_heightfield_surface(b, depth, rows, columns, m);
    const Vec3 plane = glm::normalize(Vec3(-0.5f, 1.0f, 0.0f));
    for (const Vec3& n : m.normals) {  // 1e-5: float cross products and normalisation
        EXPECT_NEAR(n.x, plane.x, 1e-5f);
        EXPECT_NEAR(n.y, plane.y, 1e-5f);
        EXPECT_NEAR(n.z, plane.z, 1e-5f);
    }
}

TEST(HeightfieldSurface, ADrySampleCutsItsTrianglesWhereTheLevelMeetsTheBed) {
    // 3 x 3 samples on a flat bed, the centre dry under its neighbours' level 0.2 m: its
    // ring level is 0.2 m below its bed, so the water ends half way to it (a hole).
    const auto b = bed(3, 3, [](int, int) { return 0.0f; });
    std::vector<float> depth(9, 0.2f);
    depth[4] = 0.0f;
    SurfaceMesh m;
    append_heightfield_surface(b, depth, 3, 3, m);
    ASSERT_EQ(m.vertex_count(), 14u);  // eight wet samples and a cut on each of the 6 edges to the centre
    for (size_t v = 8; v < m.vertex_count(); ++v) {
        const float d = std::max(std::abs(m.positions[v].x - 1.0f), std::abs(m.positions[v].z - 1.0f));
        EXPECT_NEAR(d, 0.5f, 1e-5f) << v;
        EXPECT_NEAR(m.positions[v].y, 0.0f, 1e-6f) << v;  // on the ground
    }
    // The 6 triangles touching the centre cut to quads (2 each), the 2 that do not whole.
    EXPECT_EQ(m.triangle_count(), 14u);
    // A bank: the centre sample 1 m high; its neighbours' level 0.2 m meets it a fifth of
    // the way up each edge (0.2 along, 0.16 on the diagonal's halves... all at y = 0.2).
    const auto bank = bed(3, 3, [](int i, int j) { return i == 1 && j == 1 ? 1.0f : 0.0f; });
    SurfaceMesh k;
    append_heightfield_surface(bank, depth, 3, 3, k);
    EXPECT_GT(k.vertex_count(), 8u);
    for (size_t v = 8; v < k.vertex_count(); ++v) {  // the cuts: 0.2 of the way to the centre
        EXPECT_NEAR(k.positions[v].y, 0.2f, 1e-6f) << v;
        const float d = std::max(std::abs(k.positions[v].x - 1.0f), std::abs(k.positions[v].z - 1.0f));
        EXPECT_NEAR(d, 0.8f, 1e-5f) << v;
    }
    for (size_t t = 0; t < k.indices.size(); t += 3) {
        const Vec3 a = k.positions[k.indices[t]], c1 = k.positions[k.indices[t + 1]], c2 = k.positions[k.indices[t + 2]];
        EXPECT_GT(glm::cross(c1 - a, c2 - a).y, 0.0f) << t / 3;
    }
    // Everything dry: nothing.
    SurfaceMesh none;
    append_heightfield_surface(b, std::vector<float>(9, 0.0f), 3, 3, none);
    EXPECT_EQ(none.vertex_count(), 0u);
    EXPECT_EQ(none.triangle_count(), 0u);
}

TEST(HeightfieldSurface, ALakeInABowlEndsOnTheContourNotOnTheCellsStaircase) {
    // A paraboloid bowl z = 0.02 r^2 (cells of 1 m) filled to L = 2 m: the shoreline is the
    // circle r = 10 m. The old mesh (cells with four wet corners) stopped up to a cell and
    // a half inside it; the cut mesh's shoreline lies on the bed's triangles at L.
    const int n = 41;
    const float c = 20.0f, level = 2.0f, r_shore = 10.0f;
    const auto b = bed(n, n, [&](int i, int j) {
        const float x = float(j) - c, z = float(i) - c;
        return 0.02f * (x * x + z * z);
    });
    std::vector<float> depth(b.size());
    std::vector<Vec3> velocity(b.size(), Vec3(0.0f));
    for (size_t k = 0; k < b.size(); ++k) {
        depth[k] = std::max(level - b[k].y, 0.0f);
        if (depth[k] > 0.0f) velocity[k] = Vec3(1.0f, 0.0f, 0.0f);
    }
    SurfaceMesh m;
    HeightfieldScratch scratch;
    std::vector<Vec3> vv;
    append_heightfield_surface(b, depth, n, n, m, &scratch, velocity, &vv);
    ASSERT_EQ(vv.size(), m.vertex_count());
    for (const Vec3& v : vv) EXPECT_EQ(v, Vec3(1.0f, 0.0f, 0.0f));  // a cut's velocity: its wet end's
    // The shoreline's vertices: those after the wet samples' (the cuts, and the dry
    // samples a cut snapped to).
    const size_t wet = size_t(std::count_if(depth.begin(), depth.end(), [](float d) { return d > 0.0f; }));
    ASSERT_GT(m.vertex_count(), wet + 60);  // the circle's ~63 m at under a cell per vertex
    float worst = 0.0f;
    for (size_t v = wet; v < m.vertex_count(); ++v) {
        const Vec3 p = m.positions[v];
        worst = std::max(worst, std::abs(std::hypot(p.x - c, p.z - c) - r_shore));
    }
    // Linear interpolation of the bowl along the edges, and cuts snapped by 5 % of an edge:
    // well under a tenth of a cell (the staircase: up to 1.4 cells).
    EXPECT_LT(worst, 0.1f);
    // The area seen from above is the disc's (the staircase of cells with four wet corners
    // misses 46 m^2 of it): the inscribed polygon's chords take under 1 m^2.
    double area = 0.0;
    for (size_t t = 0; t < m.indices.size(); t += 3) {
        const Vec3 a = m.positions[m.indices[t]], c1 = m.positions[m.indices[t + 1]], c2 = m.positions[m.indices[t + 2]];
        area += 0.5 * double(glm::cross(c1 - a, c2 - a).y);
    }
    EXPECT_NEAR(area, 3.14159265 * r_shore * r_shore, 1.5);
    float top = -1e9f, min_area = 1e9f;
    for (const Vec3& p : m.positions) top = std::max(top, p.y);
    EXPECT_LE(top, level + 1e-5f);  // nothing above the lake
    for (size_t t = 0; t < m.indices.size(); t += 3) {
        const Vec3 a = m.positions[m.indices[t]], c1 = m.positions[m.indices[t + 1]], c2 = m.positions[m.indices[t + 2]];
        min_area = std::min(min_area, 0.5f * glm::cross(c1 - a, c2 - a).y);
    }
    EXPECT_GT(min_area, 1e-4f);  // no sliver: the smallest cut is 5 % of an edge on two sides
    for (const Vec3& nrm : m.normals) EXPECT_GT(nrm.y, 0.999f);  // flat: normals up
}

TEST(HeightfieldSurface, AppendsAfterWhatTheMeshHoldsAndRefusesWrongSizes) {
    const auto b = bed(2, 2, [](int, int) { return 1.0f; });
    const std::vector<float> depth(4, 0.5f);
    SurfaceMesh m;
    m.positions = {Vec3(0.0f), Vec3(1.0f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 1.0f)};
    m.normals = {Vec3(0.0f, 0.0f, 1.0f), Vec3(0.0f, 0.0f, 1.0f), Vec3(0.0f, 0.0f, 1.0f)};
    m.indices = {0, 1, 2};
    HeightfieldScratch scratch;
    append_heightfield_surface(b, depth, 2, 2, m, &scratch);
    ASSERT_EQ(m.vertex_count(), 7u);
    ASSERT_EQ(m.triangle_count(), 3u);
    EXPECT_EQ(m.normals[0], Vec3(0.0f, 0.0f, 1.0f));  // what was there is kept
    for (size_t k = 3; k < m.indices.size(); ++k) EXPECT_GE(m.indices[k], 3u);
    EXPECT_EQ(m.positions[3], Vec3(0.0f, 1.5f, 0.0f));
    // Sizes that are not rows x columns (or a grid under 2 x 2) append nothing.
    append_heightfield_surface(b, depth, 3, 2, m);
    append_heightfield_surface(std::span<const Vec3>(b).first(3), depth, 2, 2, m);
    append_heightfield_surface(std::span<const Vec3>(b).first(2), std::span<const float>(depth).first(2), 1, 2, m);
    EXPECT_EQ(m.vertex_count(), 7u);
    EXPECT_EQ(m.triangle_count(), 3u);
}

/// A pinned LCG's floats in [0, 1).
struct Lcg {
    uint32_t seed;
    float operator()() {
        seed = seed * 1664525u + 1013904223u;
        return float(seed >> 8) / 16777216.0f;
    }
};

/// A mesh and its vertices' velocities, for bit-for-bit comparisons.
struct Meshed {
    SurfaceMesh mesh;
    std::vector<Vec3> velocity;
};

void expect_same(const Meshed& a, const Meshed& b, const std::string& what) {
    EXPECT_EQ(a.mesh.positions, b.mesh.positions) << what;
    EXPECT_EQ(a.mesh.normals, b.mesh.normals) << what;
    EXPECT_EQ(a.mesh.indices, b.mesh.indices) << what;
    EXPECT_EQ(a.velocity, b.velocity) << what;
}

TEST(HeightfieldSurface, TheWetRowsMeshIsTheFullScansOnRandomPatternsAndOddSizes) {
    // Random blobs of water (films under and over the 5 mm cut among them, wet samples on the
    // map's edges and corners) on a random bed, on grids of odd sizes: the mesh from the rows'
    // wet columns (given exactly, given loosely, or found by the call) is the one from every
    // row given whole (the full scan: every sample's level, every cell's triangles), bit for
    // bit, with one scratch reused across all the grids and calls (each call leaves it clean).
    Lcg next{12345u};
    HeightfieldScratch reused;
    const std::pair<int, int> sizes[] = {{2, 2}, {2, 9}, {9, 2}, {7, 13}, {31, 17}, {16, 16}, {40, 3}};
    int wet_meshes = 0;
    for (const auto& size : sizes)
        for (int pattern = 0; pattern < 12; ++pattern) {
            const int rows = size.first, columns = size.second;  // not a structured binding: clang 14 cannot capture one
            const auto b = bed(rows, columns, [&](int, int) { return 2.0f * next(); });
            const size_t n = b.size();
            std::vector<float> depth(n, 0.0f);
            std::vector<Vec3> velocity(n, Vec3(0.0f));
            const float fill = 0.05f * float(pattern);  // from a few samples to most of the map
            for (size_t k = 0; k < n; ++k) {
                const float r = next();
                if (r < fill) depth[k] = 0.5f * next();
                else if (r < fill + 0.05f) depth[k] = 0.01f * next();  // films: about half under the cut
                if (depth[k] > 0.0f) velocity[k] = Vec3(next() - 0.5f, 0.0f, next() - 0.5f);
            }
            if (pattern == 11) depth[0] = depth[n - 1] = depth[size_t(columns) - 1] = 0.3f;  // the corners
            std::vector<int> exact_first(size_t(rows), columns), exact_last(size_t(rows), -1);
            std::vector<int> loose_first(static_cast<size_t>(rows)), loose_last(static_cast<size_t>(rows));
            for (int i = 0; i < rows; ++i) {
                for (int j = 0; j < columns; ++j)
                    if (depth[size_t(i) * size_t(columns) + size_t(j)] > 0.0f) {
                        exact_first[size_t(i)] = std::min(exact_first[size_t(i)], j);
                        exact_last[size_t(i)] = j;
                    }
                // Wider than the wet columns, past the row's ends, or a dry row's "none".
                loose_first[size_t(i)] = exact_first[size_t(i)] - int(4.0f * next()) - (i % 3 == 0 ? columns : 0);
                loose_last[size_t(i)] = exact_last[size_t(i)] + int(4.0f * next()) + (i % 4 == 0 ? columns : 0);
            }
            const std::vector<int> whole_first(size_t(rows), 0), whole_last(size_t(rows), columns - 1);
            std::vector<uint8_t> skip;  // every other pattern: cells a particle field draws (the hybrid's seam)
            if (pattern % 2 == 1)
                for (int c = 0; c < (rows - 1) * (columns - 1); ++c) skip.push_back(next() < 0.2f ? 1 : 0);
            const auto mesh = [&](std::span<const int> first, std::span<const int> last, HeightfieldScratch* scratch) {
                Meshed m;
                append_heightfield_surface(b, depth, rows, columns, m.mesh, scratch, velocity, &m.velocity, skip, first, last);
                return m;
            };
            const Meshed full = mesh(whole_first, whole_last, nullptr);
            const std::string what = std::to_string(rows) + " x " + std::to_string(columns) + " #" + std::to_string(pattern);
            expect_same(mesh(exact_first, exact_last, &reused), full, what + " exact");
            expect_same(mesh(loose_first, loose_last, &reused), full, what + " loose");
            expect_same(mesh({}, {}, &reused), full, what + " found");
            expect_same(mesh(whole_first, whole_last, &reused), full, what + " whole, reused scratch");
            wet_meshes += full.mesh.triangle_count() > 0;
            // A scratch left clean: every vertex and cut slot none again.
            EXPECT_TRUE(std::all_of(reused.vertex.begin(), reused.vertex.end(), [](uint32_t v) { return v == UINT32_MAX; })) << what;
            EXPECT_TRUE(std::all_of(reused.crossing.begin(), reused.crossing.end(), [](uint32_t v) { return v == UINT32_MAX; })) << what;
        }
    EXPECT_GT(wet_meshes, 70);  // most patterns drew water (the driest may not)
}

/// The slow, obviously-right twin of append_heightfield_surface, written from its contract
/// in surface.h: every sample's level over the whole grid, a vertex table per sample and a
/// map per edge, every cell visited. Same vertices (wet samples in sample order, then cuts
/// and snapped dry samples as the cells meet them), triangles and normals, bit for bit.
struct Twin {
    std::span<const Vec3> bed, velocity;
    std::span<const float> depth;
    int rows, columns;
    SurfaceMesh mesh;
    std::vector<Vec3> vv;
    std::vector<float> level;
    std::vector<uint32_t> vertex;
    std::map<std::pair<size_t, size_t>, uint32_t> cuts;
    float min_area = 0.0f;

    bool wet(size_t k) const { return depth[k] > 0.005f; }
    uint32_t add(Vec3 p, size_t v) {
        mesh.positions.push_back(p);
        mesh.normals.emplace_back(0.0f);
        vv.push_back(velocity[v]);
        return uint32_t(mesh.positions.size() - 1);
    }
    uint32_t sample(size_t k, size_t v) {
        if (vertex[k] == UINT32_MAX) vertex[k] = add(Vec3(bed[k].x, level[k], bed[k].z), v);
        return vertex[k];
    }
    uint32_t cut(size_t p, size_t q) {  // p wet, q dry
        const auto key = std::minmax(p, q);
        if (const auto it = cuts.find(key); it != cuts.end()) return it->second;
        const float fp = level[p] - bed[p].y, fq = level[q] - bed[q].y, t = fp / (fp - fq);
        const Vec3 a(bed[p].x, level[p], bed[p].z), b(bed[q].x, level[q], bed[q].z);
        const uint32_t v = t < 0.05f ? sample(p, p) : t > 0.95f ? sample(q, p) : add(a + t * (b - a), p);
        return cuts[key] = v;
    }
    void triangle(size_t a, size_t b, size_t c) {
        const size_t k[3] = {a, b, c};
        std::vector<uint32_t> poly;
        for (int e = 0; e < 3; ++e) {
            const size_t p = k[e], q = k[(e + 1) % 3];
            if (wet(p)) poly.push_back(sample(p, p));
            if (wet(p) != wet(q)) poly.push_back(wet(p) ? cut(p, q) : cut(q, p));
        }
        poly.erase(std::unique(poly.begin(), poly.end()), poly.end());
        while (poly.size() > 1 && poly.back() == poly.front()) poly.pop_back();
        for (size_t i = 1; i + 1 < poly.size(); ++i) {
            const Vec3 *p = mesh.positions.data(), n = glm::cross(p[poly[i]] - p[poly[0]], p[poly[i + 1]] - p[poly[0]]);
            if (!(n.y > 2.0f * min_area)) continue;
            for (const uint32_t v : {poly[0], poly[i], poly[i + 1]}) {
                mesh.indices.push_back(v);
                mesh.normals[v] += n;
            }
        }
    }
    void run() {
        const size_t w = size_t(columns), n = depth.size();
        min_area = 1e-6f * std::abs((bed[1] - bed[0]).x * (bed[w] - bed[0]).z - (bed[1] - bed[0]).z * (bed[w] - bed[0]).x);
        level.resize(n);
        vertex.assign(n, UINT32_MAX);
        for (int i = 0; i < rows; ++i)
            for (int j = 0; j < columns; ++j) {  // wet: bed + depth; dry: from the lowest wet neighbour
                const size_t k = size_t(i) * w + size_t(j);
                float lowest = std::numeric_limits<float>::max();
                for (int a = std::max(i - 1, 0); a <= std::min(i + 1, rows - 1); ++a)
                    for (int b = std::max(j - 1, 0); b <= std::min(j + 1, columns - 1); ++b)
                        if (const size_t q = size_t(a) * w + size_t(b); wet(q)) lowest = std::min(lowest, bed[q].y + depth[q]);
                const bool ring = !wet(k) && lowest < std::numeric_limits<float>::max();
                level[k] = ring ? bed[k].y - std::abs(lowest - bed[k].y) : bed[k].y + std::max(depth[k], 0.0f);
            }
        for (size_t k = 0; k < n; ++k)
            if (wet(k)) sample(k, k);
        for (int i = 0; i + 1 < rows; ++i)
            for (int j = 0; j + 1 < columns; ++j) {
                const size_t c = size_t(i) * w + size_t(j);
                triangle(c, c + w, c + 1);
                triangle(c + 1, c + w, c + w + 1);
            }
        for (Vec3& v : mesh.normals) v = glm::length(v) > 0.0f ? v / glm::length(v) : Vec3(0.0f, 1.0f, 0.0f);
    }
};

TEST(HeightfieldSurface, TheMeshIsTheWholeGridTwinsOnRandomLakesBitForBit) {
    // Lakes below a level on a random bed (long ragged shorelines, islands, films under and
    // over the 5 mm cut, water on the map's edges) on grids of several sizes, one scratch
    // reused: positions, normals, indices and vertex velocities equal the twin's exactly.
    Lcg next{777u};
    HeightfieldScratch scratch;
    const std::pair<int, int> sizes[] = {{2, 2}, {3, 40}, {23, 19}, {64, 48}, {5, 5}};
    size_t cut_meshes = 0;
    for (const auto& [rows, columns] : sizes)
        for (int pattern = 0; pattern < 8; ++pattern) {
            std::vector<Vec3> bed, velocity;
            std::vector<float> depth;
            const float level = 0.2f + 0.1f * float(pattern);
            for (int i = 0; i < rows; ++i)
                for (int j = 0; j < columns; ++j) {
                    const float h = 0.5f * (std::sin(0.4f * float(i)) + std::cos(0.3f * float(j))) + 0.3f * next() + 0.5f;
                    bed.emplace_back(0.5f * float(j), h, 0.5f * float(i));
                    depth.push_back(next() < 0.03f ? 0.006f * next() : std::max(level - h, 0.0f));
                    velocity.emplace_back(next(), 0.0f, next() - 0.5f);
                }
            Twin twin{.bed = bed, .velocity = velocity, .depth = depth, .rows = rows, .columns = columns};
            twin.run();
            SurfaceMesh mesh;
            std::vector<Vec3> vv;
            append_heightfield_surface(bed, depth, rows, columns, mesh, &scratch, velocity, &vv);
            const std::string what = std::to_string(rows) + " x " + std::to_string(columns) + " #" + std::to_string(pattern);
            EXPECT_EQ(mesh.positions, twin.mesh.positions) << what;
            EXPECT_EQ(mesh.normals, twin.mesh.normals) << what;
            EXPECT_EQ(mesh.indices, twin.mesh.indices) << what;
            EXPECT_EQ(vv, twin.vv) << what;
            cut_meshes += twin.cuts.size() > 0 && !mesh.indices.empty();
        }
    EXPECT_GT(cut_meshes, 25u);  // most grids had water with a shoreline
}

}  // namespace
}  // namespace mr
