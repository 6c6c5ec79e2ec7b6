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

#include "watertight_ray.h"

#include <cmath>

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
    return watertight::hit(watertight::prepare(origin, dir), a, b, c);
}

}  // namespace mr
