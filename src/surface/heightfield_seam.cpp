// One surface where a heightfield's water and a particle field meet (issue 46's seam): the
// grid's water as a term of the field near the particles, and the heightfield mesh left out
// where the field draws it (surface.h, join_heightfield_to_field).
#include <metariver/surface.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace mr {

namespace {

constexpr float kFilm = 0.005f;  // metres: thinner water is drawn as dry (heightfield_surface.cpp's)
/// Metres the field's water lies under the heightfield's: where both are drawn (around the
/// field's cells) the heightfield shows, without the two fighting over the same depth.
constexpr float kUnder = 0.005f;
/// A column gets the grid's term where some ball's field near the water's level exceeds this
/// share of the threshold: a ball adding less lifts the water's surface by under 2 % of the
/// term's width (5 mm in the presets), which the heightfield's own surface hides.
constexpr float kReachShare = 0.02f;
/// Metres under the heightfield's surface (drop_under_water) a vertex counts as hidden:
/// 2 mm, where the field's own flat water lies 5 mm under it.
constexpr float kHiddenUnder = 0.002f;
/// Metres under the field's own flat water, over the cells it draws.
constexpr float kHiddenDepth = 0.02f;

/// A regular grid's water (bed + depth per sample): its level on the heightfield mesh's
/// triangles, (c, c + w, c + 1) and (c + 1, c + w, c + w + 1), over fully wet cells.
class Water {
public:
    Water(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns)
        : bed_(bed), depth_(depth), rows_(rows), columns_(columns), w_(size_t(columns)) {
        const size_t n = size_t(rows) * size_t(columns);
        if (rows < 2 || columns < 2 || bed.size() != n || depth.size() != n) return;
        x0_ = bed[0].x, z0_ = bed[0].z, dx_ = bed[1].x - bed[0].x, dz_ = bed[w_].z - bed[0].z;
        ok_ = dx_ > 0.0f && dz_ > 0.0f;
    }
    bool ok() const { return ok_; }
    float x0() const { return x0_; }
    float z0() const { return z0_; }
    float dx() const { return dx_; }
    float dz() const { return dz_; }
    float level(size_t k) const { return bed_[k].y + depth_[k]; }
    bool wet_cell(int i, int j) const {
        const size_t c = size_t(i) * w_ + size_t(j);
        return depth_[c] > kFilm && depth_[c + 1] > kFilm && depth_[c + w_] > kFilm && depth_[c + w_ + 1] > kFilm;
    }

