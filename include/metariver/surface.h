// metariver surface: marching cubes over a ScalarGrid into an indexed triangle mesh.
//
// Paul Bourke, "Polygonising a scalar field" (1994): corner and edge numbering and the
// 256-case edge and triangle tables. Vertices are welded by grid edge (one vertex per
// crossed edge, so uniqueness is exact, unlike the paper's position hash); normals come
// from the field's gradient; triangles wind counter-clockwise seen from outside.
#pragma once

#include <metariver/core.h>
#include <metariver/field.h>
#include <metariver/sparse_field.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace mr {

/// Indexed triangle mesh: 3 indices per triangle, counter-clockwise seen from outside
/// (the side where the field is below the threshold), unit normals pointing outward.
struct SurfaceMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;
    std::vector<uint32_t> indices;

    size_t vertex_count() const { return positions.size(); }
    size_t triangle_count() const { return indices.size() / 3; }
    void clear() {
        positions.clear();
        normals.clear();
        indices.clear();
    }
};

namespace mc {
/// Bourke's corner numbering: corner c sits at cell offset kCornerOffset[c] (x, y, z).
/// 0 (0,0,0) 1 (1,0,0) 2 (1,0,1) 3 (0,0,1) 4 (0,1,0) 5 (1,1,0) 6 (1,1,1) 7 (0,1,1)
extern const std::array<std::array<int, 3>, 8> kCornerOffset;
/// Bourke's edge numbering: edge e joins corners kEdgeCorners[e][0] and [1].
extern const std::array<std::array<int, 2>, 12> kEdgeCorners;
/// Bourke's edgeTable: bit e set when edge e is crossed, for cube index
/// sum(1 << c for corners c that are INSIDE).
extern const std::array<uint16_t, 256> kEdgeTable;
/// Triangle table in Bourke's numbering: up to 5 triangles as edge triples, terminated
/// by -1, indexed like kEdgeTable (bit c = corner c inside) and wound counter-clockwise
/// seen from outside. Generated from the cube's faces rather than copied from Bourke:
/// on a face with two diagonal corners inside, the inside corners are kept apart, so
/// neighbouring cells agree and the mesh is watertight (see mc_tables.cpp).
extern const std::array<std::array<int8_t, 16>, 256> kTriTable;
}  // namespace mc

/// Extracts the surface value == threshold. A sample is INSIDE when its value is above
/// the threshold. Vertices are placed by linear interpolation along crossed grid
/// edges, one per edge (welded). `out` is cleared and refilled; its capacity is reused.
void extract_surface(const ScalarGrid& grid, float threshold, SurfaceMesh& out);

/// Numbers from the last extract_surface_sparse, for tests and the bench.
struct SurfaceStats {
    size_t blocks = 0;            ///< blocks in the field's directory
    size_t candidate_blocks = 0;  ///< blocks whose cells' value range straddles the threshold
    size_t active_blocks = 0;     ///< candidates that own a vertex or a triangle
    size_t vertices = 0;
    size_t triangles = 0;
    double ms_select = 0.0;    ///< choosing candidate blocks from block min/max (serial)
    double ms_classify = 0.0;  ///< pass 1: inside bits, crossed-edge masks, counts (parallel)
    double ms_offsets = 0.0;   ///< prefix sums and sizing the output (serial)
    double ms_emit = 0.0;      ///< pass 2: vertices and triangles (parallel)
};

/// Per-frame scratch of extract_surface_sparse, owned by the caller and reused: once a
/// frame at least as large has run, an extraction allocates nothing (no vector grows).
struct SurfaceWorkspace {
    SurfaceWorkspace();
    ~SurfaceWorkspace();
    SurfaceWorkspace(SurfaceWorkspace&&) noexcept;
    SurfaceWorkspace& operator=(SurfaceWorkspace&&) noexcept;

    SurfaceStats stats;
    /// Bytes of reserved scratch (capacities), for steady-state checks.
    size_t capacity_bytes() const;

    struct Impl;
    std::unique_ptr<Impl> impl;
};

/// extract_surface on a SparseField, block-parallel (oneTBB) and skipping blocks whose
/// value range cannot cross the threshold. Gives the mesh extract_surface gives on
/// field.to_dense(): the same vertices (positions and normals bit for bit, same
/// arithmetic) and the same triangles, in a different but fixed order (by block, then
/// by grid edge / cell), identical for any thread count. `out` is resized once per call;
/// its capacity is reused.
void extract_surface_sparse(const SparseField& field, float threshold, SurfaceMesh& out, SurfaceWorkspace& ws);

}  // namespace mr
