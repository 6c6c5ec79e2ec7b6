// Procedural heightmaps: the paper's 'strict' and 'bowl' test shapes (fitted to
// strict17.png / strict.png and bowl.png of the paper's repository) and a valley with a
// winding river channel, so the product needs no image files for its defaults.
//
// Noise is plain value noise (random lattice values, smoothstep-interpolated) drawn
// from mr::Lcg, so every platform produces the same terrain for a seed.
#include <metariver/terrain.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mr {
namespace {

float smoothstep(float e0, float e1, float x) {
    const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

/// Value noise on a lattice of (nx+1) x (ny+1) random values in [-1, 1]; sampled at
/// (u, v) in [0, 1]^2 with smoothstep interpolation.
class ValueNoise2 {
public:
    ValueNoise2(Lcg& rng, int nx, int ny) : nx_(nx), ny_(ny), values_(static_cast<size_t>(nx + 1) * (ny + 1)) {
        for (float& v : values_) v = rng.uniform(-1.0f, 1.0f);
    }
    float operator()(float u, float v) const {
        const float x = std::clamp(u, 0.0f, 1.0f) * static_cast<float>(nx_);
        const float y = std::clamp(v, 0.0f, 1.0f) * static_cast<float>(ny_);
        const int i = std::min(static_cast<int>(x), nx_ - 1);
        const int j = std::min(static_cast<int>(y), ny_ - 1);
        const float fx = smoothstep(0.0f, 1.0f, x - static_cast<float>(i));
        const float fy = smoothstep(0.0f, 1.0f, y - static_cast<float>(j));
        const float a = at(i, j), b = at(i + 1, j), c = at(i, j + 1), d = at(i + 1, j + 1);
        return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy;
    }

private:
    float at(int i, int j) const { return values_[static_cast<size_t>(j) * (nx_ + 1) + i]; }
    int nx_, ny_;
    std::vector<float> values_;
};

/// Rescales samples to [0, 1] (a constant map becomes all zero).
void normalise(std::vector<float>& s) {
    if (s.empty()) return;
    const auto [lo, hi] = std::minmax_element(s.begin(), s.end());
    const float min = *lo, range = *hi - *lo;
    for (float& v : s) v = range > 0.0f ? std::clamp((v - min) / range, 0.0f, 1.0f) : 0.0f;
}


/// Coordinate of sample k of n in [0, 1] (0.5 for a single sample).
float unit(int k, int n) { return n > 1 ? static_cast<float>(k) / static_cast<float>(n - 1) : 0.5f; }

}  // namespace

Heightmap flat_heightmap(int width, int height, float value) {
    Heightmap m;
    m.width = std::max(width, 0);
    m.height = std::max(height, 0);
    m.bit_depth = 32;
    m.samples.assign(static_cast<size_t>(m.width) * m.height, value);
    return m;
}

Heightmap procedural_valley(int width, int height, uint32_t seed) {
    Heightmap m = flat_heightmap(width, height);
    if (m.samples.empty()) return m;

    Lcg rng(seed ^ 0x9e3779b9u);
    const float pi = std::numbers::pi_v<float>;
    // River centreline x(v) (v = 0 at image row 0, the high end): a sinusoid with a
    // seeded frequency and phase plus smooth 1-D noise, kept on the valley floor.
    const float cycles = rng.uniform(1.2f, 2.2f);
    const float phase = rng.uniform(0.0f, 2.0f * pi);
    const float amplitude = rng.uniform(0.10f, 0.15f);
    ValueNoise2 meander(rng, 6, 1);
    ValueNoise2 hills(rng, 8, 8);
    ValueNoise2 detail(rng, 24, 24);

    const float w = static_cast<float>(m.width);
    // Channel half-width (Gaussian sigma) in samples: a few samples wide at any size.
    const float sigma = std::max(1.2f, w / 64.0f);
    const float floor_half = 0.22f;  // valley floor half-width (fraction of the width)
    const float wall_height = 0.35f;
    const float depth = 0.12f;       // channel depth below its banks
    const float slope_top = 0.70f, slope_bottom = 0.10f;

    for (int r = 0; r < m.height; ++r) {
        const float v = unit(r, m.height);
        const float wiggle = amplitude * std::sin(2.0f * pi * cycles * v + phase) + 0.05f * meander(v, 0.5f);
        const float river_u = 0.5f + std::clamp(wiggle, -0.18f, 0.18f);
        const float river_c = river_u * (w - 1.0f);
        // Downhill from row 0 to the last row; slightly concave like a river profile.
        const float base = slope_bottom + (slope_top - slope_bottom) * (1.0f - v) * (0.75f + 0.25f * (1.0f - v));
        for (int c = 0; c < m.width; ++c) {
            const float u = unit(c, m.width);
            const float walls = wall_height * std::pow(smoothstep(floor_half, 0.5f, std::abs(u - 0.5f)), 1.5f);
            const float d = (static_cast<float>(c) - river_c) / sigma;  // distance from the channel, in sigmas
            const float channel = depth * std::exp(-0.5f * d * d);
            // Bumps fade out near the channel so its bed stays smooth and downhill.
            const float mask = smoothstep(1.5f, 4.0f, std::abs(d));
            const float bumps = mask * (0.05f * hills(u, v) + 0.012f * detail(u, v)) * (0.4f + walls / wall_height);
            m.samples[static_cast<size_t>(r) * m.width + c] = base + walls + bumps - channel;
        }
    }
    normalise(m.samples);
    return m;
}

Heightmap procedural_strict(int width, int height) {
    // Fitted to strict17.png / strict.png: red falls linearly from ~1.0 at image row 0
    // to ~0.13 at the last row; a strip of ~18% of the width in the middle is 8% lower.
    Heightmap m = flat_heightmap(width, height);
    const float centre = 0.5f * static_cast<float>(m.width - 1);
    const float half_strip = 0.09f * static_cast<float>(m.width);
    for (int r = 0; r < m.height; ++r) {
        const float v = unit(r, m.height);
        const float g = 0.135f + (0.995f - 0.135f) * (1.0f - v);
        for (int c = 0; c < m.width; ++c) {
            const bool strip = m.width > 2 && std::abs(static_cast<float>(c) - centre) <= half_strip;
            m.samples[static_cast<size_t>(r) * m.width + c] = std::clamp(strip ? 0.92f * g : g, 0.0f, 1.0f);
        }
    }
    return m;
}

Heightmap procedural_bowl(int width, int height) {
    // Fitted to bowl.png: value = 0.02 + 0.98 (1 - exp(-2.6 u^2)), u = distance from
    // the centre / half the shorter side (bowl.png: 5/255 at the centre, 240/255 at
    // the middle of an edge, 255 in the corners).
    Heightmap m = flat_heightmap(width, height);
    const float cx = 0.5f * static_cast<float>(m.width - 1), cy = 0.5f * static_cast<float>(m.height - 1);
    const float radius = std::max(std::min(cx, cy), 0.5f);
    for (int r = 0; r < m.height; ++r) {
        for (int c = 0; c < m.width; ++c) {
            const float dx = (static_cast<float>(c) - cx) / radius, dy = (static_cast<float>(r) - cy) / radius;
            const float u2 = dx * dx + dy * dy;
            const float value = 0.02f + 0.98f * (1.0f - std::exp(-2.6f * u2));
            m.samples[static_cast<size_t>(r) * m.width + c] = std::clamp(value, 0.0f, 1.0f);
        }
    }
    return m;
}

namespace {
/// A straight channel along the rows (the hybrid solver's scenes): `bed(t)` at row fraction
/// t in [0, 1] within `half_width(t)` columns of the centre, banks 0.15 higher outside.
template <class Bed, class Width>
Heightmap channel_heightmap(int width, int height, Bed bed, Width half_width) {
    Heightmap m = flat_heightmap(width, height, 1.0f);
    const float cx = 0.5f * static_cast<float>(m.width - 1);
    for (int r = 0; r < m.height; ++r) {
        const float t = m.height > 1 ? static_cast<float>(r) / static_cast<float>(m.height - 1) : 0.0f;
        const float b = bed(t);
        for (int c = 0; c < m.width; ++c) {
            const bool inside = std::abs(static_cast<float>(c) - cx) <= half_width(t);
            m.samples[static_cast<size_t>(r) * m.width + c] = std::clamp(inside ? b : b + 0.15f, 0.0f, 1.0f);
        }
    }
    return m;
}
}  // namespace

Heightmap procedural_waterfall(int width, int height) {
    // Upper channel 0.72 -> 0.62 at the lip (t = 0.7), a cliff to the plunge pool at 0.10
    // (t in [0.4, 0.7)), a sill at 0.16 and the outlet channel down to 0.12 at row 0.
    const float w = 0.5f * static_cast<float>(std::max(width, 2) - 1);
    const auto bed = [](float t) {
        if (t >= 0.7f) return 0.62f + 0.10f * (t - 0.7f) / 0.3f;
        if (t >= 0.4f) return 0.10f;
        return 0.12f + 0.04f * t / 0.4f;
    };
    const auto half = [w](float t) { return (t >= 0.7f ? 0.25f : t >= 0.4f ? 0.45f : 0.25f) * w; };
    return channel_heightmap(width, height, bed, half);
}

Heightmap procedural_weir(int width, int height) {
    // Upstream 0.55 -> 0.50 at the weir, the crest at 0.60 over t in [0.47, 0.53], the bed
    // downstream 0.40 -> 0.37 at row 0.
    const float w = 0.5f * static_cast<float>(std::max(width, 2) - 1);
    const auto bed = [](float t) {
        if (t >= 0.53f) return 0.50f + 0.05f * (t - 0.53f) / 0.47f;
        if (t >= 0.47f) return 0.60f;
        return 0.37f + 0.03f * t / 0.47f;
    };
    return channel_heightmap(width, height, bed, [w](float) { return 0.3f * w; });
}

}  // namespace mr
