// The bodies' triangles in world space (body_geometry.h).
#include "body_geometry.h"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>

namespace mr::render {

glm::mat4 body_transform(const BodyState& b) {
    return glm::translate(glm::mat4(1.0f), b.position) * glm::mat4_cast(glm::normalize(b.orientation));
}

void build_body_geometry(std::span<const BodyState> bodies, std::vector<BodyVertex>& vertices,
                         std::vector<uint32_t>& indices) {
    vertices.clear();
    indices.clear();
    for (const BodyState& b : bodies) {
        if (!b.mesh) continue;
        const BodyMesh& m = *b.mesh;
        const size_t n = m.positions.size();
        const bool normals = m.normals.size() == n;
        if (n == 0 || std::any_of(m.indices.begin(), m.indices.end(), [&](uint32_t i) { return i >= n; })) continue;
        const glm::mat4 to_world = body_transform(b);
        const glm::mat3 rotate = glm::mat3_cast(glm::normalize(b.orientation));
        const auto first = static_cast<uint32_t>(vertices.size());
        for (size_t i = 0; i < n; ++i)
            vertices.push_back({Vec3(to_world * glm::vec4(m.positions[i], 1.0f)),
                                normals ? rotate * m.normals[i] : Vec3(0.0f, 1.0f, 0.0f)});
        for (const uint32_t i : m.indices) indices.push_back(first + i);
    }
}

}  // namespace mr::render
