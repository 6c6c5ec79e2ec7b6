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

#include <glm/vec4.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
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

/// Scratch of append_heightfield_surface, reused by the caller (no allocation once warm).
/// Its slots cover two sample rows (a cell row reads its two and nothing else), so a
/// call's cost follows the wet samples, not the grid; they are all none between calls.
struct HeightfieldScratch {
    std::vector<uint32_t> vertex;    ///< 2 x columns: the vertex of each sample of two rows, or none
    std::vector<uint32_t> crossing;  ///< 4 x columns: the shoreline vertex on two rows' +x edges, one cell row's +z and diagonal edges
    std::vector<uint32_t> row_base;  ///< per row: the vertex of its first wet sample (vertices of wet samples in sample order)
    std::vector<int> first, last;    ///< per row: its wet columns (first > last: none)
};

/// Water given as depths over a heightfield (a solver's HeightfieldWater on the
/// terrain's grid: solver.h) as a mesh, appended to `out` (its indices offset past the
/// vertices it holds, so a particle surface and a heightfield surface make one mesh).
/// `bed` and `depth` hold rows x columns samples, row-major (index i * columns + j, as
/// Terrain::vertices()): the bed's positions and the water's depth above them, metres.
/// A sample is wet when its depth is > 5 mm (thinner films, as a shallow-water solver
/// leaves on slopes, are drawn as dry); its level is bed + depth. A dry sample beside a
/// wet one (8 neighbours: the ring) gets L, the lowest level of its wet neighbours, where
/// its bed is above L, else bed - (L - bed) (a dry sample under the water beside it ends
/// the water part way to it). Each cell is split into two triangles as the terrain's mesh splits it, and
/// each triangle is cut where level - bed (depth on wet samples, <= 0 on the ring) crosses
/// 0, linear along its edges (marching triangles): the shoreline is where the water's
/// plane meets the terrain's triangles, not the cells' staircase, and on a lake it is the
/// terrain's contour at the lake's level (a cut within `snap` = 0.05 of an edge's end
/// moves to that end, so no sliver triangles). Counter-clockwise seen from above
/// (normals up). Vertices: one per wet sample (its bed raised by the depth), in sample
/// order, then one per cut edge; normals: the normalised area-weighted mean of the
/// vertex's triangles' normals. A fully wet grid gives two triangles per cell on the
/// samples alone. `velocity` (optional, one per sample) gives `vertex_velocity` (appended,
/// one per new vertex): a sample's own, a cut's its wet end's. Nothing is appended when
/// the sizes do not match rows x columns or either is < 2.
/// `skip_cells` (optional, (rows - 1) x (columns - 1), row-major): a cell whose entry is
/// non-zero gets no triangles (join_heightfield_to_field's cells, drawn by the field).
/// `wet_first` and `wet_last` (optional, one per row: HeightfieldWater's) say where each
/// row may be wet (depth 0 outside): the call then reads only those columns and the ring
/// around them, and costs the wet samples, not the grid (without them it reads each row's
/// depths once to find its wet columns); the mesh is the same either way.
void append_heightfield_surface(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns,
                                SurfaceMesh& out, HeightfieldScratch* scratch = nullptr,
                                std::span<const Vec3> velocity = {}, std::vector<Vec3>* vertex_velocity = nullptr,
                                std::span<const uint8_t> skip_cells = {}, std::span<const int> wet_first = {},
                                std::span<const int> wet_last = {});

/// Where a heightfield's water and a particle field meet: join_heightfield_to_field's
/// result, reused from frame to frame.
struct HeightfieldSeam {
    /// Per cell ((rows - 1) x (columns - 1), row-major): 1 where the field draws the water
    /// and the heightfield mesh leaves the cell out; 0 elsewhere.
    std::vector<uint8_t> cell;
    size_t cells = 0;           ///< cells with cell = 1
    /// Per column (i, k) of the field's samples (nx x nz, i fastest): 1 where the field got
    /// the grid's term (some ball's field reaches the water's level there); 0 elsewhere.
    std::vector<uint8_t> column;
    size_t columns = 0;         ///< columns with column = 1
    /// Per column, as `column`: the level s of the term there (metres; NaN where column = 0).
    std::vector<float> level;
    void clear() {
        cell.clear();
        cells = 0;
        column.clear();
        columns = 0;
        level.clear();
    }
};

