// The water queries (water_query.h). The surface mesh's triangles are binned by their x-z
// bounding box into a 2D uniform grid: a point's vertical line meets only the triangles
// of its cell, and a ray walks the cells its x-z projection crosses (Amanatides & Woo
// 1987) in order, testing their triangles (Moller & Trumbore 1997, both sides) and
// stopping once its nearest hit lies before the next cell. The flow velocity gathers the
// active particles from a NeighborGrid of cell R (the Shepard-normalised poly6 mean of
// Mueller et al. 2003, as the renderer's surface_velocities). The per-element arithmetic
// is shared with the brute-force twins (water_query_brute.cpp): fast and brute visit
// different sets, never compute differently.
#include <metariver/water_query.h>

#include <metariver/neighbor_grid.h>
#include <metariver/scene.h>

#include "water_query_internal.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace mr {

using namespace water_detail;

namespace {

/// The surface mesh's triangles binned on a 2D grid over x-z. Each triangle's three
/// corners are copied in triangle order (corners_[3 t ..]: one contiguous read per test,
/// where the mesh's indexed vertices would be three random ones); a cell's triangle ids
/// are list_[start_[c] .. start_[c + 1]) (compressed rows by a counting sort); ylo_/yhi_
/// bound the y of a cell's triangles, so a ray skips the cells it passes over or under.
class TriangleGrid {
public:
    void build(const SurfaceMesh& m);
    /// The highest crossing of the vertical line at (x, z), in y; false when none.
    bool highest_crossing(float x, float z, float& y) const;
    /// The first hit of the ray o + t d (d unit, o finite, max_t >= 0).
    WaterRayHit first_hit(const Vec3& o, const Vec3& d, float max_t) const;

private:
    int cell_x(double x) const { return std::clamp(int(std::floor((x - box_.min.x) * inv_cell_)), 0, nx_ - 1); }
    int cell_z(double z) const { return std::clamp(int(std::floor((z - box_.min.z) * inv_cell_)), 0, nz_ - 1); }
    void choose_cells(size_t finite, double mean_extent);
    void bin(size_t triangles);
    /// Tests the triangles of cell c against the ray, keeping the nearest in `best`.
    void hit_cell(size_t c, const Vec3& o, const Vec3& d, float max_t, WaterRayHit& best) const;

