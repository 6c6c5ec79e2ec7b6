// The self-sized river (issue 10, docs/river.md "Sizing"): particles.count and
// particles.flow_rate = "auto" derive the budget and the rate from the carved channel's
// section and the main channel's length; each can be given instead.
#include <metariver/scene.h>
#include <metariver/workloads.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>
#include "require.h"

namespace mr {
namespace {

std::unique_ptr<Simulation> make(const SceneDef& d) {
    auto sim = Simulation::create(d);
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    return sim.ok() ? std::move(sim.value()) : nullptr;
}

TEST(Sizing, TheDefaultRiverSizesItsBudgetAndRateToTheMainChannel) {
    const SceneDef d = default_scene();
    ASSERT_EQ(d.spawn.count, kAutoCount);
    ASSERT_TRUE(d.spawn.auto_rate());
    auto sim = make(d);
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->sizing().has_value());
    const RiverSize& z = *sim->sizing();
    // The path's length: at least the straight line from the source to the outlet cell.
    const auto path = sim->main_channel();
    ASSERT_GE(path.size(), 2u);
    const float s = sim->terrain().area_scale();
    const float straight = s * std::hypot(float(path.front().first - path.back().first),
                                          float(path.front().second - path.back().second));
    EXPECT_GE(z.channel_length_m, straight);
    EXPECT_LE(z.channel_length_m, straight * 2.0f);
    // What the simulation runs with is the rule's result, and nothing is left automatic.
    const RiverSize rule = size_river(d, s, z.channel_length_m);
    EXPECT_EQ(sim->def().spawn.count, rule.count);
    EXPECT_FLOAT_EQ(sim->def().spawn.flow_rate, rule.rate);
    EXPECT_FALSE(sim->def().spawn.auto_rate());
    EXPECT_FALSE(z.capped);
    // The budget covers the rate over the transit at the transit speed, twice.
    EXPECT_GE(double(rule.count), double(rule.rate) * z.channel_length_m / kRiverTransitSpeed * kRiverBudgetMargin);
    EXPECT_TRUE(sim->warnings().empty()) << sim->warnings().front();
}

TEST(Sizing, ALongerChannelGetsALargerBudgetAtTheSameRateUntilTheCeiling) {
    const SceneDef d = default_scene();
    const RiverSize a = size_river(d, 1.0f, 50.0f), b = size_river(d, 1.0f, 100.0f);
    EXPECT_FLOAT_EQ(a.rate, b.rate);
    EXPECT_NEAR(double(b.count - kRiverSourcePile), 2.0 * double(a.count - kRiverSourcePile), 2.0);
    // Far longer: the budget stops at its ceiling and the rate drops so that it still
    // covers the transit (a thinner river rather than one with gaps).
    const RiverSize c = size_river(d, 1.0f, 5000.0f);
    EXPECT_TRUE(c.capped);
    EXPECT_EQ(c.count, kRiverMaxCount);
    EXPECT_LT(c.rate, a.rate);
    EXPECT_LE(double(c.rate) * 5000.0 / kRiverTransitSpeed * kRiverBudgetMargin + kRiverSourcePile, kRiverMaxCount + 1.0);
    // A wider sample spacing carves a wider channel: a larger rate.
    EXPECT_GT(size_river(d, 4.0f, 50.0f).rate, a.rate);
}

TEST(Sizing, EachDerivedValueCanBeGivenInstead) {
    auto only_count = parse_scene_toml("[particles]\ncount = 5000\n", "c.toml", default_scene());
    ASSERT_TRUE(only_count.ok()) << only_count.error().message;
    auto a = make(only_count.value());
    ASSERT_TRUE(a);
    EXPECT_EQ(a->def().spawn.count, 5000);
    ASSERT_TRUE(a->sizing().has_value());  // the rate is still derived
    EXPECT_FLOAT_EQ(a->def().spawn.flow_rate, a->sizing()->rate);

    auto only_rate = parse_scene_toml("[particles]\nflow_rate = 33.0\n", "r.toml", default_scene());
    ASSERT_TRUE(only_rate.ok());
    auto b = make(only_rate.value());
    ASSERT_TRUE(b);
    EXPECT_FLOAT_EQ(b->def().spawn.flow_rate, 33.0f);
    EXPECT_EQ(b->def().spawn.count, b->sizing()->count);

    auto both = parse_scene_toml("[particles]\ncount = 700\nflow_rate = 20.0\n", "b.toml", default_scene());
    ASSERT_TRUE(both.ok());
    auto c = make(both.value());
    ASSERT_TRUE(c);
    EXPECT_FALSE(c->sizing().has_value());
    EXPECT_EQ(c->def().spawn.count, 700);

    auto autos = parse_scene_toml("[particles]\ncount = 700\nflow_rate = 20.0\n", "x.toml", default_scene());
    ASSERT_TRUE(autos.ok());
    auto back = parse_scene_toml("[particles]\ncount = \"auto\"\nflow_rate = \"auto\"\n", "y.toml", autos.value());
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back->spawn.count, kAutoCount);
    EXPECT_TRUE(back->spawn.auto_rate());

