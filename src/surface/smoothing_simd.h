// metariver surface: the smoothing's feature-weight pass eight vertices at a time (AVX2
// gathers), the twin of the scalar loop in smoothing.cpp. Both compute the same floats in
// the same order (no FMA, the same clamps and comparisons) wherever the weight can be
// above 0, and the weights agree bit for bit (tests/surface/smoothing_test.cpp,
// Smoothing.SimdWeightsEqualTheScalarTwin).
#pragma once

#include <metariver/core.h>

#include <cstddef>
#include <cstdint>

namespace mr::smoothing_simd {

/// What the weight of a vertex reads: its position and normal, the ground (hidden below
/// it: weight 0) and the sparse field (sampled one lone ball's iso distance inside).
struct WeightPass {
    const float* pos = nullptr;  ///< x, y, z per vertex
    const float* nrm = nullptr;  ///< x, y, z per vertex (read with a field)
    // Ground (SmoothingGround): null vertices, none.
    const float* ground = nullptr;  ///< x, y, z per heightfield sample, row-major
    int columns = 0, rows = 0;
    float spacing = 1.0f;
    // Field (FieldProbe): null directory, every vertex not hidden weighs 1.
    const int32_t* dir = nullptr;
    const float* pool = nullptr;
    Vec3 origin{0.0f};
    float inv = 1.0f;
    Vec3 hi{0.0f};  ///< grid size - 1 per axis
    int nx2 = 0, ny2 = 0, nz2 = 0, bx = 0, by = 0;
    float depth = 0.0f, unit = 1.0f, half = 0.0f, inv_span = 1.0f, min_weight = 0.0f;
};

/// Whether this CPU runs weights() (AVX2; METARIVER_NO_AVX2 set: no).
bool available();

/// Weights of vertices [lo, lo + 8 m), m = (hi - lo) / 8, into w[v]; adds their moving
/// (w > 0) and hidden counts. Returns lo + 8 m (the caller does the rest). The caller
/// checks that every index the pass forms fits an int32 (sizes_fit).
size_t weights(const WeightPass& p, size_t lo, size_t hi, float* w, size_t& moving, size_t& hidden);

/// Whether the arrays of p (n vertices, `slots` field blocks) are small enough for int32
/// gather indices.
bool sizes_fit(const WeightPass& p, size_t n, size_t slots);

}  // namespace mr::smoothing_simd
