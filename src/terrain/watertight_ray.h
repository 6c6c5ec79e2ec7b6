// metariver terrain: the watertight ray/triangle test (Woop, Benthin, Wald, JCGT 2013)
// split into its per-ray part (the axis permutation and the shear, with its three
// divisions) and its per-triangle part, so a query that tests one segment against many
// triangles (heightfield_query.cpp, bvh.cpp) prepares the ray once.
// ray_triangle_watertight (ray_triangle.cpp) is prepare + test: the same operations in
// the same order, so the hits are the same bit for bit.
#pragma once

#include <metariver/core.h>

#include <cmath>
#include <optional>
#include <utility>

namespace mr::watertight {

struct Ray {
    Vec3 origin{0.0f};
    int kx = 0, ky = 1, kz = 2;
    float sx = 0.0f, sy = 0.0f, sz = 0.0f;
    bool ok = false;  ///< false: zero, NaN or infinite direction (no triangle is hit)
};

/// The dimension where the direction is largest in magnitude becomes z; the shear
/// constants map the ray onto +z.
inline Ray prepare(const Vec3& origin, const Vec3& dir) {
    Ray r;
    r.origin = origin;
    const Vec3 ad = glm::abs(dir);
    int kz = 0;
    if (ad.y > ad[kz]) kz = 1;
    if (ad.z > ad[kz]) kz = 2;
    if (!(ad[kz] > 0.0f) || !std::isfinite(ad[kz])) return r;
    int kx = kz + 1 == 3 ? 0 : kz + 1;
    int ky = kx + 1 == 3 ? 0 : kx + 1;
    if (dir[kz] < 0.0f) std::swap(kx, ky);  // keep the winding of the 2-D projection
    r.kx = kx, r.ky = ky, r.kz = kz;
    r.sx = dir[kx] / dir[kz];
    r.sy = dir[ky] / dir[kz];
    r.sz = 1.0f / dir[kz];
    r.ok = true;
    return r;
}

/// t in [0, 1] where the prepared segment meets triangle (a, b, c), either face.
inline std::optional<float> hit(const Ray& r, const Vec3& a, const Vec3& b, const Vec3& c) {
    if (!r.ok) return std::nullopt;
    const int kx = r.kx, ky = r.ky, kz = r.kz;
    // Vertices relative to the ray origin, sheared into ray space.
    const Vec3 A = a - r.origin;
    const Vec3 B = b - r.origin;
    const Vec3 C = c - r.origin;
    const float ax = A[kx] - r.sx * A[kz], ay = A[ky] - r.sy * A[kz];
    const float bx = B[kx] - r.sx * B[kz], by = B[ky] - r.sy * B[kz];
    const float cx = C[kx] - r.sx * C[kz], cy = C[ky] - r.sy * C[kz];

    // Scaled barycentrics (2-D edge functions).
    float U = cx * by - cy * bx;
    float V = ax * cy - ay * cx;
    float W = bx * ay - by * ax;
    if (U == 0.0f || V == 0.0f || W == 0.0f) {
        const double cxby = static_cast<double>(cx) * by, cybx = static_cast<double>(cy) * bx;
        const double axcy = static_cast<double>(ax) * cy, aycx = static_cast<double>(ay) * cx;
        const double bxay = static_cast<double>(bx) * ay, byax = static_cast<double>(by) * ax;
        U = static_cast<float>(cxby - cybx);
        V = static_cast<float>(axcy - aycx);
        W = static_cast<float>(bxay - byax);
    }
    // Both faces: reject only when the signs are mixed.
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return std::nullopt;
    const float det = U + V + W;
    if (det == 0.0f || !std::isfinite(det)) return std::nullopt;

    // Scaled hit distance; accept 0 <= t <= 1 without dividing first.
    const float az = r.sz * A[kz], bz = r.sz * B[kz], cz = r.sz * C[kz];
    const float T = U * az + V * bz + W * cz;
    if (det > 0.0f ? (T < 0.0f || T > det) : (T > 0.0f || T < det)) return std::nullopt;
    const float t = T / det;
    if (!(t >= 0.0f && t <= 1.0f)) return std::nullopt;  // rounding in the division, or NaN
    return t;
}

}  // namespace mr::watertight
