#include <metariver/particles.h>

#include <gtest/gtest.h>

namespace mr {
namespace {

Particles random_particles(size_t n, uint32_t seed, float extent) {
    Particles p;
    p.resize(n);
    Lcg rng(seed);
    for (size_t i = 0; i < n; ++i) {
        p.position[i] = Vec3(rng.uniform(0, extent), rng.uniform(0, extent), rng.uniform(0, extent));
        p.active[i] = (i % 7) != 3;  // some inactive particles must be ignored
    }
    return p;
}

TEST(Springs, PairForceMatchesEquation3) {
    Particles p;
    p.resize(2);
    p.active = {1, 1};
    p.position[0] = Vec3(0, 0, 0);
    p.position[1] = Vec3(1, 0, 0);  // distance 1 < r = 3: pushed apart
    SpringDef def{.stiffness = 4.0f, .min_distance = 3.0f, .max_distance = 5.0f};
    add_spring_forces_pairs(p, def);
    // v = p0 - p1 = (-1,0,0), |v| = 1: a = 0.5 * 4 * (3 * (-1,0,0) - (-1,0,0)) = (-4,0,0)
    EXPECT_FLOAT_EQ(p.force[0].x, -4.0f);
    EXPECT_FLOAT_EQ(p.force[1].x, 4.0f);
    EXPECT_FLOAT_EQ(p.force[0].y, 0.0f);
}

TEST(Springs, PullsBackBeyondRestLengthAndCutsOffBeyondMaxDistance) {
    SpringDef def{.stiffness = 1.0f, .min_distance = 3.0f, .max_distance = 5.0f};
    Particles p;
    p.resize(2);
    p.active = {1, 1};
    p.position[0] = Vec3(0, 0, 0);
    p.position[1] = Vec3(0, 0, 7.9f);  // |v| - r = 4.9 < 5: attracted
    add_spring_forces_pairs(p, def);
    EXPECT_GT(p.force[0].z, 0.0f);
    EXPECT_LT(p.force[1].z, 0.0f);

    std::fill(p.force.begin(), p.force.end(), Vec3(0.0f));
    p.position[1] = Vec3(0, 0, 8.0f);  // |v| - r = 5: cut off (strict <)
    add_spring_forces_pairs(p, def);
    EXPECT_EQ(p.force[0], Vec3(0.0f));
    EXPECT_EQ(p.force[1], Vec3(0.0f));
}

TEST(Springs, ZeroStiffnessAndInactiveParticlesAddNothing) {
    Particles p = random_particles(50, 3, 4.0f);
    add_spring_forces_pairs(p, SpringDef{.stiffness = 0.0f});
    for (const Vec3& f : p.force) EXPECT_EQ(f, Vec3(0.0f));
    add_spring_forces_pairs(p, SpringDef{.stiffness = 10.0f});
    for (size_t i = 0; i < p.size(); ++i)
        if (!p.active[i]) {
            EXPECT_EQ(p.force[i], Vec3(0.0f));
        }
}

TEST(Springs, ConserveMomentum) {
    for (uint32_t seed : {1u, 2u, 3u, 99u}) {
        Particles p = random_particles(300, seed, 6.0f);
        add_spring_forces_pairs(p, SpringDef{.stiffness = 25.0f, .min_distance = 1.5f, .max_distance = 2.0f});
        glm::dvec3 total(0.0), magnitude(0.0);
        for (const Vec3& f : p.force) {
            total += glm::dvec3(f);
            magnitude += glm::abs(glm::dvec3(f));
        }
        ASSERT_GT(magnitude.x + magnitude.y + magnitude.z, 1.0) << "springs must act in this setup";
        // Equal and opposite per pair: the sum cancels up to float rounding of the
        // per-particle accumulation (~1e-6 relative to the summed magnitudes).
        EXPECT_NEAR(total.x, 0.0, 1e-5 * magnitude.x);
        EXPECT_NEAR(total.y, 0.0, 1e-5 * magnitude.y);
        EXPECT_NEAR(total.z, 0.0, 1e-5 * magnitude.z);
    }
}

}  // namespace
}  // namespace mr
