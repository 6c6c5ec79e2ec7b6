// The Bullet solver (the paper's engine-physics mode, 2.4, and its springs future
// work): both terrain colliders are the terrain's own triangles, spheres rest at their
// radius, nothing ends below the paper's terrains, CCD and the sphere-sphere option do
// what they say, springs move the bodies exactly as the own solver moves its particles
// and conserve momentum.
#include <metariver/bullet_solver.h>
#include <metariver/scene.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>
#include "require.h"

namespace mr {
namespace {

constexpr float kFrame = 1.0f / 60.0f;

Heightmap flat_map(int w, int h) { return flat_heightmap(w, h); }

Terrain build_terrain(const Heightmap& map, float area_scale, float height_scale) {
    auto t = Terrain::build(map, TerrainDef{.area_scale = area_scale, .height_scale = height_scale});
    EXPECT_TRUE(t.ok());
    return std::move(t.value());
}

SpawnDef one_shot_spawn(int count, Vec3 center, Vec3 half) {
    return SpawnDef{.count = count, .center = center, .half_extent = half, .interval = 0};
}

using Tri = std::array<Vec3, 3>;

/// Triangle with its vertices in lexicographic order (winding-independent key).
Tri canonical(Tri t) {
    std::sort(t.begin(), t.end(), [](const Vec3& a, const Vec3& b) {
        if (a.x != b.x) return a.x < b.x;
        if (a.z != b.z) return a.z < b.z;
        return a.y < b.y;
    });
    return t;
}

bool tri_less(const Tri& a, const Tri& b) {
    for (int k = 0; k < 3; ++k) {
        // x and z are sample positions (exact multiples of the area scale, up to the
        // heightfield's recentring rounding): compare them rounded to a millimetre.
        const long ax = std::lround(a[k].x * 1000.0f), bx = std::lround(b[k].x * 1000.0f);
        if (ax != bx) return ax < bx;
        const long az = std::lround(a[k].z * 1000.0f), bz = std::lround(b[k].z * 1000.0f);
        if (az != bz) return az < bz;
    }
    return false;
}

void expect_same_triangles(const Terrain& terrain, BulletTerrainShape shape) {
    BulletSolver s(terrain, one_shot_spawn(1, Vec3(1, 50, 1), Vec3(0)), SpringDef{}, IntegratorDef{},
                   BulletDef{.terrain = shape}, 1);
    Aabb everything = terrain.bounds();
    everything.min -= Vec3(1.0f);
    everything.max += Vec3(1.0f);
    std::vector<Tri> got = s.terrain_triangles(everything);
    std::vector<Tri> want;
    const auto v = terrain.vertices();
    const auto idx = terrain.indices();
    for (size_t t = 0; t < terrain.triangle_count(); ++t)
        want.push_back({v[idx[3 * t]], v[idx[3 * t + 1]], v[idx[3 * t + 2]]});
    ASSERT_EQ(got.size(), want.size()) << to_string(shape);
    for (auto& t : got) t = canonical(t);
    for (auto& t : want) t = canonical(t);
    std::sort(got.begin(), got.end(), tri_less);
    std::sort(want.begin(), want.end(), tri_less);
    float worst = 0.0f;
    for (size_t t = 0; t < got.size(); ++t)
        for (int k = 0; k < 3; ++k) worst = std::max(worst, glm::length(got[t][k] - want[t][k]));
    // The heightfield stores heights relative to the middle of its range and scales x/z:
    // a few float ulps of the terrain's size.
    EXPECT_LT(worst, 1e-4f) << to_string(shape);
}

TEST(BulletSolver, BothTerrainCollidersAreTheTerrainsOwnTriangles) {
    // Not square, not unit spacing: catches swapped axes, a wrong centre and the
    // other diagonal.
    const Terrain valley = build_terrain(procedural_valley(23, 17, 5), 1.5f, 9.0f);
    expect_same_triangles(valley, BulletTerrainShape::Mesh);
    expect_same_triangles(valley, BulletTerrainShape::Heightfield);
}

TEST(BulletSolver, RayTestsOnBothCollidersHitTheMeshHeight) {
    const Terrain t = build_terrain(procedural_valley(33, 21, 3), 1.25f, 12.0f);
    const BulletDef shapes[] = {{.terrain = BulletTerrainShape::Mesh}, {.terrain = BulletTerrainShape::Heightfield}};
    for (const BulletDef& def : shapes) {
        BulletSolver s(t, one_shot_spawn(1, Vec3(1, 50, 1), Vec3(0)), SpringDef{}, IntegratorDef{}, def, 1);
        Lcg rng(99);
        const float xmax = 32 * 1.25f, zmax = 20 * 1.25f;
        float worst = 0.0f;
        int misses = 0;
        for (int k = 0; k < 2000; ++k) {
            float x = rng.uniform(0.01f, xmax - 0.01f), z = rng.uniform(0.01f, zmax - 0.01f);
            if (k % 4 == 0) {  // on a cell diagonal (x + z = cell corner sum): the split itself
                const float cx = std::floor(x / 1.25f), cz = std::floor(z / 1.25f);
                const float f = rng.uniform(0.05f, 0.95f);
                x = (cx + f) * 1.25f;
                z = (cz + 1.0f - f) * 1.25f;
            }
            const auto hit = s.raycast_terrain(Vec3(x, 100.0f, z), Vec3(x, -100.0f, z));
            if (!hit) {
                ++misses;
                continue;
            }
            worst = std::max(worst, std::fabs(hit->y - t.height_mesh(x, z)));
        }
        EXPECT_EQ(misses, 0) << to_string(def.terrain);
        // Bullet's hit point is from + fraction * (to - from) over a 200 m ray: float
        // rounding of the fraction is ~1e-7 * 200.
        EXPECT_LT(worst, 1e-4f) << to_string(def.terrain);
    }
}

TEST(BulletSolver, SpheresComeToRestOnFlatGroundAtTheirRadius) {
    const Terrain t = build_terrain(flat_map(17, 17), 1.0f, 1.0f);
    for (auto shape : {BulletTerrainShape::Mesh, BulletTerrainShape::Heightfield}) {
        const float r = 0.5f;
        BulletSolver s(t, one_shot_spawn(25, Vec3(8, 3, 8), Vec3(5, 1.5f, 5)), SpringDef{}, IntegratorDef{},
                       BulletDef{.terrain = shape, .sphere_radius = r}, 7);
        for (int f = 0; f < 240; ++f) s.step_frame(kFrame);
        const Particles& p = s.particles();
        ASSERT_EQ(p.active_count(), 25u);
        for (size_t i = 0; i < p.size(); ++i) {
            // Measured: 0.5000 on both shapes; 2 mm allows Bullet's resting contact to
            // settle a step later (g dt^2 = 2.7 mm per step).
            EXPECT_NEAR(p.position[i].y, r, 0.002f) << to_string(shape) << " sphere " << i;
            EXPECT_LT(glm::length(p.velocity[i]), 0.05f) << to_string(shape) << " sphere " << i;
        }
        EXPECT_EQ(s.counters().tunneled, 0u);
        EXPECT_EQ(s.counters().respawned, 0u);
        EXPECT_GT(s.counters().collisions, 0u);
        EXPECT_EQ(s.internal_steps(), 240u);
        EXPECT_EQ(s.awake_count(), 0u) << "resting spheres fall asleep (sleep = true)";
    }
}

struct PaperCase {
    const char* preset;
    const char* file;
};

TEST(BulletSolver, NoSphereEndsBelowThePapersTerrainsOverALongRun) {
    const std::string dir = METARIVER_SHARED_DIR "/heightmaps/metawater/";
    for (PaperCase c : {PaperCase{"paper-engine", "strict17.png"}, PaperCase{"paper-nile-engine", "nile.png"}}) {
        const std::string path = dir + c.file;
        if (!std::filesystem::exists(path)) MR_SKIP_OR_FAIL("no " << path);
        for (auto shape : {BulletTerrainShape::Mesh, BulletTerrainShape::Heightfield}) {
            SceneDef d = preset(c.preset).value();
            d.source.heightmap = path;
            d.surface = false;
            d.bullet.terrain = shape;
            auto sim = Simulation::create(d);
            ASSERT_TRUE(sim.ok()) << sim.error().message;
            Simulation& s = *sim.value();
            for (int f = 0; f < 3600; ++f) {  // one minute at 60 frames per second
                s.step(kFrame);
                if (f % 60 != 59) continue;
                const Particles& p = s.particles();
                for (size_t i = 0; i < p.size(); ++i) {
                    if (!p.active[i] || !s.terrain().contains_xz(p.position[i].x, p.position[i].z)) continue;
                    ASSERT_GT(p.position[i].y, s.terrain().height_mesh(p.position[i].x, p.position[i].z))
                        << c.preset << " " << to_string(shape) << " frame " << f << " sphere " << i;
                }
            }
            EXPECT_EQ(s.particles().active_count(), static_cast<size_t>(d.spawn.count));
            EXPECT_EQ(s.counters().tunneled, 0u) << c.preset << " " << to_string(shape);
            EXPECT_GT(s.counters().collisions, 0u);
        }
    }
}

TEST(BulletSolver, ContinuousCollisionDetectionStopsAFastSphere) {
    const Terrain t = build_terrain(flat_map(9, 9), 1.0f, 1.0f);
    SpawnDef spawn = one_shot_spawn(1, Vec3(4, 5, 4), Vec3(0));
    spawn.initial_velocity = Vec3(0, -600, 0);  // 10 m per step: past the terrain box (y >= -1) in one
    for (bool ccd : {false, true}) {
        BulletSolver s(t, spawn, SpringDef{}, IntegratorDef{}, BulletDef{.ccd = ccd}, 1);
        for (int f = 0; f < 30; ++f) s.step_frame(kFrame);
        if (ccd) {
            EXPECT_EQ(s.counters().respawned, 0u);
            EXPECT_EQ(s.counters().tunneled, 0u);
            EXPECT_GT(s.particles().position[0].y, 0.0f);
        } else {
            EXPECT_GT(s.counters().respawned, 0u) << "without CCD the sphere passes through the ground";
        }
    }
}

TEST(BulletSolver, SpheresCollideWithEachOtherOnlyWhenAsked) {
    const Terrain t = build_terrain(flat_map(17, 17), 1.0f, 1.0f);
    const float r = 0.5f;
    for (bool on : {false, true}) {
        // Ten spheres in one vertical column.
        BulletSolver s(t, one_shot_spawn(10, Vec3(8, 8, 8), Vec3(0, 6, 0)), SpringDef{}, IntegratorDef{},
                       BulletDef{.sphere_radius = r, .particle_collisions = on}, 3);
        for (int f = 0; f < 120; ++f) s.step_frame(kFrame);
        const Particles& p = s.particles();
        float closest = 1e9f;
        for (size_t i = 0; i < p.size(); ++i)
            for (size_t j = i + 1; j < p.size(); ++j) closest = std::min(closest, glm::length(p.position[i] - p.position[j]));
        if (on) {
            EXPECT_GT(closest, 2.0f * r * 0.95f) << "touching spheres, 5 % for contact slop";
        } else {
            EXPECT_LT(closest, 0.05f) << "without sphere-sphere contacts they all end on the same spot";
        }
    }
}

SceneDef springs_scene(SolverKind solver) {
    SceneDef d = default_scene();
    d.name = "springs-twin";
    d.solver = solver;
    d.source = {.kind = TerrainSource::Flat, .heightmap = {}, .width = 65, .height = 65, .seed = 1};
    d.terrain = {.area_scale = 1.0f, .height_scale = 1.0f, .paper_row_orientation = true};
    d.spawn = {.count = 40, .center = Vec3(32, 200, 32), .half_extent = Vec3(3, 3, 3), .interval = 0};
    d.springs = {.stiffness = 2.0f, .min_distance = 3.0f, .max_distance = 5.0f, .mode = SpringMode::Pairs};
    d.collision.mode = CollisionMode::None;
    d.integrator = {.gravity = 0.0f, .fixed_dt = 0.0f, .substeps = 1};
    d.bullet.springs = true;
    d.surface = false;
    return d;
}

Vec3 momentum(const Particles& p) {
    Vec3 m(0.0f);
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i]) m += p.velocity[i];
    return m;
}