    /// The corners and weights of (x, z) on its cell's triangle, when the cell is fully wet.
    bool locate(float x, float z, size_t (&k)[3], float (&a)[3]) const {
        const float u = (x - x0_) / dx_, v = (z - z0_) / dz_;
        if (!(u >= 0.0f && v >= 0.0f) || u > float(columns_ - 1) || v > float(rows_ - 1)) return false;
        const int j = std::min(int(u), columns_ - 2), i = std::min(int(v), rows_ - 2);
        if (!wet_cell(i, j)) return false;
        const float fu = u - float(j), fv = v - float(i);
        const size_t c = size_t(i) * w_ + size_t(j);
        if (fu + fv <= 1.0f) {
            k[0] = c, k[1] = c + 1, k[2] = c + w_;
            a[0] = 1.0f - fu - fv, a[1] = fu, a[2] = fv;
        } else {
            k[0] = c + w_ + 1, k[1] = c + w_, k[2] = c + 1;
            a[0] = fu + fv - 1.0f, a[1] = 1.0f - fu, a[2] = 1.0f - fv;
        }
        return true;
    }
    /// The level at (x, z) less kUnder, over a fully wet cell.
    bool at(float x, float z, float& s) const {
        size_t k[3];
        float a[3];
        if (!locate(x, z, k, a)) return false;
        s = a[0] * level(k[0]) + a[1] * level(k[1]) + a[2] * level(k[2]) - kUnder;
        return true;
    }

private:
    std::span<const Vec3> bed_;
    std::span<const float> depth_;
    int rows_, columns_;
    size_t w_;
    float x0_ = 0.0f, z0_ = 0.0f, dx_ = 0.0f, dz_ = 0.0f;
    bool ok_ = false;
};

/// seam.column and seam.level: the field's columns where some ball's field (> `floor`)
/// reaches within `reach` of the water's level, in the stored blocks over fully wet cells,
/// and the level there. In parallel over the columns of blocks (each writes its own
/// columns), each column's level found once for all its blocks: a column's mark is an "or"
/// over its blocks, the same in any order.
void mark_columns(const Water& water, const SparseField& f, float reach, float floor, HeightfieldSeam& seam) {
    const SampleGrid& g = f.grid();
    constexpr int B = SparseField::kBlock;
    const size_t columns = size_t(g.nx) * size_t(g.nz);
    seam.column.assign(columns, 0);
    seam.level.assign(columns, std::numeric_limits<float>::quiet_NaN());
    const auto dir = f.directory();
    const int bx = f.blocks_x(), by = f.blocks_y();
    const auto column = [&](int bi, int bk, int x, int z) {
        float s = 0.0f;
        bool located = false;
        for (int bj = 0; bj < by; ++bj) {
            const int32_t slot = dir[f.block_index(bi, bj, bk)];
            if (slot == SparseField::kNoBlock || !(f.block_max(slot) > floor)) continue;
            if (!located) {
                const Vec3 p = g.position(bi * B + x, 0, bk * B + z);
                if (!water.at(p.x, p.z, s)) return;
                located = true;
            }
            const float* v = f.block_values(slot);
            const int ny = std::min(B, g.ny - bj * B);
            const float y0 = g.origin.y + g.spacing * float(bj * B);
            const int lo = std::max(0, int(std::floor((s - reach - y0) / g.spacing)));
            const int hi = std::min(ny - 1, int(std::ceil((s + reach - y0) / g.spacing)));
            for (int y = lo; y <= hi; ++y)
                if (v[x + B * (y + B * z)] > floor) {
                    const size_t c = size_t(bi * B + x) + size_t(g.nx) * size_t(bk * B + z);
                    seam.column[c] = 1;
                    seam.level[c] = s;
                    return;
                }
        }
    };
    tbb::parallel_for(tbb::blocked_range<int>(0, bx * f.blocks_z()), [&](const tbb::blocked_range<int>& r) {
        for (int b = r.begin(); b != r.end(); ++b) {
            const int bi = b % bx, bk = b / bx;
            const int nx = std::min(B, g.nx - bi * B), nz = std::min(B, g.nz - bk * B);
            for (int z = 0; z < nz; ++z)
                for (int x = 0; x < nx; ++x) column(bi, bk, x, z);
        }
    });
    seam.columns = size_t(std::count(seam.column.begin(), seam.column.end(), uint8_t{1}));
}

/// f(n) for every vertex n < count, in parallel (each call writes vertex n's entries only).
template <class F>
void for_vertices(size_t count, const F& f) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t n = r.begin(); n != r.end(); ++n) f(n);
    });
}

/// Whether the field stores every sample around the box [lo, hi] (one sample beyond it on
/// every side, inside the grid), and every column of them got the term.
bool stored(const SparseField& f, const std::vector<uint8_t>& column, const Vec3& lo, const Vec3& hi) {
    const SampleGrid& g = f.grid();
    const auto index = [&](float v, float o, bool up) {
        const float t = (v - o) / g.spacing;
        return up ? int(std::ceil(t)) + 1 : int(std::floor(t)) - 1;
    };
    const int i0 = index(lo.x, g.origin.x, false), i1 = index(hi.x, g.origin.x, true);
    const int j0 = index(lo.y, g.origin.y, false), j1 = index(hi.y, g.origin.y, true);
    const int k0 = index(lo.z, g.origin.z, false), k1 = index(hi.z, g.origin.z, true);
    if (i0 < 0 || j0 < 0 || k0 < 0 || i1 >= g.nx || j1 >= g.ny || k1 >= g.nz) return false;
    for (int k = k0; k <= k1; ++k)
        for (int i = i0; i <= i1; ++i)
            if (!column[size_t(i) + size_t(g.nx) * size_t(k)]) return false;
    constexpr int B = SparseField::kBlock;
    for (int bk = k0 / B; bk <= k1 / B; ++bk)
        for (int bj = j0 / B; bj <= j1 / B; ++bj)
            for (int bi = i0 / B; bi <= i1 / B; ++bi)
                if (f.slot(bi, bj, bk) == SparseField::kNoBlock) return false;
    return true;
}

}  // namespace

