// The surface of water given as depths over a heightfield (a solver's HeightfieldWater):
// the wet samples' triangles at bed + depth, split as the terrain's mesh is, cut along the
// line where the water's level meets the bed (marching triangles over level - bed), with
// area-weighted vertex normals.
//
// Cost: one pass over the rows' wet columns for the wet samples' vertices, one over the
// cells beside them for the triangles. The vertex and cut slots live in two rows of
// scratch (a cell row reads its two sample rows and nothing else), and a dry sample's level
// is computed where a cut needs it, so nothing per sample of the grid is written or cleared.
#include <metariver/surface.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace mr {

namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr float kSnap = 0.05f;  // a cut this close to an edge's end (of its length) moves to the end
constexpr float kFilm = 0.005f;  // metres: thinner water is drawn as dry (films left on slopes)

/// The rows' wet columns: row i's samples with depth > kFilm lie in [first[i], last[i]]
/// (first = columns, last = -1: none), narrowed from the caller's spans (a superset of
/// the wet samples, hint_first/hint_last) or, without them, from a scan of the row.
void wet_rows(std::span<const float> depth, int rows, int columns, std::span<const int> hint_first,
              std::span<const int> hint_last, HeightfieldScratch& s) {
    const bool hinted = hint_first.size() == size_t(rows) && hint_last.size() == size_t(rows);
    s.first.resize(size_t(rows));
    s.last.resize(size_t(rows));
    for (int i = 0; i < rows; ++i) {
        int a = hinted ? std::max(hint_first[size_t(i)], 0) : 0, b = hinted ? std::min(hint_last[size_t(i)], columns - 1) : columns - 1;
        const float* d = depth.data() + size_t(i) * size_t(columns);
        while (a <= b && !(d[a] > kFilm)) ++a;
        while (b >= a && !(d[b] > kFilm)) --b;
        s.first[size_t(i)] = a <= b ? a : columns;
        s.last[size_t(i)] = a <= b ? b : -1;
    }
}

/// A cell row's and a sample row's columns. Cell row i (samples i and i + 1) has triangles
/// in cells [lo, hi] (cell j: columns j and j + 1), those beside rows i and i + 1's wet
/// samples; sample row r is read by cell rows r - 1 and r, in columns [lo, hi + 1] of each.
struct Span {
    int lo = 0, hi = -1;
};

Span joined(Span a, Span b) {
    if (a.lo > a.hi) return b;
    if (b.lo > b.hi) return a;
    return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
}

Span cell_span(const HeightfieldScratch& s, int i, int columns) {
    const size_t a = size_t(i), b = size_t(i) + 1;
    return {std::max(std::min(s.first[a], s.first[b]) - 1, 0), std::min(std::max(s.last[a], s.last[b]), columns - 2)};
}

class Builder {
public:
    Builder(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns, SurfaceMesh& out,
            HeightfieldScratch& s, std::span<const Vec3> velocity, std::vector<Vec3>* vertex_velocity)
        : bed_(bed), depth_(depth), rows_(rows), columns_(columns), w_(size_t(columns)), out_(out), s_(s),
          velocity_(velocity), vv_(vertex_velocity) {
        const Vec3 dx = bed[1] - bed[0], dz = bed[w_] - bed[0];
        min_area_ = 1e-6f * std::abs(dx.x * dz.z - dx.z * dz.x);  // of a cell's, seen from above
        // Rolling slots: two sample rows of vertices and of cuts on their +x edges, one
        // cell row of cuts on its +z (vertical) and diagonal edges.
        s_.vertex.assign(2 * w_, kNone);
        s_.crossing.assign(4 * w_, kNone);
    }

    bool wet(size_t k) const { return depth_[k] > kFilm; }

    /// The wet samples' vertices, in sample order (row r's first is s.row_base[r]).
    void wet_vertices() {
        s_.row_base.resize(size_t(rows_));
        for (int i = 0; i < rows_; ++i) {
            s_.row_base[size_t(i)] = uint32_t(out_.positions.size());
            for (int j = s_.first[size_t(i)]; j <= s_.last[size_t(i)]; ++j)
                if (const size_t k = size_t(i) * w_ + size_t(j); wet(k)) add(Vec3(bed_[k].x, level(k, i, j), bed_[k].z), k);
        }
    }