float speed_sum(const Particles& p) {
    float s = 0.0f;
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i]) s += glm::length(p.velocity[i]);
    return s;
}

TEST(BulletSolver, SpringsConserveMomentumAndMatchTheOwnSolver) {
    // Zero gravity, 200 m above the ground: only the springs act.
    auto own = Simulation::create(springs_scene(SolverKind::Springs));
    auto eng = Simulation::create(springs_scene(SolverKind::Bullet));
    ASSERT_TRUE(own.ok()) << own.error().message;
    ASSERT_TRUE(eng.ok()) << eng.error().message;
    float moved = 0.0f;
    for (int f = 0; f < 120; ++f) {
        own.value()->step(kFrame);
        eng.value()->step(kFrame);
        const Particles& a = own.value()->particles();
        const Particles& b = eng.value()->particles();
        // Pair forces cancel exactly up to float rounding of each particle's sum.
        const float tol = 1e-4f * std::max(speed_sum(a), 1.0f);
        ASSERT_LT(glm::length(momentum(a)), tol) << "own solver, frame " << f;
        ASSERT_LT(glm::length(momentum(b)), tol) << "bullet, frame " << f;
    }
    const Particles& a = own.value()->particles();
    const Particles& b = eng.value()->particles();
    ASSERT_EQ(a.active_count(), b.active_count());
    EXPECT_GT(speed_sum(b), 1.0f) << "the springs did move the spheres";
    // Same spawn draws, same eq. 3, same semi-implicit Euler step (v += a dt; p += v dt):
    // the trajectories agree up to float rounding (Bullet applies m a and divides by m).
    float worst = 0.0f;
    for (size_t i = 0; i < a.size(); ++i) {
        if (!a.active[i]) continue;
        const size_t j = i;  // the pairs spring mode never reorders particles
        worst = std::max(worst, glm::length(a.position[i] - b.position[j]));
        moved = std::max(moved, glm::length(b.position[j] - Vec3(32, 200, 32)));
    }
    EXPECT_LT(worst, 1e-3f);
    EXPECT_GT(moved, 3.0f);
}

