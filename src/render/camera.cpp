// Orbit camera, framing and the picking ray (no OpenGL here: tests use it without a context).
#include <metariver/render.h>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

namespace mr::render {

Vec3 Camera::eye() const {
    const float yaw = glm::radians(yaw_deg), pitch = glm::radians(pitch_deg);
    const Vec3 dir(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
    return target + distance * dir;
}

glm::mat4 Camera::view() const { return glm::lookAt(eye(), target, Vec3(0.0f, 1.0f, 0.0f)); }

glm::mat4 Camera::projection(float aspect) const {
    return glm::perspective(glm::radians(fov_y_deg), aspect, near_m, far_m);
}

void Camera::orbit(float dyaw_deg, float dpitch_deg) {
    yaw_deg = std::fmod(yaw_deg + dyaw_deg, 360.0f);
    pitch_deg = std::clamp(pitch_deg + dpitch_deg, -89.0f, 89.0f);
}

void Camera::pan(float dx, float dy) {
    const glm::mat4 v = view();
    const Vec3 right(v[0][0], v[1][0], v[2][0]);
    const Vec3 up(v[0][1], v[1][1], v[2][1]);
    target += distance * (-dx * right + dy * up);
}

void Camera::zoom(float factor) { distance = std::clamp(distance * factor, 0.5f, 1e5f); }

void fit_clip_planes(Camera& camera, const Terrain& terrain) {
    const Aabb& b = terrain.bounds();
    const float radius = 0.5f * glm::length(b.extent());
    const float d = glm::length(camera.eye() - b.center());
    camera.far_m = std::max(d + 2.0f * radius, 10.0f);
    camera.near_m = std::clamp((d - radius) * 0.5f, camera.far_m / 4000.0f, 1.0f);
    camera.near_m = std::max(camera.near_m, 0.02f);
}

Camera frame_terrain(const Terrain& terrain) {
    Camera c;
    const Aabb& b = terrain.bounds();
    const Vec3 ext = b.extent();
    // Look at the middle of the rectangle, a little above the mean ground.
    c.target = Vec3(b.center().x, b.min.y + 0.35f * ext.y, b.center().z);
    c.yaw_deg = 35.0f;
    // 32 degrees down for ordinary relief; steeper where the relief is high for the
    // terrain's width (the paper's 33 x 33 m maps at 24 m, spikes), or the near rim and
    // the block's side hide everything inside: 10 degrees over the slope from the
    // highest ground to the middle, at most 65.
    const float half_width = 0.5f * std::max(std::min(ext.x, ext.z), 1e-3f);
    c.pitch_deg = std::clamp(glm::degrees(std::atan2(ext.y, half_width)) + 10.0f, 32.0f, 65.0f);
    const float radius = 0.5f * std::sqrt(ext.x * ext.x + ext.z * ext.z + 0.25f * ext.y * ext.y);
    // Closer than the bounding sphere for ordinary relief (the terrain fills the image);
    // a steeper look sees more of the rectangle's depth, so it backs off up to 1.1.
    const float back = 0.8f + 0.3f * (c.pitch_deg - 32.0f) / (65.0f - 32.0f);
    c.distance = radius / std::tan(glm::radians(c.fov_y_deg) * 0.5f) * back;
    fit_clip_planes(c, terrain);
    return c;
}

Camera frame_terrain_from_above(const Terrain& terrain, float aspect) {
    Camera c;
    const Aabb& b = terrain.bounds();
    const Vec3 ext = b.extent();
    c.target = Vec3(b.center().x, b.min.y, b.center().z);
    c.yaw_deg = 0.0f;
    c.pitch_deg = 89.0f;
    const float t = std::tan(glm::radians(c.fov_y_deg) * 0.5f);
    // Half the rectangle on each axis fits the half view at the height of the highest
    // ground (ext.y above the target), with a 4 % margin.
    const float fit = std::max(0.5f * ext.z / t, 0.5f * ext.x / (t * std::max(aspect, 1e-3f)));
    c.distance = std::clamp(1.04f * fit + ext.y, 1.0f, 1e5f);
    fit_clip_planes(c, terrain);
    return c;
}

Status parse_camera(const std::string& text, Camera& camera) {
    std::vector<float> v;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        char* end = nullptr;
        const float f = std::strtof(item.c_str(), &end);
        if (item.empty() || end == item.c_str() || *end != '\0' || !std::isfinite(f))
            return Error{fmt::format("--camera: expected YAW,PITCH,DISTANCE[,TX,TY,TZ] (degrees, metres), got '{}'", text)};
        v.push_back(f);
    }
    if (v.size() != 3 && v.size() != 6)
        return Error{fmt::format("--camera: expected YAW,PITCH,DISTANCE[,TX,TY,TZ] (degrees, metres), got '{}'", text)};
    if (v[1] < -89.0f || v[1] > 89.0f)
        return Error{fmt::format("--camera: pitch must be in [-89, 89] degrees (got {})", v[1])};
    if (v[2] <= 0.0f || v[2] > 1e5f)
        return Error{fmt::format("--camera: distance must be in (0, 100000] metres (got {})", v[2])};
    camera.yaw_deg = v[0];
    camera.pitch_deg = v[1];
    camera.distance = v[2];
    if (v.size() == 6) camera.target = Vec3(v[3], v[4], v[5]);
    return Ok{};
}

Ray pixel_ray(const Camera& camera, float x, float y, int width, int height) {
    const float aspect = static_cast<float>(width) / static_cast<float>(std::max(height, 1));
    const glm::mat4 inv = glm::inverse(camera.projection(aspect) * camera.view());
    const float nx = 2.0f * x / static_cast<float>(width) - 1.0f;
    const float ny = 1.0f - 2.0f * y / static_cast<float>(height);
    glm::vec4 a = inv * glm::vec4(nx, ny, -1.0f, 1.0f);
    glm::vec4 b = inv * glm::vec4(nx, ny, 1.0f, 1.0f);
    const Vec3 pa = Vec3(a) / a.w, pb = Vec3(b) / b.w;
    return Ray{pa, glm::normalize(pb - pa)};
}

std::optional<Vec3> pick_terrain(const Camera& camera, float x, float y, int width, int height,
                                 const Terrain& terrain, const Bvh& bvh) {
    const Ray r = pixel_ray(camera, x, y, width, height);
    const Aabb& b = terrain.bounds();
    const float reach = glm::length(camera.eye() - b.center()) + glm::length(b.extent());
    auto hit = bvh.intersect_segment(terrain, r.origin, r.origin + reach * r.direction);
    if (!hit) return std::nullopt;
    return hit->point;
}

}  // namespace mr::render
