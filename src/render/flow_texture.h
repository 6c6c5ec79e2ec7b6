// The tiling detail texture the water's flow detail advects (docs/rendering.md, "Flow
// detail"): generated at start-up, no asset files.
#pragma once

#include <cstdint>
#include <vector>

namespace mr::render {

/// Side of the square flow texture, texels.
inline constexpr int kFlowTextureSide = 256;

/// RGBA8, kFlowTextureSide^2 texels, tiling in both directions (every noise lattice
/// has a period that divides the side): R, G = the slope of a ripple height field along
/// u and v, as 0.5 + slope / 2 (clamped to [-1, 1]); B = a foam-streak mask in [0, 1];
/// A = the height itself. Fractal value noise, deterministic (a fixed integer hash).
std::vector<uint8_t> make_flow_texture();

}  // namespace mr::render
