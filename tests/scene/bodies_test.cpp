// Bodies in the water (issue 44): draft, level rise, inside count, determinism.
#include <metariver/scene.h>

#include "bodies_pool.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

namespace mr {
namespace {

/// The level of the water farther than `clear` from (4, 4) horizontally: the mean height
/// of the highest particle per 2-spacing column, plus half a spacing.
float level_away(const Simulation& s, float spacing, float clear) {
    const Particles& p = s.particles();
    const int n = int(6.0f / (2.0f * spacing)) + 1;
    std::vector<float> top(size_t(n * n), -1e30f);
    for (size_t i = 0; i < p.size(); ++i) {
        if (!p.active[i]) continue;
        const Vec3 x = p.position[i];
        if (std::max(std::abs(x.x - 4.0f), std::abs(x.z - 4.0f)) < clear) continue;
        const int a = std::clamp(int((x.x - 1.0f) / (2.0f * spacing)), 0, n - 1);
        const int b = std::clamp(int((x.z - 1.0f) / (2.0f * spacing)), 0, n - 1);
        top[size_t(a * n + b)] = std::max(top[size_t(a * n + b)], x.y);
    }
    double sum = 0.0;
    int cnt = 0;
    for (float t : top)
        if (t > -1e29f) sum += t, ++cnt;
    return cnt ? float(sum / cnt) + 0.5f * spacing : 0.0f;
}

TEST(Bodies, FloatExperiment) {
    const float s = 0.2f;
    test::Pool pool = test::still_pool(s, 8);
    auto sim = Simulation::create(pool.def, pool.map);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& w = *sim.value();
    for (int f = 0; f < 60; ++f) w.step(1.0f / 60.0f);
    const float level0 = level_away(w, s, 0.0f);
    std::printf("particles %zu level0 %.3f (lattice depth %.3f)\n", w.particles().size(), level0, pool.depth);
    const float H = 1.0f;
    for (float rho : {250.0f, 500.0f, 750.0f}) {
        BodyDef b;
        b.shape = BodyShape::Box;
        b.size = Vec3(1.2f, H, 1.2f);
        b.density = rho;
        b.position = Vec3(4.0f, level0 + 0.5f * H - 0.0f, 4.0f);
        auto id = w.add_body(b);
        ASSERT_TRUE(id.ok()) << id.error().message;
        for (int f = 0; f < 600; ++f) {
            w.step(1.0f / 60.0f);
            if (f % 60 == 59) {
                const BodyState& st = w.bodies()[0];
                const float level = level_away(w, s, 1.2f);
                std::printf("rho %.0f t %.0f y %.3f draft %.3f (want %.3f) speed %.3f level %.3f sub %.2f inside %llu\n", rho,
                            (f + 1) / 60.0f, st.position.y, level - (st.position.y - 0.5f * H), rho / 1000.0f * H,
                            glm::length(st.velocity), level, st.submerged_fraction,
                            (unsigned long long)w.counters().inside_bodies);
            }
        }
        ASSERT_TRUE(w.remove_body(id.value()).ok());
    }
}

}  // namespace
}  // namespace mr
