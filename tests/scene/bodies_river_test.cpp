// Bodies in the default river (issue 44): a log rides the current to the outlet, a heavy
// block dams the channel. Prints the numbers of the physics table.
#include <metariver/scene.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace mr {
namespace {

struct River {
    std::unique_ptr<Simulation> sim;
    std::vector<Vec3> path;  ///< the main channel's cells, source to outlet (y = 0)
};

/// The default river after `seconds`; `flow_rate` > 0: its source's particles per second
/// (the default sizes it: 27/s, 3.4 m^3/s).
River flowing_river(float seconds, float flow_rate = 0.0f) {
    SceneDef d = default_scene();
    d.surface = false;
    d.foam.enabled = false;
    if (flow_rate > 0.0f) d.spawn.flow_rate = flow_rate;
    auto s = Simulation::create(d);
    EXPECT_TRUE(s.ok()) << s.error().message;
    River r{std::move(s.value()), {}};
    const float as = r.sim->terrain().area_scale();
    for (const auto& [i, j] : r.sim->main_channel()) r.path.push_back(Vec3(float(j) * as, 0.0f, float(i) * as));
    for (int f = 0; f < int(seconds * 60.0f); ++f) r.sim->step(1.0f / 60.0f);
    return r;
}

/// The path cell nearest to x horizontally (its index) and the distance to the path's
/// polyline (the channel's centre line) there.
std::pair<size_t, float> nearest_cell(const std::vector<Vec3>& path, const Vec3& x) {
    size_t best = 0;
    float bd = 1e30f, line = 1e30f;
    const glm::vec2 q(x.x, x.z);
    for (size_t k = 0; k < path.size(); ++k) {
        const glm::vec2 a(path[k].x, path[k].z);
        const float d = glm::length(q - a);
        if (d < bd) bd = d, best = k;
        if (k + 1 == path.size()) continue;
        const glm::vec2 b(path[k + 1].x, path[k + 1].z);
        const float t = std::clamp(glm::dot(q - a, b - a) / glm::dot(b - a, b - a), 0.0f, 1.0f);
        line = std::min(line, glm::length(q - (a + t * (b - a))));
    }
    return {best, line};
}

/// The channel's direction at cell k (downstream, unit, horizontal).
Vec3 downstream(const std::vector<Vec3>& path, size_t k) {
    const size_t a = k >= 3 ? k - 3 : 0, b = std::min(path.size() - 1, k + 3);
    const Vec3 t = path[b] - path[a];
    return glm::normalize(Vec3(t.x, 0.0f, t.z));
}

/// The water within `radius` of x horizontally: its highest particle, and the mean
/// velocity of those within `layer` of it (the surface).
struct Surface {
    float top = -1e30f;
    Vec3 velocity{0.0f};
    int count = 0;
};
Surface surface_near(const Particles& p, const Vec3& x, float radius, float layer) {
    Surface s;
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i] && std::hypot(p.position[i].x - x.x, p.position[i].z - x.z) < radius) s.top = std::max(s.top, p.position[i].y);
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i] && std::hypot(p.position[i].x - x.x, p.position[i].z - x.z) < radius && p.position[i].y > s.top - layer) {
            s.velocity += p.velocity[i];
            ++s.count;
        }
    if (s.count) s.velocity /= float(s.count);
    return s;
}

