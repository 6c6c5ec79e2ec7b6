// append_heightfield_surface: water given as depths over a heightfield becomes a triangle
// grid over the wet cells at bed + depth, wound up, with smooth normals, appended.
#include <metariver/surface.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <map>
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

TEST(HeightfieldSurface, ACellWithADryCornerIsLeftOut) {
    // 3 x 3 samples, four cells; the centre sample dry: no cell has four wet corners.
    const auto b = bed(3, 3, [](int, int) { return 0.0f; });
    std::vector<float> depth(9, 0.2f);
    depth[4] = 0.0f;
    SurfaceMesh m;
    append_heightfield_surface(b, depth, 3, 3, m);
    EXPECT_EQ(m.triangle_count(), 0u);
    EXPECT_EQ(m.vertex_count(), 0u);
    // The corner sample (2, 2) dry instead: three wet cells, eight samples used.
    depth[4] = 0.2f;
    depth[8] = 0.0f;
    append_heightfield_surface(b, depth, 3, 3, m);
    EXPECT_EQ(m.triangle_count(), 6u);
    EXPECT_EQ(m.vertex_count(), 8u);
}

TEST(HeightfieldSurface, AppendsAfterWhatTheMeshHoldsAndRefusesWrongSizes) {
    const auto b = bed(2, 2, [](int, int) { return 1.0f; });
    const std::vector<float> depth(4, 0.5f);
    SurfaceMesh m;
    m.positions = {Vec3(0.0f), Vec3(1.0f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 1.0f)};
    m.normals = {Vec3(0.0f, 0.0f, 1.0f), Vec3(0.0f, 0.0f, 1.0f), Vec3(0.0f, 0.0f, 1.0f)};
    m.indices = {0, 1, 2};
    std::vector<uint32_t> scratch;
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

}  // namespace
}  // namespace mr