    auto bad = parse_scene_toml("[particles]\ncount = \"many\"\n", "bad.toml", default_scene());
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("bad.toml: particles.count: must be \"auto\""), std::string::npos)
        << bad.error().message;
    auto bad_rate = parse_scene_toml("[particles]\nflow_rate = \"fast\"\n", "bad.toml", default_scene());
    ASSERT_FALSE(bad_rate.ok());
    EXPECT_NE(bad_rate.error().message.find("particles.flow_rate: must be \"auto\""), std::string::npos);
}

// pbf.spacing = "auto" (docs/river.md, "Spacing"): two particles per sample, at most
// the shorter side over 32, coarser while the budget would thin the river.
TEST(Sizing, TheSpacingFollowsTheTerrainsScale) {
    const SceneDef base = default_scene();
    ASSERT_TRUE(base.pbf.auto_spacing);
    auto one = make(base);  // the valley at 1 m per sample: the spacing as given
    ASSERT_TRUE(one);
    EXPECT_FLOAT_EQ(one->def().pbf.spacing, 0.5f);
    EXPECT_FLOAT_EQ(one->def().pbf.kernel_radius, 1.0f);
    EXPECT_FALSE(one->def().pbf.auto_spacing);  // resolved
    // At 3 m per sample every length sized in spacings is three times longer.
    SceneDef three = base;
    three.terrain.area_scale = 3.0f;
    three.terrain.auto_area_scale = false;
    auto big = make(three);
    ASSERT_TRUE(big);
    const SceneDef& r = big->def();
    EXPECT_FLOAT_EQ(r.pbf.spacing, 1.5f);
    EXPECT_FLOAT_EQ(r.pbf.kernel_radius, 3.0f * base.pbf.kernel_radius);
    EXPECT_FLOAT_EQ(r.collision.radius, 3.0f * base.collision.radius);
    EXPECT_FLOAT_EQ(r.collision.offset, 3.0f * base.collision.offset);
    EXPECT_FLOAT_EQ(r.field.radius, 3.0f * base.field.radius);
    EXPECT_FLOAT_EQ(r.field.resolution, base.field.resolution / 3.0f);
    EXPECT_FLOAT_EQ(r.spawn.half_extent.x, 3.0f * base.spawn.half_extent.x);
    // The carved section is the same in samples and in particles: the budget is the one
    // at 1 m within what the gentler slope changes (the speed, 0.75-1.5 m/s).
    ASSERT_TRUE(one->sizing() && big->sizing());
    EXPECT_EQ(carve_def(r, 3.0f).floor_m, 3.0f * carve_def(one->def(), 1.0f).floor_m);
    EXPECT_NEAR(double(big->sizing()->count), double(one->sizing()->count), 0.5 * double(one->sizing()->count));
    // A number is used as given.
    auto given = parse_scene_toml("[pbf]\nspacing = 0.5\n", "g.toml", three);
    ASSERT_TRUE(given.ok()) << given.error().message;
    EXPECT_FALSE(given->pbf.auto_spacing);
    auto fixed = make(given.value());
    ASSERT_TRUE(fixed);
    EXPECT_FLOAT_EQ(fixed->def().pbf.spacing, 0.5f);
    auto back = parse_scene_toml("[pbf]\nspacing = \"auto\"\n", "a.toml", given.value());
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_TRUE(back->pbf.auto_spacing);
}

