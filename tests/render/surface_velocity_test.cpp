// The fluid's velocity at the water surface's vertices (the flow detail's input):
// the grid gather against the all-pairs twin on random and real inputs, the Shepard
// average's partition of unity, zero far from the water, and thread-count determinism.
// No OpenGL needed.
#include <metariver/render.h>
#include <metariver/scene.h>

#include "bowl_drop.h"
#include "render_support.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

using namespace mr;

namespace {

/// Random particles in a 12 x 4 x 12 m box (a quarter inactive) with random velocities.
Particles random_particles(size_t n, Lcg& rng) {
    Particles p;
    p.resize(n);
    for (size_t i = 0; i < n; ++i) {
        p.position[i] = Vec3(rng.uniform(0.0f, 12.0f), rng.uniform(0.0f, 4.0f), rng.uniform(0.0f, 12.0f));
        p.velocity[i] = Vec3(rng.uniform(-2.0f, 2.0f), rng.uniform(-0.5f, 0.5f), rng.uniform(-2.0f, 2.0f));
        p.active[i] = rng.uniform(0.0f, 1.0f) < 0.75f ? 1 : 0;
        p.id[i] = static_cast<uint32_t>(i);
    }
    return p;
}

/// Largest difference between two velocity lists, relative to the largest speed (m/s).
float max_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    EXPECT_EQ(a.size(), b.size());
    float worst = 0.0f;
    for (size_t i = 0; i < a.size() && i < b.size(); ++i) worst = std::max(worst, glm::length(a[i] - b[i]));
    return worst;
}

}  // namespace

TEST(SurfaceVelocity, GridGatherEqualsAllPairsOnRandomPoints) {
    Lcg rng(7);
    const Particles p = random_particles(3000, rng);
    std::vector<Vec3> vertices(2000);
    for (Vec3& v : vertices)  // some outside the particles' box: no neighbour there
        v = Vec3(rng.uniform(-2.0f, 14.0f), rng.uniform(-1.0f, 5.0f), rng.uniform(-2.0f, 14.0f));
    for (float radius : {0.4f, 1.0f, 2.5f}) {
        render::SurfaceVelocityWorkspace ws;
        std::vector<Vec3> fast, slow;
        render::surface_velocities(vertices, p, radius, ws, fast);
        render::surface_velocities_brute(vertices, p, radius, slow);
        size_t zero = 0;
        for (const Vec3& v : slow) zero += v == Vec3(0.0f);
        // The sums run in another order (grid cells vs index): float rounding only,
        // a few ulps of speeds up to 2 m/s.
        EXPECT_LT(max_difference(fast, slow), 1e-5f) << "radius " << radius;
        EXPECT_GT(zero, 0u) << "some vertices lie beyond every particle's reach (radius " << radius << ")";
        EXPECT_LT(zero, vertices.size()) << "radius " << radius;
    }
}

TEST(SurfaceVelocity, UniformFlowIsReproducedAndFarVerticesAreStill) {
    Lcg rng(3);
    Particles p = random_particles(2000, rng);
    const Vec3 flow(1.25f, -0.5f, 0.75f);
    for (Vec3& v : p.velocity) v = flow;
    std::vector<Vec3> vertices{Vec3(6.0f, 2.0f, 6.0f), Vec3(0.5f, 0.5f, 11.5f), Vec3(6.0f, 30.0f, 6.0f)};
    render::SurfaceVelocityWorkspace ws;
    std::vector<Vec3> out;
    render::surface_velocities(vertices, p, 1.0f, ws, out);
    ASSERT_EQ(out.size(), 3u);
    // A weighted average of equal vectors is that vector (normalised weights: rounding only).
    EXPECT_LT(glm::length(out[0] - flow), 1e-5f);
    EXPECT_LT(glm::length(out[1] - flow), 1e-5f);
    EXPECT_EQ(out[2], Vec3(0.0f)) << "26 m above the particles: no flow there";
    for (Vec3& v : p.velocity) v = Vec3(0.0f);
    render::surface_velocities(vertices, p, 1.0f, ws, out);
    for (const Vec3& v : out) EXPECT_EQ(v, Vec3(0.0f)) << "particles at rest: exactly zero (the shader adds nothing)";
}

TEST(SurfaceVelocity, RealSurfaceMatchesTwinAndIsTheSameForAnyThreadCount) {
    // A splash in the bowl (the default river's fluid): a real mesh over real particles.
    SceneDef d = test::bowl_drop(1200, Vec3(16, 6, 16), Vec3(2.5f, 1.0f, 2.5f));
    d.spawn.initial_velocity = Vec3(3.0f, -6.0f, 0.0f);
    d.foam.enabled = false;
    auto sim = test::stepped(d, 30);
    ASSERT_TRUE(sim);
    const SurfaceMesh& m = sim->surface();
    ASSERT_GT(m.positions.size(), 1000u);
    const float radius = flow_radius(d);
    EXPECT_EQ(radius, d.field.radius) << "poly6 field: its support";
    std::vector<Vec3> one, two, slow;
    render::SurfaceVelocityWorkspace ws;
    {
        tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
        render::surface_velocities(m.positions, sim->particles(), radius, ws, one);
    }
    {
        tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 2);
        render::surface_velocities(m.positions, sim->particles(), radius, ws, two);
    }
    render::surface_velocities_brute(m.positions, sim->particles(), radius, slow);
    EXPECT_EQ(one, two) << "per-vertex gathers in the grid's fixed order";
    EXPECT_LT(max_difference(one, slow), 1e-4f) << "float rounding of speeds up to ~10 m/s";
    size_t moving = 0, none = 0;
    for (const Vec3& v : one) {
        moving += glm::length(v) > 0.5f;
        none += v == Vec3(0.0f);
    }
    EXPECT_GT(moving, m.positions.size() / 2) << "the splash moves";
    EXPECT_EQ(none, 0u) << "every vertex of a poly6 surface has a particle within the support";
}
