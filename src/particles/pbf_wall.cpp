// PBF wall density (PbfDef::wall_density; the method in pbf.cpp's header comment): the
// share of a poly6 kernel that lies under the terrain, by a quadrature over the
// heightfield's triangles near the particle, and its gradient; the closed form for a
// plane (pbf_wall_share) the tests check it against.
#include "pbf_state.h"

#include <algorithm>
#include <cmath>

namespace mr {

namespace {

constexpr float kPi = 3.14159265358979f;

/// F(z) = integral_0^z (h^2 - t^2)^4 dt (odd in z): a slab at depth t beyond a plane holds
/// pi/4 (h^2 - t^2)^4 of the poly6 kernel's integral (times its constant).
float wall_primitive(float z, float h2) {
    const float h4 = h2 * h2, z2 = z * z;
    return z * (h4 * h4 - z2 * (4.0f / 3.0f * h4 * h2 - z2 * (6.0f / 5.0f * h4 - z2 * (4.0f / 7.0f * h2 - z2 / 9.0f))));
}

/// Wall density quadrature: samples per h along a triangle (the wall density).
constexpr int kWallSamplesPerH = 4;

}  // namespace

float pbf_wall_share(float distance, float h) {
    if (!(h > 0.0f)) return 0.0f;
    const float d = std::clamp(distance, -h, h);
    const float fh = wall_primitive(h, h * h);
    return (fh - wall_primitive(d, h * h)) / (2.0f * fh);
}

float pbf_terrain_share(const Terrain& terrain, float kernel_radius, const Vec3& x, Vec3& grad) {
    grad = Vec3(0.0f);
    const int w = terrain.columns(), r = terrain.rows();
    if (w < 2 || r < 2) return 0.0f;
    const float h = kernel_radius, h2 = h * h;
    const float s = terrain.area_scale();
    // The cells the kernel's footprint touches; nothing of the mesh there is higher than
    // their highest sample: nothing within h, no share.
    const int j0 = std::clamp(int(std::floor((x.x - h) / s)), 0, w - 2), j1 = std::clamp(int(std::floor((x.x + h) / s)), 0, w - 2);
    const int i0 = std::clamp(int(std::floor((x.z - h) / s)), 0, r - 2), i1 = std::clamp(int(std::floor((x.z + h) / s)), 0, r - 2);
    float top = -1e30f;
    for (int i = i0; i <= i1 + 1; ++i)
        for (int j = j0; j <= j1 + 1; ++j) top = std::max(top, terrain.sample(i, j));
    if (x.y - h >= top) return 0.0f;
    const float kc = 315.0f / (64.0f * kPi * std::pow(h, 9.0f));  // poly6's constant
    const float sample_len = h / float(kWallSamplesPerH);
    float share = 0.0f;
    Vec3 g(0.0f);
    // One triangle: midpoints of an m x m subdivision (m from its area, so a steep face,
    // narrow in x and z, is sampled as densely as flat ground).
    const auto triangle = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
        if (std::max({a.y, b.y, c.y}) <= x.y - h) return;  // every column's kernel above it
        const float dx = std::max({std::min({a.x, b.x, c.x}) - x.x, x.x - std::max({a.x, b.x, c.x}), 0.0f});
        const float dz = std::max({std::min({a.z, b.z, c.z}) - x.z, x.z - std::max({a.z, b.z, c.z}), 0.0f});
        if (dx * dx + dz * dz >= h2) return;  // outside the kernel's footprint
        const Vec3 e1 = b - a, e2 = c - a;
        const Vec3 cr = glm::cross(e2, e1);  // up: the heightfield's triangles wind so
        const float area2 = glm::length(cr);
        if (!(area2 > 0.0f)) return;
        const Vec3 n = cr / area2;
        const int m = std::clamp(int(std::ceil(std::sqrt(0.5f * area2) / sample_len)), 1, 16);
        const float ds = 0.5f * area2 / float(m * m), da = ds * std::abs(n.y);
        const float inv_m = 1.0f / float(m);
        const auto sample = [&](float u, float v) {
            const Vec3 q = a + (u * inv_m) * e1 + (v * inv_m) * e2;
            const float dx = q.x - x.x, dz = q.z - x.z;
            const float a2 = h2 - dx * dx - dz * dz;
            if (a2 <= 0.0f) return;
            const float t = q.y - x.y, al = std::sqrt(a2);
            if (t <= -al) return;  // the column's kernel is all above the ground here
            const float a4 = a2 * a2, pa = 16.0f / 35.0f * a4 * a2 * al;  // P(a)
            if (t >= al) {         // all under it
                share += kc * 2.0f * pa * da;
                return;
            }
            // int_{-a}^{t} (a^2 - u^2)^3 du = P(t) + P(a), P(u) = a^6 u - a^4 u^3 + 3/5 a^2 u^5 - u^7 / 7.
            const float t2 = t * t;
            share += kc * (t * (a4 * a2 - t2 * (a4 - t2 * (0.6f * a2 - t2 / 7.0f))) + pa) * da;
            const float qq = a2 - t2;
            g -= (kc * qq * qq * qq * ds) * n;  // -W n dS
        };
        for (int u = 0; u < m; ++u)
            for (int v = 0; u + v < m; ++v) {
                sample(float(u) + 1.0f / 3.0f, float(v) + 1.0f / 3.0f);
                if (u + v + 2 <= m) sample(float(u) + 2.0f / 3.0f, float(v) + 2.0f / 3.0f);
            }
    };
    for (int i = i0; i <= i1; ++i)
        for (int j = j0; j <= j1; ++j) {
            const Vec3 p00(float(j) * s, terrain.sample(i, j), float(i) * s);
            const Vec3 p01(float(j + 1) * s, terrain.sample(i, j + 1), float(i) * s);
            const Vec3 p10(float(j) * s, terrain.sample(i + 1, j), float(i + 1) * s);
            const Vec3 p11(float(j + 1) * s, terrain.sample(i + 1, j + 1), float(i + 1) * s);
            triangle(p00, p01, p10);  // u + v <= 1 (Terrain::height_mesh)
            triangle(p11, p10, p01);
        }
    grad = g;
    return std::clamp(share, 0.0f, 1.0f);
}

}  // namespace mr