TEST(Sizing, TheAutoSpacingIsAtMostTheShorterSideOver32) {
    const SceneDef d = default_scene();
    auto tiny = Terrain::build(flat_heightmap(9, 9), TerrainDef{.area_scale = 1.0f, .height_scale = 1.0f});
    ASSERT_TRUE(tiny.ok());
    EXPECT_FLOAT_EQ(auto_spacing(d, tiny.value()), 8.0f / kAutoSpacingAcross);  // 0.25 m, not 0.5
    // random_2x2 under the default scene: 16 m per sample ("auto" area scale), 0.5 m
    // particles rather than 8 m ones.
    auto one_cell = Terrain::build(flat_heightmap(2, 2), TerrainDef{.area_scale = 1.0f, .height_scale = 24.0f,
                                                                    .auto_area_scale = true});
    ASSERT_TRUE(one_cell.ok());
    EXPECT_FLOAT_EQ(auto_spacing(d, one_cell.value()), 0.5f);
    auto wide = Terrain::build(flat_heightmap(200, 100), TerrainDef{.area_scale = 4.0f, .height_scale = 24.0f});
    ASSERT_TRUE(wide.ok());
    EXPECT_FLOAT_EQ(auto_spacing(d, wide.value()), 2.0f);
}

// `bench --scenario pbf` (issue 12): the default river at a finer spacing keeps the
// default's terrain (carve and basin sized for 0.5 m) and its volume of water per second.
TEST(Sizing, ThePbfBenchRiverIsTheDefaultRiverFiner) {
    auto base = make(default_scene());
    const SceneDef d = pbf_river_scene(6400);  // 8x the default's steady particles: half the spacing
    EXPECT_NEAR(d.pbf.spacing, 0.25f, 1e-5f);
    EXPECT_NEAR(d.pbf.kernel_radius, 0.5f, 1e-5f);
    ASSERT_TRUE(base && base->sizing());
    EXPECT_NEAR(d.spawn.flow_rate * std::pow(d.pbf.spacing, 3.0f), base->sizing()->rate * 0.125f, 1e-3f);
    auto fine = make(d);
    ASSERT_TRUE(fine);
    EXPECT_FALSE(fine->sizing().has_value()) << "count and rate are given";
    const Terrain& a = base->terrain();
    const Terrain& b = fine->terrain();
    ASSERT_EQ(a.rows(), b.rows());
    ASSERT_EQ(a.columns(), b.columns());
    for (int i = 0; i < a.rows(); ++i)
        for (int j = 0; j < a.columns(); ++j) ASSERT_EQ(a.sample(i, j), b.sample(i, j)) << i << ", " << j;
    // Without carve_spacing the finer river would carve a shallower channel.
    SceneDef shallow = d;
    shallow.carve_spacing = 0.0f;
    EXPECT_LT(carve_def(shallow, 1.0f).depth_m, carve_def(d, 1.0f).depth_m);
}

