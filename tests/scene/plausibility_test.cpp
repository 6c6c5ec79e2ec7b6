// spray_fraction(): the neighbour-grid version against an all-pairs twin written from the
// definition, and two states whose answer is known without computing (0 and 1).
#include <metariver/neighbor_grid.h>
#include <metariver/scene.h>

#include <gtest/gtest.h>

#include <random>
#include <set>
#include <vector>

namespace mr {
namespace {

Terrain make_terrain(const Heightmap& map) {
    auto t = Terrain::build(map, TerrainDef{.area_scale = 1.0f, .height_scale = 7.0f});
    EXPECT_TRUE(t.ok()) << t.error().message;
    return std::move(t.value());
}

/// The definition, O(N^2): isolated (fewer than 3 other active particles closer than
/// the kernel radius) and airborne (more than two spacings above the mesh, or outside
/// the terrain's rectangle), over the active particles.
float spray_brute_force(const Terrain& t, const std::vector<Vec3>& pos, const std::vector<uint8_t>& active,
                        float kernel_radius, float spacing) {
    size_t n_active = 0, spray = 0;
    for (size_t i = 0; i < pos.size(); ++i) {
        if (!active[i]) continue;
        ++n_active;
        const Vec3 p = pos[i];
        const bool airborne = !t.contains_xz(p.x, p.z) || p.y - t.height_mesh(p.x, p.z) > 2.0f * spacing;
        int neighbours = 0;
        for (size_t j = 0; j < pos.size(); ++j) {
            const Vec3 d = pos[j] - p;
            if (j != i && active[j] && d.x * d.x + d.y * d.y + d.z * d.z < kernel_radius * kernel_radius) ++neighbours;
        }
        spray += airborne && neighbours < 3;
    }
    return n_active ? static_cast<float>(double(spray) / double(n_active)) : 0.0f;
}

TEST(SprayFraction, AgreesExactlyWithTheAllPairsDefinition) {
    const Terrain t = make_terrain(procedural_valley(33, 33, 5));
    std::mt19937 rng(1234);
    int mixed = 0;
    std::set<NeighborGrid::Layout> layouts;  // the grid layouts these particles lead to
    for (const float kernel : {0.7f, 1.0f, 1.6f}) {
        for (const float extent : {4.0f, 10.0f, 40.0f}) {  // dense to sparse
            // 1 % far outliers (none, up to 2 x extent, up to 3000 x extent) spread the
            // grid's box: its dense, blocked and hashed layouts.
            for (const float far_scale : {0.0f, 2.0f, 3000.0f}) {
                std::uniform_real_distribution<float> xz(-2.0f, 35.0f), y(-1.0f, 9.0f), u(-extent, extent);
                std::bernoulli_distribution inactive(0.15), far(far_scale > 0.0f ? 0.01 : 0.0);
                const Vec3 centre(xz(rng), y(rng), xz(rng));
                std::vector<Vec3> pos;
                std::vector<uint8_t> active;
                for (int i = 0; i < 1500; ++i) {
                    pos.push_back(far(rng) ? far_scale * Vec3(u(rng), u(rng), u(rng))
                                           : centre + Vec3(u(rng), 0.3f * u(rng), u(rng)));
                    active.push_back(!inactive(rng));
                }
                const float spacing = 0.5f * kernel;
                const float want = spray_brute_force(t, pos, active, kernel, spacing);
                EXPECT_EQ(spray_fraction(t, pos, active, kernel, spacing), want)
                    << "kernel " << kernel << " extent " << extent << " far " << far_scale;
                mixed += want > 0.0f && want < 1.0f;
                NeighborGrid grid;
                grid.build(pos, active, kernel);
                layouts.insert(grid.layout());
            }
        }
    }
    EXPECT_GE(mixed, 15) << "most cases must be mixed, or the comparison proves little";
    EXPECT_EQ(layouts.size(), 3u) << "the particles must reach every grid layout";
}

// A 10 x 10 x 10 lattice block at spacing d resting on flat ground, kernel radius 2d:
// every particle has at least its 7 lattice neighbours of one corner cube (distances
// d, d*sqrt 2, d*sqrt 3 < 2d), so none is isolated; the fraction is 0 although the top
// layers are far more than two spacings above the ground.
TEST(SprayFraction, ZeroForADenseBlockOnFlatGround) {
    const Terrain t = make_terrain(flat_heightmap(21, 21));
    const float d = 0.5f;
    std::vector<Vec3> pos;
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j)
            for (int k = 0; k < 10; ++k)
                pos.emplace_back(5.0f + d * float(i), 0.5f * d + d * float(j), 5.0f + d * float(k));
    const std::vector<uint8_t> active(pos.size(), 1);
    EXPECT_EQ(spray_fraction(t, pos, active, 2.0f * d, d), 0.0f);
    EXPECT_EQ(spray_brute_force(t, pos, active, 2.0f * d, d), 0.0f);
}

// Particles 10 m apart, 50 m above the ground or outside the terrain's rectangle: each
// is isolated and airborne, so the fraction is 1. Inactive particles packed around them
// are not neighbours.
TEST(SprayFraction, OneForIsolatedParticlesFarAboveTheGround) {
    const Terrain t = make_terrain(procedural_bowl(33, 33));
    std::vector<Vec3> pos;
    std::vector<uint8_t> active;
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 4; ++k) {
            const Vec3 p(10.0f * float(i) - 4.0f, 60.0f, 10.0f * float(k) - 4.0f);  // some outside the rectangle
            pos.push_back(p);
            active.push_back(1);
            for (int m = 0; m < 4; ++m) {
                pos.push_back(p + Vec3(0.1f * float(m + 1), 0.0f, 0.0f));
                active.push_back(0);
            }
        }
    pos.emplace_back(-20.0f, -30.0f, 16.0f);  // outside the rectangle, below: still airborne by definition
    active.push_back(1);
    EXPECT_EQ(spray_fraction(t, pos, active, 1.0f, 0.5f), 1.0f);
    // Making the packed ones active: no particle is isolated any more.
    std::vector<uint8_t> all(pos.size(), 1);
    all.back() = 0;
    EXPECT_EQ(spray_fraction(t, pos, all, 1.0f, 0.5f), 0.0f);
}

