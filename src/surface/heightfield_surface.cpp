// The surface of water given as depths over a heightfield (a solver's HeightfieldWater):
// the wet samples' triangles at bed + depth, split as the terrain's mesh is, cut along the
// line where the water's level meets the bed (marching triangles over level - bed), with
// area-weighted vertex normals.
#include <metariver/surface.h>

#include <glm/geometric.hpp>

#include <algorithm>
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
/// the wet samples, hint_first/hint_last) or, without them, from a scan of the row. Then
/// the region each row's work touches: ring_first/ring_last, the wet columns of the row and
/// its two neighbours widened by one column (the wet samples and the ring around them).
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
    s.ring_first.resize(size_t(rows));
    s.ring_last.resize(size_t(rows));
    for (int i = 0; i < rows; ++i) {
        int a = columns, b = -1;
        for (int r = std::max(i - 1, 0); r <= std::min(i + 1, rows - 1); ++r) {
            a = std::min(a, s.first[size_t(r)]);
            b = std::max(b, s.last[size_t(r)]);
        }
        s.ring_first[size_t(i)] = a <= b ? std::max(a - 1, 0) : columns;
        s.ring_last[size_t(i)] = a <= b ? std::min(b + 1, columns - 1) : -1;
    }
}

/// The water's level per sample: bed + depth where wet; on the ring (dry beside a wet
/// sample, 8 neighbours) from L, the lowest of the wet neighbours' levels: L where the
/// sample's bed is above it (the cut is the contour), else as far below the bed as L is
/// above it (bed - |L - bed|), so level - bed is > 0 exactly on the wet samples and
/// continuous in L. A dry sample lower than the water beside it (a front, a steep stream's
/// bank) then ends the water part way to it, not at it (which drew teeth along such banks).
/// The lowest, not the mean: upstream neighbours would lift the ring over the banks.
/// Only the rows' ring regions are written (samples beyond the ring are never read).
void water_levels(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns, HeightfieldScratch& s) {
    s.level.resize(bed.size());
    for (int i = 0; i < rows; ++i)
        for (int j = s.ring_first[size_t(i)]; j <= s.ring_last[size_t(i)]; ++j) {
            const size_t k = size_t(i) * size_t(columns) + size_t(j);
            s.level[k] = bed[k].y + std::max(depth[k], 0.0f);
            if (depth[k] > kFilm) continue;
            float lowest = std::numeric_limits<float>::max();
            for (int di = -1; di <= 1; ++di)
                for (int dj = -1; dj <= 1; ++dj) {
                    const int a = i + di, b = j + dj;
                    if (a < 0 || b < 0 || a >= rows || b >= columns) continue;
                    const size_t q = size_t(a) * size_t(columns) + size_t(b);
                    if (depth[q] > kFilm) lowest = std::min(lowest, bed[q].y + depth[q]);
                }
            if (lowest < std::numeric_limits<float>::max()) s.level[k] = bed[k].y - std::abs(lowest - bed[k].y);
        }
}

class Builder {
public:
    Builder(std::span<const Vec3> bed, std::span<const float> depth, int columns, SurfaceMesh& out,
            HeightfieldScratch& s, std::span<const Vec3> velocity, std::vector<Vec3>* vertex_velocity)
        : bed_(bed), depth_(depth), w_(size_t(columns)), out_(out), s_(s), velocity_(velocity), vv_(vertex_velocity) {
        const Vec3 dx = bed[1] - bed[0], dz = bed[w_] - bed[0];
        min_area_ = 1e-6f * std::abs(dx.x * dz.z - dx.z * dz.x);  // of a cell's, seen from above
    }

    bool wet(size_t k) const { return depth_[k] > kFilm; }

    /// The vertex of sample k at its level (created on first use, with the velocity of
    /// sample `velocity_of`: k's own, or for a dry k a cut's wet end's).
    uint32_t sample_vertex(size_t k, size_t velocity_of) {
        uint32_t& v = s_.vertex[k];
        if (v == kNone) v = add(Vec3(bed_[k].x, s_.level[k], bed_[k].z), velocity_of);
        return v;
    }

    /// Triangle (a, b, c), counter-clockwise from above: its part where level > bed.
    void triangle(size_t a, size_t b, size_t c) {
        const size_t corner[3] = {a, b, c};
        const bool in[3] = {wet(a), wet(b), wet(c)};
        if (!in[0] && !in[1] && !in[2]) return;
        uint32_t poly[4];
        int n = 0;
        for (int e = 0; e < 3; ++e) {
            const size_t p = corner[e], q = corner[(e + 1) % 3];
            if (in[e]) poly[n++] = sample_vertex(p, p);
            if (in[e] != in[(e + 1) % 3]) poly[n++] = in[e] ? cut(p, q) : cut(q, p);
        }
        int m = 0;  // snapped cuts may repeat a vertex: drop the repeats
        for (int k = 0; k < n; ++k)
            if (m == 0 || poly[m - 1] != poly[k]) poly[m++] = poly[k];
        while (m > 1 && poly[m - 1] == poly[0]) --m;
        for (int k = 1; k + 1 < m; ++k) emit(poly[0], poly[k], poly[k + 1]);
    }

private:
    uint32_t add(const Vec3& p, size_t velocity_of) {
        out_.positions.push_back(p);
        out_.normals.emplace_back(0.0f);
        if (vv_) vv_->push_back(velocity_.empty() ? Vec3(0.0f) : velocity_[velocity_of]);
        return uint32_t(out_.positions.size() - 1);
    }

