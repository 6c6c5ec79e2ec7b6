// The bodies' triangles in world space (bodies.h, SceneView::bodies), for the renderer:
// each body's BodyMesh under its transform (position, orientation), all bodies in one
// vertex and index array, so a frame draws them in one call whatever their number.
#pragma once

#include <metariver/bodies.h>

#include <glm/mat4x4.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace mr::render {

struct BodyVertex {
    Vec3 pos;
    Vec3 normal;
};

/// Body to world: the translation to the centre of mass after the rotation.
glm::mat4 body_transform(const BodyState& b);

/// Replaces `vertices` and `indices` (capacity reused) with every body's mesh in world
/// space; a body without a mesh, or with indices outside its vertices, is left out.
void build_body_geometry(std::span<const BodyState> bodies, std::vector<BodyVertex>& vertices,
                         std::vector<uint32_t>& indices);

}  // namespace mr::render