    /// Cell row i's two triangles per cell, (c, c + w, c + 1) and (c + 1, c + w, c + w + 1)
    /// as the terrain's, each cut to its wet part. `skip` (empty or the row's cells) leaves
    /// cells out.
    void cell_row(int i, std::span<const uint8_t> skip) {
        const Span cells = cell_span(s_, i, columns_);
        if (i == 0) start_sample_row(0, cells);
        start_sample_row(i + 1, i + 2 < rows_ ? joined(cells, cell_span(s_, i + 1, columns_)) : cells);
        if (cells.lo > cells.hi) return;
        top_ = (size_t(i) & 1) * w_;
        bottom_ = w_ - top_;
        uint32_t* vertical = s_.crossing.data() + 2 * w_;
        uint32_t* diagonal = vertical + w_;
        std::fill(vertical + cells.lo, vertical + cells.hi + 2, kNone);
        std::fill(diagonal + cells.lo, diagonal + cells.hi + 1, kNone);
        row_ = i;
        for (int j = cells.lo; j <= cells.hi; ++j) {
            const size_t c = size_t(i) * w_ + size_t(j);
            if (!skip.empty() && skip[size_t(j)]) continue;
            if (!wet(c) && !wet(c + 1) && !wet(c + w_) && !wet(c + w_ + 1)) continue;
            const size_t jj = size_t(j);
            uint32_t* up = s_.crossing.data() + top_;
            uint32_t* down = s_.crossing.data() + bottom_;
            triangle({c, c + w_, c + 1}, {{{0, j}, {1, j}, {0, j + 1}}}, {vertical + jj, diagonal + jj, up + jj});
            triangle({c + 1, c + w_, c + w_ + 1}, {{{0, j + 1}, {1, j}, {1, j + 1}}}, {diagonal + jj, down + jj, vertical + jj + 1});
        }
    }

    /// Leaves the slots none (a reused scratch is clean between calls).
    void finish() {
        std::fill(s_.vertex.begin(), s_.vertex.end(), kNone);
        std::fill(s_.crossing.begin(), s_.crossing.end(), kNone);
    }

private:
    struct Corner {
        int di, j;  ///< row (0: the cell row's top sample row, 1: its bottom) and column
    };

    /// Sample row r's slots over `cells` (the cells of the rows beside it that read it):
    /// its wet samples' vertices (made by wet_vertices, in order) and none elsewhere.
    void start_sample_row(int r, Span cells) {
        if (cells.lo > cells.hi) return;
        const size_t at = (size_t(r) & 1) * w_;
        uint32_t* v = s_.vertex.data() + at;
        uint32_t* h = s_.crossing.data() + at;
        uint32_t next = s_.row_base[size_t(r)];
        const int first = s_.first[size_t(r)], last = s_.last[size_t(r)];
        for (int j = cells.lo; j <= cells.hi + 1; ++j) {
            const bool w = j >= first && j <= last && wet(size_t(r) * w_ + size_t(j));
            v[j] = w ? next++ : kNone;
            h[j] = kNone;
        }
    }

    /// The water's level at sample k = (i, j): bed + depth where wet. A dry sample (cut
    /// ends only: beside a wet one, 8 neighbours) from L, the lowest of the wet neighbours'
    /// levels: L where the sample's bed is above it (the cut is the contour), else as far
    /// below the bed as L is above it (bed - |L - bed|), so level - bed is > 0 exactly on
    /// the wet samples and continuous in L. A dry sample lower than the water beside it (a
    /// front, a steep stream's bank) then ends the water part way to it, not at it (which
    /// drew teeth along such banks). The lowest, not the mean: upstream neighbours would
    /// lift the ring over the banks.
    float level(size_t k, int i, int j) const {
        const float own = bed_[k].y + std::max(depth_[k], 0.0f);
        if (wet(k)) return own;
        float lowest = std::numeric_limits<float>::max();
        for (int di = -1; di <= 1; ++di)
            for (int dj = -1; dj <= 1; ++dj) {
                const int a = i + di, b = j + dj;
                if (a < 0 || b < 0 || a >= rows_ || b >= columns_) continue;
                const size_t q = size_t(a) * w_ + size_t(b);
                if (wet(q)) lowest = std::min(lowest, bed_[q].y + depth_[q]);
            }
        return lowest < std::numeric_limits<float>::max() ? bed_[k].y - std::abs(lowest - bed_[k].y) : own;
    }

    uint32_t& vertex_slot(Corner c) { return s_.vertex[(c.di ? bottom_ : top_) + size_t(c.j)]; }

    /// The vertex of a dry sample (a snapped cut's end) at its level, with the velocity of
    /// sample `velocity_of` (the cut's wet end), made on first use. Wet samples have theirs.
    uint32_t sample_vertex(size_t k, Corner c, size_t velocity_of) {
        uint32_t& v = vertex_slot(c);
        if (v == kNone) v = add(Vec3(bed_[k].x, level(k, row_ + c.di, c.j), bed_[k].z), velocity_of);
        return v;
    }

