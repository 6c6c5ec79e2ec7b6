#include <metariver/field.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace mr {
namespace {

TEST(PaperField, GridSpansBallBoundsGrownByOffset) {
    std::vector<Vec3> balls = {Vec3(1, 2, 3), Vec3(4, 2.5f, 3)};
    FieldDef def{.resolution = 2.0f, .bounds_offset = 4.0f};
    ScalarGrid g;
    ASSERT_TRUE(compute_field_paper(balls, def, g));
    EXPECT_EQ(g.origin, Vec3(-3, -2, -1));
    EXPECT_FLOAT_EQ(g.spacing, 0.5f);
    // extents 11, 8.5, 8 metres at 2 cells per metre: ceil(e * 2) + 1 samples
    EXPECT_EQ(g.nx, 23);
    EXPECT_EQ(g.ny, 18);
    EXPECT_EQ(g.nz, 17);
    EXPECT_EQ(g.values.size(), g.size());
}

TEST(PaperField, ValuesAreTheMeanOfInverseSquaresOverBallsPlusOne) {
    std::vector<Vec3> balls = {Vec3(0.3f, 0.1f, 0.2f), Vec3(2.2f, 1.0f, -0.7f), Vec3(-1.0f, 0.4f, 1.9f)};
    FieldDef def{.kernel = FieldKernel::InverseSquare, .resolution = 1.5f, .bounds_offset = 2.0f};
    ScalarGrid g;
    ASSERT_TRUE(compute_field_paper(balls, def, g));
    for (int k = 0; k < g.nz; k += 3)
        for (int j = 0; j < g.ny; j += 2)
            for (int i = 0; i < g.nx; ++i) {
                const Vec3 x = g.position(i, j, k);
                double sum = 0.0;
                for (const Vec3& b : balls) {
                    const glm::dvec3 d = glm::dvec3(x) - glm::dvec3(b);
                    sum += 1.0 / glm::dot(d, d);
                }
                const double want = sum / 4.0;
                // float accumulation of three terms: a few ulps relative
                ASSERT_NEAR(g.at(i, j, k), want, 1e-5 * want) << i << "," << j << "," << k;
            }
}

TEST(PaperField, RadiusOverRKernel) {
    std::vector<Vec3> balls = {Vec3(0.25f, 0.0f, 0.0f)};
    FieldDef def{.kernel = FieldKernel::RadiusOverR, .radius = 2.0f, .resolution = 1.0f, .bounds_offset = 3.0f};
    ScalarGrid g;
    ASSERT_TRUE(compute_field_paper(balls, def, g));
    for (int i = 0; i < g.nx; ++i) {
        const Vec3 x = g.position(i, 3, 3);  // sample row through the ball's y, z
        const double r = std::abs(double(x.x) - 0.25);
        if (r < 0.5) continue;  // the centre sample is the clamped case, tested below
        EXPECT_NEAR(g.at(i, 3, 3), 2.0 / r / 2.0, 1e-5) << i;  // one ball: divided by 2
    }
}

TEST(PaperField, CoincidentBallsScaleAsNOverNPlusOneAndStayFiniteOnCentres) {
    std::vector<Vec3> balls(9, Vec3(0.0f));
    FieldDef def{.resolution = 1.0f, .bounds_offset = 2.0f};
    ScalarGrid g;
    ASSERT_TRUE(compute_field_paper(balls, def, g));
    EXPECT_NEAR(g.at(0, 2, 2), 9.0 / 10.0 * (1.0 / 4.0), 1e-6);  // sample (-2,0,0)
    for (float v : g.values) ASSERT_TRUE(std::isfinite(v));
    EXPECT_GT(g.at(2, 2, 2), 1e5f);  // the centre sample uses the clamped r^2 = 1e-6
}

TEST(PaperField, NoBallsGivesAnEmptyGridAndHugeGridsAreRefused) {
    ScalarGrid g;
    EXPECT_TRUE(compute_field_paper({}, FieldDef{}, g));
    EXPECT_EQ(g.size(), 0u);
    std::vector<Vec3> far = {Vec3(0.0f), Vec3(5000.0f, 5000.0f, 5000.0f)};
    EXPECT_FALSE(compute_field_paper(far, FieldDef{.resolution = 8.0f}, g));
    EXPECT_EQ(g.size(), 0u);
}

TEST(ScalarGrid, ResetReusesCapacityAndFills) {
    ScalarGrid g;
    g.reset(4, 5, 6, Vec3(1, 2, 3), 0.25f, 7.0f);
    EXPECT_EQ(g.values.size(), 120u);
    for (float v : g.values) EXPECT_EQ(v, 7.0f);
    const float* data = g.values.data();
    g.reset(3, 3, 3, Vec3(0.0f), 1.0f);
    EXPECT_EQ(g.values.data(), data);
    EXPECT_EQ(g.index(1, 2, 0), 7u);
    EXPECT_EQ(g.position(1, 2, 0), Vec3(1, 2, 0));
}

}  // namespace
}  // namespace mr
