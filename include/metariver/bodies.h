// metariver bodies: rigid things in the river (logs, boats, crates, debris), two-way coupled
// with the PBF water. A scene lists them under [[bodies]] (docs/scene-format.md); the
// Simulation adds, moves and removes them live (scene.h). This header is plain data: the
// description of a body, its state each frame, and the mesh it is drawn and exported with.
#pragma once

#include <metariver/core.h>

#include <glm/gtc/quaternion.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace mr {

enum class BodyShape {
    Box,           ///< size: full extents along the body's x, y, z
    Sphere,        ///< size.x: radius
    Capsule,       ///< size.x: radius, size.y: length of the cylinder between the caps, along the body's x
    ConvexMesh,    ///< the convex hull of an OBJ file's vertices (mesh), scaled by size.x
    TriangleMesh,  ///< a closed OBJ triangle mesh (mesh), scaled by size.x
};
std::string_view to_string(BodyShape s);

/// Most bodies a scene or a Simulation holds.
inline constexpr size_t kMaxBodies = 1024;

/// One body as the scene file gives it ([[bodies]]): every field is a key of the table.
struct BodyDef {
    BodyShape shape = BodyShape::Box;
    Vec3 size{2.0f, 0.5f, 0.5f};  ///< metres, see BodyShape; each used component in (0, 1000]
    std::string mesh;             ///< ConvexMesh / TriangleMesh: OBJ path (relative: to the scene file)
    float density = 500.0f;       ///< kg/m^3, (0, 100000]; water is 1000
    Vec3 position{0.0f};          ///< metres: the centre of mass at the start
    Vec3 rotation{0.0f};          ///< degrees: rotations about x, then y, then z (world axes)
    Vec3 velocity{0.0f};          ///< m/s at the start
    Vec3 angular_velocity{0.0f};  ///< rad/s at the start (world axes)
    float friction = 0.5f;        ///< Coulomb coefficient against the terrain and other bodies, [0, 2]
    bool operator==(const BodyDef&) const = default;
};

/// Checks a BodyDef's values (not its mesh file) against the [[bodies]] key table's
/// ranges, the scene file's (docs/scene-format.md: one definition), and its shape's needs:
/// the scene reader's message with `bodies.` for `bodies[i].`
/// ("bodies.density: must be in (0, 100000] (got -1)"). Simulation::add_body checks the
/// mesh file too.
Status validate_body(const BodyDef& def);

/// The triangles a body is drawn and exported with, in the body's own frame (centre of
/// mass at the origin): generated for the primitives, the OBJ's for mesh shapes.
struct BodyMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;
    std::vector<uint32_t> indices;
};

/// A body after the latest frame.
struct BodyState {
    uint32_t id = 0;          ///< stable handle (Simulation::add_body), never reused in a Simulation
    BodyShape shape = BodyShape::Box;
    Vec3 size{0.0f};
    Vec3 position{0.0f};      ///< centre of mass, metres
    glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};  ///< body to world
    Vec3 velocity{0.0f};      ///< m/s
    Vec3 angular_velocity{0.0f};  ///< rad/s, world axes
    float mass = 0.0f;        ///< kg
    float volume = 0.0f;      ///< m^3
    /// Share of the body's volume under the water, [0, 1], as the coupling measured it.
    float submerged_fraction = 0.0f;
    std::shared_ptr<const BodyMesh> mesh;  ///< shared by the states of one body
};

}  // namespace mr
