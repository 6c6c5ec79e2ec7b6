// The C API's water queries (include/metariver/metariver.h) over mr::WaterQuery
// (water_query.h): the world keeps one, updated on the first query after a step or an
// edit, and answers batches of points into the caller's arrays. A non-finite point is
// answered as WaterQuery answers it (dry, zero velocity, no hit), never refused: one bad
// point does not cost the batch its other answers.
#include "capi_internal.h"

#include <cmath>
#include <vector>

using mr::capi::fail;
using mr::capi::guarded;
using mr::capi::null_argument;

namespace {

std::vector<mr::Vec3> vec3s(const float* p, size_t count) {
    std::vector<mr::Vec3> v(count);
    for (size_t i = 0; i < count; ++i) v[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    return v;
}

/// The world's queries on its latest frame (built on the first query after a change).
const mr::WaterQuery& fresh_query(mr_world* w) {
    if (!w->query_fresh) {
        w->query.update(*w->sim);
        w->query_fresh = true;
    }
    return w->query;
}

}  // namespace

extern "C" {

mr_status mr_world_sample_water(mr_world* world, const float* xz, size_t count, mr_water_sample* out) {
    constexpr const char* kName = "mr_world_sample_water";
    return guarded(world, kName, true, [&] {
        if (!xz && count > 0) return null_argument(world, kName, "xz");
        if (!out && count > 0) return null_argument(world, kName, "out");
        if (count == 0) return MR_OK;
        std::vector<mr::WaterSample> samples(count);
        fresh_query(world).sample(std::span<const float>(xz, 2 * count), samples);
        for (size_t i = 0; i < count; ++i) {
            const mr::WaterSample& s = samples[i];
            out[i] = {s.surface_y, s.depth, {s.velocity.x, s.velocity.y, s.velocity.z}, s.wet ? 1 : 0};
        }
        return MR_OK;
    });
}

mr_status mr_world_water_velocity(mr_world* world, const float* points, size_t count, float* velocities) {
    constexpr const char* kName = "mr_world_water_velocity";
    return guarded(world, kName, true, [&] {
        if (!points && count > 0) return null_argument(world, kName, "points");
        if (!velocities && count > 0) return null_argument(world, kName, "velocities");
        if (count == 0) return MR_OK;
        const std::vector<mr::Vec3> p = vec3s(points, count);
        std::vector<mr::Vec3> v(count);
        fresh_query(world).velocity_at(p, v);
        for (size_t i = 0; i < count; ++i) {
            velocities[3 * i] = v[i].x;
            velocities[3 * i + 1] = v[i].y;
            velocities[3 * i + 2] = v[i].z;
        }
        return MR_OK;
    });
}

mr_status mr_world_raycast_water(mr_world* world, const float* origins, const float* directions, size_t count,
                                 float max_distance, mr_ray_hit* out) {
    constexpr const char* kName = "mr_world_raycast_water";
    return guarded(world, kName, true, [&] {
        if (!origins && count > 0) return null_argument(world, kName, "origins");
        if (!directions && count > 0) return null_argument(world, kName, "directions");
        if (!out && count > 0) return null_argument(world, kName, "out");
        if (!(std::isfinite(max_distance) && max_distance >= 0.0f))
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("{}: max_distance: must be finite and >= 0 metres (got {})", kName, max_distance));
        if (count == 0) return MR_OK;
        std::vector<mr::WaterRayHit> hits(count);
        fresh_query(world).raycast(vec3s(origins, count), vec3s(directions, count), max_distance, hits);
        for (size_t i = 0; i < count; ++i) {
            const mr::WaterRayHit& h = hits[i];
            out[i] = {h.t, {h.point.x, h.point.y, h.point.z}, {h.normal.x, h.normal.y, h.normal.z}, h.hit ? 1 : 0};
        }
        return MR_OK;
    });
}

}  // extern "C"