void join_heightfield_to_field(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns,
                               float threshold, float width, SparseField& field, HeightfieldSeam& seam) {
    seam.clear();
    const Water water(bed, depth, rows, columns);
    if (!water.ok() || field.allocated_blocks() == 0) return;
    const SampleGrid& g = field.grid();
    // The term in the columns over fully wet cells (s is defined there) where a ball's field
    // reaches the water's band: there its skirt rises from the water's level, and the term
    // ends where the balls add (almost) 0 near the water, under the heightfield drawn there.
    mark_columns(water, field, width + g.spacing, kReachShare * threshold, seam);
    field.add_level_term(std::span<const float>(seam.level), threshold, width);
    // The cells the field draws in full: the heightfield mesh leaves them out.
    const size_t w = size_t(columns);
    seam.cell.assign(size_t(rows - 1) * size_t(columns - 1), 0);
    const auto span_of = [](float lo, float hi, float o, float d, int last) {
        return std::pair<int, int>{std::max(0, int(std::floor((lo - o) / d))), std::min(last, int(std::ceil((hi - o) / d)))};
    };
    const auto [j0, j1] = span_of(g.origin.x, g.origin.x + g.spacing * float(g.nx - 1), water.x0(), water.dx(), columns - 2);
    const auto [i0, i1] = span_of(g.origin.z, g.origin.z + g.spacing * float(g.nz - 1), water.z0(), water.dz(), rows - 2);
    for (int i = i0; i <= i1; ++i)
        for (int j = j0; j <= j1; ++j) {
            if (!water.wet_cell(i, j)) continue;
            const size_t c = size_t(i) * w + size_t(j);
            const float a = water.level(c), b = water.level(c + 1), d = water.level(c + w), e = water.level(c + w + 1);
            const Vec3 lo(bed[c].x, std::min({a, b, d, e}), bed[c].z);
            const Vec3 hi(bed[c + w + 1].x, std::max({a, b, d, e}), bed[c + w + 1].z);
            if (!stored(field, seam.column, lo, hi)) continue;
            seam.cell[size_t(i) * (w - 1) + size_t(j)] = 1;
            ++seam.cells;
        }
}

void drop_under_water(std::span<const Vec3> bed, std::span<const float> depth, int rows, int columns,
                      const HeightfieldSeam& seam, SurfaceMesh& mesh, std::vector<uint32_t>& scratch) {
    const Water water(bed, depth, rows, columns);
    if (!water.ok() || seam.columns == 0) return;
    const bool cells = seam.cell.size() == size_t(rows - 1) * size_t(columns - 1);
    // Per vertex: kept (its new index) or under the water (kNone), first as 0 / 1.
    constexpr uint32_t kHidden = 1, kNone = ~uint32_t{0};
    std::vector<uint32_t>& map = scratch;
    map.assign(mesh.positions.size(), 0);
    for_vertices(mesh.positions.size(), [&](size_t n) {
        const Vec3 p = mesh.positions[n];
        float s = 0.0f;
        if (!water.at(p.x, p.z, s)) return;
        const int j = std::min(int((p.x - water.x0()) / water.dx()), columns - 2);
        const int i = std::min(int((p.z - water.z0()) / water.dz()), rows - 2);
        const bool field_draws = cells && seam.cell[size_t(i) * size_t(columns - 1) + size_t(j)];
        // Under the heightfield's surface (s + kUnder), or the field's own flat water (s).
        if (p.y < s + (field_draws ? -kHiddenDepth : kUnder - kHiddenUnder)) map[n] = kHidden;
    });
    size_t t = 0;
    for (size_t k = 0; k + 2 < mesh.indices.size(); k += 3) {
        const uint32_t a = mesh.indices[k], b = mesh.indices[k + 1], c = mesh.indices[k + 2];
        if (map[a] == kHidden && map[b] == kHidden && map[c] == kHidden) continue;
        mesh.indices[t++] = a, mesh.indices[t++] = b, mesh.indices[t++] = c;
    }
    mesh.indices.resize(t);
    std::fill(map.begin(), map.end(), kNone);
    for (const uint32_t v : mesh.indices) map[v] = 0;
    uint32_t next = 0;
    for (size_t n = 0; n < map.size(); ++n) {
        if (map[n] == kNone) continue;
        map[n] = next;
        mesh.positions[next] = mesh.positions[n];
        mesh.normals[next] = mesh.normals[n];
        ++next;
    }
    mesh.positions.resize(next);
    mesh.normals.resize(next);
    for (uint32_t& v : mesh.indices) v = map[v];
}

void seam_grid_velocities(std::span<const Vec3> bed, std::span<const float> depth, std::span<const Vec3> velocity,
                          int rows, int columns, float width, std::span<const Vec3> vertices,
                          std::vector<glm::vec4>& out) {
    out.assign(vertices.size(), glm::vec4(0.0f));
    const Water water(bed, depth, rows, columns);
    if (!water.ok() || velocity.size() != bed.size() || !(width > 0.0f)) return;
    for_vertices(vertices.size(), [&](size_t n) {
        const Vec3 p = vertices[n];
        size_t k[3];
        float a[3];
        if (!water.locate(p.x, p.z, k, a)) return;
        const float s = a[0] * water.level(k[0]) + a[1] * water.level(k[1]) + a[2] * water.level(k[2]) - kUnder;
        const Vec3 v = a[0] * velocity[k[0]] + a[1] * velocity[k[1]] + a[2] * velocity[k[2]];
        out[n] = glm::vec4(v, std::clamp(1.0f + (s - p.y) / width, 0.0f, 1.0f));
    });
}

}  // namespace mr