/// One surface where a heightfield's water and a particle field meet (issue 46's seam;
/// docs/waterfalls.md). The grid's water becomes a term of the field wherever the field
/// stores samples (near the particles): in the columns over a fully wet cell (4 samples
/// deeper than 5 mm) the field gets threshold * clamp(1 + (s - y) / width, 0, 2), s the
/// water's level on the heightfield mesh's triangles less 5 mm (so that where both are
/// drawn the heightfield shows, without z-fighting; SparseField::add_level_term).
/// Marching cubes then puts the water's surface at s where no particle is near, and where
/// particles are, the metaballs rise out of it with a smooth skirt: no crease, and no
/// metaball under the water's surface. A cell is the field's (`seam.cell`) when the field
/// stores every sample around it, from a sample under its lowest level to one over its
/// highest: the heightfield mesh leaves it out (append_heightfield_surface's skip_cells).
/// Around those cells both are drawn, the field's surface on or over the heightfield's,
/// and the field's ends at its stored blocks' edge, where the particles add (almost) 0.
/// The term goes only into the columns where some ball's field (> 2 % of the threshold)
/// reaches the band within width + one sample of the water's level (`seam.column`): where no
/// ball is near the water's surface the heightfield draws it alone, at its own cost, and no
/// flat water is drawn twice.
/// `bed`, `depth`, rows and columns as append_heightfield_surface's (a regular grid).
/// Nothing is joined (seam cleared) when the sizes do not match or the field is empty.
void join_heightfield_to_field(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns,
                               float threshold, float width, SparseField& field, HeightfieldSeam& seam);

/// Removes a joined field's triangles that lie under the water's surface, never seen (the
/// heightfield's surface, or the field's own flat water over `seam.cell`, is in front of
/// them from above): those whose three vertices lie over fully wet cells, more than 2 mm
/// under the heightfield's level (where it is drawn) or 2 cm under the field's flat water
/// (over seam.cell); the term's closing faces under the water, the flat water the
/// heightfield covers, the balls inside the pool. Vertices no triangle uses are dropped
/// (kept in order). `mesh` must be the field's surface alone (before the heightfield is
/// appended); nothing happens when the sizes do not match or seam.columns is 0. `scratch`
/// is reused from call to call.
void drop_under_water(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns,
                      const HeightfieldSeam& seam, SurfaceMesh& mesh, std::vector<uint32_t>& scratch);

/// The grid's part in the velocity of a joined field's vertices (the water's flow detail):
/// per vertex, xyz the grid's velocity under it (its samples' `velocity` interpolated on the
/// heightfield mesh's triangles, as the heightfield's own vertices' are) and w the grid's
/// share of the field there, clamp(1 + (s - y) / width, 0, 1) with s as in
/// join_heightfield_to_field: 1 on the flat water the term draws, falling to 0 up a drop's
/// skirt. (0, 0, 0, 0) over dry or partly dry cells and beyond the grid. The vertex's
/// velocity is then w * xyz + (1 - w) * the particles' (render::surface_velocities), so
/// that the field's flat water flows as the heightfield around it does.
/// `out` is resized to vertices.size(); all 0 when the sizes do not match rows x columns.
void seam_grid_velocities(std::span<const Vec3> bed, std::span<const float> depth, std::span<const Vec3> velocity,
                          int rows, int columns, float width, std::span<const Vec3> vertices,
                          std::vector<glm::vec4>& out);

/// extract_surface on a SparseField, block-parallel (oneTBB) and skipping blocks whose
/// value range cannot cross the threshold. Gives the mesh extract_surface gives on
/// field.to_dense(): the same vertices (positions and normals bit for bit, same
/// arithmetic) and the same triangles, in a different but fixed order (by block, then
/// by grid edge / cell), identical for any thread count. `out` is resized once per call;
/// its capacity is reused.
void extract_surface_sparse(const SparseField& field, float threshold, SurfaceMesh& out, SurfaceWorkspace& ws);


