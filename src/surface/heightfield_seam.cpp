// One surface where a heightfield's water and a particle field meet (issue 46's seam): the
// grid's water as a term of the field near the particles, and the heightfield mesh left out
// where the field draws it (surface.h, join_heightfield_to_field).
#include <metariver/surface.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace mr {

namespace {

constexpr float kFilm = 0.005f;  // metres: thinner water is drawn as dry (heightfield_surface.cpp's)
/// Metres the field's water lies under the heightfield's: where both are drawn (around the
/// field's cells) the heightfield shows, without the two fighting over the same depth.
constexpr float kUnder = 0.005f;

/// The terrain's regular grid: sample (i, j) at origin + (j dx, i dz).
struct Lattice {
    float x0, z0, dx, dz;
    int rows, columns;
    size_t cell(int i, int j) const { return size_t(i) * size_t(columns - 1) + size_t(j); }
};

/// Whether the field stores every sample around the box [lo, hi] (one sample beyond it on
/// every side, inside the grid).
bool stored(const SparseField& f, const Vec3& lo, const Vec3& hi) {
    const SampleGrid& g = f.grid();
    const auto index = [&](float v, float o, bool up) {
        const float t = (v - o) / g.spacing;
        return up ? int(std::ceil(t)) + 1 : int(std::floor(t)) - 1;
    };
    const int i0 = index(lo.x, g.origin.x, false), i1 = index(hi.x, g.origin.x, true);
    const int j0 = index(lo.y, g.origin.y, false), j1 = index(hi.y, g.origin.y, true);
    const int k0 = index(lo.z, g.origin.z, false), k1 = index(hi.z, g.origin.z, true);
    if (i0 < 0 || j0 < 0 || k0 < 0 || i1 >= g.nx || j1 >= g.ny || k1 >= g.nz) return false;
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
    const size_t n = size_t(rows) * size_t(columns);
    if (rows < 2 || columns < 2 || bed.size() != n || depth.size() != n || field.allocated_blocks() == 0) return;
    const size_t w = size_t(columns);
    const Lattice lat{bed[0].x, bed[0].z, bed[1].x - bed[0].x, bed[w].z - bed[0].z, rows, columns};
    if (!(lat.dx > 0.0f) || !(lat.dz > 0.0f)) return;
    const size_t cells = size_t(rows - 1) * size_t(columns - 1);
    seam.cell.assign(cells, 0);
    const auto level = [&](size_t k) { return bed[k].y + depth[k]; };
    const auto wet_cell = [&](int i, int j) {
        const size_t c = size_t(i) * w + size_t(j);
        return depth[c] > kFilm && depth[c + 1] > kFilm && depth[c + w] > kFilm && depth[c + w + 1] > kFilm;
    };
    // Only the cells under the field's grid can be its.
    const SampleGrid& g = field.grid();
    const auto span_of = [](float lo, float hi, float o, float d, int last) {
        return std::pair<int, int>{std::max(0, int(std::floor((lo - o) / d))), std::min(last, int(std::ceil((hi - o) / d)))};
    };
    const auto [j0, j1] = span_of(g.origin.x, g.origin.x + g.spacing * float(g.nx - 1), lat.x0, lat.dx, columns - 2);
    const auto [i0, i1] = span_of(g.origin.z, g.origin.z + g.spacing * float(g.nz - 1), lat.z0, lat.dz, rows - 2);
    for (int i = i0; i <= i1; ++i)
        for (int j = j0; j <= j1; ++j) {
            if (!wet_cell(i, j)) continue;
            const size_t c = size_t(i) * w + size_t(j);
            const float a = level(c), b = level(c + 1), d = level(c + w), e = level(c + w + 1);
            const Vec3 lo(bed[c].x, std::min({a, b, d, e}), bed[c].z);
            const Vec3 hi(bed[c + w + 1].x, std::max({a, b, d, e}), bed[c + w + 1].z);
            if (!stored(field, lo, hi)) continue;
            seam.cell[lat.cell(i, j)] = 1;
            ++seam.cells;
        }
    // The term in every column over a fully wet cell (s is defined there) wherever the field
    // stores samples: where a ball's support reaches the water, its skirt rises from the
    // water's level, and it ends at the stored blocks' edge, where the balls add (almost) 0.
    const auto at = [&](float x, float z, float& s) {
        const float u = (x - lat.x0) / lat.dx, v = (z - lat.z0) / lat.dz;
        if (!(u >= 0.0f && v >= 0.0f)) return false;
        const int j = std::min(int(u), columns - 2), i = std::min(int(v), rows - 2);
        if (u > float(columns - 1) || v > float(rows - 1) || !wet_cell(i, j)) return false;
        const float fu = u - float(j), fv = v - float(i);
        const size_t c = size_t(i) * w + size_t(j);
        // On the heightfield mesh's triangles, (c, c + w, c + 1) and (c + 1, c + w, c + w + 1).
        if (fu + fv <= 1.0f) {
            s = level(c) + fu * (level(c + 1) - level(c)) + fv * (level(c + w) - level(c));
        } else {
            const float e = level(c + w + 1);
            s = e + (1.0f - fu) * (level(c + w) - e) + (1.0f - fv) * (level(c + 1) - e);
        }
        return true;
    };
    field.add_level_term(
        [&](float x, float z, float& s) {
            if (!at(x, z, s)) return false;
            s -= kUnder;
            return true;
        },
        threshold, width);
}

}  // namespace mr
