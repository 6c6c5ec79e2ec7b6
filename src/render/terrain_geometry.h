// The CPU side of the renderer's terrain buffers (private to mr_render): the mesh with
// smooth normals and its skirts, the AABB tree's boxes by depth, built whole for a new
// terrain and updated in place after a sculpt stroke, so the renderer uploads only the
// vertex rows and box spans that changed (issue 14: incremental terrain upload).
#pragma once

#include <metariver/terrain.h>

#include <glm/vec4.hpp>

#include <cstdint>
#include <utility>
#include <vector>

namespace mr::render {

/// Terrain vertex: position, normal, and 1 on the skirt (the cut at the edge).
struct TerrainVertex {
    Vec3 pos;
    Vec3 normal;
    float skirt;
};

/// One AABB tree box for the debug view.
struct BoxInstance {
    Vec3 min;
    Vec3 max;
    float depth;
};

struct TerrainGeometry {
    int columns = 0, rows = 0;
    /// rows x columns grid vertices (index i * columns + j), then the skirts: a wall from
    /// each border edge down to `skirt_bottom`.
    std::vector<TerrainVertex> vertices;
    std::vector<uint32_t> indices;
    float skirt_bottom = 0.0f;
    Aabb bounds;      ///< the grid vertices' box (height colours)
    glm::vec4 rect{}; ///< x0, z0, x1, z1 of the draped texture

    size_t grid_vertices() const { return size_t(columns) * size_t(rows); }
};

/// The whole mesh of `t`: every vertex normal the normalised sum of the (upward) face
/// normals around it, in triangle order.
void build_terrain_geometry(const Terrain& t, bool paper_rows, TerrainGeometry& g);

/// After heights changed in the samples of `changed` (rows i0..i1, columns j0..j1):
/// recomputes the grid vertices whose position or normal that can change (one sample
/// around the rectangle) with the same sums as build_terrain_geometry (bit for bit), the
/// skirts when the rectangle reaches a border, and the bounds. Returns false (nothing
/// changed) when `g` is not this terrain's mesh or its skirts' bottom moved: build again.
/// `rows_out` gets the vertex rectangle rewritten.
bool update_terrain_geometry(const Terrain& t, const TerrainEdit& changed, TerrainGeometry& g, TerrainEdit& rows_out);

/// Whether a sample rectangle reaches the terrain's border (its skirts change with it).
bool touches_border(const TerrainGeometry& g, const TerrainEdit& r);

struct TreeBoxes {
    std::vector<BoxInstance> boxes;              ///< by depth, then the leaves again
    std::vector<uint32_t> node;                  ///< per box, the tree node it shows
    size_t nodes = 0;                            ///< the tree's node count
    std::vector<uint32_t> level_first, level_count;
    uint32_t leaves_first = 0, leaves_count = 0;
    int depth = 0;
};
void build_tree_boxes(const Bvh& bvh, TreeBoxes& out);

/// After Bvh::refit_heights (the same tree, new boxes): every box taken from its node
/// again, in place; `spans` gets, per depth and for the leaves, the [first, end) of the
/// boxes from the first to the last that moved (none when nothing did). False, nothing
/// changed, when `bvh` has another node count than the boxes were built from: build again.
bool refit_tree_boxes(const Bvh& bvh, TreeBoxes& t, std::vector<std::pair<uint32_t, uint32_t>>& spans);

}  // namespace mr::render