// ---- Smoothing (issue 11) ----------------------------------------------------------
//
// Marching cubes over a particle field is bumpy at the scale of the particles: still
// water reads as hammered metal. smooth_surface() moves the vertices of the extracted
// mesh (never its connectivity) with feature-weighted Laplacian steps, as splashsurf does
// (Loeschner, Boettcher, Jeske, Bender, "Weighted Laplacian smoothing for surface
// reconstruction of particle-based fluids", VMV 2023): every step moves a vertex toward
// the mean of its neighbours by w times the step size, where the feature weight w in
// [0, 1] is small where little water lies behind the surface (spray, lone drops, thin
// strands), so they keep their shape. What the steps take from the volume (a pool's rim
// rounds off) is given back by moving every moved vertex along its normal by w times one
// common distance. Taubin's lambda|mu steps (Taubin, "A signal processing approach to
// fair surface design", SIGGRAPH 1995) are the alternative that keeps the volume by
// itself but flattens far less per step. The moved vertices get normals from the smoothed
// triangles; the others keep the field's gradient normal.

enum class SmoothingMethod {
    None,       ///< the marching-cubes mesh as extracted (normals from the field's gradient)
    Laplacian,  ///< feature-weighted Laplacian steps, then the volume restored (the default scene's)
    Taubin,     ///< lambda and mu steps alternate (Taubin 1995): keeps volume, flattens less
};
std::string_view to_string(SmoothingMethod m);

/// The step sizes of the Laplacian method.
enum class SmoothingSteps {
    Uniform,    ///< every step lambda (splashsurf)
    Chebyshev,  ///< sizes from the Chebyshev polynomial that damps the band [pass_band, 2]
                ///< evenly (Taubin, Zhang, Golub 1996), in cycles of up to 8 steps: more
                ///< than twice as many uniform steps of 1 do at the band's low end
};
std::string_view to_string(SmoothingSteps s);

struct SmoothingDef {
    SmoothingMethod method = SmoothingMethod::None;
    SmoothingSteps steps = SmoothingSteps::Chebyshev;  ///< Laplacian only
    int iterations = 8;      ///< [0, 100] steps (Taubin: lambda, mu, lambda, ... one each)
    float lambda = 0.9f;     ///< (0, 1] share of the way to the neighbours' mean per step (uniform, Taubin)
    /// (0, 1): frequencies (eigenvalues of the mesh Laplacian, 0 to 2) below it are
    /// kept: Taubin's k_PB (mu = 1 / (k_PB - 1 / lambda)); Chebyshev steps damp [pass_band, 2].
    float pass_band = 0.1f;
    /// Feature weights, with a compact (poly6) field: the field is read one lone ball's
    /// iso distance inside the surface along the field's gradient, in units of the
    /// kernel's centre value (about the number of balls behind the vertex: a lone drop
    /// reads 1, two touching drops about 1.4, still water 2 to 4), and
    /// w = smoothstep((value - N / 2) / (N / 2)), N = feature_count: from N / 2 down
    /// a vertex does not move, from N up it moves fully. 0: off (w = 1 everywhere, as
    /// with the paper's dense kernels). 0 or [2, 1000].
    float feature_count = 3.0f;
    bool keep_volume = true;    ///< Laplacian: give back the volume the steps took (Taubin: ignored)
    int normal_iterations = 0;  ///< [0, 100] passes that average each normal with its neighbours'
    /// With a ground (SmoothingGround): false, the vertices below it stay where marching
    /// cubes put them (the terrain hides them: about half of a river's mesh is its bed);
    /// true, they are smoothed too.
    bool smooth_hidden = false;
};

/// The step sizes smooth_surface uses for `def`, in order (for tests and docs).
std::vector<float> smoothing_step_sizes(const SmoothingDef& def);

/// The field the feature weights read: the compact kernel the field was built with and
/// the threshold the mesh was extracted at.
struct SmoothingField {
    const SparseField* field = nullptr;
    KernelDef kernel;
    float threshold = 0.0f;
};

/// The ground the water lies on: a heightfield of rows x columns samples, sample (i, j) at
/// x = j spacing, z = i spacing, its height the y of vertices[i * columns + j] (a Terrain's
/// vertices), between samples the two triangles per cell of the terrain's rendered mesh
/// (Terrain::height_mesh). A vertex below it is hidden and, unless
/// SmoothingDef::smooth_hidden, does not move.
struct SmoothingGround {
    const Vec3* vertices = nullptr;
    int columns = 0, rows = 0;  ///< >= 2 each, else no ground
    float spacing = 0.0f;       ///< metres between samples, > 0
    /// The height at (x, z), clamped into the heightfield as Terrain::height_mesh does.
    float height(float x, float z) const;
};

