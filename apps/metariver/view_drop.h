// The viewer's drop / throw body tool, its arithmetic without a window (view_tools.cpp
// calls it; tests/apps/view_drop_test.cpp checks it): where a click's ray drops a body
// (on the water where the ray meets the water's surface before the terrain), where the
// body is held over that point, and the velocity a drag throws it with.
#pragma once

#include <metariver/bodies.h>
#include <metariver/water_query.h>

#include <optional>

namespace mr::view {

/// Where a click drops a body.
struct DropPoint {
    Vec3 point{0.0f};
    bool on_water = false;  ///< the water's surface (else the terrain)
};

/// The click's ray (origin, unit direction) against the water and the terrain:
/// `terrain_hit` is where it meets the terrain (none: it misses); `water` the frame's
/// water (none: the terrain only). The water's surface where the ray meets it no farther
/// than the terrain (the terrain's reach when the ray misses it: `max_t`), else the
/// terrain hit; none when it meets neither.
std::optional<DropPoint> drop_point(const Vec3& origin, const Vec3& direction, const std::optional<Vec3>& terrain_hit,
                                    const WaterQuery* water, float max_t);

/// The radius of a sphere around the body's centre that holds it (box, sphere, capsule).
float body_reach(BodyShape shape, const Vec3& size);

/// The body's centre while the drag holds it: `lift` metres over the drop point plus its reach.
Vec3 held_position(const DropPoint& at, BodyShape shape, const Vec3& size, float lift);

/// The velocity of the cursor over the ground between two hits `frame_s` apart, times
/// `gain`, horizontal, at most `most` m/s (zero for frame_s <= 0).
Vec3 cursor_velocity(const Vec3& from, const Vec3& to, double frame_s, float gain, float most);

}  // namespace mr::view