TEST(Sizing, SolversThatDoNotSizeThemselvesKeepTheFixedBudget) {
    SceneDef d = default_scene();
    d.solver = SolverKind::Springs;
    d.spawn.flow_rate = 0.0f;
    d.spawn.interval = 10;
    d.sink.kind = SinkKind::None;
    auto sim = make(d);
    ASSERT_TRUE(sim);
    EXPECT_FALSE(sim->sizing().has_value());
    EXPECT_EQ(sim->def().spawn.count, kFixedDefaultCount);
}

}  // namespace
}  // namespace mr

namespace mr {
namespace {

/// Share of the river's main channel (from its source) that lies in the carved channel:
/// each cell lowered by at least half the carve's depth against the breached terrain.
double carved_share(const SceneDef& d) {
    auto carved = Simulation::create(d);
    EXPECT_TRUE(carved.ok()) << carved.error().message;
    SceneDef b = d;
    b.terrain.condition = TerrainCondition::Breach;
    auto breached = Simulation::create(b);
    EXPECT_TRUE(breached.ok()) << breached.error().message;
    if (!carved.ok() || !breached.ok()) return 0.0;
    const Terrain& t = carved.value()->terrain();
    const Terrain& u = breached.value()->terrain();
    const auto path = carved.value()->main_channel();
    if (path.empty()) return 0.0;
    const float half_depth = d.pbf.spacing;  // the carve is two spacings deep
    size_t in = 0;
    for (const auto& [i, j] : path) in += t.sample(i, j) <= u.sample(i, j) - half_depth;
    return double(in) / double(path.size());
}

TEST(Carve, TheRiverRunsDownTheChannelItsCarveWasCutFor) {
    // The source is placed on the breached terrain and the channel carved from it; the
    // river then has to start there. Placed again on the carved ground, the main head
    // had moved on colorado_rockies (the carve changes the flow accumulation): the river
    // ran down an uncarved path with 4 m sills at its diagonal steps while the carved
    // channel stayed dry (share 0.0 there before the fix).
    std::vector<std::pair<std::string, SceneDef>> maps{{"valley", default_scene()}};
    std::vector<std::pair<std::string, std::string>> files;  // name, path
    for (const char* name : {"alps.png", "andes_peru.png", "colorado_rockies.png", "pyrenees.png", "western_usa.png"})
        files.emplace_back(std::string("real/") + name, test::real_dem(name));
    for (const char* name : {"nile.png", "strict.png"})
        if (test::have_file(test::paper_map(name))) files.emplace_back(std::string("metawater/") + name, test::paper_map(name));
    for (const auto& [name, path] : files) {
        SceneDef d = default_scene();
        d.source.kind = TerrainSource::File;
        d.source.heightmap = path;
        maps.emplace_back(name, d);
    }
    for (auto& [name, d] : maps) {
        d.surface = false;
        const double share = carved_share(d);
        std::printf("%-26s main channel in the carved channel: %.2f\n", name.c_str(), share);
        EXPECT_GE(share, 0.9) << name;
    }
}

TEST(Prefill, TheCarvedChannelStartsFullSoTheRiverRunsFromTheFirstFrame) {
    // particles.prefill (docs/river.md, "... a channel that starts full"): the default river on the valley, the
    // same scene with and without. The front from the source needs about 25 s to reach
    // the outlet; the filled channel's water leaves within seconds.
    SceneDef d = default_scene();
    d.surface = false;
    d.spawn.prefill = true;
    auto sim = make(d);
    ASSERT_TRUE(sim);
    const size_t n = sim->prefilled();
    ASSERT_GT(n, 200u);
    EXPECT_LE(n, size_t(sim->def().spawn.count) / 2);
    const Particles& p = sim->particles();
    std::vector<Vec3> placed;
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i]) placed.push_back(p.position[i]);
    ASSERT_EQ(placed.size(), n);
    // Each in the carved channel: above the mesh by the collision clearance, within the
    // carve's half width (and a spacing) of a path cell; none nearer than 0.9 spacing.
    const Terrain& t = sim->terrain();
    const float a = t.area_scale(), sp = sim->def().pbf.spacing;
    const CarveDef carve = carve_def(sim->def(), a);
    for (const Vec3& q : placed) {
        EXPECT_GE(q.y, t.height_mesh(q.x, q.z) + sim->def().collision.radius);
        float nearest = 1e30f;
        for (const auto& [i, j] : sim->main_channel())
            nearest = std::min(nearest, std::hypot(q.x - float(j) * a, q.z - float(i) * a));
        EXPECT_LE(nearest, 0.5f * carve.floor_m + sp) << "outside the channel's bed";
    }
    for (size_t i = 0; i < placed.size(); ++i)
        for (size_t j = i + 1; j < placed.size(); ++j)
            ASSERT_GE(glm::length(placed[i] - placed[j]), 0.9f * sp - 1e-4f) << "overlapping particles " << i << ", " << j;
    EXPECT_GE(sim->channel_coverage(), 0.8f) << "the channel is not filled";

