// `run --stats`'s bodies (issue 44): what bodies_json makes of the bodies' states (built
// by hand here: the stats read SceneView::bodies, plain data).
#include "run_stats.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <vector>

namespace mr::app {
namespace {

TEST(RunStatsBodies, CountMeansAndEachBody) {
    std::vector<BodyState> b(2);
    b[0].id = 3;
    b[0].shape = BodyShape::Capsule;
    b[0].position = Vec3(1, 2, 3);
    b[0].velocity = Vec3(3, 0, 4);  // 5 m/s
    b[0].submerged_fraction = 0.25f;
    b[0].mass = 120.0f;
    b[1].id = 7;
    b[1].velocity = Vec3(0, 1, 0);
    b[1].submerged_fraction = 0.75f;
    const nlohmann::json j = bodies_json(b, 12);
    EXPECT_EQ(j["count"], 2);
    EXPECT_DOUBLE_EQ(j["submerged_fraction_mean"].get<double>(), 0.5);
    EXPECT_NEAR(j["speed_mean"].get<double>(), 3.0, 1e-6);
    EXPECT_NEAR(j["speed_max"].get<double>(), 5.0, 1e-6);
    EXPECT_EQ(j["inside_bodies"], 12);
    ASSERT_EQ(j["bodies"].size(), 2u);
    EXPECT_EQ(j["bodies"][0]["id"], 3);
    EXPECT_EQ(j["bodies"][0]["shape"], "capsule");
    EXPECT_EQ(j["bodies"][1]["shape"], "box");
    EXPECT_FLOAT_EQ(j["bodies"][0]["position"][2].get<float>(), 3.0f);
    EXPECT_FLOAT_EQ(j["bodies"][0]["mass"].get<float>(), 120.0f);
    EXPECT_FLOAT_EQ(j["bodies"][1]["submerged_fraction"].get<float>(), 0.75f);
}

TEST(RunStatsBodies, NoBodiesIsZeroNotNaN) {
    const nlohmann::json j = bodies_json({}, 0);
    EXPECT_EQ(j["count"], 0);
    EXPECT_EQ(j["submerged_fraction_mean"].get<double>(), 0.0);
    EXPECT_EQ(j["speed_mean"].get<double>(), 0.0);
    EXPECT_TRUE(j["bodies"].empty());
}

}  // namespace
}  // namespace mr::app
