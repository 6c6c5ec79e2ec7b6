// metariver terrain: heightmaps (PNG or procedural), the terrain triangle mesh of
// the paper's figure 2, height/normal queries, and the AABB tree (BVH) with the
// paper's point query and a robust swept-segment query.
//
// Paper: "Real-time river simulation using metaballs", section 2.2 (terrain) and
// 2.3.3 (collision). Ray/triangle tests: Moller-Trumbore (the paper's eq. 4) and the
// watertight test of Woop, Benthin and Wald, JCGT 2013.
#pragma once

#include <metariver/core.h>

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace mr {

/// Heights sampled on a regular grid, normalised to [0, 1], in IMAGE order:
/// samples[r * width + c] is image row r (r = 0 is the top row), column c.
struct Heightmap {
    int width = 0;   ///< samples per row (>= 2)
    int height = 0;  ///< rows (>= 2)
    std::vector<float> samples;
    int bit_depth = 8;  ///< 8 or 16 for images; 32 for procedural (float) maps

    float at(int row, int col) const { return samples[static_cast<size_t>(row) * width + col]; }
};

/// Largest accepted heightmap side, in samples (keeps the mesh under ~33 M triangles).
inline constexpr int kMaxHeightmapSide = 4097;

/// Loads a PNG heightmap. 8- or 16-bit; gray, gray+alpha, RGB or RGBA. Height is the
/// RED channel (gray for gray images) divided by 255 (8-bit) or 65535 (16-bit); 16-bit
/// images keep their full precision. Errors (missing, empty, truncated, not a PNG,
/// smaller than 2 x 2, larger than kMaxHeightmapSide) name the file.
Result<Heightmap> load_heightmap_png(const std::string& path);
/// The same from bytes in memory; `name` is used in error messages.
Result<Heightmap> load_heightmap_png_memory(std::span<const uint8_t> bytes, const std::string& name);
/// A PNG's structure, checked before any decoder sees it: the signature, every chunk's
/// length within the bytes, the CRC of every critical chunk, IHDR first, up to IEND.
/// Returns IHDR's width and height; errors (truncated, corrupt) name `name`. The heightmap
/// and the image loader run it (stb_image alone takes a file cut inside IEND, and
/// allocates what a chunk's length field claims before reading it).
Result<std::array<uint32_t, 2>> check_png_structure(std::span<const uint8_t> bytes, const std::string& name);
/// CRC-32 (ISO 3309) as PNG chunks carry it: over a chunk's type and data.
uint32_t png_crc32(const uint8_t* data, size_t n);

/// A width x height map with every sample = value (procedural, bit_depth 32);
/// negative sizes count as 0. Callers shape it from there.
Heightmap flat_heightmap(int width, int height, float value = 0.0f);

/// Procedural terrains, deterministic for a seed.
/// A valley with a winding river channel running downhill from the far end (high z
/// in terrain space, low image row) to the near end.
Heightmap procedural_valley(int width, int height, uint32_t seed);
/// The paper's 'strict' shape: a gradient from black to white along the rows with a
/// darker strip along the middle.
Heightmap procedural_strict(int width, int height);
/// The paper's 'bowl': radial, lowest at the centre.
Heightmap procedural_bowl(int width, int height);
/// A river over a cliff: a channel from the top rows down to a lip at 70 % of the rows,
/// a drop of 0.52 of the height range into a plunge pool, and a channel out over row 0;
/// banks 0.15 above the bed on both sides (the hybrid solver's waterfall scene).
Heightmap procedural_waterfall(int width, int height);
/// A channel with a weir across it at half its length: the crest 0.1 of the height range
/// above the bed upstream, 0.2 above the bed downstream; banks 0.15 above the bed.
Heightmap procedural_weir(int width, int height);

/// Drainage conditioning of a terrain before its mesh is built (Barnes et al. 2014,
/// Lindsay 2016): a depression has no way out for water running downhill.
enum class TerrainCondition {
    None,    ///< heights as given: water fills a depression and spills over its rim
    Fill,    ///< priority-flood filling: every depression is raised to its spill height,
             ///< with a slope of `kConditionSlope` towards the spill point
    Breach,  ///< priority-flood breaching: a channel is carved from each depression's
             ///< bottom through its rim, descending by `kConditionSlope` per metre
    Carve,   ///< breaching, then the river's main channel is carved into the terrain
             ///< (Terrain::carve_channel; the scene supplies the channel): a bed that
             ///< descends all the way from the source to the outlet, with banks
    Auto,    ///< resolved by the scene before the terrain is built: carve for a PBF
             ///< river (a continuous source and an edge sink), none otherwise;
             ///< Terrain::build treats it as none
};
std::string_view to_string(TerrainCondition c);

/// Slope (metres per metre) that filled surfaces and carved channels keep towards the
/// terrain's edge, so every cell has a strictly lower neighbour on its way out.
inline constexpr float kConditionSlope = 1e-3f;

/// The cross-section of a carved channel (Terrain::carve_channel).
struct CarveDef {
    float width_m = 6.0f;  ///< bank to bank, metres, > 0
    /// Width of the flat bed, metres, [0, width_m]: at least three samples, or a path's
    /// diagonal step would cross the mesh's cell diagonal as a dam.
    float floor_m = 3.0f;
    float depth_m = 1.0f;  ///< bed below the path's ground (at least), metres, > 0
    /// A basin under the source (radius 0: none): centre (x, z; y ignored) and radius,
    /// metres, its bottom the channel's first bed, so a source wider than the channel
    /// does not spill beside it.
    Vec3 basin_center{0.0f};
    float basin_radius_m = 0.0f;
};

/// The least slope (metres per metre) a carved bed keeps along its path
/// (Terrain::carve_channel): on a flat reach the river runs at walking pace. Less (the
/// rule was half the path's mean slope, 0.1 % on a flat) and slow water on a flat
/// floor stops: measured in docs/river.md, "A least slope of 2 %".
inline constexpr float kCarveLeastSlope = 0.02f;
/// The steepest drop a carved bed keeps (Terrain::carve_channel), unless the path's mean
/// slope is steeper: water leaving a cliff's edge flies off as spray.
inline constexpr float kCarveSteepest = 1.0f;

/// What conditioning changed.
struct ConditionReport {
    TerrainCondition mode = TerrainCondition::None;
    uint64_t cells_raised = 0;   ///< cells whose height went up (fill)
    uint64_t cells_lowered = 0;  ///< cells whose height went down (breach, carve)
    float max_change_m = 0.0f;   ///< largest |change| of one cell, metres
    double volume_m3 = 0.0;      ///< sum of |change| x cell area, cubic metres
};

/// Conditions a grid of heights (metres, row-major, `columns` per row) in place.
/// Deterministic (ties by cell index). O(n log n).
ConditionReport condition_heights(std::vector<float>& heights, int columns, int rows, float area_scale,
                                  TerrainCondition mode);

/// `terrain.area_scale = "auto"` (the default scene's): area_scale metres per sample (1 m
/// in the default scene), raised so that the terrain's shorter side is at least
/// kAutoMinSide metres. A PNG has no units; at 1 m a 2 x 2 map is a 1 m terrain (two
/// triangles under the default 24 m of relief) on which no channel, source or river fits
/// (docs/river.md, "Sizing": random_2x2 ran 0 of its inflow at 1 m and all of it at 16 m).
inline constexpr float kAutoMinSide = 16.0f;

struct TerrainDef {
    /// Metres between neighbouring samples (x and z); with auto_area_scale the least
    /// (resolved_area_scale).
    float area_scale = 1.0f;
    float height_scale = 7.0f;  ///< metres for a normalised height of 1
    /// The paper's (Unity's) row orientation: image row r maps to z = (H-1-r)*area_scale.
    /// false: image row r maps to z = r*area_scale.
    bool paper_row_orientation = true;
    /// Drainage conditioning applied to the heights before the mesh is built.
    TerrainCondition condition = TerrainCondition::None;
    /// `area_scale = "auto"`: raised for a small map (kAutoMinSide). A number clears it.
    bool auto_area_scale = false;
};

/// The metres per sample a terrain of `columns` x `rows` samples is built with:
/// def.area_scale, or with auto_area_scale max(def.area_scale, kAutoMinSide /
/// (min(columns, rows) - 1)).
float resolved_area_scale(const TerrainDef& def, int columns, int rows);

/// A sculpting brush (Terrain::sculpt, Simulation::sculpt): what it does to the heights
/// within `radius` of its centre, weighted by (1 - (d / radius)^2)^2 (1 at the centre, 0
/// at the rim with a flat tangent, so repeated strokes leave no ridge).
enum class BrushMode {
    Raise,    ///< height += strength x weight (metres)
    Lower,    ///< height -= strength x weight (metres)
    Smooth,   ///< towards the mean of the 3 x 3 samples around, strength x weight of the way
    Flatten,  ///< towards `target`, strength x weight of the way
};
struct Brush {
    float x = 0.0f, z = 0.0f;  ///< centre, metres (world x and z)
    float radius = 3.0f;       ///< metres, > 0 and finite
    /// Raise / lower: metres at the centre per stroke, >= 0; smooth / flatten: the share of
    /// the way at the centre, [0, 1].
    float strength = 0.5f;
    BrushMode mode = BrushMode::Raise;
    float target = 0.0f;  ///< flatten: the height, metres
};
/// The samples one stroke changed and their heights before it (for undo): rows i0..i1
/// and columns j0..j1 (inclusive), `before` row by row. Empty (i1 < i0) when the brush
/// touched no sample.
struct TerrainEdit {
    int i0 = 0, j0 = 0, i1 = -1, j1 = -1;
    std::vector<float> before;
    bool empty() const { return i1 < i0 || j1 < j0; }
};

/// The terrain mesh exactly as the paper's figure 2: one vertex per sample, vertex
/// index c = i*W + j for grid row i (z) and column j (x) at (j*s, h*height_scale, i*s);
/// two triangles per cell, (c, c+W, c+1) and (c+1, c+W, c+W+1), both wound so their
/// geometric normal points up (+y). 2(W-1)(H-1) triangles; triangle 2*(i*(W-1)+j) and
/// 2*(i*(W-1)+j)+1 belong to cell (i, j).
class Terrain {
public:
    /// Builds the mesh; fails on a bad heightmap or def (non-finite or <= 0 scales).
    static Result<Terrain> build(const Heightmap& map, const TerrainDef& def);

    int columns() const { return columns_; }  ///< samples along x (W)
    int rows() const { return rows_; }        ///< samples along z (H)
    float area_scale() const { return area_scale_; }
    /// Height (metres) of grid sample (row i along z, column j along x).
    float sample(int i, int j) const { return vertices_[static_cast<size_t>(i) * columns_ + j].y; }

    std::span<const Vec3> vertices() const { return vertices_; }
    /// 3 vertex indices per triangle.
    std::span<const uint32_t> indices() const { return indices_; }
    size_t triangle_count() const { return indices_.size() / 3; }
    /// Geometric (face) normal of a triangle, unit length, pointing up.
    Vec3 triangle_normal(uint32_t tri) const;

    /// Mesh bounds grown by 1 m up and down (the paper's terrain bounding box).
    const Aabb& bounds() const { return bounds_; }
    /// The vertices' own box (bounds() before the 1 m growth: the height colours' range).
    const Aabb& mesh_bounds() const { return mesh_bounds_; }
    /// True when (x, z) lies inside the terrain's rectangle [0, (W-1)s] x [0, (H-1)s].
    bool contains_xz(float x, float z) const;

    /// Bilinear interpolation of the samples at (x, z), clamped to the rectangle.
    float height_bilinear(float x, float z) const;
    /// Normal of the bilinear surface at (x, z) (from its analytic gradient), unit, up.
    Vec3 normal_bilinear(float x, float z) const;
    /// Height of the triangle MESH at (x, z) (the surface collisions use), clamped.
    float height_mesh(float x, float z) const;
    /// Normal of the mesh triangle under (x, z).
    Vec3 normal_mesh(float x, float z) const;
    /// Index of the mesh triangle under (x, z) (clamped into the rectangle).
    uint32_t triangle_at(float x, float z) const;
    /// What TerrainDef::condition changed (mode None: nothing).
    const ConditionReport& condition_report() const { return condition_; }
    /// Which heights these are: a number unique in the process, new each time build(),
    /// carve_channel(), sculpt() or restore() writes the heights; a copy keeps
    /// it. Two terrains with the same revision have the same heights, so a reader holding a
    /// copy (WaterQuery) copies again only when it changed. 0: a default-constructed terrain.
    uint64_t revision() const { return revision_; }

    /// Carves a river bed along `path` (grid cells (row, column), source to outlet,
    /// neighbours 8-connected): the bed under path cell k is the lower of its ground
    /// minus `depth_m` and the previous bed minus kCarveLeastSlope per metre, so it
    /// descends all the way, and where the bed would drop faster than kCarveSteepest per
    /// metre (or 1.5 x the path's mean slope, if steeper) the bed upstream is cut down into
    /// a ramp of that slope; every sample within width_m / 2 of a path cell is lowered
    /// to at most the bed (within floor_m / 2) or bed + depth_m u^2, u rising from 0 at
    /// the floor's edge to 1 at the bank (parabolic walls); the samples just outside
    /// the banks (1.5 samples) are raised to bed + depth_m where lower (levees); the basin (if any) likewise around its centre with the
    /// first bed as its bottom. Heights only go down; the condition report (mode Carve)
    /// then counts every change against the heights as given. Cells outside the grid
    /// are ignored; an empty path changes nothing.
    void carve_channel(std::span<const std::pair<int, int>> path, const CarveDef& def);
    /// One brush stroke on the heights (a bad brush: non-finite or non-positive radius,
    /// strength out of range: an error naming the field, nothing changed). The bounds
    /// follow (the paper's box: the mesh grown by 1 m up and down); the tree's boxes do
    /// not: Bvh::refit_heights. Returns what it changed, for restore().
    Result<TerrainEdit> sculpt(const Brush& brush);
    /// Puts back the heights an edit changed (undo; edits undone newest first restore
    /// the terrain bit for bit).
    void restore(const TerrainEdit& edit);

private:
    /// Heights of the four corners of the cell under (x, z) (clamped into the rectangle):
    /// h00 at (i, j), h01 at (i, j+1), h10 at (i+1, j), h11 at (i+1, j+1), and the
    /// fractions u (along x) and v (along z) inside the cell.
    struct CellCorners {
        float h00, h01, h10, h11, u, v;
    };
    CellCorners cell_corners(float x, float z) const;
    /// Cell index and fraction along one axis for coordinate x (clamped; NaN: 0), n samples.
    struct AxisCell {
        int index;
        float frac;
    };
    static AxisCell axis_cell(float x, float s, int n);

    int columns_ = 0, rows_ = 0;
    float area_scale_ = 1.0f;
    std::vector<Vec3> vertices_;
    std::vector<uint32_t> indices_;
    Aabb bounds_;
    Aabb mesh_bounds_;
    ConditionReport condition_;
    std::vector<float> given_heights_;  ///< the heights before conditioning (when conditioned)
    uint64_t revision_ = 0;

    void update_condition_report();
    /// After every change of the heights (each mutator ends here): the bounds, and a new
    /// revision().
    void recompute_bounds();
};

/// A ray/segment hit on a triangle.
struct RayHit {
    float t = 0.0f;         ///< parameter along the segment: hit = origin + t * dir, t in [0, 1]
    uint32_t triangle = 0;  ///< triangle index
    Vec3 point{0.0f};
    Vec3 normal{0.0f, 1.0f, 0.0f};  ///< the triangle's unit geometric normal
};

/// The paper's eq. 4 (Moller-Trumbore): intersects origin + t*dir, t in [0, 1], with
/// triangle (a, b, c), both faces. Returns t on a hit. Not watertight: rays through
/// shared edges and vertices can miss both neighbours.
std::optional<float> ray_triangle_paper(const Vec3& origin, const Vec3& dir, const Vec3& a,
                                        const Vec3& b, const Vec3& c);
/// Watertight ray/triangle test (Woop, Benthin, Wald 2013), both faces, t in [0, 1]: a
/// ray through a shared edge or vertex hits at least one of the triangles sharing it.
std::optional<float> ray_triangle_watertight(const Vec3& origin, const Vec3& dir, const Vec3& a,
                                             const Vec3& b, const Vec3& c);

/// Robust segment query that walks the heightfield's cells instead of the tree: every
/// cell whose x/z rectangle the segment's x/z bounding box touches (grown by a hair so
/// edges shared with a neighbour cell are always tested from both sides), culled by the
/// cell's highest corner, watertight test on its two triangles, nearest hit. Returns
/// the same hits as Bvh::intersect_segment (tests check the twin), O(cells crossed)
/// instead of O(log T) box tests, which wins for the short per-step segments of
/// particles. Segments whose box spans more than `max_cells` cells report
/// `too_long = true` so the caller falls back to the tree.
struct HeightfieldQuery {
    std::optional<RayHit> hit;
    bool too_long = false;
};
HeightfieldQuery intersect_segment_heightfield(const Terrain& terrain, const Vec3& from, const Vec3& to,
                                               int max_cells = 64);

struct BvhDef {
    int leaf_triangles = 8;  ///< max triangles per leaf, in [2, 4096]
};

/// Index-based node (box2d's b2DynamicTree style). Leaves have count > 0 and own
/// triangle ids [first, first + count) of Bvh::leaf_triangle_ids(); inner nodes have
/// count == 0 and children left/right.
struct BvhNode {
    Aabb box;
    uint32_t first = 0;
    uint32_t count = 0;
    uint32_t left = 0;
    uint32_t right = 0;
};

struct BvhStats {
    size_t nodes = 0;
    size_t leaves = 0;
    int depth = 0;              ///< levels from the root (a single leaf has depth 1)
    size_t max_leaf_triangles = 0;
};

/// The paper's AABB tree: the triangle list is split in halves recursively (cells
/// halved by rows while a range spans more than one row, then by columns: exactly
/// the paper's list halving for 2^k+1 sides, and non-overlapping boxes for any size)
/// down to leaves of at most leaf_triangles. Every box spans the terrain's full height.
class Bvh {
public:
    static Result<Bvh> build(const Terrain& terrain, const BvhDef& def);

    std::span<const BvhNode> nodes() const { return nodes_; }
    std::span<const uint32_t> leaf_triangle_ids() const { return tri_ids_; }
    BvhStats stats() const;

    /// The paper's point query: descends to the leaf whose box contains p. Returns the
    /// node index of that leaf, or -1 when p is outside the root box.
    int leaf_containing(const Vec3& p) const;
    /// Triangles of a leaf node.
    std::span<const uint32_t> leaf_triangles(int leaf) const;

    /// The paper's collision query: triangles of the leaf holding `to`, tested with
    /// ray_triangle_paper against the segment from -> to. Nearest hit.
    std::optional<RayHit> intersect_paper(const Terrain& terrain, const Vec3& from, const Vec3& to) const;
    /// Robust query: every leaf whose box the segment from -> to crosses, watertight
    /// test, nearest hit.
    std::optional<RayHit> intersect_segment(const Terrain& terrain, const Vec3& from, const Vec3& to) const;
    /// After the terrain's heights changed (sculpt, restore): every box's y range is the
    /// terrain's bounds again, as build() makes them (the x and z ranges do not change).
    void refit_heights(const Terrain& terrain);

private:
    std::vector<BvhNode> nodes_;
    std::vector<uint32_t> tri_ids_;
};

// The queries the particles make every step (height, triangle, containment), inline: they
// were calls, and the axis lookup's floor a second one, about a tenth of a PBF river's
// frame (perf, `bench --scenario pbf --particles 16000`).

inline Terrain::AxisCell Terrain::axis_cell(float x, float s, int n) {
    const float extent = static_cast<float>(n - 1) * s;
    // Clamped into [0, extent] (NaN: 0), so u >= 0 and truncation is the floor.
    const float c = !(x >= 0.0f) ? 0.0f : (x > extent ? extent : x);
    const float u = c / s;
    int k = static_cast<int>(u);
    k = k < 0 ? 0 : (k > n - 2 ? n - 2 : k);
    float f = u - static_cast<float>(k);
    f = f < 0.0f ? 0.0f : (f > 1.0f ? 1.0f : f);
    return {k, f};
}

inline bool Terrain::contains_xz(float x, float z) const {
    const float ex = static_cast<float>(columns_ - 1) * area_scale_;
    const float ez = static_cast<float>(rows_ - 1) * area_scale_;
    return x >= 0.0f && x <= ex && z >= 0.0f && z <= ez;
}

inline Terrain::CellCorners Terrain::cell_corners(float x, float z) const {
    const AxisCell cx = axis_cell(x, area_scale_, columns_);
    const AxisCell cz = axis_cell(z, area_scale_, rows_);
    return {sample(cz.index, cx.index), sample(cz.index, cx.index + 1), sample(cz.index + 1, cx.index),
            sample(cz.index + 1, cx.index + 1), cx.frac, cz.frac};
}

inline uint32_t Terrain::triangle_at(float x, float z) const {
    if (vertices_.empty()) return 0;
    const AxisCell cx = axis_cell(x, area_scale_, columns_);
    const AxisCell cz = axis_cell(z, area_scale_, rows_);
    const uint32_t cell = static_cast<uint32_t>(cz.index) * static_cast<uint32_t>(columns_ - 1) +
                          static_cast<uint32_t>(cx.index);
    return 2u * cell + (cx.frac + cz.frac > 1.0f ? 1u : 0u);
}

inline float Terrain::height_mesh(float x, float z) const {
    if (vertices_.empty()) return 0.0f;
    const auto [h00, h01, h10, h11, u, v] = cell_corners(x, z);
    if (u + v <= 1.0f) {
        // Triangle (c, c+W, c+1): vertices (i, j), (i+1, j), (i, j+1).
        return h00 + u * (h01 - h00) + v * (h10 - h00);
    }
    // Triangle (c+1, c+W, c+W+1): vertices (i, j+1), (i+1, j), (i+1, j+1).
    return h11 + (1.0f - u) * (h10 - h11) + (1.0f - v) * (h01 - h11);
}

}  // namespace mr