    // A river a third of its section's rate starts a third as full.
    SceneDef thin = d;
    thin.spawn.flow_rate = sim->def().spawn.flow_rate / 3.0f;
    auto third = make(thin);
    ASSERT_TRUE(third);
    // (Within 10 %: a thinned station no longer blocks its neighbour at a bend.)
    EXPECT_NEAR(double(third->prefilled()), double(n) / 3.0, 0.1 * double(n) / 3.0);

    SceneDef off = d;
    off.spawn.prefill = false;
    auto empty = make(off);
    ASSERT_TRUE(empty);
    EXPECT_EQ(empty->prefilled(), 0u);
    for (int f = 0; f < 600; ++f) {  // 10 s
        sim->step(1.0f / 60.0f);
        empty->step(1.0f / 60.0f);
    }
    std::printf("prefill: %zu particles; after 10 s: %llu sunk (without: %llu)\n", n,
                (unsigned long long)sim->counters().sunk, (unsigned long long)empty->counters().sunk);
    EXPECT_GT(sim->counters().sunk, 100u) << "the filled channel's water did not reach the outlet";
    EXPECT_EQ(empty->counters().sunk, 0u) << "the front reached the outlet in 10 s: the test no longer tells them apart";
    EXPECT_EQ(sim->counters().tunneled, 0u);
    EXPECT_EQ(sim->counters().guarded, 0u);
}

TEST(Prefill, FillChannelStaysInsideTheBudgetAndTheTerrain) {
    // The raw fill on a straight path: particles across the bed, layers, the cap.
    auto sim = make(default_scene());
    ASSERT_TRUE(sim);
    const Terrain& t = sim->terrain();
    std::vector<std::pair<int, int>> path;
    for (int i = 2; i < t.rows() - 2; ++i) path.emplace_back(i, t.columns() / 2);
    ChannelFillDef fd{.spacing = 0.5f, .floor_m = 3.0f, .depth_m = 0.75f, .clearance_m = 0.1f, .speed = 1.0f,
                      .most = 100000};
    const ChannelFill all = fill_channel(t, path, fd);
    const float length = t.area_scale() * float(path.size() - 1);
    // 5 across, 2 layers, a station every 0.5 m.
    EXPECT_NEAR(double(all.position.size()), 5.0 * 2.0 * double(length) / 0.5, 10.0);
    ASSERT_EQ(all.velocity.size(), all.position.size());
    for (const Vec3& v : all.velocity) EXPECT_NEAR(glm::length(v), 1.0f, 1e-4f);
    // A quarter of them, evenly spread (a capped budget's thinner river).
    fd.share = 0.25f;
    const ChannelFill quarter = fill_channel(t, path, fd);
    EXPECT_NEAR(double(quarter.position.size()), 0.25 * double(all.position.size()), 1.0);
    EXPECT_GT(quarter.position.back().z - quarter.position.front().z, 0.9f * length) << "not spread along the path";
    fd.share = 1.0f;
    fd.most = 37;
    EXPECT_EQ(fill_channel(t, path, fd).position.size(), 37u);
    fd.most = 0;
    EXPECT_TRUE(fill_channel(t, path, fd).position.empty());
    EXPECT_TRUE(fill_channel(t, std::span(path).first(1), ChannelFillDef{.most = 10}).position.empty());
}

