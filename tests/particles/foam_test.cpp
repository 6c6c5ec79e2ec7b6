// Diffuse particles (src/particles/foam.cpp): made where the fluid is fast and broken,
// never in water at rest; removed when their life ends; classified by neighbour count;
// the same for any thread count; never more than the cap.
#include <metariver/foam.h>
#include <metariver/particles.h>

#include "pbf_simd.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>
#include "require.h"

namespace mr {
namespace {

constexpr float kSpacing = 0.5f, kH = 1.0f, kDt = 1.0f / 60.0f;

Terrain flat_terrain() {
    auto t = Terrain::build(flat_heightmap(33, 33), TerrainDef{.area_scale = 1.0f, .height_scale = 1.0f});
    EXPECT_TRUE(t.ok());
    return std::move(t.value());
}

/// A block of nx x ny x nz fluid particles at the rest spacing, on the ground at (4, 0, 4).
Particles block(int nx, int ny, int nz, Vec3 velocity = Vec3(0.0f)) {
    Particles p;
    for (int y = 0; y < ny; ++y)
        for (int z = 0; z < nz; ++z)
            for (int x = 0; x < nx; ++x) {
                p.position.push_back(Vec3(4.0f, 0.25f, 4.0f) + kSpacing * Vec3(float(x), float(y), float(z)));
                p.velocity.push_back(velocity);
            }
    const size_t n = p.position.size();
    p.last_position = p.position;
    p.force.assign(n, Vec3(0.0f));
    p.active.assign(n, 1);
    p.id.resize(n);
    for (size_t i = 0; i < n; ++i) p.id[i] = uint32_t(i);
    p.birth_frame.assign(n, 0);
    return p;
}

/// Broken water: the top layers of the block shoot along +x at `speed` while the rest
/// stays, and the very top layer also rises (a crest moving along its normal).
void shear(Particles& p, float speed) {
    float top = 0.0f;
    for (const Vec3& x : p.position) top = std::max(top, x.y);
    for (size_t i = 0; i < p.size(); ++i) {
        if (p.position[i].y > top - 1.01f * kSpacing) p.velocity[i] = Vec3(speed, 0.5f * speed, 0.0f);
        else if (p.position[i].y > top - 2.01f * kSpacing) p.velocity[i] = Vec3(speed, 0.0f, 0.0f);
    }
}

/// Moves the fluid one frame along its velocity (what a solver would do, without one).
void drift(Particles& p) {
    for (size_t i = 0; i < p.size(); ++i) p.position[i] += p.velocity[i] * kDt;
}

FoamDef foam_def() {
    FoamDef d;
    d.enabled = true;
    return d;
}

TEST(Foam, NothingInAPoolAtRest) {
    const Terrain t = flat_terrain();
    Particles p = block(20, 6, 20);
    FoamSystem foam(foam_def(), kH, 9.82f);
    for (int f = 0; f < 120; ++f) {
        foam.step(p, t, kDt, uint64_t(f));
        ASSERT_EQ(foam.particles().size(), 0u) << "frame " << f;
    }
    EXPECT_EQ(foam.stats().generated_total, 0u);
    for (float e : foam.kinetic_energy()) EXPECT_EQ(e, 0.0f);
    for (float a : foam.trapped_air()) EXPECT_EQ(a, 0.0f) << "no relative motion, no trapped air";
}

TEST(Foam, UniformFlowTrapsNoAirAndCrestsOnlyAtItsFront) {
    // Water gliding as one body (no relative velocity) traps no air: a steady, unbroken
    // river stays clear although it is fast. Only its leading face moves along its
    // surface normal (a wave crest); the sides, top and back do not.
    const Terrain t = flat_terrain();
    Particles p = block(12, 4, 12, Vec3(3.0f, 0.0f, 0.0f));
    FoamSystem foam(foam_def(), kH, 9.82f);
    foam.step(p, t, kDt, 0);
    float front = 0.0f;
    for (const Vec3& x : p.position) front = std::max(front, x.x);
    size_t crest = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        EXPECT_EQ(foam.trapped_air()[i], 0.0f);
        if (foam.wave_crest()[i] > 0.0f) {
            ++crest;
            EXPECT_GE(p.position[i].x, front - 2.01f * kSpacing) << "a crest away from the leading face";
        }
    }
    EXPECT_GT(crest, 0u) << "the leading face is a crest moving along its normal";
}

TEST(Foam, MadeWhereTheWaterIsFastAndBroken) {
    const Terrain t = flat_terrain();
    Particles p = block(16, 6, 16);
    shear(p, 4.0f);
    FoamSystem foam(foam_def(), kH, 9.82f);
    foam.step(p, t, kDt, 0);
    // Every new particle starts within h/2 (the emission disc) plus one frame's travel of
    // a moving fluid particle: the still lower layers make none.
    for (const Vec3& q : foam.particles().position) {
        float nearest = 1e30f;
        for (size_t i = 0; i < p.size(); ++i)
            if (glm::length(p.velocity[i]) > 0.0f) nearest = std::min(nearest, glm::length(q - p.position[i]));
        EXPECT_LE(nearest, 0.5f * kH + 4.5f * kDt + 1e-4f);
    }
    size_t made = foam.stats().generated;
    for (int f = 1; f < 30; ++f) {
        drift(p);
        foam.step(p, t, kDt, uint64_t(f));
        made += foam.stats().generated;
    }
    EXPECT_GT(made, 100u) << "a sheared, breaking top layer must make diffuse particles";
    EXPECT_GT(foam.stats().total(), 0u);
}

// The potentials' sums eight candidates at a time (AVX2, pbf_simd.h) against the scalar
// passes: the same pairs and formulas in another order, so the same potentials to float
// rounding, on a sheared block whose particles are jittered (irregular normals, a broken
// top: every potential non-zero somewhere).
TEST(Foam, SimdPotentialsAgreeWithTheScalarTwin) {
    if (!pbf_simd::available()) MR_SKIP_OR_FAIL("no AVX2 and FMA on this CPU");
    const Terrain t = flat_terrain();
    Particles p = block(16, 6, 16);
    shear(p, 4.0f);
    Lcg rng(7);
    for (Vec3& x : p.position) x += Vec3(rng.uniform(-0.1f, 0.1f), rng.uniform(-0.1f, 0.1f), rng.uniform(-0.1f, 0.1f));
    FoamSystem fast(foam_def(), kH, 9.82f), twin(foam_def(), kH, 9.82f);
    twin.set_simd(false);
    fast.step(p, t, kDt, 0);
    twin.step(p, t, kDt, 0);
    size_t trapped = 0, crest = 0;
    float worst = 0.0f;
    for (size_t i = 0; i < p.size(); ++i) {
        const float pairs[3][2] = {{fast.trapped_air()[i], twin.trapped_air()[i]},
                                   {fast.wave_crest()[i], twin.wave_crest()[i]},
                                   {fast.kinetic_energy()[i], twin.kinetic_energy()[i]}};
        for (const auto& [a, b] : pairs) {
            EXPECT_NEAR(a, b, 1e-4f * (1.0f + std::abs(b))) << "particle " << i;
            worst = std::max(worst, std::abs(a - b) / (1.0f + std::abs(b)));
        }
        trapped += twin.trapped_air()[i] > 0.0f;
        crest += twin.wave_crest()[i] > 0.0f;
    }
    std::printf("%zu particles: %zu trap air, %zu on a crest; largest difference %.2e (relative)\n", p.size(), trapped,
                crest, worst);
    EXPECT_GT(trapped, 100u);
    EXPECT_GT(crest, 10u);
}

TEST(Foam, ClassifiedByNeighbourCount) {
    const FoamDef d = foam_def();
    EXPECT_EQ(FoamSystem::classify(0, d), DiffuseKind::Spray);
    EXPECT_EQ(FoamSystem::classify(d.spray_neighbours - 1, d), DiffuseKind::Spray);
    EXPECT_EQ(FoamSystem::classify(d.spray_neighbours, d), DiffuseKind::Foam);
    EXPECT_EQ(FoamSystem::classify(d.bubble_neighbours, d), DiffuseKind::Foam);
    EXPECT_EQ(FoamSystem::classify(d.bubble_neighbours + 1, d), DiffuseKind::Bubble);

    // In a run, each particle's kind follows its fluid neighbour count, and that count
    // equals a brute-force count over every fluid particle (the grid's twin).
    // The fluid velocity there is the W~-weighted mean, brute force too. Both walks: the
    // SIMD sums over the cells' ranges (where the CPU has AVX2) and the scalar twin.
    const Terrain t = flat_terrain();
    for (const bool simd : {true, false}) {
        Particles p = block(16, 6, 16);
        shear(p, 5.0f);
        FoamSystem foam(d, kH, 9.82f);
        foam.set_simd(simd);
        size_t kinds[3] = {0, 0, 0};
        float worst = 0.0f;
        for (int f = 0; f < 40; ++f) {
            foam.step(p, t, kDt, uint64_t(f));
            const DiffuseParticles& q = foam.particles();
            for (size_t i = 0; i < q.size(); ++i) {
                int brute = 0;
                float wsum = 0.0f;
                Vec3 vsum(0.0f);
                for (size_t j = 0; j < p.size(); ++j) {
                    const float r2 = glm::dot(q.position[i] - p.position[j], q.position[i] - p.position[j]);
                    if (r2 >= kH * kH) continue;
                    ++brute;
                    const float w = 1.0f - std::sqrt(r2) / kH;
                    wsum += w;
                    vsum += w * p.velocity[j];
                }
                ASSERT_EQ(int(q.neighbours[i]), brute) << "frame " << f << " particle " << i << " simd " << simd;
                ASSERT_EQ(q.kind[i], uint8_t(FoamSystem::classify(brute, d)));
                const Vec3 want = wsum > 0.0f ? vsum / wsum : Vec3(0.0f);
                const float err = glm::length(q.fluid_velocity[i] - want) / (1.0f + glm::length(want));
                ASSERT_LT(err, 1e-5f) << "frame " << f << " particle " << i << " simd " << simd;
                worst = std::max(worst, err);
                ++kinds[q.kind[i]];
            }
            drift(p);
        }
        std::printf("%s: spray %zu, foam %zu, bubbles %zu (particle-frames); fluid velocity within %.1e\n",
                    simd ? "simd" : "scalar", kinds[0], kinds[1], kinds[2], worst);
        EXPECT_GT(kinds[0], 0u) << "spray: thrown clear of the water";
        EXPECT_GT(kinds[1], 0u) << "foam: at the surface";
        const FoamStats& s = foam.stats();
        EXPECT_EQ(s.spray + s.foam + s.bubbles, foam.particles().size());
    }
}

TEST(Foam, RemovedWhenTheirLifeEnds) {
    const Terrain t = flat_terrain();
    FoamDef d = foam_def();
    d.lifetime_min = 0.5f;
    d.lifetime_max = 1.0f;
    Particles p = block(16, 6, 16);
    shear(p, 4.0f);
    FoamSystem foam(d, kH, 9.82f);
    for (int f = 0; f < 10; ++f) {
        foam.step(p, t, kDt, uint64_t(f));
        drift(p);
    }
    const size_t made = foam.particles().size();
    ASSERT_GT(made, 0u);
    for (float l : foam.particles().life) EXPECT_LE(l, d.lifetime_max);
    // The water comes to rest: nothing new; every particle dies within lifetime_max.
    for (Vec3& v : p.velocity) v = Vec3(0.0f);
    size_t expired = 0, left = 0;
    const int frames = int(std::ceil(d.lifetime_max / kDt)) + 1;
    for (int f = 0; f < frames; ++f) {
        foam.step(p, t, kDt, uint64_t(100 + f));
        EXPECT_EQ(foam.stats().generated, 0u);
        expired += foam.stats().expired;
        left += foam.stats().left;
        if (f < int(d.lifetime_min / kDt) - 1) {
            EXPECT_GT(foam.particles().size(), 0u) << "none dies before lifetime_min";
        }
    }
    EXPECT_EQ(foam.particles().size(), 0u);
    EXPECT_EQ(expired + left, made);
    EXPECT_GT(expired, 0u);
}

TEST(Foam, RemovedWhenTheyLeaveTheTerrain) {
    const Terrain t = flat_terrain();
    FoamDef d = foam_def();
    d.lifetime_min = d.lifetime_max = 100.0f;
    // A fast block at the terrain's +x edge, shooting outwards.
    Particles p = block(6, 4, 6);
    for (Vec3& x : p.position) x.x += 24.5f;
    shear(p, 6.0f);
    FoamSystem foam(d, kH, 9.82f);
    foam.step(p, t, kDt, 0);
    ASSERT_GT(foam.particles().size(), 0u);
    for (Vec3& v : p.velocity) v = Vec3(0.0f);
    for (Vec3& x : p.position) x.x -= 20.0f;  // the fluid leaves; the diffuse particles keep flying out
    size_t left = 0;
    for (int f = 0; f < 240 && foam.particles().size() > 0; ++f) {
        foam.step(p, t, kDt, uint64_t(f + 1));
        left += foam.stats().left;
        for (const Vec3& x : foam.particles().position) {
            EXPECT_GE(x.x, t.bounds().min.x);
            EXPECT_LE(x.x, t.bounds().max.x);
        }
    }
    EXPECT_EQ(foam.particles().size(), 0u) << "spray lands or flies off the terrain";
    EXPECT_GT(left, 0u);
}

TEST(Foam, NeverMoreThanTheCap) {
    const Terrain t = flat_terrain();
    FoamDef d = foam_def();
    d.max_particles = 150;
    Particles p = block(16, 6, 16);
    shear(p, 5.0f);
    FoamSystem foam(d, kH, 9.82f);
    for (int f = 0; f < 30; ++f) {
        foam.step(p, t, kDt, uint64_t(f));
        ASSERT_LE(foam.particles().size(), 150u);
        drift(p);
    }
    EXPECT_EQ(foam.particles().size(), 150u) << "the cap is reached";
    EXPECT_GT(foam.stats().capped_total, 0u);

    d.max_particles = 0;
    FoamSystem none(d, kH, 9.82f);
    none.step(p, t, kDt, 0);
    EXPECT_EQ(none.particles().size(), 0u);
}

TEST(Foam, SameResultForAnyThreadCount) {
    const Terrain t = flat_terrain();
    auto run = [&](int threads) {
        tbb::global_control gc(tbb::global_control::max_allowed_parallelism, size_t(threads));
        Particles p = block(24, 6, 24);
        shear(p, 5.0f);
        FoamSystem foam(foam_def(), kH, 9.82f);
        for (int f = 0; f < 60; ++f) {
            foam.step(p, t, kDt, uint64_t(f));
            drift(p);
        }
        EXPECT_GT(foam.particles().size(), 500u);
        return foam.state_hash();
    };
    const uint64_t one = run(1);
    EXPECT_EQ(run(2), one);
    EXPECT_EQ(run(4), one);
}

}  // namespace
}  // namespace mr