TEST(BodiesRiver, ALogRidesTheCurrentToTheOutlet) {
    River r = flowing_river(10.0f);
    ASSERT_GE(r.path.size(), 20u);
    Simulation& s = *r.sim;
    const float sp = s.def().pbf.spacing;
    const size_t k0 = r.path.size() / 6;
    const Surface at = surface_near(s.particles(), r.path[k0], 2.0f, 2.0f * sp);
    ASSERT_GT(at.count, 0) << "no water at the drop";
    // A round log for a river 2 spacings (1 m) deep: 0.2 m radius, 1.6 m long, 500 kg/m^3.
    BodyDef log;
    log.shape = BodyShape::Capsule;
    log.size = Vec3(0.2f, 1.2f, 0.0f);
    log.density = 500.0f;
    log.position = Vec3(r.path[k0].x, at.top + 0.5f * sp + 0.3f, r.path[k0].z);
    const Vec3 t0 = downstream(r.path, k0);
    log.rotation = Vec3(0.0f, glm::degrees(std::atan2(-t0.z, t0.x)), 0.0f);  // along the flow
    auto id = s.add_body(log);
    ASSERT_TRUE(id.ok()) << id.error().message;
    const uint64_t inside0 = s.counters().inside_bodies;
    double body_along = 0.0, water_along = 0.0;
    float off_channel = 0.0f, t_outlet = -1.0f;
    const int max_frames = 150 * 60;
    for (int f = 0; f < max_frames; ++f) {
        s.step(1.0f / 60.0f);
        const BodyState& b = s.bodies()[0];
        const auto [k, dist] = nearest_cell(r.path, b.position);
        off_channel = std::max(off_channel, dist);
        if (k + 4 >= r.path.size() || !s.terrain().contains_xz(b.position.x, b.position.z)) {
            t_outlet = float(f + 1) / 60.0f;
            break;
        }
        if (f < 60) continue;  // the drop's splash
        const Vec3 t = downstream(r.path, k);
        const Surface w = surface_near(s.particles(), b.position, 3.0f, 2.0f * sp);
        if (f % 300 == 0)
            std::printf("  t %.0f cell %zu dist %.2f y %.2f ground %.2f top %.2f v %.2f water %.2f (n %d) sub %.2f\n", f / 60.0f, k,
                        dist, b.position.y, s.terrain().height_mesh(b.position.x, b.position.z), w.top,
                        glm::dot(b.velocity, t), glm::dot(w.velocity, t), w.count, b.submerged_fraction);
        body_along += glm::dot(b.velocity, t);
        water_along += glm::dot(w.velocity, t);
    }
    const double ratio = water_along > 0.0 ? body_along / water_along : 0.0;
    std::printf("log: path %zu cells, dropped at cell %zu; drift speed ratio %.2f; farthest from the channel's "
                "centre line %.2f m (half width %.1f m); time to the outlet %.1f s; particles inside bodies %llu\n",
                r.path.size(), k0, ratio, off_channel, 0.5f * carve_def(s.def(), s.terrain().area_scale()).width_m, t_outlet,
                (unsigned long long)(s.counters().inside_bodies - inside0));
    EXPECT_GT(t_outlet, 0.0f) << "the log did not reach the outlet in 150 s";
    EXPECT_GE(ratio, 0.7);
    // The carved section's half width at the top of its walls (6 m wide in the default).
    const float half_width = 0.5f * carve_def(s.def(), s.terrain().area_scale()).width_m;
    EXPECT_LE(off_channel, half_width) << "the log left the channel";
    EXPECT_EQ(s.counters().inside_bodies - inside0, 0u);
}

/// The 90th percentile of the particles' heights within 1.5 m of x horizontally (the
/// water's level there; 0 when there are none).
float level_at(const Simulation& s, const Vec3& x) {
    std::vector<float> y;
    const Particles& p = s.particles();
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i] && std::hypot(p.position[i].x - x.x, p.position[i].z - x.z) < 1.5f) y.push_back(p.position[i].y);
    if (y.empty()) return 0.0f;
    std::sort(y.begin(), y.end());
    return y[y.size() * 9 / 10];
}

struct Dam {
    float rise = 0.0f;        ///< level 2 m upstream of the block, with it minus without
    float depth_up = 0.0f;    ///< water depth 2 m upstream of the block (with it)
    float depth_down = 0.0f;  ///< water depth 3 m downstream of the block (with it)
    float moved = 0.0f;       ///< the block's horizontal move after settling, metres
    uint64_t sunk = 0, sunk_free = 0;  ///< particles through the outlet over the window, with and without
    uint64_t inside = 0;
};