TEST(Carve, APathAlongTheEdgeIsMovedInAndTurnsToItsOutlet) {
    // A path along row 1 of a 40 x 30 grid, from (1, 30) west to its outlet (0, 2).
    std::vector<std::pair<int, int>> path;
    for (int j = 30; j >= 3; --j) path.emplace_back(1, j);
    path.emplace_back(0, 2);
    const auto moved = keep_off_edges(path, 30, 40, 5);
    ASSERT_GE(moved.size(), path.size());
    EXPECT_EQ(moved.front(), path.front());
    EXPECT_EQ(moved.back(), path.back());
    for (size_t k = 1; k < moved.size(); ++k) {
        EXPECT_LE(std::abs(moved[k].first - moved[k - 1].first), 1) << k;
        EXPECT_LE(std::abs(moved[k].second - moved[k - 1].second), 1) << k;
        EXPECT_NE(moved[k], moved[k - 1]) << k;
    }
    // Every cell but the ends' approaches at least 5 in: the run along the edge is row 5.
    int on_row5 = 0;
    for (const auto& [i, j] : moved) {
        EXPECT_GE(j, 2);
        if (i == 5) ++on_row5;
    }
    EXPECT_GE(on_row5, 20);
    // The margin is at most a quarter of a side: a 9 x 9 grid keeps 2 cells.
    const auto small = keep_off_edges(std::vector<std::pair<int, int>>{{4, 8}, {0, 4}, {0, 3}, {0, 0}}, 9, 9, 5);
    for (size_t k = 1; k + 1 < small.size(); ++k)
        if (small[k] != small.back() && small[k] != small.front()) {
            EXPECT_GE(small[k].first, 0);
        }
    EXPECT_EQ(small.back(), std::make_pair(0, 0));
    EXPECT_TRUE(keep_off_edges({}, 9, 9, 5).empty());
}

TEST(Carve, TheRiversChannelKeepsOffTheMapsEdges) {
    // The main channel of the carved ground, away from its outlet, keeps the section's
    // half width and its levee from every edge: its banks lie inside the map. andes_peru's ran along
    // the east edge (3.7 particles/s lost over it) before keep_off_edges.
    std::vector<std::string> files{test::real_dem("andes_peru.png")};
    if (test::have_file(test::paper_map("nile.png"))) files.push_back(test::paper_map("nile.png"));
    for (const std::string& file : files) {
        const char* name = file.c_str();
        SceneDef d = default_scene();
        d.source.kind = TerrainSource::File;
        d.source.heightmap = file;
        d.surface = false;
        auto sim = make(d);
        ASSERT_TRUE(sim) << name;
        const Terrain& t = sim->terrain();
        const auto path = sim->main_channel();
        ASSERT_GE(path.size(), 10u) << name;
        const CarveDef carve = carve_def(sim->def(), t.area_scale());
        // The section's half width and its levee (1.5 samples), as the carve keeps.
        const int margin = int(std::ceil(0.5f * carve.width_m / t.area_scale() + 1.5f));
        int near_edge = 0;
        for (size_t k = 1; k + size_t(margin) + 1 < path.size(); ++k) {
            const auto [i, j] = path[k];
            if (std::min({i, j, t.rows() - 1 - i, t.columns() - 1 - j}) < margin) ++near_edge;
        }
        std::printf("%s: %d of %zu main channel cells within %d of an edge\n", name, near_edge, path.size(), margin);
        EXPECT_EQ(near_edge, 0) << name << ": the main channel runs along an edge of the map";
    }
}

}  // namespace
}  // namespace mr
