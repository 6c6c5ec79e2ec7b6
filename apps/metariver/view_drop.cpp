// The drop / throw body tool's arithmetic (view_drop.h).
#include "view_drop.h"

#include <glm/geometric.hpp>

#include <cmath>

namespace mr::view {

std::optional<DropPoint> drop_point(const Vec3& origin, const Vec3& direction, const std::optional<Vec3>& terrain_hit,
                                    const WaterQuery* water, float max_t) {
    const float reach = terrain_hit ? glm::length(*terrain_hit - origin) : max_t;
    if (water && std::isfinite(reach)) {
        const WaterRayHit w = water->raycast(origin, direction, reach);
        if (w.hit) return DropPoint{w.point, true};
    }
    if (terrain_hit) return DropPoint{*terrain_hit, false};
    return std::nullopt;
}

float body_reach(BodyShape shape, const Vec3& size) {
    if (shape == BodyShape::Box) return 0.5f * glm::length(size);
    if (shape == BodyShape::Capsule) return size.x + 0.5f * size.y;
    return size.x;
}

Vec3 held_position(const DropPoint& at, BodyShape shape, const Vec3& size, float lift) {
    return at.point + Vec3(0.0f, body_reach(shape, size) + lift, 0.0f);
}

Vec3 cursor_velocity(const Vec3& from, const Vec3& to, double frame_s, float gain, float most) {
    if (!(frame_s > 0.0)) return Vec3(0.0f);
    Vec3 v = (to - from) * float(gain / frame_s);
    v.y = 0.0f;
    const float speed = glm::length(v);
    return speed > most ? v * (most / speed) : v;
}

}  // namespace mr::view