    Aabb box_;
    float cell_ = 1.0f, inv_cell_ = 1.0f, pad_ = 0.0f;
    int nx_ = 0, nz_ = 0;
    std::vector<Vec3> corners_;
    std::vector<uint8_t> valid_;  ///< per triangle: finite corners and indices in range
    std::vector<uint32_t> start_, list_;
    std::vector<float> ylo_, yhi_;
};

void TriangleGrid::build(const SurfaceMesh& m) {
    const size_t n = m.indices.size() / 3;
    corners_.resize(3 * n);
    valid_.assign(n, 0);
    box_ = {};
    size_t finite_count = 0;
    double extent = 0.0;
    for (size_t t = 0; t < n; ++t) {
        bool ok = true;
        for (size_t k = 0; k < 3; ++k) {
            const uint32_t v = m.indices[3 * t + k];
            ok = ok && v < m.positions.size() && finite(m.positions[v]);
            corners_[3 * t + k] = ok ? m.positions[v] : Vec3(0.0f);
        }
        if (!ok) continue;
        valid_[t] = 1;
        ++finite_count;
        const Vec3 &a = corners_[3 * t], &b = corners_[3 * t + 1], &c = corners_[3 * t + 2];
        const Vec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
        box_.grow(lo);
        box_.grow(hi);
        extent += std::max(hi.x - lo.x, hi.z - lo.z);
    }
    if (finite_count == 0) {
        nx_ = nz_ = 0;
        return;
    }
    choose_cells(finite_count, extent / double(finite_count));
    bin(n);
}

/// Cells about twice the mean triangle's x-z extent or one per two triangles over the
/// box, whichever is larger, at most kMaxCells in all.
void TriangleGrid::choose_cells(size_t finite, double mean_extent) {
    constexpr double kMaxCells = 4.0e6;
    const double ex = double(box_.max.x) - box_.min.x, ez = double(box_.max.z) - box_.min.z;
    double cell = std::max(2.0 * mean_extent, std::sqrt(ex * ez / std::max(1.0, double(finite) / 2.0)));
    const double span = std::max({ex, ez, 1e-6});
    if (!(cell > span * 1e-6)) cell = span;  // a mesh of vertical or zero-size triangles
    while ((std::floor(ex / cell) + 1.0) * (std::floor(ez / cell) + 1.0) > kMaxCells) cell *= 1.5;
    cell_ = float(cell);
    inv_cell_ = float(1.0 / cell);
    nx_ = int(std::floor(ex / cell)) + 1;
    nz_ = int(std::floor(ez / cell)) + 1;
    // Triangles are binned with their boxes grown by pad_, so rounding at a cell face
    // never leaves a triangle out of a cell the line or ray meets it in.
    pad_ = float(1e-5 * cell + 1e-6 * span);
}

void TriangleGrid::bin(size_t triangles) {
    const size_t cells = size_t(nx_) * size_t(nz_);
    start_.assign(cells + 1, 0);
    ylo_.assign(cells, std::numeric_limits<float>::max());
    yhi_.assign(cells, std::numeric_limits<float>::lowest());
    // Visits the cells of triangle t's padded box: f(cell, lowest y, highest y).
    const auto for_cells = [&](size_t t, auto&& f) {
        const Vec3 &a = corners_[3 * t], &b = corners_[3 * t + 1], &c = corners_[3 * t + 2];
        const Vec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
        const int x0 = cell_x(double(lo.x) - pad_), x1 = cell_x(double(hi.x) + pad_);
        const int z0 = cell_z(double(lo.z) - pad_), z1 = cell_z(double(hi.z) + pad_);
        for (int z = z0; z <= z1; ++z)
            for (int x = x0; x <= x1; ++x) f(size_t(z) * size_t(nx_) + size_t(x), lo.y, hi.y);
    };
    for (size_t t = 0; t < triangles; ++t) {
        if (!valid_[t]) continue;
        for_cells(t, [&](size_t c, float lo, float hi) {
            ++start_[c + 1];
            ylo_[c] = std::min(ylo_[c], lo);
            yhi_[c] = std::max(yhi_[c], hi);
        });
    }
    for (size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
    list_.resize(start_[cells]);
    std::vector<uint32_t> cursor(start_.begin(), start_.end() - 1);
    for (size_t t = 0; t < triangles; ++t)
        if (valid_[t]) for_cells(t, [&](size_t c, float, float) { list_[cursor[c]++] = uint32_t(t); });
}

bool TriangleGrid::highest_crossing(float x, float z, float& y) const {
    if (nx_ == 0 || !(x >= box_.min.x && x <= box_.max.x && z >= box_.min.z && z <= box_.max.z)) return false;
    const size_t c = size_t(cell_z(z)) * size_t(nx_) + size_t(cell_x(x));
    bool wet = false;
    for (uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
        const Vec3* v = &corners_[3 * size_t(list_[k])];
        if (wet && std::max({v[0].y, v[1].y, v[2].y}) <= y) continue;  // cannot cross higher
        float cy;
        if (!vertical_crossing(v[0], v[1], v[2], x, z, cy)) continue;
        if (!wet || cy > y) y = cy;
        wet = true;
    }
    return wet;
}

void TriangleGrid::hit_cell(size_t c, const Vec3& o, const Vec3& d, float max_t, WaterRayHit& best) const {
    for (uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
        const uint32_t tri = list_[k];
        const Vec3* v = &corners_[3 * size_t(tri)];
        float t;
        if (ray_triangle(o, d, v[0], v[1], v[2], max_t, t) && nearer(t, tri, best))
            best = make_hit(o, d, t, tri, v[0], v[1], v[2]);
    }
}

/// The ray's parameter range inside `box` (grown by pad) intersected with [t0, t1];
/// false when it misses the box.
bool clip_to_box(const Aabb& box, float pad, const Vec3& o, const Vec3& d, double& t0, double& t1) {
    for (int a = 0; a < 3; ++a) {
        const double lo = double(box.min[a]) - pad, hi = double(box.max[a]) + pad;
        if (d[a] == 0.0f) {
            if (o[a] < lo || o[a] > hi) return false;
            continue;
        }
        double ta = (lo - o[a]) / d[a], tb = (hi - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 <= t1;
}

WaterRayHit TriangleGrid::first_hit(const Vec3& o, const Vec3& d, float max_t) const {
    WaterRayHit best;
    double t0 = 0.0, t1 = max_t;
    if (nx_ == 0 || !clip_to_box(box_, pad_, o, d, t0, t1)) return best;
    int ix = cell_x(o.x + t0 * d.x), iz = cell_z(o.z + t0 * d.z);
    constexpr double kInf = std::numeric_limits<double>::infinity();
    const int sx = d.x > 0.0f ? 1 : -1, sz = d.z > 0.0f ? 1 : -1;
    const auto face = [&](int i, int s, float origin, float o_a, float d_a) {  // t of the cell's exit face
        return d_a == 0.0f ? kInf : (double(origin) + double(i + (s > 0)) * cell_ - o_a) / d_a;
    };
    double tx = face(ix, sx, box_.min.x, o.x, d.x), tz = face(iz, sz, box_.min.z, o.z, d.z);
    const double dtx = d.x == 0.0f ? kInf : cell_ / std::abs(double(d.x));
    const double dtz = d.z == 0.0f ? kInf : cell_ / std::abs(double(d.z));
    const double tol = 1e-3 * cell_ + pad_;  // a hit this near the next cell's face may lie in it
    for (double entry = t0;;) {
        const double exit = std::min({tx, tz, t1});
        const size_t c = size_t(iz) * size_t(nx_) + size_t(ix);
        const double ya = o.y + std::max(entry - tol, 0.0) * d.y, yb = o.y + (exit + tol) * d.y;
        if (std::max(ya, yb) >= double(ylo_[c]) - pad_ && std::min(ya, yb) <= double(yhi_[c]) + pad_)
            hit_cell(c, o, d, max_t, best);
        if ((best.hit && double(best.t) < exit - tol) || exit >= t1) break;
        if (tx < tz) {
            ix += sx;
            entry = tx;
            tx += dtx;
        } else {
            iz += sz;
            entry = tz;
            tz += dtz;
        }
        if (ix < 0 || ix >= nx_ || iz < 0 || iz >= nz_) break;
    }
    return best;
}

/// Runs f(i) for i in [0, n) in parallel blocks.
template <class F>
void parallel_each(size_t n, F&& f) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
}

}  // namespace

/// One frame's copy of what the queries read (update()).
struct WaterQuery::Impl {
    TriangleGrid triangles;
    Terrain terrain;                  ///< for the depth (Terrain::height_mesh); copied when its revision() changes
    bool has_heightfield = false;
    HeightfieldWater heightfield;
    float radius = 0.0f;              ///< flow_radius(def)
    std::vector<Vec3> position, velocity;  ///< the active particles with finite positions
    std::vector<uint8_t> binned;      ///< all 1 (NeighborGrid::build's mask)
    Aabb particle_box;
    NeighborGrid grid;
};

WaterQuery::WaterQuery() : impl_(std::make_unique<Impl>()) {}
WaterQuery::~WaterQuery() = default;
WaterQuery::WaterQuery(WaterQuery&&) noexcept = default;
WaterQuery& WaterQuery::operator=(WaterQuery&&) noexcept = default;

void WaterQuery::update(const Simulation& sim) {
    if (!impl_) impl_ = std::make_unique<Impl>();
    Impl& q = *impl_;
    q.triangles.build(sim.surface());
    if (q.terrain.revision() != sim.terrain().revision()) q.terrain = sim.terrain();  // a sculpt, another sim
    q.has_heightfield = sim.heightfield() != nullptr;
    if (q.has_heightfield) q.heightfield = *sim.heightfield();
    q.radius = flow_radius(sim.def());
    const Particles& ps = sim.particles();
    q.position.clear();
    q.velocity.clear();
    q.particle_box = {};
    for (size_t i = 0; i < ps.size(); ++i) {
        if (!ps.active[i] || !finite(ps.position[i])) continue;
        q.position.push_back(ps.position[i]);
        q.velocity.push_back(ps.velocity[i]);
        q.particle_box.grow(ps.position[i]);
    }
    q.binned.assign(q.position.size(), 1);
    if (q.radius > 0.0f && !q.position.empty()) q.grid.build(q.position, q.binned, q.radius);
}

Vec3 WaterQuery::velocity_at(const Vec3& p) const {
    if (!impl_ || !finite(p)) return Vec3(0.0f);
    const Impl& q = *impl_;
    Vec3 v;
    if (q.has_heightfield && heightfield_velocity(q.heightfield, p.x, p.z, v)) return v;
    const float r = q.radius;
    if (!(r > 0.0f) || q.position.empty()) return Vec3(0.0f);
    const Aabb& b = q.particle_box;  // beyond it (and far off, where cell indices would overflow): none within r
    if (p.x < b.min.x - r || p.y < b.min.y - r || p.z < b.min.z - r || p.x > b.max.x + r || p.y > b.max.y + r ||
        p.z > b.max.z + r)
        return Vec3(0.0f);
    const float r2 = r * r, inv_r2 = 1.0f / r2;
    const auto order = q.grid.order();
    const auto sx = q.grid.sorted_x(), sy = q.grid.sorted_y(), sz = q.grid.sorted_z();
    FlowSum sum;
    q.grid.for_each_candidate_slot(p, [&](uint32_t k) {
        const Vec3 d(p.x - sx[k], p.y - sy[k], p.z - sz[k]);
        const float d2 = glm::dot(d, d);
        if (d2 < r2) sum.add(d2, inv_r2, q.velocity[order[k]]);
    });
    return sum.mean();
}

WaterSample WaterQuery::sample(float x, float z) const {
    if (!impl_ || !std::isfinite(x) || !std::isfinite(z)) return {};
    float top = 0.0f;
    const float ground = impl_->terrain.height_mesh(x, z);
    if (!impl_->triangles.highest_crossing(x, z, top)) return {.surface_y = ground};
    return {.wet = true,
            .surface_y = top,
            .depth = std::max(0.0f, top - ground),
            .velocity = velocity_at(Vec3(x, top, z))};
}

WaterRayHit WaterQuery::raycast(const Vec3& origin, const Vec3& direction, float max_t) const {
    Vec3 d;
    if (!impl_ || !ray_setup(origin, direction, max_t, d)) return {};
    return impl_->triangles.first_hit(origin, d, max_t);
}

void WaterQuery::sample(std::span<const float> xz, std::span<WaterSample> out) const {
    const size_t n = std::min(xz.size() / 2, out.size());
    parallel_each(n, [&](size_t i) { out[i] = sample(xz[2 * i], xz[2 * i + 1]); });
    std::fill(out.begin() + ptrdiff_t(n), out.end(), WaterSample{});
}

void WaterQuery::velocity_at(std::span<const Vec3> points, std::span<Vec3> out) const {
    const size_t n = std::min(points.size(), out.size());
    parallel_each(n, [&](size_t i) { out[i] = velocity_at(points[i]); });
    std::fill(out.begin() + ptrdiff_t(n), out.end(), Vec3(0.0f));
}

void WaterQuery::raycast(std::span<const Vec3> origins, std::span<const Vec3> directions, float max_t,
                         std::span<WaterRayHit> out) const {
    const size_t n = std::min({origins.size(), directions.size(), out.size()});
    parallel_each(n, [&](size_t i) { out[i] = raycast(origins[i], directions[i], max_t); });
    std::fill(out.begin() + ptrdiff_t(n), out.end(), WaterRayHit{});
}

}  // namespace mr
