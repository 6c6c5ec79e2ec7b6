// Particle ages for exporters: Particles::birth_frame is the solver frame of a
// particle's latest emission and follows the particle (by its stable id) through the
// solver's reordering by grid cell and the pool's swaps.
#include <metariver/scene.h>
#include <metariver/workloads.h>

#include <gtest/gtest.h>

#include <set>
#include <unordered_map>

namespace mr {
namespace {

/// Steps `def` for `frames` frames and checks, after every frame, that each active
/// particle's birth frame is the one it had before (found by id) or, when it was
/// (re)emitted during the frame, the frame just stepped. Returns the distinct births seen.
std::set<uint32_t> check_births(const SceneDef& def, int frames) {
    auto sim = Simulation::create(def);
    EXPECT_TRUE(sim.ok()) << (sim.ok() ? "" : sim.error().message);
    if (!sim.ok()) return {};
    Simulation& s = *sim.value();
    std::unordered_map<uint32_t, uint32_t> before;  // id -> birth frame, active particles of the previous frame
    std::set<uint32_t> births;
    for (int f = 0; f < frames; ++f) {
        s.step(1.0f / 60.0f);
        const Particles& p = s.particles();
        EXPECT_EQ(p.birth_frame.size(), p.size());
        std::unordered_map<uint32_t, uint32_t> now;
        for (size_t i = 0; i < p.size(); ++i) {
            if (!p.active[i]) continue;
            const uint32_t b = p.birth_frame[i];
            now[p.id[i]] = b;
            births.insert(b);
            EXPECT_LE(b, static_cast<uint32_t>(f)) << "born after the frame just stepped, id " << p.id[i];
            const auto it = before.find(p.id[i]);
            if (it == before.end()) {
                EXPECT_EQ(b, static_cast<uint32_t>(f)) << "newly active particle " << p.id[i] << " at frame " << f;
            } else if (b != it->second) {
                EXPECT_EQ(b, static_cast<uint32_t>(f)) << "birth changed without a re-emission, id " << p.id[i];
            }
        }
        before.swap(now);
        if (::testing::Test::HasFailure()) break;
    }
    return births;
}

TEST(ParticleAge, PbfRiverBirthFramesFollowTheParticlesThroughReordering) {
    SceneDef d = default_scene();
    d.spawn.count = 1500;  // the default source (420/s) is still emitting after 120 frames
    const std::set<uint32_t> births = check_births(d, 120);
    // Emission spreads over the frames: many distinct birth frames, not one.
    EXPECT_GT(births.size(), 50u);
}

TEST(ParticleAge, GridSpringRiverBirthFramesFollowTheParticles) {
    // river_scene: springs through the neighbour grid (arrays sorted by cell every step);
    // one activation per frame instead of all at once.
    SceneDef d = river_scene(400);
    d.spawn.interval = 1;
    const std::set<uint32_t> births = check_births(d, 90);
    EXPECT_GT(births.size(), 60u);
}

}  // namespace
}  // namespace mr