// The same river twice from the same state (deterministic): with a block dropped across
// the channel at 10 s, and without; the levels and what the outlet takes are compared
// between the two over 15-20 s.
Dam dam_channel(float flow_rate, const BodyDef& shape) {
    River with = flowing_river(10.0f, flow_rate);
    Simulation& s = *with.sim;
    const size_t k0 = with.path.size() / 3;
    const Vec3 t0 = downstream(with.path, k0);
    BodyDef block = shape;
    const float ground = s.terrain().height_mesh(with.path[k0].x, with.path[k0].z);
    block.position = Vec3(with.path[k0].x, ground + 0.5f * block.size.y + 0.05f, with.path[k0].z);
    block.rotation = Vec3(0.0f, glm::degrees(std::atan2(-t0.z, t0.x)), 0.0f);
    auto id = s.add_body(block);
    EXPECT_TRUE(id.ok()) << id.error().message;
    Dam r;
    const uint64_t inside0 = s.counters().inside_bodies;
    for (int f = 0; f < 300; ++f) s.step(1.0f / 60.0f);
    const Vec3 rest = s.bodies()[0].position;
    for (int f = 0; f < 600; ++f) s.step(1.0f / 60.0f);
    const Vec3 behind = s.bodies()[0].position - 2.0f * t0;  // 1.25 m before its upstream face
    const Vec3 below = s.bodies()[0].position + 3.0f * t0;   // 2.25 m after its downstream face
    River without = flowing_river(25.0f, flow_rate);
    const uint64_t sunk0 = s.counters().sunk, free0 = without.sim->counters().sunk;
    double dammed = 0.0, free = 0.0, down = 0.0;
    for (int f = 0; f < 300; ++f) {
        s.step(1.0f / 60.0f);
        without.sim->step(1.0f / 60.0f);
        dammed += level_at(s, behind) / 300.0;
        free += level_at(*without.sim, behind) / 300.0;
        down += level_at(s, below) / 300.0;
    }
    for (float back : {-3.0f, 1.2f, 2.0f, 3.0f, 5.0f}) {
        const Vec3 at = s.bodies()[0].position - back * t0;
        std::printf("  %.1f m upstream: level %.2f with, %.2f without, ground %.2f\n", back, level_at(s, at), level_at(*without.sim, at),
                    s.terrain().height_mesh(at.x, at.z));
    }
    const Vec3 end = s.bodies()[0].position;
    r.rise = float(dammed - free);
    r.depth_up = float(dammed) - s.terrain().height_mesh(behind.x, behind.z);
    r.depth_down = float(down) - s.terrain().height_mesh(below.x, below.z);
    r.moved = std::hypot(end.x - rest.x, end.z - rest.z);
    r.sunk = s.counters().sunk - sunk0;
    r.sunk_free = without.sim->counters().sunk - free0;
    r.inside = s.counters().inside_bodies - inside0;
    std::printf("dam, %.0f particles/s, a %.1f x %.1f x %.1f m block of %.0f kg/m^3: level 2 m upstream %.3f m with it, %.3f m "
                "without (rise %.3f m); depth 2 m upstream %.2f m, 3 m downstream %.2f m; through the outlet in 5 s %llu particles "
                "(%llu without); the block moved %.2f m after settling; particles inside bodies %llu\n",
                flow_rate, shape.size.x, shape.size.y, shape.size.z, shape.density, dammed, free, r.rise, r.depth_up, r.depth_down,
                (unsigned long long)r.sunk, (unsigned long long)r.sunk_free, r.moved, (unsigned long long)r.inside);
    return r;
}

// A steel block (7800 kg/m^3, 1.5 m along the flow, 1.6 m high, 2.9 m across the 3 m bed)
// dropped into the channel of the default river at three times its discharge (81
// particles/s, 10 m^3/s): the water rises behind it and still reaches the outlet, around
// its ends. At the default discharge (27/s, one layer of particles 0.3-0.4 m deep) the
// block rests on the channel's rising banks 0.1 m over the middle of the bed and that one
// layer runs under it (printed, not asserted: rise -0.005 m measured); a granite block
// (2700) at three times the discharge is lifted by the water under it and carried away.
TEST(BodiesRiver, AHeavyBlockDamsTheChannel) {
    const BodyDef steel{.size = Vec3(1.5f, 1.6f, 2.9f), .density = 7800.0f, .friction = 1.0f};
    const Dam d = dam_channel(3.0f * 27.0f, steel);
    EXPECT_GT(d.rise, 0.15f) << "the water does not rise behind the block";
    EXPECT_GT(d.depth_up, d.depth_down + 0.15f) << "no deeper upstream than downstream";
    EXPECT_GT(d.sunk, d.sunk_free / 3) << "the water does not get past the block to the outlet";
    EXPECT_LT(d.moved, 1.0f) << "the block was carried away";
    EXPECT_EQ(d.inside, 0u);
    const Dam thin = dam_channel(27.0f, steel);  // the default discharge: printed
    EXPECT_EQ(thin.inside, 0u);
}

}  // namespace
}  // namespace mr