/// Numbers from the last smooth_surface, for tests and the bench.
struct SmoothingStats {
    size_t vertices = 0;
    size_t moving = 0;           ///< vertices that moved (weight > 0, not pinned)
    size_t pinned = 0;           ///< vertices with a weight > 0 on an open boundary (not moved)
    size_t hidden = 0;           ///< vertices below the ground, kept in place (not read from the field)
    double mean_weight = 0.0;    ///< mean feature weight over the vertices
    size_t triangles = 0;        ///< triangles with a moving corner
    double volume_change = 0.0;  ///< m^3 the steps changed the enclosed volume by, before it was given back (keep_volume; else 0)
    double ms_rings = 0.0;       ///< fans of the moving vertices, pinning (serial)
    double ms_weights = 0.0;     ///< feature weights (parallel)
    double ms_smooth = 0.0;      ///< the position steps (parallel)
    double ms_normals = 0.0;     ///< normals, the volume given back (parallel)
    bool simd_weights = false;   ///< the weights ran eight at a time (AVX2; else the scalar loop)
};

/// Scratch of smooth_surface, owned by the caller and reused: a frame no larger than one
/// already smoothed allocates nothing.
struct SmoothingWorkspace {
    /// A position padded to 16 bytes (one SSE load).
    struct alignas(16) P4 {
        float x, y, z, w;
    };
    SmoothingStats stats;
    std::vector<uint32_t> moving;        ///< vertices with a weight > 0, ascending
    std::vector<uint32_t> moving_index;  ///< per vertex: its index in `moving`, or 0xffffffff
    std::vector<uint32_t> listed;        ///< triangles with a moving corner, each share's from its first triangle on
    std::vector<uint32_t> ring_start;    ///< per moving vertex + 1: its first corner in next / prev
    std::vector<uint32_t> next, prev;    ///< per corner of a moving vertex: the triangle's next and previous vertex
    std::vector<uint32_t> next_m;        ///< per corner of a moving vertex: moving_index of its next vertex
    std::vector<uint32_t> fan_counts;    ///< per share of the triangles and moving vertex: corners, then cursors
    std::vector<float> weight;           ///< per vertex: feature weight (0: does not move)
    std::vector<float> moving_weight;    ///< per moving vertex: weight (0: pinned on an open boundary)
    std::vector<float> step_weight;      ///< per moving vertex: weight / degree
    std::vector<uint32_t> inner;         ///< per moving vertex: its moving neighbours (the first of its range in nbr)
    std::vector<uint32_t> nbr;           ///< per corner of a moving vertex: a moving neighbour's index in `moving`
    std::vector<P4> fixed_sum;         ///< per moving vertex: the sum of its neighbours that do not move
    std::vector<P4> orig;              ///< per moving vertex: its position as extracted
    std::vector<P4> a, b;              ///< per moving vertex: double-buffered positions of the steps
    std::vector<Vec3> area_normal;     ///< per moving vertex: sum of its fan's cross products
    std::vector<float> area_len;       ///< per moving vertex: the length of area_normal
    std::vector<float> volume_term;    ///< per moving vertex: its share of 6 x the volume change
    std::vector<float> step_sizes;     ///< smoothing_step_sizes() of the latest call
    /// Run the scalar twins of the SIMD passes (tests compare the two; the result is the
    /// same bit for bit).
    bool scalar = false;
    size_t capacity_bytes() const;
};

/// Smooths `mesh` in place as `def` says (method None: nothing is touched). `field`
/// (optional) gives the feature weights; without it, or with feature_count 0, every
/// vertex has weight 1. Vertices on an open boundary (an edge with one triangle) stay
/// where they are, so a mesh clipped by the field's box keeps its rim. Positions and
/// normals depend only on the mesh and the field, not on the thread count. A mesh without
/// one normal per vertex gets them (moved vertices from their triangles, the others +y)
/// and no feature weights. `ground` (optional): the vertices below it stay in place
/// (SmoothingDef::smooth_hidden).
void smooth_surface(SurfaceMesh& mesh, const SmoothingDef& def, SmoothingWorkspace& ws,
                    const SmoothingField* field = nullptr, const SmoothingGround* ground = nullptr);

/// The distance from a lone ball's centre to the iso surface of `threshold` (the depth
/// at which the feature weights read the field), 0 when one ball cannot reach it.
float lone_ball_iso_distance(const KernelDef& kernel, float threshold);

}  // namespace mr
