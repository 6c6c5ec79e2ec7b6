// The per-element tests the water queries (water_query.cpp) and their brute-force twins
// (water_query_brute.cpp) share, so both answer with the same arithmetic: the twins
// differ only in which triangles and particles they visit.
#pragma once

#include <metariver/solver.h>
#include <metariver/water_query.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <span>
#include <utility>

namespace mr::water_detail {

/// The 2D edge function of p against the edge a -> b in x-z, computed from the edge's
/// endpoints in a fixed (lexicographic) order and negated when they come the other way,
/// so the two triangles sharing an edge get exactly opposite values: a point on the edge
/// is inside (all edge functions of one sign, zero allowed) for at least one of them.
inline double edge_xz(const Vec3& a, const Vec3& b, double px, double pz) {
    const bool swap = a.x > b.x || (a.x == b.x && a.z > b.z);
    const Vec3& u = swap ? b : a;
    const Vec3& v = swap ? a : b;
    const double e = (double(v.x) - u.x) * (pz - u.z) - (double(v.z) - u.z) * (px - u.x);
    return swap ? -e : e;
}

/// Where the vertical line at (x, z) crosses triangle (a, b, c): its y (barycentric) in
/// `y`, true when (x, z) lies inside or on the triangle's x-z projection. A vertical
/// triangle (zero projected area) or a non-finite vertex never counts.
inline bool vertical_crossing(const Vec3& a, const Vec3& b, const Vec3& c, float x, float z, float& y) {
    const double wa = edge_xz(b, c, x, z), wb = edge_xz(c, a, x, z), wc = edge_xz(a, b, x, z);
    const bool negative = wa < 0.0 || wb < 0.0 || wc < 0.0;
    const bool positive = wa > 0.0 || wb > 0.0 || wc > 0.0;
    if (negative && positive) return false;
    const double d = wa + wb + wc;
    if (!(std::abs(d) > 0.0)) return false;  // vertical, or NaN
    y = float((wa * a.y + wb * b.y + wc * c.y) / d);
    return true;
}

/// Moller & Trumbore (1997), both sides: the ray o + t d (d unit) against triangle
/// (a, b, c) in double precision; true with t in [0, max_t].
inline bool ray_triangle(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c, float max_t,
                         float& t) {
    using D3 = glm::dvec3;
    const D3 da(a), e1 = D3(b) - da, e2 = D3(c) - da, dir(d);
    const D3 p = glm::cross(dir, e2);
    const double det = glm::dot(e1, p);
    if (!(std::abs(det) > 0.0)) return false;  // parallel, degenerate, or NaN
    const double inv = 1.0 / det;
    const D3 s = D3(o) - da;
    const double u = glm::dot(s, p) * inv;
    if (u < 0.0 || u > 1.0) return false;
    const D3 q = glm::cross(s, e1);
    const double v = glm::dot(dir, q) * inv;
    if (v < 0.0 || u + v > 1.0) return false;
    const double th = glm::dot(e2, q) * inv;
    if (!(th >= 0.0 && th <= double(max_t))) return false;
    t = float(th);
    return true;
}

/// The ray's unit direction, or false (no hit) for a zero or non-finite direction or
/// origin, or a max_t that is not >= 0.
inline bool ray_setup(const Vec3& origin, const Vec3& direction, float max_t, Vec3& unit) {
    if (!(max_t >= 0.0f)) return false;
    if (!std::isfinite(origin.x) || !std::isfinite(origin.y) || !std::isfinite(origin.z)) return false;
    const double len = glm::length(glm::dvec3(direction));
    if (!(len > 0.0) || !std::isfinite(len)) return false;
    unit = Vec3(glm::dvec3(direction) / len);
    return true;
}

/// The hit for triangle `tri` at t (its normal facing the ray's origin).
inline WaterRayHit make_hit(const Vec3& o, const Vec3& d, float t, uint32_t tri, const Vec3& a, const Vec3& b,
                            const Vec3& c) {
    const glm::dvec3 cr = glm::cross(glm::dvec3(b) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a));
    const double len = glm::length(cr);
    Vec3 n = len > 0.0 ? Vec3(cr / len) : -d;
    if (glm::dot(n, d) > 0.0f) n = -n;
    return {.hit = true, .t = t, .point = o + t * d, .normal = n, .triangle = tri};
}

/// Keeps the nearer of two hits; at equal t the lower triangle index (so the order in
/// which triangles are visited does not change the answer).
inline bool nearer(float t, uint32_t tri, const WaterRayHit& best) {
    return !best.hit || t < best.t || (t == best.t && tri < best.triangle);
}

/// The kernel-weighted velocity sum: weight (1 - r^2/R^2)^3 for r < R, in double so the
/// order of the particles changes the mean by rounding of double only.
struct FlowSum {
    double x = 0.0, y = 0.0, z = 0.0, w = 0.0;
    void add(float d2, float inv_r2, const Vec3& v) {
        const double q = 1.0 - double(d2) * double(inv_r2);
        const double wt = q * q * q;
        x += wt * v.x;
        y += wt * v.y;
        z += wt * v.z;
        w += wt;
    }
    Vec3 mean() const { return w > 0.0 ? Vec3(float(x / w), float(y / w), float(z / w)) : Vec3(0.0f); }
};

inline bool finite(const Vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

/// The heightfield's velocity at (x, z): the bilinear weights of the cell around (x, z),
/// over its wet samples (depth > 0) only, normalised; false outside the grid or where no
/// sample of the cell with a weight above 0 is wet (then the particles answer).
bool heightfield_velocity(const HeightfieldWater& hf, float x, float z, Vec3& out);

}  // namespace mr::water_detail
