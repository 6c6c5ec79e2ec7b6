// The water queries' brute-force twins (water_query.h): every triangle of the surface
// mesh, every active particle, no acceleration structure. They share the per-element
// arithmetic with the fast queries (water_query_internal.h), so the two differ only in
// what they visit; the tests compare them on random points and rays.
#include <metariver/scene.h>
#include <metariver/water_query.h>

#include "water_query_internal.h"

#include <algorithm>

namespace mr {

namespace water_detail {

bool heightfield_velocity(const HeightfieldWater& hf, float x, float z, Vec3& out) {
    if (hf.rows < 2 || hf.columns < 2 || hf.depth.size() != hf.size() || !(hf.spacing > 0.0f)) return false;
    const float fx = (x - hf.origin.x) / hf.spacing, fz = (z - hf.origin.z) / hf.spacing;
    if (!(fx >= 0.0f && fx <= float(hf.columns - 1) && fz >= 0.0f && fz <= float(hf.rows - 1))) return false;
    const int j = std::min(int(fx), hf.columns - 2), i = std::min(int(fz), hf.rows - 2);
    const float u = fx - float(j), v = fz - float(i);
    const bool moving = hf.velocity.size() == hf.size();
    const float weights[4] = {(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v};
    const size_t c = size_t(i) * size_t(hf.columns) + size_t(j), w = size_t(hf.columns);
    const size_t samples[4] = {c, c + 1, c + w, c + w + 1};
    double sx = 0.0, sy = 0.0, sz = 0.0, sw = 0.0;
    for (int k = 0; k < 4; ++k) {
        if (!(hf.depth[samples[k]] > 0.0f) || !(weights[k] > 0.0f)) continue;
        const Vec3 vel = moving ? hf.velocity[samples[k]] : Vec3(0.0f);
        sx += double(weights[k]) * vel.x;
        sy += double(weights[k]) * vel.y;
        sz += double(weights[k]) * vel.z;
        sw += weights[k];
    }
    if (!(sw > 0.0)) return false;
    out = Vec3(float(sx / sw), float(sy / sw), float(sz / sw));
    return true;
}

}  // namespace water_detail

using namespace water_detail;

Vec3 water_velocity_brute(const Simulation& sim, const Vec3& p) {
    if (!finite(p)) return Vec3(0.0f);
    Vec3 v;
    if (const HeightfieldWater* hf = sim.heightfield(); hf && heightfield_velocity(*hf, p.x, p.z, v)) return v;
    const float r = flow_radius(sim.def());
    if (!(r > 0.0f)) return Vec3(0.0f);
    const float r2 = r * r, inv_r2 = 1.0f / r2;
    const Particles& ps = sim.particles();
    FlowSum sum;
    for (size_t j = 0; j < ps.size(); ++j) {
        if (!ps.active[j]) continue;
        const Vec3 d = p - ps.position[j];
        const float d2 = glm::dot(d, d);
        if (d2 < r2) sum.add(d2, inv_r2, ps.velocity[j]);
    }
    return sum.mean();
}

WaterSample sample_water_brute(const Simulation& sim, float x, float z) {
    if (!std::isfinite(x) || !std::isfinite(z)) return {};
    const SurfaceMesh& m = sim.surface();
    bool wet = false;
    float top = 0.0f;
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
        float y;
        if (!vertical_crossing(m.positions[m.indices[t]], m.positions[m.indices[t + 1]], m.positions[m.indices[t + 2]],
                               x, z, y))
            continue;
        if (!wet || y > top) top = y;
        wet = true;
    }
    const float ground = sim.terrain().height_mesh(x, z);
    if (!wet) return {.surface_y = ground};
    return {.wet = true,
            .surface_y = top,
            .depth = std::max(0.0f, top - ground),
            .velocity = water_velocity_brute(sim, Vec3(x, top, z))};
}

WaterRayHit raycast_water_brute(const Simulation& sim, const Vec3& origin, const Vec3& direction, float max_t) {
    Vec3 d;
    if (!ray_setup(origin, direction, max_t, d)) return {};
    const SurfaceMesh& m = sim.surface();
    WaterRayHit best;
    for (size_t k = 0; k + 2 < m.indices.size(); k += 3) {
        const Vec3 &a = m.positions[m.indices[k]], &b = m.positions[m.indices[k + 1]], &c = m.positions[m.indices[k + 2]];
        float t;
        const uint32_t tri = uint32_t(k / 3);
        if (ray_triangle(origin, d, a, b, c, max_t, t) && nearer(t, tri, best)) best = make_hit(origin, d, t, tri, a, b, c);
    }
    return best;
}

}  // namespace mr
