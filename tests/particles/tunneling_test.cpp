// Zero tunneling, proven by volume: more than 10 million particle-steps of the robust
// collision mode over the paper's heightmaps, the procedural valley and random steep
// terrains (spikes, cliffs), in the situations where the paper's particles fall through:
//  - rain: particles falling from a few metres anywhere over the terrain;
//  - a drop from 100 m (impact at ~44 m/s: 0.74 m per step);
//  - slow sliding along seams and vertices: particles placed exactly on grid lines,
//    cell diagonals and vertices, on the surface, with tiny velocities (the paper's
//    worst case: rays through shared edges);
//  - the terrain's edges (the border grid lines are seams too) and steep cliffs;
//  - a particle radius > 0 (the centre must stay a radius above the mesh).
// Robust mode must report tunneled == 0 and no particle may be found below the mesh
// at the end of any frame; the same runs in paper mode report their (non-zero) count.
// METARIVER_LONG_SCALE (tests/support/long_scale.h; the asan preset's 0.1) runs that
// share of the particles (every scenario, terrain and mode; a share of the seam points).
#include <metariver/particles.h>
#include <metariver/pbf_solver.h>
#include <metariver/spring_solver.h>

#include "long_scale.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>
#include "require.h"

namespace mr {
namespace {

struct World {
    std::string name;
    Terrain terrain;
    Bvh bvh;
};

std::optional<World> make_world(const std::string& name, const Heightmap& map, TerrainDef def) {
    auto t = Terrain::build(map, def);
    if (!t) return std::nullopt;
    auto b = Bvh::build(t.value(), BvhDef{});
    if (!b) return std::nullopt;
    return World{name, std::move(t.value()), std::move(b.value())};
}

Heightmap blank(int w, int h) { return flat_heightmap(w, h); }

/// Independent random heights per sample: neighbouring samples differ by up to the
/// full height scale (slopes up to 40:1 with height_scale 40).
Heightmap spikes(int w, int h, uint32_t seed) {
    Heightmap m = blank(w, h);
    Lcg rng(seed);
    for (float& v : m.samples) v = rng.uniform(0.0f, 1.0f);
    return m;
}

/// Terraces with vertical-ish cliffs: random step heights along x and z.
Heightmap cliffs(int w, int h, uint32_t seed) {
    Heightmap m = blank(w, h);
    Lcg rng(seed);
    std::vector<float> sx(static_cast<size_t>(w)), sz(static_cast<size_t>(h));
    float a = 0.0f;
    for (auto& v : sx) v = (a += rng.next() < 0.25 ? rng.uniform(0.1f, 0.4f) : 0.0f);
    a = 0.0f;
    for (auto& v : sz) v = (a += rng.next() < 0.25 ? rng.uniform(0.1f, 0.4f) : 0.0f);
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) m.samples[static_cast<size_t>(r) * w + c] = std::fmod(sx[size_t(c)] + sz[size_t(r)], 1.0f);
    return m;
}

/// Terrain worlds: the procedural ones (always), then the paper's maps and the real
/// DEMs of ../shared when they are there (`shared_maps` counts those).
struct Worlds {
    std::vector<World> all;
    int shared_maps = 0;
};

Worlds worlds() {
    Worlds out;
    if (auto w = make_world("valley", procedural_valley(65, 97, 7), TerrainDef{.area_scale = 1.0f, .height_scale = 24.0f}))
        out.all.push_back(std::move(*w));
    if (auto w = make_world("spikes", spikes(33, 29, 5), TerrainDef{.area_scale = 1.0f, .height_scale = 40.0f}))
        out.all.push_back(std::move(*w));
    if (auto w = make_world("cliffs", cliffs(41, 33, 9), TerrainDef{.area_scale = 0.5f, .height_scale = 30.0f}))
        out.all.push_back(std::move(*w));
    for (const char* f : {"strict17.png", "strict.png", "nile.png", "bowl.png", "small.png", "flat0.png"}) {
        if (!test::have_file(test::paper_map(f))) continue;
        auto map = load_heightmap_png(test::paper_map(f));
        EXPECT_TRUE(map.ok()) << f;
        if (!map) continue;
        if (auto w = make_world(f, map.value(), TerrainDef{.area_scale = 1.0f, .height_scale = 7.0f})) {
            out.all.push_back(std::move(*w));
            ++out.shared_maps;
        }
    }
    // Real DEMs as steep game terrain: 1 m per sample, 40 m of relief (slopes to 20:1
    // where the crop's relief is concentrated).
    for (const char* f : {"alps.png", "andes_peru.png", "colorado_rockies.png", "pyrenees.png", "western_usa.png"}) {
        auto map = load_heightmap_png(test::real_dem(f));
        EXPECT_TRUE(map.ok()) << f;
        if (!map) continue;
        if (auto w = make_world(f, map.value(), TerrainDef{.area_scale = 1.0f, .height_scale = 40.0f})) {
            out.all.push_back(std::move(*w));
            ++out.shared_maps;
        }
    }
    return out;
}

/// Points exactly on the mesh's seams: every vertex, the midpoint of every grid edge
/// along x and z (including the border lines), and points on every cell's diagonal
/// (from (j+1, i) to (j, i+1)), at the exact mesh height.
std::vector<Vec3> seam_points(const Terrain& t) {
    std::vector<Vec3> p;
    const float s = t.area_scale();
    for (int i = 0; i < t.rows(); ++i)
        for (int j = 0; j < t.columns(); ++j) {
            const float x = float(j) * s, z = float(i) * s;
            auto add = [&](float px, float pz) {
                if (t.contains_xz(px, pz)) p.emplace_back(px, t.height_mesh(px, pz), pz);
            };
            add(x, z);
            if (j + 1 < t.columns()) add(x + 0.5f * s, z);
            if (i + 1 < t.rows()) add(x, z + 0.37f * s);
            if (i + 1 < t.rows() && j + 1 < t.columns()) {
                add(x + 0.75f * s, z + 0.25f * s);  // on the diagonal x + z = (j + i + 1) s
                add(x + 0.5f * s, z + 0.5f * s);
            }
        }
    return p;
}

struct Tally {
    uint64_t steps = 0, tunneled = 0, below = 0, collisions = 0, guarded = 0;  // below: found under the mesh after a frame
    void add(const Tally& o) {
        steps += o.steps;
        tunneled += o.tunneled;
        below += o.below;
        collisions += o.collisions;
        guarded += o.guarded;
    }
};

/// Runs one solver for `frames` frames; counts particles found at the end of a frame
/// below the mesh lifted by the radius (more than kTunnelEpsilon).
Tally run(const World& w, SpawnDef spawn, const std::vector<Vec3>* placed, CollisionDef col, int frames) {
    IntegratorDef integ{.gravity = 9.82f, .fixed_dt = 1.0f / 60.0f, .substeps = 1};
    SpringSolver s(w.terrain, w.bvh, spawn, SpringDef{}, col, integ, 17);
    if (placed) s.place(*placed);
    Tally t;
    for (int f = 0; f < frames; ++f) {
        s.step_frame(1.0f / 60.0f);
        const Particles& p = s.particles();
        for (size_t i = 0; i < p.size(); ++i) {
            if (!p.active[i] || !w.terrain.contains_xz(p.position[i].x, p.position[i].z)) continue;
            if (p.position[i].y < w.terrain.height_mesh(p.position[i].x, p.position[i].z) + col.radius - kTunnelEpsilon)
                ++t.below;
        }
    }
    t.steps = s.counters().particle_steps;
    t.tunneled = s.counters().tunneled;
    t.collisions = s.counters().collisions;
    t.guarded = s.counters().guarded;
    return t;
}

/// All scenarios on one terrain in one collision mode.
Tally scenarios(const World& w, CollisionMode mode) {
    const Aabb b = w.terrain.bounds();
    const Vec3 mid = b.center();
    const Vec3 half_xz(0.5f * b.extent().x, 0.0f, 0.5f * b.extent().z);
    Tally total;
    CollisionDef col{.mode = mode, .damping = 0.3f, .offset = 0.02f, .leaf_triangles = 8};

    // Rain over the whole terrain, tree query.
    SpawnDef rain{.count = test::scaled(12000), .center = Vec3(mid.x, b.max.y + 4.0f, mid.z),
                  .half_extent = half_xz + Vec3(0, 3, 0), .interval = 0, .initial_velocity = Vec3(0.4f, -1.0f, -0.3f)};
    total.add(run(w, rain, nullptr, col, 80));
    // The same with a radius and the heightfield query.
    CollisionDef col_r = col;
    col_r.radius = 0.25f;
    col_r.query = CollisionQuery::Heightfield;
    total.add(run(w, rain, nullptr, col_r, 60));
    // A drop from 100 m: start 100 m above the top at the speed of a 100 m fall.
    SpawnDef drop{.count = test::scaled(6000), .center = Vec3(mid.x, b.max.y + 100.0f, mid.z), .half_extent = half_xz + Vec3(0, 60, 0),
                  .interval = 0, .initial_velocity = Vec3(0.0f, -44.3f, 0.0f)};
    total.add(run(w, drop, nullptr, col, 110));
    // Seams, vertices and edges, on the surface, with tiny velocities in four directions
    // (respawns fall as rain from the spawn volume).
    std::vector<Vec3> seams = seam_points(w.terrain);
    if (!test::full_size()) {
        // Every k-th point, k not a multiple of 5: a cell adds up to five kinds of seam
        // point in turn (vertex, x edge, z edge, two on the diagonal), and all kinds stay.
        size_t k = std::max<size_t>(1, size_t(std::lround(1.0 / test::long_scale())));
        if (k % 5 == 0) ++k;
        std::vector<Vec3> some;
        for (size_t i = 0; i < seams.size(); i += k) some.push_back(seams[i]);
        seams.swap(some);
    }
    std::vector<Vec3> seams_r = seams;  // the centres of particles with a radius, resting on the seams
    for (Vec3& q : seams_r) q.y += col_r.radius;
    for (Vec3 v : {Vec3(1e-3f, 0, 0), Vec3(0, 0, -1e-3f), Vec3(-7e-4f, 0, 7e-4f), Vec3(0, -1e-4f, 0)}) {
        SpawnDef sd = rain;
        sd.count = static_cast<int>(seams.size());
        sd.initial_velocity = v;
        const bool with_radius = mode == CollisionMode::Robust && v.y < 0;
        total.add(run(w, sd, with_radius ? &seams_r : &seams, with_radius ? col_r : col, 40));
    }
    return total;
}

TEST(Tunneling, RobustModeLosesNothingInTenMillionParticleStepsPaperModeLosesMany) {
    const Worlds ws = worlds();
    ASSERT_GE(ws.all.size(), 3u) << "the procedural worlds run everywhere";
    if (ws.shared_maps < 11)
        std::printf("note: %d of the 11 maps are here (the 5 real DEMs of the repository, the paper's 6 from %s)\n",
                    ws.shared_maps, METARIVER_SHARED_DIR "/heightmaps/metawater");
    Tally robust, paper;
    for (const World& w : ws.all) {
        const Tally r = scenarios(w, CollisionMode::Robust);
        const Tally p = scenarios(w, CollisionMode::Paper);
        std::printf("%-25s robust: %9llu steps, tunneled %llu, guarded %llu, below %llu | paper: tunneled %llu, below %llu\n",
                    w.name.c_str(), (unsigned long long)r.steps, (unsigned long long)r.tunneled,
                    (unsigned long long)r.guarded, (unsigned long long)r.below, (unsigned long long)p.tunneled,
                    (unsigned long long)p.below);
        EXPECT_EQ(r.tunneled, 0u) << w.name;
        EXPECT_EQ(r.guarded, 0u) << w.name << ": the guard had to lift particles the swept query missed";
        EXPECT_EQ(r.below, 0u) << w.name;
        robust.add(r);
        paper.add(p);
    }
    std::printf("TOTAL robust: %llu particle-steps, tunneled %llu, guarded %llu | paper: %llu particle-steps, tunneled %llu\n",
                (unsigned long long)robust.steps, (unsigned long long)robust.tunneled,
                (unsigned long long)robust.guarded, (unsigned long long)paper.steps,
                (unsigned long long)paper.tunneled);
    EXPECT_GE(double(robust.steps), test::long_scale() * (ws.shared_maps >= 11 ? 10e6 : 2e6));
    EXPECT_GT(paper.tunneled, 0u) << "the paper's query is expected to lose particles through the ground";
}

/// PBF water rained onto the torture terrains: the fluid's terrain handling (push-out
/// in every iteration, swept sliding contact) must not lose a particle either.
TEST(Tunneling, PbfWaterOnSpikesAndCliffsLosesNothing) {
    const Worlds ws = worlds();
    uint64_t steps = 0;
    // A river's PBF (a bare PbfDef) and still water's: the terrain counted in the density
    // (wall_density, whose gradient near a spike's tip once threw rain over the bound
    // below), the contact band, the slow-water damping and the drift-aware sleep.
    PbfDef still{};
    still.wall_density = kStillWallDensity;
    still.contact_band = kStillContactBand;
    still.damping = kStillDamping;
    still.sleep_drift = kStillSleepDrift;
    for (const PbfDef& pbf : {PbfDef{}, still})
        for (const World& w : ws.all) {
            if (w.name != "spikes" && w.name != "cliffs" && w.name != "valley") continue;
            const Aabb b = w.terrain.bounds();
            const Vec3 mid = b.center();
            SpawnDef rain{.count = test::scaled(3000), .center = Vec3(mid.x, b.max.y + 3.0f, mid.z),
                          .half_extent = Vec3(0.4f * b.extent().x, 2.0f, 0.4f * b.extent().z), .interval = 0,
                          .initial_velocity = Vec3(0.3f, -2.0f, -0.2f)};
            PbfSolver s(w.terrain, w.bvh, rain, pbf,
                        CollisionDef{.mode = CollisionMode::Robust, .damping = 0.02f, .offset = 0.005f, .radius = 0.1f,
                                     .query = CollisionQuery::Heightfield},
                        IntegratorDef{.gravity = 9.82f, .fixed_dt = 1.0f / 120.0f, .substeps = 1}, 5, SinkDef{});
            float max_speed = 0.0f;  // any frame's
            for (int f = 0; f < 360; ++f) {
                s.step_frame(1.0f / 120.0f);
                max_speed = std::max(max_speed, s.counters().max_speed);
            }
            const SolverCounters& c = s.counters();
            const std::string what = w.name + (pbf.wall_density > 0.0f ? " (still water)" : " (river)");
            std::printf("pbf %-22s %llu steps, tunneled %llu, guarded %llu, respawned %llu, max speed %.1f\n",
                        what.c_str(), (unsigned long long)c.particle_steps, (unsigned long long)c.tunneled,
                        (unsigned long long)c.guarded, (unsigned long long)c.respawned, max_speed);
            EXPECT_EQ(c.tunneled, 0u) << what;
            EXPECT_EQ(c.guarded, 0u) << what;
            // Nothing is thrown: free fall from the top of the rain to the lowest ground plus
            // the inflow speed, + 20 % (a push-out onto a terrace top launched drops at
            // 70-150 m/s before the cliff-face rule).
            const float drop = rain.center.y + rain.half_extent.y - b.min.y;
            const float bound = 1.2f * (std::sqrt(2.0f * 9.82f * drop) + glm::length(rain.initial_velocity));
            EXPECT_LE(max_speed, bound) << what;
            steps += c.particle_steps;
        }
    EXPECT_GT(double(steps), test::long_scale() * 1e6);
}

/// The counters are honest. Robust mode: a segment the swept query cannot see (it
/// starts below the ground) ends below the mesh, and `tunneled` and `guarded` both
/// count it before the guard lifts the particle back up. PBF without collision: water
/// falling through the ground is counted as tunneled (no guard acts). Without these
/// the zeros above would prove nothing.
TEST(Tunneling, CountersSeeACrossingTheQueryMisses) {
    World w = *make_world("flat", blank(9, 9), TerrainDef{.area_scale = 1.0f, .height_scale = 1.0f});
    std::vector<Vec3> below;
    for (int k = 0; k < 10; ++k) below.emplace_back(1.0f + 0.5f * float(k), -0.3f, 4.0f);  // under the flat ground at 0
    {
        SpawnDef spawn{.count = 10, .center = Vec3(4, 2, 4), .half_extent = Vec3(0.5f), .interval = 0,
                       .initial_velocity = Vec3(0.0f, -1.0f, 0.0f)};
        SpringSolver s(w.terrain, w.bvh, spawn, SpringDef{},
                         CollisionDef{.mode = CollisionMode::Robust, .damping = 0.1f, .offset = 0.01f},
                         IntegratorDef{.gravity = 9.82f, .fixed_dt = 1.0f / 60.0f}, 1);
        s.place(below);
        s.step_frame(1.0f / 60.0f);
        EXPECT_EQ(s.counters().tunneled, 10u);
        EXPECT_EQ(s.counters().guarded, 10u) << "every guard action is a tunneling event";
        for (size_t i = 0; i < s.particles().size(); ++i) EXPECT_GE(s.particles().position[i].y, 0.0f) << "lifted";
    }
    {
        SpawnDef spawn{.count = 10, .center = Vec3(4, 2, 4), .half_extent = Vec3(0.5f), .interval = 0};
        PbfSolver s(w.terrain, w.bvh, spawn, PbfDef{}, CollisionDef{.mode = CollisionMode::None},
                         IntegratorDef{.gravity = 9.82f, .fixed_dt = 1.0f / 60.0f}, 1, SinkDef{});
        for (int f = 0; f < 60; ++f) s.step_frame(1.0f / 60.0f);
        EXPECT_GT(s.counters().tunneled, 10u) << "pbf water falling through the ground";
        EXPECT_EQ(s.counters().guarded, 0u);
    }
}

// A source volume cut by the terrain (a box through a slope): the springs solver drew
// spawn points in the whole box, a third of them underground, and each counted as
// tunneled in its first step (the springs valley: 18 in 600 frames; `bench --scenario
// river`: 773 at 10,000 particles). Spawn points under the ground start on it; the
// collision-free mode keeps the volume as drawn.
TEST(Tunneling, ASourceVolumeThroughTheGroundSpawnsNothingUnderIt) {
    Heightmap ramp = blank(17, 17);
    for (int i = 0; i < 17; ++i)
        for (int j = 0; j < 17; ++j) ramp.samples[size_t(i) * 17 + size_t(j)] = float(j) / 16.0f;  // 0..8 m along x
    World w = *make_world("ramp", ramp, TerrainDef{.area_scale = 1.0f, .height_scale = 8.0f});
    const SpawnDef spawn{.count = 2000, .center = Vec3(8, 4, 8), .half_extent = Vec3(3, 1, 3), .interval = 1,
                         .initial_velocity = Vec3(0.0f, 0.0f, -1.0f)};
    for (const float radius : {0.0f, 0.2f}) {
        const CollisionDef collision{.mode = CollisionMode::Robust, .damping = 0.05f, .offset = 0.01f, .radius = radius};
        SpringSolver s(w.terrain, w.bvh, spawn, SpringDef{}, collision,
                         IntegratorDef{.gravity = 9.82f, .fixed_dt = 1.0f / 60.0f}, 3);
        size_t born_checked = 0;
        for (int f = 0; f < 120; ++f) {
            s.step_frame(1.0f / 60.0f);
            const Particles& p = s.particles();
            for (size_t i = 0; i < p.size(); ++i)
                if (p.active[i] && p.birth_frame[i] + 1 >= uint32_t(f + 1)) {  // born this frame
                    EXPECT_GE(p.position[i].y - radius, w.terrain.height_mesh(p.position[i].x, p.position[i].z) - 1e-4f);
                    ++born_checked;
                }
        }
        EXPECT_GT(born_checked, 100u);
        EXPECT_EQ(s.counters().tunneled, 0u) << "radius " << radius;
        EXPECT_EQ(s.counters().guarded, 0u) << "radius " << radius;
    }
    // Without collision nothing is lifted: about a third of the box is under the ramp.
    SpawnDef at_once = spawn;
    at_once.interval = 0;
    SpringSolver none(w.terrain, w.bvh, at_once, SpringDef{}, CollisionDef{.mode = CollisionMode::None},
                        IntegratorDef{.gravity = 0.0f, .fixed_dt = 1.0f / 60.0f}, 3);
    none.step_frame(1.0f / 60.0f);
    size_t under = 0, active = 0;
    for (size_t i = 0; i < none.particles().size(); ++i)
        if (none.particles().active[i]) {
            ++active;
            const Vec3 q = none.particles().position[i];
            under += q.y < w.terrain.height_mesh(q.x, q.z);
        }
    EXPECT_GT(under, active / 5) << under << " of " << active;
}

}  // namespace
}  // namespace mr
