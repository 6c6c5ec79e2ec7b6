// `metariver bench --scenario bodies`: the default river with and without 20 logs (issue
// 44's cost bound: the logs add at most 20 % to the frame).
#include "bench_scenarios.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace mr::app {

namespace {

/// The median (robust to the other processes of a shared machine).
double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
}

/// n round logs (capsules 0.2 m x 1.6 m, 500 kg/m^3) on the water along the main channel.
void drop_logs(Simulation& s, int n) {
    const auto path = s.main_channel();
    const float as = s.terrain().area_scale();
    const Particles& p = s.particles();
    for (int k = 0; k < n; ++k) {
        const auto [i, j] = path[path.size() * size_t(k + 1) / size_t(n + 2)];
        const Vec3 c(float(j) * as, 0.0f, float(i) * as);
        float top = s.terrain().height_mesh(c.x, c.z);
        for (size_t q = 0; q < p.size(); ++q)
            if (p.active[q] && std::hypot(p.position[q].x - c.x, p.position[q].z - c.z) < 1.5f) top = std::max(top, p.position[q].y);
        (void)s.add_body(BodyDef{.shape = BodyShape::Capsule, .size = Vec3(0.2f, 1.2f, 0.0f), .density = 500.0f,
                                 .position = c + Vec3(0.0f, top + 0.5f, 0.0f)});
    }
}

}  // namespace

void bench_river_bodies(int warmup, int frames, std::vector<ScenarioResult>& out) {
    double without = 0.0;
    for (int logs : {0, 20}) {
        ScenarioResult r;
        r.name = logs ? fmt::format("default + {} logs", logs) : "default (no bodies)";
        SceneDef def = default_scene();
        auto sim = Simulation::create(def);
        if (!sim) {
            r.note = "skipped: " + sim.error().message;
            out.push_back(std::move(r));
            continue;
        }
        Simulation& s = *sim.value();
        for (int f = 0; f < warmup; ++f) s.step(1.0f / 60.0f);
        if (logs) drop_logs(s, logs);
        for (int f = 0; f < 60; ++f) s.step(1.0f / 60.0f);  // the drop's splash (both rows alike)
        const uint64_t inside0 = s.counters().inside_bodies;
        for (int f = 0; f < frames; ++f) {
            s.step(1.0f / 60.0f);
            const FrameTimings& t = s.last_timings();
            r.sample("simulate", t.simulate_ms);
            r.sample("total", t.simulate_ms + t.foam_ms + t.field_ms + t.surface_ms);
        }
        r.particles = s.particles().active_count();
        r.triangles = s.surface().triangle_count();
        r.params = {{"scene", def.name}, {"bodies", s.bodies().size()}, {"warmup", warmup}, {"frames", frames}};
        r.quality = {{"inside_bodies", s.counters().inside_bodies - inside0}};
        const double total = median(r.stage_ms["total"]);
        if (!logs) without = total;
        else if (without > 0.0) r.quality["frame_ratio"] = total / without;
        r.note = logs ? fmt::format("{} logs dropped on the water after {} frames; median frame {:.2f}x the river's without them",
                                    s.bodies().size(), warmup, without > 0.0 ? total / without : 0.0)
                      : fmt::format("{} warm-up frames", warmup);
        out.push_back(std::move(r));
    }
}

}  // namespace mr::app