    /// Triangle (a, b, c), counter-clockwise from above: its part where level > bed.
    /// `edge[e]` is the cut slot of the edge from corner e to corner e + 1.
    void triangle(const std::array<size_t, 3>& k, const std::array<Corner, 3>& at, const std::array<uint32_t*, 3>& edge) {
        const bool in[3] = {wet(k[0]), wet(k[1]), wet(k[2])};
        if (in[0] && in[1] && in[2]) return emit(vertex_slot(at[0]), vertex_slot(at[1]), vertex_slot(at[2]));
        if (!in[0] && !in[1] && !in[2]) return;
        uint32_t poly[4];
        int n = 0;
        for (int e = 0; e < 3; ++e) {
            const int f = (e + 1) % 3;
            if (in[e]) poly[n++] = vertex_slot(at[e]);
            if (in[e] != in[f]) poly[n++] = in[e] ? cut(k[e], at[e], k[f], at[f], *edge[e]) : cut(k[f], at[f], k[e], at[e], *edge[e]);
        }
        int m = 0;  // snapped cuts may repeat a vertex: drop the repeats
        for (int q = 0; q < n; ++q)
            if (m == 0 || poly[m - 1] != poly[q]) poly[m++] = poly[q];
        while (m > 1 && poly[m - 1] == poly[0]) --m;
        for (int q = 1; q + 1 < m; ++q) emit(poly[0], poly[q], poly[q + 1]);
    }

    uint32_t add(const Vec3& p, size_t velocity_of) {
        out_.positions.push_back(p);
        out_.normals.emplace_back(0.0f);
        if (vv_) vv_->push_back(velocity_.empty() ? Vec3(0.0f) : velocity_[velocity_of]);
        return uint32_t(out_.positions.size() - 1);
    }

    /// The shoreline's vertex on the edge from wet sample p to dry sample q (one per edge,
    /// kept in `slot`).
    uint32_t cut(size_t p, Corner pc, size_t q, Corner qc, uint32_t& slot) {
        if (slot != kNone) return slot;
        const float lp = bed_[p].y + depth_[p], lq = level(q, row_ + qc.di, qc.j);
        const float fp = lp - bed_[p].y, fq = lq - bed_[q].y;  // > 0, <= 0
        const float t = fp / (fp - fq);
        if (t < kSnap) return slot = vertex_slot(pc);
        if (t > 1.0f - kSnap) return slot = sample_vertex(q, qc, p);
        const Vec3 a(bed_[p].x, lp, bed_[p].z), b(bed_[q].x, lq, bed_[q].z);
        return slot = add(a + t * (b - a), p);
    }

    void emit(uint32_t a, uint32_t b, uint32_t c) {
        Vec3* n = out_.normals.data();
        const Vec3* p = out_.positions.data();
        const Vec3 nrm = glm::cross(p[b] - p[a], p[c] - p[a]);
        if (!(nrm.y > 2.0f * min_area_)) return;  // collinear (or turned over): no triangle
        out_.indices.push_back(a);  // not insert({a, b, c}): that is a range insert's memmove per triangle
        out_.indices.push_back(b);
        out_.indices.push_back(c);
        n[a] += nrm;
        n[b] += nrm;
        n[c] += nrm;
    }

    std::span<const Vec3> bed_;
    std::span<const float> depth_;
    int rows_, columns_;
    size_t w_;
    SurfaceMesh& out_;
    HeightfieldScratch& s_;
    std::span<const Vec3> velocity_;
    std::vector<Vec3>* vv_;
    float min_area_ = 0.0f;
    int row_ = 0;
    size_t top_ = 0, bottom_ = 0;  ///< offsets of the cell row's sample rows in the rolling slots
};

}  // namespace

void append_heightfield_surface(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns,
                                SurfaceMesh& out, HeightfieldScratch* scratch, std::span<const Vec3> velocity,
                                std::vector<Vec3>* vertex_velocity, std::span<const uint8_t> skip_cells,
                                std::span<const int> wet_first, std::span<const int> wet_last) {
    if (rows < 2 || columns < 2) return;
    const size_t n = size_t(rows) * size_t(columns), w = size_t(columns);
    if (bed.size() != n || depth.size() != n) return;
    if (!velocity.empty() && velocity.size() != n) velocity = {};
    if (skip_cells.size() != size_t(rows - 1) * size_t(columns - 1)) skip_cells = {};
    HeightfieldScratch own;
    HeightfieldScratch& s = scratch ? *scratch : own;
    wet_rows(depth, rows, columns, wet_first, wet_last, s);
    const size_t first = out.positions.size();
    out.normals.resize(first, Vec3(0.0f, 1.0f, 0.0f));
    Builder build(bed, depth, rows, columns, out, s, velocity, vertex_velocity);
    build.wet_vertices();
    for (int i = 0; i + 1 < rows; ++i)
        build.cell_row(i, skip_cells.empty() ? skip_cells : skip_cells.subspan(size_t(i) * (w - 1), w - 1));
    build.finish();
    for (size_t v = first; v < out.normals.size(); ++v) {
        const float len = glm::length(out.normals[v]);
        out.normals[v] = len > 0.0f ? out.normals[v] / len : Vec3(0.0f, 1.0f, 0.0f);
    }
}

}  // namespace mr
