// The flow detail's texture: tiling fractal value noise, see flow_texture.h.
#include "flow_texture.h"

#include <algorithm>
#include <cmath>

namespace mr::render {

namespace {

/// A lattice value in [0, 1] for integer (x, y) on a torus of `period` cells.
float lattice(int x, int y, int period, uint32_t seed) {
    x = ((x % period) + period) % period;
    y = ((y % period) + period) % period;
    uint32_t h = static_cast<uint32_t>(x) * 374761393u + static_cast<uint32_t>(y) * 668265263u + seed * 2246822519u;
    h = (h ^ (h >> 13)) * 1274126177u;
    h ^= h >> 16;
    return static_cast<float>(h & 0xFFFFFFu) / static_cast<float>(0xFFFFFF);
}

/// Smooth value noise at texel (u, v) with `period` lattice cells across the texture.
float value_noise(float u, float v, int period, uint32_t seed) {
    const float x = u * static_cast<float>(period) / kFlowTextureSide;
    const float y = v * static_cast<float>(period) / kFlowTextureSide;
    const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
    float fx = x - static_cast<float>(ix), fy = y - static_cast<float>(iy);
    fx = fx * fx * (3.0f - 2.0f * fx);
    fy = fy * fy * (3.0f - 2.0f * fy);
    const float a = lattice(ix, iy, period, seed), b = lattice(ix + 1, iy, period, seed);
    const float c = lattice(ix, iy + 1, period, seed), d = lattice(ix + 1, iy + 1, period, seed);
    return (a + (b - a) * fx) + ((c + (d - c) * fx) - (a + (b - a) * fx)) * fy;
}

/// Octaves of value noise with periods base, 2 base, 4 base, ... (all divide the side).
float fractal(float u, float v, int base, int octaves, uint32_t seed) {
    float sum = 0.0f, amp = 0.5f, norm = 0.0f;
    for (int o = 0; o < octaves; ++o) {
        sum += amp * value_noise(u, v, base << o, seed + static_cast<uint32_t>(o));
        norm += amp;
        amp *= 0.5f;
    }
    return sum / norm;
}

uint8_t unorm8(float x) { return static_cast<uint8_t>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f)); }

}  // namespace

std::vector<uint8_t> make_flow_texture() {
    constexpr int n = kFlowTextureSide;
    std::vector<float> height(static_cast<size_t>(n) * n), streak(static_cast<size_t>(n) * n);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const float u = static_cast<float>(x), v = static_cast<float>(y);
            height[static_cast<size_t>(y) * n + x] = fractal(u, v, 4, 4, 11u);
            streak[static_cast<size_t>(y) * n + x] = fractal(u, v, 8, 3, 97u);
        }
    // Slopes by central differences on the torus, in height per texel, scaled so that
    // the steepest ripples reach about 1.
    constexpr float kSlopeScale = 48.0f;
    std::vector<uint8_t> rgba(static_cast<size_t>(n) * n * 4);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            auto h = [&](int xx, int yy) { return height[static_cast<size_t>((yy + n) % n) * n + (xx + n) % n]; };
            const float du = (h(x + 1, y) - h(x - 1, y)) * 0.5f * kSlopeScale;
            const float dv = (h(x, y + 1) - h(x, y - 1)) * 0.5f * kSlopeScale;
            // Streaks: the upper part of a second noise, sharpened into white lines.
            const float s = streak[static_cast<size_t>(y) * n + x];
            const float foam = std::clamp((s - 0.55f) / 0.2f, 0.0f, 1.0f);
            uint8_t* t = rgba.data() + (static_cast<size_t>(y) * n + x) * 4;
            t[0] = unorm8(0.5f + 0.5f * std::clamp(du, -1.0f, 1.0f));
            t[1] = unorm8(0.5f + 0.5f * std::clamp(dv, -1.0f, 1.0f));
            t[2] = unorm8(foam * foam);
            t[3] = unorm8(h(x, y));
        }
    return rgba;
}

}  // namespace mr::render
