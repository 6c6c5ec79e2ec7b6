// The hybrid's frame runs the grid and the particles side by side (parallel_invoke in
// HybridSolver::step_frame) and the seam's passes in parallel: the state and the surface
// after a second of the waterfall, with water handed both ways, are the same bits at one
// and two threads. Short, so that preset tsan runs it too (label hybrid_threads).
#include <metariver/hybrid_solver.h>
#include <metariver/scene.h>
#include <metariver/scene_keys.h>
#include <metariver/surface.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>

namespace mr {
namespace {

uint64_t fnv(uint64_t h, const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t k = 0; k < bytes; ++k) h = (h ^ p[k]) * 1099511628211ull;
    return h;
}

uint64_t surface_hash(const SurfaceMesh& m) {
    uint64_t h = 14695981039346656037ull;
    h = fnv(h, m.positions.data(), m.positions.size() * sizeof(Vec3));
    h = fnv(h, m.normals.data(), m.normals.size() * sizeof(Vec3));
    return fnv(h, m.indices.data(), m.indices.size() * sizeof(uint32_t));
}

TEST(HybridThreads, TheWaterfallIsTheSameAtOneAndTwoThreads) {
    uint64_t state[2] = {0, 0}, surface[2] = {0, 0};
    for (int t = 1; t <= 2; ++t) {
        auto sim = Simulation::create(preset("waterfall").value());
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        Simulation& s = *sim.value();
        ASSERT_TRUE(s.set_threads(t).ok());
        for (int f = 0; f < 60; ++f) s.step(1.0f / 60.0f);
        const HybridStats& st = dynamic_cast<const HybridSolver&>(s.solver()).stats();
        state[t - 1] = s.state_hash();
        surface[t - 1] = surface_hash(s.surface());
        std::printf("threads %d: state %016llx surface %016llx (%zu triangles), %.3f m^3 to particles, %.3f m^3 back\n", t,
                    (unsigned long long)state[t - 1], (unsigned long long)surface[t - 1], s.surface().triangle_count(),
                    st.to_particles, st.to_grid);
        // Both ways handed over within the second, and both drawn: the test covers the exchange and the seam.
        EXPECT_GT(st.to_particles, 0.0);
        EXPECT_GT(st.to_grid, 0.0);
        EXPECT_GT(s.particles().active_count(), 0u);
        EXPECT_GT(s.surface().triangle_count(), 0u);
    }
    EXPECT_EQ(state[0], state[1]);
    EXPECT_EQ(surface[0], surface[1]);
}

}  // namespace
}  // namespace mr
