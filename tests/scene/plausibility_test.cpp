// spray_fraction(): the neighbour-grid version against an all-pairs twin written from the
// definition, and two states whose answer is known without computing (0 and 1).
// ChannelCoverage against its all-pairs twin and constructed answers (0, 1/2, 1);
// OutletMeter's assignment of exits to outlets and its rates.
#include <metariver/neighbor_grid.h>
#include <metariver/scene.h>
#include <metariver/spring_solver.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

/// 33 columns (x) x 17 rows (z), 1 m samples, 8 m relief. `v` = 0: a plane falling
/// along +x (every low-edge cell is an outlet); `v` > 0: also falling towards row 8 by
/// `v` of the relief, so all water gathers into row 8 and leaves at cell (8, 32) alone.
Terrain ramp_terrain(float v) {
    Heightmap m = flat_heightmap(33, 17);
    for (int r = 0; r < 17; ++r)
        for (int c = 0; c < 33; ++c)
            m.samples[size_t(r) * 33 + c] = v * float(std::abs(r - 8)) / 8.0f + (1.0f - v) * (1.0f - float(c) / 32.0f);
    auto t = Terrain::build(m, TerrainDef{.area_scale = 1.0f, .height_scale = 8.0f});
    EXPECT_TRUE(t.ok()) << t.error().message;
    return std::move(t.value());
}

/// The definition, O(cells x particles): a cell is covered when an active particle is
/// within 1.5 samples horizontally of its centre and at most 3 m above its ground sample.
float coverage_brute_force(const Terrain& t, std::span<const std::pair<int, int>> cells, const std::vector<Vec3>& pos,
                           const std::vector<uint8_t>& active) {
    const float s = t.area_scale(), r = 1.5f * s;
    size_t covered = 0;
    for (const auto& [i, j] : cells) {
        bool wet = false;
        for (size_t k = 0; k < pos.size() && !wet; ++k) {
            const float dx = pos[k].x - float(j) * s, dz = pos[k].z - float(i) * s;
            wet = active[k] && dx * dx + dz * dz <= r * r && pos[k].y - t.sample(i, j) <= 3.0f;
        }
        covered += wet;
    }
    return cells.empty() ? 0.0f : float(double(covered) / double(cells.size()));
}

TEST(ChannelCoverage, AgreesExactlyWithTheDefinition) {
    for (const float scale : {1.0f, 2.5f}) {
        auto t = Terrain::build(procedural_valley(65, 97, 7), TerrainDef{.area_scale = scale, .height_scale = 24.0f});
        ASSERT_TRUE(t.ok());
        const ChannelMap m = ChannelMap::build(t.value());
        const auto path = m.path_from(m.main_head().first, m.main_head().second);
        const ChannelCoverage cov(t.value(), path);
        ASSERT_EQ(cov.cells(), path.size());
        std::mt19937 rng(99);
        int mixed = 0;
        for (int trial = 0; trial < 12; ++trial) {
            // Particles scattered around random path cells (some off the grid, some high).
            std::uniform_int_distribution<size_t> cell(0, path.size() - 1);
            std::normal_distribution<float> off(0.0f, 2.0f * scale), up(1.0f, 2.5f);
            std::bernoulli_distribution inactive(0.2);
            std::vector<Vec3> pos;
            std::vector<uint8_t> active;
            const int n = 5 * (trial + 1);
            for (int k = 0; k < n; ++k) {
                const auto [i, j] = path[cell(rng)];
                pos.emplace_back(float(j) * scale + off(rng), t.value().sample(i, j) + up(rng),
                                 float(i) * scale + off(rng));
                active.push_back(!inactive(rng));
            }
            pos.emplace_back(-1e9f, 0.0f, 5.0f);  // far off the grid
            active.push_back(1);
            const float want = coverage_brute_force(t.value(), path, pos, active);
            EXPECT_EQ(cov.measure(pos, active), want) << "scale " << scale << " trial " << trial;
            mixed += want > 0.0f && want < 1.0f;
        }
        EXPECT_GE(mixed, 10) << "mostly partial coverage, or the comparison proves little";
    }
}