TEST(BulletSolver, SpringsOffMeansThePapersEngineModeEvenWithAStiffness) {
    SceneDef d = springs_scene(SolverKind::Bullet);
    d.bullet.springs = false;
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    for (int f = 0; f < 30; ++f) sim.value()->step(kFrame);
    EXPECT_EQ(speed_sum(sim.value()->particles()), 0.0f);
}

TEST(BulletSolver, GravityFallMatchesTheOwnSolver) {
    SceneDef d = springs_scene(SolverKind::Springs);
    d.springs.stiffness = 0.0f;
    d.integrator.gravity = 9.81f;
    auto own = Simulation::create(d);
    d.solver = SolverKind::Bullet;
    auto eng = Simulation::create(d);
    ASSERT_TRUE(own.ok() && eng.ok());
    for (int f = 0; f < 60; ++f) {
        own.value()->step(kFrame);
        eng.value()->step(kFrame);
    }
    const Particles& a = own.value()->particles();
    const Particles& b = eng.value()->particles();
    for (size_t i = 0; i < a.size(); ++i) {
        const size_t j = i;
        EXPECT_NEAR(a.position[i].y, b.position[j].y, 1e-3f);  // float rounding over 60 steps
        EXPECT_NEAR(b.velocity[j].y, -9.81f, 1e-3f);
    }
}

