// The water queries (include/metariver/water_query.h) against their brute-force twins
// (every triangle, every active particle) on 10,000 random points and rays (fixed seed)
// over real frames: the default river after 300 frames, the paper's springs on the
// procedural strict17 twin, and a still PBF pool in the bowl; then properties that need
// no twin (a ray straight down meets the surface at sample()'s height, NaN answers
// "dry"), and a heightfield lake whose level and flow are known exactly.
//
// Tolerances: the fast queries and the twins share the per-element arithmetic
// (src/scene/water_query_internal.h), so wet flags, surface heights and hits agree
// exactly; the bounds below are the (1e-4 m for heights and t) and admit only
// a different rounding. Velocities sum the same particles in another order, in double:
// 1e-5 relative (plus 1e-7 m/s for sums that cancel to near zero).
#include <metariver/scene.h>
#include <metariver/water_query.h>

#include "bowl_drop.h"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

namespace mr {
namespace {

constexpr int kQueries = 10'000;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::unique_ptr<Simulation> run(const SceneDef& def, int frames, const SolverRegistry& solvers = SolverRegistry::builtin()) {
    auto sim = Simulation::create(def, solvers);
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    if (!sim.ok()) return nullptr;
    for (int f = 0; f < frames; ++f) sim.value()->step(1.0f / 60.0f);
    return std::move(sim.value());
}

/// The terrain's rectangle grown by 10 % on each side (points off the terrain too).
Aabb query_box(const Simulation& s) {
    Aabb b = s.terrain().mesh_bounds();
    const Vec3 grow = 0.1f * b.extent();
    b.min -= grow;
    b.max += grow;
    return b;
}

/// Distance in x-z from (x, z) to the nearest edge of any surface triangle.
float edge_distance_xz(const SurfaceMesh& m, float x, float z) {
    float best = std::numeric_limits<float>::max();
    for (size_t t = 0; t < m.indices.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            const Vec3 a = m.positions[m.indices[t + k]], b = m.positions[m.indices[t + (k + 1) % 3]];
            const glm::vec2 pa(x - a.x, z - a.z), ab(b.x - a.x, b.z - a.z);
            const float len2 = glm::dot(ab, ab);
            const float u = len2 > 0.0f ? std::clamp(glm::dot(pa, ab) / len2, 0.0f, 1.0f) : 0.0f;
            best = std::min(best, glm::length(pa - u * ab));
        }
    return best;
}

bool velocity_close(const Vec3& fast, const Vec3& brute) {
    return glm::length(fast - brute) <= 1e-5f * glm::length(brute) + 1e-7f;
}

/// sample() and velocity_at() against their twins at kQueries random points; the batch
/// calls give the single calls' answers. Returns how many points were wet.
int compare_samples(const Simulation& s, const WaterQuery& q, uint32_t seed) {
    const Aabb box = query_box(s);
    Lcg rng(seed);
    std::vector<float> xz(2 * kQueries);
    for (int i = 0; i < kQueries; ++i) {
        xz[2 * i] = rng.uniform(box.min.x, box.max.x);
        xz[2 * i + 1] = rng.uniform(box.min.z, box.max.z);
    }
    std::vector<WaterSample> batch(kQueries);
    q.sample(xz, batch);
    int wet = 0, edge_cases = 0, checked_velocity = 0;
    for (int i = 0; i < kQueries; ++i) {
        const float x = xz[2 * i], z = xz[2 * i + 1];
        const WaterSample f = q.sample(x, z), b = sample_water_brute(s, x, z);
        EXPECT_EQ(f.wet, batch[i].wet);
        EXPECT_EQ(f.surface_y, batch[i].surface_y);
        EXPECT_EQ(f.velocity, batch[i].velocity);
        if (f.wet != b.wet) {
            ++edge_cases;
            EXPECT_LT(edge_distance_xz(s.surface(), x, z), 1e-5f) << "wet " << f.wet << " vs brute " << b.wet << " at " << x << ", " << z;
            continue;
        }
        wet += f.wet;
        EXPECT_NEAR(f.surface_y, b.surface_y, 1e-4f) << x << ", " << z;
        EXPECT_NEAR(f.depth, b.depth, 1e-4f) << x << ", " << z;
        EXPECT_GE(f.depth, 0.0f);
        if (!f.wet) {
            EXPECT_EQ(f.depth, 0.0f);
            EXPECT_EQ(f.velocity, Vec3(0.0f));
        }
        EXPECT_TRUE(velocity_close(f.velocity, b.velocity)) << x << ", " << z;
        // velocity_at at points off the surface too: between the ground and 2 m above the water.
        const Vec3 p(x, rng.uniform(b.surface_y - 1.0f, b.surface_y + 2.0f), z);
        const Vec3 vf = q.velocity_at(p), vb = water_velocity_brute(s, p);
        EXPECT_TRUE(velocity_close(vf, vb)) << p.x << ", " << p.y << ", " << p.z;
        checked_velocity += glm::length(vb) > 0.0f;
    }
    EXPECT_LE(edge_cases, 2) << "points on triangle edges are measure zero";
    std::printf("%d of %d points wet, %d velocities non-zero, %d edge cases\n", wet, kQueries, checked_velocity,
                edge_cases);
    return wet;
}

/// raycast() against its twin: half the rays aimed at a random surface vertex (so they
/// hit), half in random directions; the batch gives the single calls' answers.
int compare_rays(const Simulation& s, const WaterQuery& q, uint32_t seed) {
    const Aabb box = query_box(s);
    const float reach = 2.0f * glm::length(box.extent());
    const SurfaceMesh& m = s.surface();
    Lcg rng(seed);
    std::vector<Vec3> origins(kQueries), dirs(kQueries);
    for (int i = 0; i < kQueries; ++i) {
        origins[i] = Vec3(rng.uniform(box.min.x, box.max.x), rng.uniform(box.min.y, box.max.y + 20.0f),
                          rng.uniform(box.min.z, box.max.z));
        const Vec3 random_dir(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
        const bool aimed = i % 2 == 0 && !m.positions.empty();
        dirs[i] = aimed ? m.positions[rng.next_u32() % m.positions.size()] - origins[i] : random_dir;
    }
    std::vector<WaterRayHit> batch(kQueries);
    q.raycast(origins, dirs, reach, batch);
    int hits = 0;
    for (int i = 0; i < kQueries; ++i) {
        const WaterRayHit f = q.raycast(origins[i], dirs[i], reach), b = raycast_water_brute(s, origins[i], dirs[i], reach);
        EXPECT_EQ(f.hit, batch[i].hit);
        EXPECT_EQ(f.t, batch[i].t);
        EXPECT_EQ(f.triangle, batch[i].triangle);
        EXPECT_EQ(f.hit, b.hit) << "ray " << i;
        if (!f.hit) continue;
        ++hits;
        EXPECT_TRUE(f.triangle == b.triangle || std::abs(f.t - b.t) <= 1e-4f) << "ray " << i;
        EXPECT_NEAR(f.t, b.t, 1e-4f);
        EXPECT_LE(glm::length(f.point - (origins[i] + f.t * glm::normalize(dirs[i]))), 1e-3f);
        EXPECT_NEAR(glm::length(f.normal), 1.0f, 1e-5f);
        EXPECT_LE(glm::dot(f.normal, dirs[i]), 0.0f) << "the normal faces the ray's origin";
    }
    std::printf("%d of %d rays hit\n", hits, kQueries);
    return hits;
}

/// A ray from 10 m above a wet point straight down hits the surface at sample()'s
/// height; pointing up from there it misses.
void check_vertical_rays(const Simulation& s, const WaterQuery& q, uint32_t seed) {
    const Aabb box = query_box(s);
    Lcg rng(seed);
    int checked = 0;
    for (int i = 0; i < 20'000 && checked < 200; ++i) {
        const float x = rng.uniform(box.min.x, box.max.x), z = rng.uniform(box.min.z, box.max.z);
        const WaterSample w = q.sample(x, z);
        if (!w.wet) continue;
        ++checked;
        const Vec3 above(x, w.surface_y + 10.0f, z);
        const WaterRayHit down = q.raycast(above, Vec3(0, -1, 0), 100.0f);
        ASSERT_TRUE(down.hit) << x << ", " << z;
        EXPECT_NEAR(down.point.y, w.surface_y, 1e-4f);
        EXPECT_NEAR(down.t, 10.0f, 1e-4f);
        EXPECT_EQ(down.normal.y > 0.0f, true) << "facing up, to the ray's origin";
        EXPECT_FALSE(q.raycast(above, Vec3(0, 1, 0), 100.0f).hit) << "pointing away";
        EXPECT_FALSE(q.raycast(above, Vec3(0, -1, 0), 9.99f).hit) << "max_t short of the surface";
    }
    EXPECT_GE(checked, 50);
}

/// Points farther than 2 m + R (x-z) from every surface vertex: dry, at the ground's
/// height, with no flow there.
void check_dry_far(const Simulation& s, const WaterQuery& q, uint32_t seed) {
    const Aabb box = s.terrain().mesh_bounds();
    const float far = 2.0f + flow_radius(s.def());
    Lcg rng(seed);
    int tested = 0;
    for (int i = 0; i < 2000 && tested < 20; ++i) {
        const float x = rng.uniform(box.min.x, box.max.x), z = rng.uniform(box.min.z, box.max.z);
        bool away = true;
        for (const Vec3& v : s.surface().positions) away = away && glm::length(glm::vec2(v.x - x, v.z - z)) > far;
        if (!away) continue;
        const WaterSample w = q.sample(x, z);
        EXPECT_FALSE(w.wet) << x << ", " << z;
        EXPECT_EQ(w.surface_y, s.terrain().height_mesh(x, z));
        EXPECT_EQ(w.depth, 0.0f);
        EXPECT_EQ(q.velocity_at(Vec3(x, w.surface_y, z)), Vec3(0.0f));
        ++tested;
    }
    EXPECT_GE(tested, 1) << "no point lies away from the water";
}

void check_against_twins(const Simulation& s, uint32_t seed) {
    ASSERT_GT(s.surface().triangle_count(), 0u);
    std::printf("%zu triangles, %zu active particles\n", s.surface().triangle_count(), s.particles().active_count());
    WaterQuery q;
    q.update(s);
    EXPECT_GT(compare_samples(s, q, seed), kQueries / 100) << "too few wet points to compare";
    EXPECT_GT(compare_rays(s, q, seed + 1), kQueries / 4) << "too few hits to compare";
    check_vertical_rays(s, q, seed + 2);
    check_dry_far(s, q, seed + 3);
}

TEST(WaterQuery, TheDefaultRiverAfter300FramesAgreesWithTheBruteForceTwins) {
    const auto s = run(default_scene(), 300);
    ASSERT_TRUE(s);
    check_against_twins(*s, 43);
}

TEST(WaterQuery, ThePapersSpringsWithAllTheirBallsAgreeWithTheBruteForceTwins) {
    SceneDef d = preset("paper-full").value();  // the paper's springs on the strict17 twin
    d.source.kind = TerrainSource::Strict;
    const auto s = run(d, 20 * 80 + 100);  // all 20 balls out (one every 80 frames)
    ASSERT_TRUE(s);
    EXPECT_EQ(s->particles().active_count(), 20u);
    check_against_twins(*s, 17);
}

TEST(WaterQuery, AStillPoolAgreesWithTheBruteForceTwins) {
    SceneDef d = test::bowl_drop(1500, Vec3(16, 6, 16), Vec3(5, 2, 5));
    const auto s = run(d, 240);
    ASSERT_TRUE(s);
    check_against_twins(*s, 7);
}

TEST(WaterQuery, NonFiniteInputsAreDryAndMissAndAnEmptyQueryAnswersDry) {
    const auto s = run(default_scene(), 60);
    ASSERT_TRUE(s);
    WaterQuery q;
    const WaterSample before = q.sample(10.0f, 10.0f);  // nothing seen yet
    EXPECT_FALSE(before.wet);
    q.update(*s);
    constexpr float kInf = std::numeric_limits<float>::infinity();
    for (const float bad : {kNaN, kInf, -kInf}) {
        for (const WaterSample& w : {q.sample(bad, 10.0f), q.sample(10.0f, bad), sample_water_brute(*s, bad, 10.0f)}) {
            EXPECT_FALSE(w.wet);
            EXPECT_EQ(w.depth, 0.0f);
            EXPECT_EQ(w.velocity, Vec3(0.0f));
        }
        EXPECT_EQ(q.velocity_at(Vec3(bad, 1.0f, 1.0f)), Vec3(0.0f));
        EXPECT_EQ(water_velocity_brute(*s, Vec3(1.0f, bad, 1.0f)), Vec3(0.0f));
        EXPECT_FALSE(q.raycast(Vec3(bad, 10.0f, 10.0f), Vec3(0, -1, 0), 100.0f).hit);
        EXPECT_FALSE(q.raycast(Vec3(10.0f, 10.0f, 10.0f), Vec3(0, bad, 0), 100.0f).hit);
        EXPECT_FALSE(raycast_water_brute(*s, Vec3(10.0f, 10.0f, 10.0f), Vec3(bad, -1, 0), 100.0f).hit);
    }
    EXPECT_FALSE(q.raycast(Vec3(10.0f, 50.0f, 10.0f), Vec3(0, -1, 0), kNaN).hit);
    EXPECT_FALSE(q.raycast(Vec3(10.0f, 50.0f, 10.0f), Vec3(0.0f), 100.0f).hit) << "zero direction";
    EXPECT_FALSE(q.raycast(Vec3(10.0f, 50.0f, 10.0f), Vec3(0, -1, 0), -1.0f).hit) << "negative max_t";
    EXPECT_EQ(q.velocity_at(Vec3(1e30f, 0.0f, -1e30f)), Vec3(0.0f)) << "far off";
    EXPECT_FALSE(q.sample(1e30f, -1e30f).wet);
    // Batches: NaN entries answer as the single calls; outputs longer than the input are
    // filled with "dry".
    const std::vector<float> xz = {kNaN, 1.0f, 2.0f, kNaN};
    std::vector<WaterSample> out(3, WaterSample{.wet = true});
    q.sample(xz, out);
    for (const WaterSample& w : out) EXPECT_FALSE(w.wet);
}

// One rule in every binding (the C API and Python answer so too): a non-finite point in a
// batch is answered alone as dry / zero / no hit, and its neighbours exactly as without it.
TEST(WaterQuery, ANonFinitePointInABatchLeavesTheOthersAnswered) {
    const auto s = run(default_scene(), 120);
    ASSERT_TRUE(s);
    WaterQuery q;
    q.update(*s);
    const auto& v = s->surface().positions;
    ASSERT_GT(v.size(), 100u);
    std::vector<float> xz;
    std::vector<Vec3> points, origins, directions;
    for (size_t i = 0; i < 64; ++i) {  // surface vertices: wet points, moving water, rays that hit
        const Vec3 p = v[i * (v.size() / 64)];
        xz.insert(xz.end(), {p.x, p.z});
        points.push_back(p - Vec3(0.0f, 0.1f, 0.0f));
        origins.push_back(p + Vec3(0.01f, 20.0f, 0.01f));
        directions.emplace_back(0.0f, -1.0f, 0.0f);
    }
    const size_t n = points.size();
    std::vector<WaterSample> good_s(n), bad_s(n);
    std::vector<Vec3> good_v(n), bad_v(n);
    std::vector<WaterRayHit> good_h(n), bad_h(n);
    q.sample(xz, good_s);
    q.velocity_at(points, good_v);
    q.raycast(origins, directions, 100.0f, good_h);
    size_t k = 0;  // the first point that is wet, moving and hit: made bad below
    while (k < n && !(good_s[k].wet && good_h[k].hit && good_v[k] != Vec3(0.0f))) ++k;
    ASSERT_LT(k, n);
    xz[2 * k + 1] = kNaN;
    points[k].x = std::numeric_limits<float>::infinity();
    directions[k].y = kNaN;
    q.sample(xz, bad_s);
    q.velocity_at(points, bad_v);
    q.raycast(origins, directions, 100.0f, bad_h);
    for (size_t i = 0; i < n; ++i) {
        EXPECT_EQ(bad_s[i].wet, i != k && good_s[i].wet) << i;
        EXPECT_EQ(bad_s[i].surface_y, i == k ? 0.0f : good_s[i].surface_y) << i;
        EXPECT_EQ(bad_v[i], i == k ? Vec3(0.0f) : good_v[i]) << i;
        EXPECT_EQ(bad_h[i].hit, i != k && good_h[i].hit) << i;
        EXPECT_EQ(bad_h[i].t, i == k ? 0.0f : good_h[i].t) << i;
    }
}

// update() copies the terrain only when its revision changed: after a sculpt, an undo, or
// on another Simulation the depth is measured from the new ground, and between them the
// revision (and so the copy) stays.
TEST(WaterQuery, AfterASculptOrOnAnotherSimulationTheGroundIsTheNewOne) {
    auto a = run(default_scene(), 30);
    auto b = run(default_scene(), 30);
    ASSERT_TRUE(a && b);
    WaterQuery q;
    q.update(*a);
    const float x = 3.0f, z = 3.0f;  // the valley's rim: dry
    const WaterSample before = q.sample(x, z);
    ASSERT_FALSE(before.wet);
    ASSERT_EQ(before.surface_y, a->terrain().height_mesh(x, z));
    const uint64_t revision = a->terrain().revision();
    a->step(1.0f / 60.0f);
    EXPECT_EQ(a->terrain().revision(), revision) << "a step leaves the heights' revision";
    auto edit = a->sculpt(Brush{.x = x, .z = z, .radius = 2.0f, .strength = 1.5f, .mode = BrushMode::Raise});
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    EXPECT_NE(a->terrain().revision(), revision);
    q.update(*a);
    const float raised = a->terrain().height_mesh(x, z);
    EXPECT_GT(raised, before.surface_y + 1.0f);
    EXPECT_EQ(q.sample(x, z).surface_y, raised) << "the sculpted ground";
    a->restore(edit.value());
    q.update(*a);
    EXPECT_EQ(q.sample(x, z).surface_y, before.surface_y) << "the ground after undo";
    ASSERT_TRUE(b->sculpt(Brush{.x = x, .z = z, .radius = 2.0f, .strength = 0.7f, .mode = BrushMode::Lower}).ok());
    q.update(*b);
    EXPECT_EQ(q.sample(x, z).surface_y, b->terrain().height_mesh(x, z)) << "another Simulation's ground";
    EXPECT_LT(q.sample(x, z).surface_y, before.surface_y - 0.5f);
    EXPECT_NE(a->terrain().revision(), b->terrain().revision()) << "revisions are unique across terrains";
}

constexpr SolverKind kStillLake{"test-still-lake"};
constexpr float kLakeRise = 0.4f;             ///< metres above the lowest sample
const Vec3 kLakeFlow(0.75f, 0.0f, -0.25f);    ///< the lake's velocity everywhere, m/s

/// A lake at a fixed level (kLakeRise above the terrain's lowest sample), flowing at
/// kLakeFlow on every wet sample: its surface is flat at a known height.
class StillLake final : public Solver {
public:
    explicit StillLake(const Terrain& t) {
        water_ = {.rows = t.rows(), .columns = t.columns(), .origin = t.vertices().front(), .spacing = t.area_scale()};
        level_ = t.mesh_bounds().min.y + kLakeRise;
        for (const Vec3& v : t.vertices()) water_.depth.push_back(std::max(0.0f, level_ - v.y));
        water_.velocity.assign(water_.size(), kLakeFlow);
    }
    void step_frame(float) override { ++frame_; }
    const SolverCounters& counters() const override { return counters_; }
    uint64_t frame() const override { return frame_; }
    const HeightfieldWater* water_heightfield() const override { return &water_; }
    float level() const { return level_; }

private:
    HeightfieldWater water_;
    float level_ = 0.0f;
    SolverCounters counters_;
    uint64_t frame_ = 0;
};

TEST(WaterQuery, AHeightfieldLakeIsFlatAtItsLevelAndFlowsAtItsVelocity) {
    SolverRegistry solvers = SolverRegistry::builtin();
    float level = 0.0f;
    ASSERT_TRUE(solvers
                    .add({.kind = kStillLake,
                          .help = "a still lake (test)",
                          .create = [&level](const SceneDef&, const Terrain& t, const Bvh&) -> std::unique_ptr<Solver> {
                              auto lake = std::make_unique<StillLake>(t);
                              level = lake->level();
                              return lake;
                          },
                          .no_push = "still",
                          .no_sculpt = "still"})
                    .ok());
    SceneDef d = preset("paper-full").value();
    d.source.kind = TerrainSource::Strict;
    d.source.width = d.source.height = 33;
    d.solver = kStillLake;
    const auto s = run(d, 2, solvers);
    ASSERT_TRUE(s);
    ASSERT_GT(s->surface().triangle_count(), 0u);
    WaterQuery q;
    q.update(*s);
    const Aabb box = query_box(*s);
    Lcg rng(5);
    int wet = 0;
    for (int i = 0; i < kQueries; ++i) {
        const float x = rng.uniform(box.min.x, box.max.x), z = rng.uniform(box.min.z, box.max.z);
        const WaterSample w = q.sample(x, z);
        if (!w.wet) continue;
        ++wet;
        // The vertices lie at bed + (level - bed): within a float's rounding of the level.
        EXPECT_NEAR(w.surface_y, level, 1e-5f * std::max(1.0f, std::abs(level)));
        EXPECT_NEAR(w.depth, level - s->terrain().height_mesh(x, z), 1e-4f);
        EXPECT_LE(glm::length(w.velocity - kLakeFlow), 1e-6f);
        const WaterRayHit down = q.raycast(Vec3(x, level + 5.0f, z), Vec3(0, -1, 0), 10.0f);
        ASSERT_TRUE(down.hit);
        EXPECT_NEAR(down.point.y, level, 1e-4f);
        EXPECT_NEAR(down.normal.y, 1.0f, 1e-6f) << "a flat surface, facing up";
    }
    std::printf("lake at %.3f m: %d of %d points wet, %zu triangles\n", level, wet, kQueries, s->surface().triangle_count());
    EXPECT_GT(wet, kQueries / 50);
    // Beside the lake, on dry ground far above its level: no water, no flow.
    const Aabb t = s->terrain().mesh_bounds();
    for (const float fx : {0.0f, 1.0f})
        for (const float fz : {0.0f, 1.0f}) {
            const float x = t.min.x + fx * t.extent().x, z = t.min.z + fz * t.extent().z;
            if (s->terrain().height_mesh(x, z) < level + 1.0f) continue;
            EXPECT_FALSE(q.sample(x, z).wet);
            EXPECT_EQ(q.velocity_at(Vec3(x, level, z)), Vec3(0.0f));
        }
}

}  // namespace
}  // namespace mr