TEST(ChannelCoverage, OneAlongTheWholePathNoneWithoutWaterHalfForHalf) {
    const Terrain t = ramp_terrain(0.0f);
    const ChannelMap m = ChannelMap::build(t);
    const auto path = m.path_from(8, 1);  // columns 1 .. 32 of row 8
    ASSERT_EQ(path.size(), 32u);
    const ChannelCoverage cov(t, path);
    auto at = [&](float i, float j, float up) { return Vec3(j, t.height_mesh(j, i) + up, i); };
    std::vector<Vec3> pos;
    for (const auto& [i, j] : path) pos.push_back(at(float(i), float(j), 1.0f));
    std::vector<uint8_t> on(pos.size(), 1), off(pos.size(), 0);
    EXPECT_EQ(cov.measure(pos, on), 1.0f);
    EXPECT_EQ(cov.measure(pos, off), 0.0f) << "inactive particles are no water";
    EXPECT_EQ(cov.measure({}, {}), 0.0f);
    // 1.2 samples to the side of columns 1 .. 16: each is within 1.5 samples of its own
    // cell only (the next one is sqrt(1.2^2 + 1) = 1.56 away): exactly half.
    std::vector<Vec3> side;
    for (int j = 1; j <= 16; ++j) side.push_back(at(9.2f, float(j), 0.5f));
    EXPECT_EQ(cov.measure(side, std::vector<uint8_t>(side.size(), 1)), 0.5f);
    // Exactly 1.5 samples counts: one particle at x = 2.5 covers columns 1 .. 4.
    const std::vector<Vec3> one{at(8.0f, 2.5f, 0.5f)};
    EXPECT_EQ(cov.measure(one, std::vector<uint8_t>{1}), 4.0f / 32.0f);
    // 1.6 samples to the side: too far; 3.5 m up: too high; 2.9 m up: water.
    std::vector<Vec3> far, high, deep;
    for (const auto& [i, j] : path) {
        far.push_back(at(float(i) + 1.6f, float(j), 0.5f));
        high.push_back(Vec3(float(j), t.sample(i, j) + 3.5f, float(i)));
        deep.push_back(Vec3(float(j), t.sample(i, j) + 2.9f, float(i)));
    }
    EXPECT_EQ(cov.measure(far, on), 0.0f);
    EXPECT_EQ(cov.measure(high, on), 0.0f);
    EXPECT_EQ(cov.measure(deep, on), 1.0f);
}

TEST(OutletMeter, ExitsGoToTheMainOutletWithinItsRadiusElseTheNearestOrToOther) {
    // The plane: every low-edge cell is an outlet; the main channel from (8, 1) leaves at (8, 32).
    const Terrain plane = ramp_terrain(0.0f);
    const ChannelMap pm = ChannelMap::build(plane);
    const OutletMeter p(plane, pm, pm.outlet_of(8, 1));
    ASSERT_EQ(p.outlets().size(), 17u);
    auto cell = [&](const OutletMeter& m, int k) { return std::pair(m.outlets()[size_t(k)].row, m.outlets()[size_t(k)].column); };
    const int main = p.assign(Vec3(32.3f, 0.0f, 8.1f));
    ASSERT_GE(main, 0);
    EXPECT_TRUE(p.outlets()[size_t(main)].main);
    EXPECT_EQ(cell(p, main), std::pair(8, 32));
    const int beside = p.assign(Vec3(32.3f, 0.0f, 2.2f));
    ASSERT_GE(beside, 0);
    EXPECT_EQ(cell(p, beside), std::pair(2, 32)) << "another outlet, not the main one";
    EXPECT_FALSE(p.outlets()[size_t(beside)].main);
    EXPECT_EQ(cell(p, p.assign(Vec3(32.3f, 0.0f, 9.9f))), std::pair(8, 32))
        << "nearer the outlet cell (10, 32), but within the main mouth's 3 m: the river's";
    EXPECT_EQ(cell(p, p.assign(Vec3(32.3f, 0.0f, 11.2f))), std::pair(11, 32)) << "beyond the mouth's 3 m";
    EXPECT_EQ(p.assign(Vec3(-0.3f, 5.0f, 8.0f)), -1) << "over the upstream edge";
    EXPECT_EQ(p.assign(Vec3(5.0f, 5.0f, -0.3f)), -1) << "over a side edge, far from the outlets";
    EXPECT_EQ(cell(p, p.assign(Vec3(31.0f, 5.0f, -0.3f))), std::pair(0, 32)) << "over a side edge, at the corner outlet";

    // The V: one outlet, (8, 32); within max(3 samples, 3 m) = 3 m along the border, or other.
    const Terrain v = ramp_terrain(0.5f);
    const ChannelMap vm = ChannelMap::build(v);
    ASSERT_EQ(vm.outlets().size(), 1u);
    EXPECT_EQ(vm.outlet_of(8, 1), std::pair(8, 32));
    const OutletMeter o(v, vm, vm.outlet_of(8, 1));
    // Measured along the border: a fast particle 1.5 m past the edge counts where it crossed.
    EXPECT_EQ(o.assign(Vec3(33.5f, 3.0f, 8.0f + 2.9f)), 0);
    EXPECT_EQ(o.assign(Vec3(33.5f, 3.0f, 8.0f - 2.9f)), 0);
    EXPECT_EQ(o.assign(Vec3(32.1f, 3.0f, 8.0f + 3.1f)), -1);
    EXPECT_EQ(o.assign(Vec3(std::nanf(""), 3.0f, 8.0f)), -1);
}