    /// The shoreline's vertex on the edge from wet sample p to dry sample q (one per edge).
    uint32_t cut(size_t p, size_t q) {
        const size_t lo = std::min(p, q), hi = std::max(p, q);
        const size_t slot = 3 * lo + (hi == lo + 1 ? 0 : hi == lo + w_ ? 1 : 2);
        uint32_t& v = s_.crossing[slot];
        if (v != kNone) return v;
        const float fp = s_.level[p] - bed_[p].y, fq = s_.level[q] - bed_[q].y;  // > 0, <= 0
        const float t = fp / (fp - fq);
        if (t < kSnap) return v = sample_vertex(p, p);
        if (t > 1.0f - kSnap) return v = sample_vertex(q, p);
        const Vec3 a(bed_[p].x, s_.level[p], bed_[p].z), b(bed_[q].x, s_.level[q], bed_[q].z);
        return v = add(a + t * (b - a), p);
    }

    void emit(uint32_t a, uint32_t b, uint32_t c) {
        const Vec3 nrm = glm::cross(out_.positions[b] - out_.positions[a], out_.positions[c] - out_.positions[a]);
        if (!(nrm.y > 2.0f * min_area_)) return;  // collinear (or turned over): no triangle
        out_.indices.insert(out_.indices.end(), {a, b, c});
        for (const uint32_t v : {a, b, c}) out_.normals[v] += nrm;
    }

    std::span<const Vec3> bed_;
    std::span<const float> depth_;
    size_t w_;
    SurfaceMesh& out_;
    HeightfieldScratch& s_;
    std::span<const Vec3> velocity_;
    std::vector<Vec3>* vv_;
    float min_area_ = 0.0f;
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
    water_levels(bed, depth, rows, columns, s);
    if (s.vertex.size() != n) s.vertex.assign(n, kNone);  // else all none since the last call
    if (s.crossing.size() != 3 * n) s.crossing.assign(3 * n, kNone);
    const size_t first = out.positions.size();
    out.normals.resize(first, Vec3(0.0f, 1.0f, 0.0f));
    Builder build(bed, depth, columns, out, s, velocity, vertex_velocity);
    for (int i = 0; i < rows; ++i)  // the wet samples' vertices first, in sample order
        for (int j = s.first[size_t(i)]; j <= s.last[size_t(i)]; ++j)
            if (const size_t k = size_t(i) * w + size_t(j); build.wet(k)) build.sample_vertex(k, k);
    // Two triangles per cell, (c, c + w, c + 1) and (c + 1, c + w, c + w + 1) as the
    // terrain's, each cut to its wet part: the cells of rows i and i + 1's wet columns.
    for (int i = 0; i + 1 < rows; ++i) {
        const int lo = std::max(std::min(s.first[size_t(i)], s.first[size_t(i) + 1]) - 1, 0);
        const int hi = std::min(std::max(s.last[size_t(i)], s.last[size_t(i) + 1]), columns - 2);
        for (int j = lo; j <= hi; ++j) {
            const size_t c = size_t(i) * w + size_t(j);
            if (!skip_cells.empty() && skip_cells[size_t(i) * (w - 1) + size_t(j)]) continue;
            if (!build.wet(c) && !build.wet(c + 1) && !build.wet(c + w) && !build.wet(c + w + 1)) continue;
            build.triangle(c, c + w, c + 1);
            build.triangle(c + 1, c + w, c + w + 1);
        }
    }
    for (size_t v = first; v < out.normals.size(); ++v) {
        const float len = glm::length(out.normals[v]);
        out.normals[v] = len > 0.0f ? out.normals[v] / len : Vec3(0.0f, 1.0f, 0.0f);
    }
    // Every vertex and cut lies on a ring region's sample: clear them there for the next call.
    for (int i = 0; i < rows; ++i)
        for (int j = s.ring_first[size_t(i)]; j <= s.ring_last[size_t(i)]; ++j) {
            const size_t k = size_t(i) * w + size_t(j);
            s.vertex[k] = kNone;
            std::fill_n(s.crossing.begin() + std::ptrdiff_t(3 * k), 3, kNone);
        }
}

}  // namespace mr
