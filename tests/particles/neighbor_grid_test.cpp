#include <metariver/neighbor_grid.h>
#include <metariver/particles.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <set>

namespace mr {
namespace {

Particles random_particles(size_t n, uint32_t seed, Vec3 extent, float inactive_fraction = 0.1f) {
    Particles p;
    p.resize(n);
    Lcg rng(seed);
    for (size_t i = 0; i < n; ++i) {
        p.position[i] = Vec3(rng.uniform(0, extent.x), rng.uniform(0, extent.y), rng.uniform(0, extent.z));
        p.active[i] = rng.next() >= inactive_fraction;
    }
    return p;
}

TEST(NeighborGrid, CandidatesContainEveryParticleWithinOneCellDenseAndHashed) {
    struct Case {
        size_t n;
        Vec3 extent;
        float cell;
    };
    // Compact clouds give a dense grid; a cloud spread far (> 32 cells per particle)
    // forces the hash table.
    for (const Case& c : {Case{500, Vec3(5, 5, 5), 0.7f}, Case{2000, Vec3(300, 2, 300), 0.5f},
                          Case{300, Vec3(1e4f, 1e4f, 1e4f), 50.0f}}) {
        Particles p = random_particles(c.n, 17, c.extent);
        NeighborGrid g;
        g.build(p.position, p.active, c.cell);
        const bool hashed = g.hashed();
        for (size_t i = 0; i < p.size(); i += 3) {
            std::set<uint32_t> cand;
            g.for_each_candidate(p.position[i], [&](uint32_t j) {
                EXPECT_TRUE(p.active[j]) << "inactive particles are never binned";
                EXPECT_TRUE(cand.insert(j).second) << "candidate visited twice";
            });
            for (size_t j = 0; j < p.size(); ++j) {
                if (p.active[j] && glm::length(p.position[i] - p.position[j]) < c.cell) {
                    ASSERT_TRUE(cand.count(static_cast<uint32_t>(j))) << "missed neighbour, hashed=" << hashed;
                }
            }
        }
        if (c.n == 2000) {
            EXPECT_TRUE(hashed);
        }
        if (c.n == 500) {
            EXPECT_FALSE(hashed);
        }
    }
}

TEST(NeighborGrid, GridSpringForcesEqualThePaperPairLoop) {
    for (uint32_t seed : {1u, 2u, 3u}) {
        for (float spread : {3.0f, 12.0f, 400.0f}) {
            Particles a = random_particles(700, seed, Vec3(spread, spread * 0.3f, spread));
            Particles b = a;
            SpringDef def{.stiffness = 20.0f, .min_distance = 1.0f, .max_distance = 0.7f, .mode = SpringMode::Grid};
            add_spring_forces_pairs(a, def);
            NeighborGrid g;
            g.build(b.position, b.active, spring_reach(def));
            add_spring_forces_grid(b, g, def);
            size_t nonzero = 0;
            for (size_t i = 0; i < a.size(); ++i) {
                nonzero += glm::length(a.force[i]) > 0.0f;
                // Same terms summed in a different order: float rounding of up to ~50
                // terms of magnitude <= k r, relative 1e-5 of the term scale.
                ASSERT_NEAR(a.force[i].x, b.force[i].x, 1e-4f * 20.0f) << i;
                ASSERT_NEAR(a.force[i].y, b.force[i].y, 1e-4f * 20.0f) << i;
                ASSERT_NEAR(a.force[i].z, b.force[i].z, 1e-4f * 20.0f) << i;
            }
            if (spread < 100.0f) {
                EXPECT_GT(nonzero, 100u) << "the case must exercise springs";
            }
        }
    }
}

}  // namespace
}  // namespace mr