TEST(OutletMeter, CountsRatesOverTheSecondHalfAndTheFirstExit) {
    const Terrain v = ramp_terrain(0.5f);
    const ChannelMap vm = ChannelMap::build(v);
    OutletMeter o(v, vm, vm.outlet_of(8, 1));
    const Vec3 main(32.2f, 1.0f, 8.0f), spray(-0.2f, 9.0f, 8.0f);
    // 16 frames at t = 1 .. 16 s: the second half is frames 9 .. 15 (t 10 .. 16, 7 s).
    for (int k = 0; k < 16; ++k) {
        std::vector<Vec3> exits;
        if (k == 2) exits = {main};
        if (k == 3) exits = {spray};
        if (k >= 9) exits = {main, main};
        o.record(double(k + 1), exits);
    }
    const OutletMeter::Summary s = o.summary();
    ASSERT_EQ(s.outlets.size(), 1u);
    EXPECT_EQ(s.main.particles, 15u);
    EXPECT_DOUBLE_EQ(s.main.rate, 14.0 / 7.0);
    EXPECT_EQ(s.main.first_s, 3.0);
    EXPECT_EQ(s.other.particles, 1u);
    EXPECT_EQ(s.other.rate, 0.0);
    EXPECT_EQ(s.other.first_s, 4.0);
    EXPECT_EQ(OutletMeter(v, vm, vm.outlet_of(8, 1)).summary().main.first_s, -1.0);
}

// A solver with the outlet-edge sink on the V: water let go at the top runs to the main
// outlet; water thrown back over the upstream edge is "other", never the main outlet.
TEST(OutletMeter, WaterThrownOverTheUpstreamEdgeIsNotTheMainOutlet) {
    const Terrain v = ramp_terrain(0.5f);
    auto bvh = Bvh::build(v, BvhDef{});
    ASSERT_TRUE(bvh.ok());
    const ChannelMap vm = ChannelMap::build(v);
    auto run = [&](Vec3 centre, Vec3 velocity) {
        OutletMeter meter(v, vm, vm.outlet_of(8, 1));
        SpawnDef spawn{.count = 60, .center = centre, .half_extent = Vec3(0.5f, 0.1f, 0.5f), .interval = 0,
                       .initial_velocity = velocity};
        spawn.flow_rate = 30.0f;
        SpringSolver s(v, bvh.value(), spawn, SpringDef{},
                         CollisionDef{.mode = CollisionMode::Robust, .damping = 0.0f, .offset = 0.01f},
                         IntegratorDef{.fixed_dt = 1.0f / 60.0f}, 1, SinkDef{.kind = SinkKind::Edges});
        for (int f = 0; f < 900; ++f) {
            s.step_frame(1.0f / 60.0f);
            meter.record(double(f + 1) / 60.0, s.last_exits());
        }
        const OutletMeter::Summary sum = meter.summary();
        EXPECT_EQ(sum.main.particles + sum.other.particles, s.counters().sunk) << "every exit is somewhere";
        return sum;
    };
    const float top = v.height_mesh(3.0f, 8.0f);
    const OutletMeter::Summary down = run(Vec3(3.0f, top + 0.5f, 8.0f), Vec3(0.0f));
    EXPECT_GT(down.main.particles, 50u);
    EXPECT_GT(down.main.rate, 0.0);
    const OutletMeter::Summary back = run(Vec3(1.5f, top + 0.5f, 8.0f), Vec3(-8.0f, 2.0f, 0.0f));
    EXPECT_GT(back.other.particles, 50u);
    EXPECT_EQ(back.main.particles, 0u);
}

// The Simulation's main channel: from the channel cell nearest the source (the
// automatic source sits at the head of the channel the carve was cut for: on the
// carved valley the main head moves 9 samples downstream into the source's basin, and
// the river starts where the source is), to its outlet.
TEST(ChannelCoverage, SimulationMainChannelStartsAtTheSource) {
    SceneDef d = default_scene();
    d.surface = false;
    d.spawn.prefill = false;  // the channel starts empty: no coverage before the source emits
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    const ChannelMap& m = sim.value()->channel();
    const auto path = sim.value()->main_channel();
    ASSERT_GT(path.size(), 1u);
    {
        const Vec3 c = sim.value()->def().spawn.center;
        const float as = sim.value()->terrain().area_scale();
        EXPECT_EQ(path.front(), m.nearest_channel_cell(int(std::lround(c.z / as)), int(std::lround(c.x / as))));
        EXPECT_LE(std::hypot(float(path.front().second) * as - c.x, float(path.front().first) * as - c.z),
                  sim.value()->def().spawn.half_extent.x)
            << "the river starts under its source";
    }
    EXPECT_EQ(path.back(), std::pair(m.outlets()[0].row, m.outlets()[0].column));
    EXPECT_EQ(sim.value()->channel_coverage(), 0.0f) << "no water yet";
    d.spawn.auto_center = false;
    const float s = sim.value()->terrain().area_scale();
    const auto [i, j] = path[path.size() / 2];
    d.spawn.center = Vec3(float(j) * s, sim.value()->terrain().sample(i, j) + 2.0f, float(i) * s);
    auto mid = Simulation::create(d);
    ASSERT_TRUE(mid.ok()) << mid.error().message;
    const auto half = mid.value()->main_channel();
    ASSERT_EQ(half.size(), path.size() - path.size() / 2);
    EXPECT_TRUE(std::equal(half.begin(), half.end(), path.begin() + std::ptrdiff_t(path.size() / 2)));
}

}  // namespace
}  // namespace mr