TEST(BulletSolver, SpawnsOnTheOwnSolversScheduleAndRespawnsOutsideTheRectangle) {
    const Terrain t = build_terrain(flat_map(9, 9), 1.0f, 1.0f);
    SpawnDef spawn{.count = 6, .center = Vec3(4, 2, 4), .half_extent = Vec3(1, 0.5f, 1), .interval = 5,
                   .initial_velocity = Vec3(30, 0, 0)};
    BulletSolver s(t, spawn, SpringDef{}, IntegratorDef{}, BulletDef{}, 11);
    for (int f = 0; f < 11; ++f) s.step_frame(kFrame);
    EXPECT_EQ(s.particles().active_count(), 3u);  // frames 0, 5, 10
    for (int f = 0; f < 100; ++f) s.step_frame(kFrame);
    EXPECT_EQ(s.particles().active_count(), 6u);
    EXPECT_GT(s.counters().respawned, 0u);
    for (size_t i = 0; i < 6; ++i) EXPECT_TRUE(t.contains_xz(s.particles().position[i].x, s.particles().position[i].z));
    EXPECT_EQ(s.counters().tunneled, 0u);

    s.pour(Vec3(2, 3, 2), 2);
    EXPECT_EQ(s.particles().active_count(), 6u);
    EXPECT_NEAR(s.particles().position[0].x, 2.0f, 1.0f);  // the oldest poured first
}

TEST(BulletSolver, SameSeedSameState) {
    const std::string path = METARIVER_SHARED_DIR "/heightmaps/metawater/strict17.png";
    SceneDef d = preset("paper-engine").value();
    if (test::have_file(path)) {
        d.source.heightmap = path;
    } else {
        d.source.kind = TerrainSource::Strict;
        d.source.width = d.source.height = 17;
    }
    d.surface = false;
    uint64_t hash[2] = {0, 0};
    for (int run = 0; run < 2; ++run) {
        auto sim = Simulation::create(d);
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        for (int f = 0; f < 400; ++f) sim.value()->step(kFrame);
        hash[run] = sim.value()->state_hash();
    }
    EXPECT_EQ(hash[0], hash[1]);
}

TEST(BulletSolver, SubstepsFollowBulletsFixedStep) {
    const Terrain t = build_terrain(flat_map(9, 9), 1.0f, 1.0f);
    BulletSolver s(t, one_shot_spawn(1, Vec3(4, 3, 4), Vec3(0)), SpringDef{}, IntegratorDef{},
                   BulletDef{.fixed_dt = 1.0f / 240.0f, .max_substeps = 8}, 1);
    for (int f = 0; f < 10; ++f) s.step_frame(kFrame);
    EXPECT_NEAR(static_cast<double>(s.internal_steps()), 40.0, 1.0);  // 4 per frame, float accumulator
    EXPECT_EQ(s.counters().particle_steps, s.internal_steps());
}

}  // namespace
}  // namespace mr
