// Rigid bodies' shapes (bodies.h): mass properties, the drawn mesh, the surface points the
// contacts sample, and the signed distance the water and other bodies meet. Not part of
// the library's API (rigid_shapes.cpp; the solver in rigid_bodies.h).
#pragma once

#include <metariver/bodies.h>

#include <glm/mat3x3.hpp>

#include <memory>
#include <vector>

namespace mr {

/// What a body's shape is, in its own frame (centre of mass at the origin).
struct RigidShape {
    BodyShape kind = BodyShape::Box;
    Vec3 half{0.0f};       ///< Box: half extents; Sphere: x = radius; Capsule: x = radius, y = half length
    float volume = 0.0f;   ///< m^3
    glm::mat3 inertia_unit{1.0f};  ///< inertia tensor per unit density (kg m^2 / (kg/m^3))
    float bound = 0.0f;    ///< radius of the sphere around the origin that holds the shape
    /// Mesh shapes: the convex hull's planes (n, d: n.x <= d inside), its vertices.
    std::vector<glm::vec4> planes;
    std::shared_ptr<const BodyMesh> mesh;
    std::vector<Vec3> samples;  ///< surface points for the contacts (corners included)
    Vec3 sample_extent{0.0f};   ///< the largest |coordinate| of the samples per axis (their box)

    /// Signed distance from a point in the body's frame (< 0 inside) and its gradient.
    float sdf(const Vec3& p, Vec3& normal) const;
    /// sdf()'s distance alone (the same value, cheaper).
    float distance(const Vec3& p) const;
};

/// The shape of a valid BodyDef (reads the OBJ of mesh shapes; errors name bodies.mesh and the file).
Result<RigidShape> make_shape(const BodyDef& def);
/// Body to world rotation from the scene's degrees about x, then y, then z (world axes).
glm::quat rotation_from_degrees(const Vec3& degrees);

}  // namespace mr
