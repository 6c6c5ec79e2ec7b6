// Segment vs heightfield by walking cells: the fast path of the robust collision mode.
// Watertight ray/triangle test: Woop, Benthin, Wald, "Watertight Ray/Triangle
// Intersection", JCGT 2013 (watertight_ray.h, prepared once per segment).
#include <metariver/terrain.h>

#include "watertight_ray.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace mr {

HeightfieldQuery intersect_segment_heightfield(const Terrain& terrain, const Vec3& from, const Vec3& to,
                                               int max_cells) {
    HeightfieldQuery q;
    const int W = terrain.columns(), H = terrain.rows();
    if (W < 2 || H < 2) return q;
    const float s = terrain.area_scale();
    const float inv = 1.0f / s;
    // Cells touched by the segment's x/z box, grown by a relative hair so a segment
    // running along a shared edge tests the triangles on both sides.
    const float eps = 1e-4f;
    const float x0 = std::min(from.x, to.x) * inv - eps, x1 = std::max(from.x, to.x) * inv + eps;
    const float z0 = std::min(from.z, to.z) * inv - eps, z1 = std::max(from.z, to.z) * inv + eps;
    if (!(x1 >= 0.0f && z1 >= 0.0f && x0 <= float(W - 1) && z0 <= float(H - 1))) return q;  // also NaN
    // Clamp in float before converting: an exploding coordinate (1e30) must not reach
    // the int conversion (undefined behaviour). Every clamped value is finite and at least 0
    // (the test above), so truncation is the floor (std::floor is a call in the
    // portable build, four per particle and step).
    const int j0 = static_cast<int>(std::max(x0, 0.0f));
    const int j1 = static_cast<int>(std::min(x1, float(W - 2)));
    const int i0 = static_cast<int>(std::max(z0, 0.0f));
    const int i1 = static_cast<int>(std::min(z1, float(H - 2)));
    if (static_cast<int64_t>(j1 - j0 + 1) * (i1 - i0 + 1) > max_cells) {
        q.too_long = true;
        return q;
    }
    const float ymin = std::min(from.y, to.y);
    // Plane heights are rounded relative to the coordinates' size (and to the heights',
    // which a cell the segment reaches shares): 1e-5 of it, plus 0.1 mm, is hundreds of
    // float roundings.
    const float margin = 1e-4f + 1e-5f * (std::abs(from.x) + std::abs(from.y) + std::abs(from.z) +
                                          std::abs(to.x) + std::abs(to.y) + std::abs(to.z));
    const Vec3 dir = to - from;
    // Prepared at the first cell that reaches the segment: most particles' segments reach
    // none, and the preparation's three divisions would cost them more than the culling.
    watertight::Ray ray;
    bool prepared = false;
    const auto verts = terrain.vertices();
    float best_t = 2.0f;
    uint32_t best_tri = 0;
    for (int i = i0; i <= i1; ++i) {
        for (int j = j0; j <= j1; ++j) {
            const size_t c = static_cast<size_t>(i) * W + j;
            const Vec3& a = verts[c];
            const Vec3& b = verts[c + 1];
            const Vec3& d = verts[c + W];
            const Vec3& e = verts[c + W + 1];
            // The segment cannot reach a cell whose highest corner is below its lowest point.
            if (std::max(std::max(a.y, b.y), std::max(d.y, e.y)) < ymin) continue;
            // Nor a triangle whose plane both ends lie above by more than `margin`: the
            // segment then lies above the plane, and the watertight test could claim it
            // only within its rounding (far under the margin). The common case of a
            // particle moving in water near the ground costs two plane heights per end.
            // Height of p above the planes of (a, d, b) and (b, d, e), in the cell's (u, v).
            const auto clearance = [&](const Vec3& p) {
                const float u = (p.x - a.x) * inv, v = (p.z - a.z) * inv;
                const float lower = a.y + u * (b.y - a.y) + v * (d.y - a.y);
                const float upper = e.y + (1.0f - u) * (d.y - e.y) + (1.0f - v) * (b.y - e.y);
                return std::pair{p.y - lower, p.y - upper};
            };
            const auto [lower_f, upper_f] = clearance(from);
            const auto [lower_t, upper_t] = clearance(to);
            const bool test_lower = !(lower_f > margin && lower_t > margin);
            const bool test_upper = !(upper_f > margin && upper_t > margin);
            if (!test_lower && !test_upper) continue;
            if (!prepared) ray = watertight::prepare(from, dir), prepared = true;
            const uint32_t tri = 2u * static_cast<uint32_t>(static_cast<size_t>(i) * (W - 1) + j);
            if (auto t = test_lower ? watertight::hit(ray, a, d, b) : std::nullopt; t && *t < best_t) {
                best_t = *t;
                best_tri = tri;
            }
            if (auto t = test_upper ? watertight::hit(ray, b, d, e) : std::nullopt; t && *t < best_t) {
                best_t = *t;
                best_tri = tri + 1;
            }
        }
    }
    if (best_t <= 1.0f) {
        RayHit h;
        h.t = best_t;
        h.triangle = best_tri;
        h.point = from + best_t * dir;
        h.normal = terrain.triangle_normal(best_tri);
        q.hit = h;
    }
    return q;
}

}  // namespace mr
