// metariver scene view: what a reader of a running scene's frame needs (the renderer,
// tools), as plain read-only views: the terrain and its tree, the particles, the water
// surface, the diffuse particles. Readers take a SceneView, not the Simulation, so the
// layers below the app do not depend on the one that runs them (issue 14).
// Simulation::view() makes one; any producer of these types can.
#pragma once

#include <metariver/bodies.h>
#include <metariver/foam.h>
#include <metariver/particles.h>
#include <metariver/surface.h>
#include <metariver/terrain.h>

#include <cstdint>
#include <span>

namespace mr {

struct SceneView {
    const Terrain* terrain = nullptr;        ///< required
    const Bvh* bvh = nullptr;                ///< required: the tree over the terrain (debug boxes)
    bool paper_rows = false;                 ///< terrain.paper_row_orientation: how an image drapes
    const Particles* particles = nullptr;    ///< required
    const SurfaceMesh* surface = nullptr;    ///< required; empty when the scene has no surface
    const DiffuseParticles* foam = nullptr;  ///< null: no diffuse particles
    /// Metres: the particles' neighbourhood for the surface's velocities (flow_radius in
    /// scene.h); 0 gives every vertex velocity 0.
    float flow_radius = 0.0f;
    /// The fluid's velocity at the surface's last vertices, when the producer knows it (a
    /// heightfield's water: append_heightfield_surface's vertex_velocity), m/s; the
    /// vertices before them take theirs from the particles. Empty: all from the particles.
    std::span<const Vec3> surface_velocity;
    /// For the vertices before those (the particles' surface), when the producer joined a
    /// grid's water to it (the hybrid; seam_grid_velocities in surface.h): xyz the grid's
    /// velocity under the vertex, w the grid's share there (0 .. 1); the vertex takes
    /// w * xyz + (1 - w) * the particles'. Empty (or not one per such vertex): the
    /// particles' alone.
    std::span<const glm::vec4> surface_grid_velocity;
    /// The rigid bodies in the water (their meshes and transforms); empty: none.
    std::span<const BodyState> bodies;
    /// Who made the view and at which of its frames: a reader that saw the same owner
    /// at the same frame has nothing new to read.
    const void* owner = nullptr;
    uint64_t frame = 0;

    /// The required views are set.
    bool complete() const { return terrain && bvh && particles && surface; }
};

}  // namespace mr
