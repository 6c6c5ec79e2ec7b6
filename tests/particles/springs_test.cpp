#include <metariver/particles.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "spring_kernel.h"
#include "require.h"

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

// The AVX2 kernel skips blocks of eight candidates beyond reach; the portable loop
// computes every one. Both must give the same floats bit for bit, including candidates
// a few ulps either side of the reach (where a skip bound without its margin would drop
// a live term), at distance 0, and counts that are not a multiple of 8.
TEST(SpringKernel, Avx2EqualsThePortableLoopBitForBit) {
    if (!spring_kernel::available()) MR_SKIP_OR_FAIL("no AVX2 here");
    Lcg rng(7);
    std::vector<float> cx(spring_kernel::kMaxCandidates + 8), cy(cx.size()), cz(cx.size());
    size_t skipped_some = 0, boundary_live = 0;
    for (int round = 0; round < 400; ++round) {
        const float r = rng.uniform(0.05f, 2.0f), max_d = rng.uniform(0.0f, 1.5f), half_k = rng.uniform(1.0f, 500.0f);
        const float reach = r + max_d;
        const int m = int(rng.uniform(0.0f, float(spring_kernel::kMaxCandidates) + 0.99f));
        const Vec3 xi(rng.uniform(-50.0f, 50.0f), rng.uniform(-50.0f, 50.0f), rng.uniform(-50.0f, 50.0f));
        std::fill(cx.begin(), cx.end(), 0.0f);
        std::fill(cy.begin(), cy.end(), 0.0f);
        std::fill(cz.begin(), cz.end(), 0.0f);
        int far_blocks = 0;
        for (int k = 0; k < m; ++k) {
            // Whole blocks far away (skipped), whole blocks on the reach's sphere (moved by
            // a few ulps either way: a bound without its margin skips them), and mixed
            // blocks: near, on the sphere, or exactly on top of xi.
            const int block_kind = (k / 8) % 3;
            const bool far_block = block_kind == 2;
            far_blocks += far_block && k % 8 == 0;
            Vec3 d(rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f));
            if (glm::length(d) < 1e-3f) d = Vec3(1.0f, 0.0f, 0.0f);
            d = glm::normalize(d);
            float dist = rng.uniform(0.0f, 1.3f * reach);
            const int kind = block_kind == 1 ? 1 : int(rng.uniform(0.0f, 4.0f));
            if (far_block) dist = reach * rng.uniform(1.01f, 3.0f);
            else if (kind == 0) dist = 0.0f;
            else if (kind == 1) dist = std::nextafter(reach, 0.0f) * (1.0f + float(int(rng.uniform(-4.0f, 4.0f))) * 6e-8f);
            const Vec3 c = xi - dist * d;
            cx[size_t(k)] = c.x, cy[size_t(k)] = c.y, cz[size_t(k)] = c.z;
            if (!far_block && kind == 1) {
                const Vec3 dd = xi - c;
                const float len = std::sqrt((dd.x * dd.x + dd.y * dd.y) + dd.z * dd.z);
                boundary_live += len > 0.99f * reach && len - r < max_d;
            }
        }
        float a[3], b[3];
        spring_kernel::sum_portable(xi.x, xi.y, xi.z, cx.data(), cy.data(), cz.data(), m, r, max_d, half_k, a);
        spring_kernel::sum_avx2(xi.x, xi.y, xi.z, cx.data(), cy.data(), cz.data(), m, r, max_d, half_k, b);
        ASSERT_EQ(std::memcmp(a, b, sizeof a), 0) << "round " << round << ", m " << m << ": " << a[0] << " " << a[1]
                                                  << " " << a[2] << " against " << b[0] << " " << b[1] << " " << b[2];
        skipped_some += far_blocks > 0;
    }
    EXPECT_GT(skipped_some, 300u) << "the case must exercise skipped blocks";
    EXPECT_GT(boundary_live, 1000u) << "the case must put live terms just inside the reach";
}

}  // namespace
}  // namespace mr
