// Ray/triangle intersection, segment form: origin + t*dir with t in [0, 1].
//
// ray_triangle_paper: Moller and Trumbore, "Fast, minimum storage ray-triangle
//   intersection", JGT 1997 -- the paper's equation 4 (Cramer's rule on
//   o + t d = (1-u-v) a + u b + v c). Both faces. Not watertight: u, v and t are
//   rounded per triangle, so a ray exactly through a shared edge can miss both sides.
// ray_triangle_watertight: Woop, Benthin and Wald, "Watertight Ray/Triangle
//   Intersection", JCGT 2(1), 2013. The vertices are translated to the ray origin and
//   sheared so the ray runs along +z; the 2-D edge functions U, V, W of a shared edge
//   are then computed from the same transformed vertices in both triangles, so they
//   are exact negatives of each other and at least one triangle claims the ray.
//   When an edge function is exactly 0 it is recomputed in double precision (exact
//   for products of floats), as in the paper's section 4.
#include <metariver/terrain.h>

#include <cmath>
#include <utility>

namespace mr {

std::optional<float> ray_triangle_paper(const Vec3& origin, const Vec3& dir, const Vec3& a, const Vec3& b,
                                        const Vec3& c) {
    const Vec3 e1 = b - a;
    const Vec3 e2 = c - a;
    const Vec3 p = glm::cross(dir, e2);
    const float det = glm::dot(e1, p);
    if (det == 0.0f || !std::isfinite(det)) return std::nullopt;  // parallel (or garbage input)
    const float inv = 1.0f / det;
    const Vec3 s = origin - a;
    const float u = glm::dot(s, p) * inv;
    if (!(u >= 0.0f && u <= 1.0f)) return std::nullopt;
    const Vec3 q = glm::cross(s, e1);
    const float v = glm::dot(dir, q) * inv;
    if (!(v >= 0.0f && u + v <= 1.0f)) return std::nullopt;
    const float t = glm::dot(e2, q) * inv;
    if (!(t >= 0.0f && t <= 1.0f)) return std::nullopt;
    return t;
}

std::optional<float> ray_triangle_watertight(const Vec3& origin, const Vec3& dir, const Vec3& a, const Vec3& b,
                                             const Vec3& c) {
    // Dimension where the ray direction is largest in magnitude becomes z.
    const Vec3 ad = glm::abs(dir);
    int kz = 0;
    if (ad.y > ad[kz]) kz = 1;
    if (ad.z > ad[kz]) kz = 2;
    if (!(ad[kz] > 0.0f) || !std::isfinite(ad[kz])) return std::nullopt;  // zero, NaN or infinite direction
    int kx = kz + 1 == 3 ? 0 : kz + 1;
    int ky = kx + 1 == 3 ? 0 : kx + 1;
    if (dir[kz] < 0.0f) std::swap(kx, ky);  // keep the winding of the 2-D projection

    // Shear constants.
    const float sx = dir[kx] / dir[kz];
    const float sy = dir[ky] / dir[kz];
    const float sz = 1.0f / dir[kz];

    // Vertices relative to the ray origin, sheared into ray space.
    const Vec3 A = a - origin;
    const Vec3 B = b - origin;
    const Vec3 C = c - origin;
    const float ax = A[kx] - sx * A[kz], ay = A[ky] - sy * A[kz];
    const float bx = B[kx] - sx * B[kz], by = B[ky] - sy * B[kz];
    const float cx = C[kx] - sx * C[kz], cy = C[ky] - sy * C[kz];

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
    const float az = sz * A[kz], bz = sz * B[kz], cz = sz * C[kz];
    const float T = U * az + V * bz + W * cz;
    if (det > 0.0f ? (T < 0.0f || T > det) : (T > 0.0f || T < det)) return std::nullopt;
    const float t = T / det;
    if (!(t >= 0.0f && t <= 1.0f)) return std::nullopt;  // rounding in the division, or NaN
    return t;
}

}  // namespace mr