TEST(SprayFraction, ZeroWithoutActiveParticles) {
    const Terrain t = make_terrain(flat_heightmap(5, 5));
    const std::vector<Vec3> pos{Vec3(1.0f, 30.0f, 1.0f)};
    EXPECT_EQ(spray_fraction(t, pos, std::vector<uint8_t>{0}, 1.0f, 0.5f), 0.0f);
    EXPECT_EQ(spray_fraction(t, {}, {}, 1.0f, 0.5f), 0.0f);
}

// The Simulation picks the scale from its solver: springs use min_distance as the
// spacing (1 m when 0) and twice that as the kernel radius.
TEST(SprayFraction, SimulationUsesTheSolversScale) {
    SceneDef d = springs_valley_scene();
    d.source = {.kind = TerrainSource::Flat, .width = 9, .height = 9};
    d.spawn.count = 2;
    d.spawn.center = Vec3(4.0f, 1.5f, 4.0f);  // 1.5 m up: above two spacings only for spacing < 0.75
    d.spawn.half_extent = Vec3(0.5f, 0.0f, 0.5f);
    d.spawn.interval = 0;
    d.spawn.auto_center = false;
    d.surface = false;
    d.springs.stiffness = 0.0f;
    d.springs.min_distance = 0.5f;
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    sim.value()->step(1.0f / 600.0f);
    EXPECT_EQ(sim.value()->particles().active_count(), 2u);
    EXPECT_EQ(sim.value()->spray_fraction(), 1.0f);
    d.springs.min_distance = 1.0f;  // two spacings = 2 m: the particles are on the ground's side
    sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    sim.value()->step(1.0f / 600.0f);
    EXPECT_EQ(sim.value()->spray_fraction(), 0.0f);
}

}  // namespace
}  // namespace mr
