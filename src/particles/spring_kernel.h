// metariver particles, private: the springs' per-particle sum over gathered candidates
// (springs.cpp), as a portable loop and, picked at run time, an AVX2 one that skips each
// block of eight candidates with none within reach. Both give the same floats bit for bit
// for finite candidates, as both require (tests/particles/springs_test.cpp): the skipped
// lanes' terms are exactly zero, and the AVX2 loop runs the portable loop's operations in
// its order (no fused multiply-adds). (A NaN candidate would make the portable sum NaN;
// the AVX2 one masks it to 0.)
#pragma once

#include <cstdint>

namespace mr::spring_kernel {

/// The most candidates one call may take (springs.cpp gathers them in chunks of this).
constexpr int kMaxCandidates = 512;

/// The sum of the spring accelerations on a particle at (xi, yi, zi) from m candidates
/// (cx, cy, cz): out = sum over the candidates j with 0 < |d| and |d| - r < max_d of
/// half_k (r / |d| - 1) d, d = x_i - x_j. Eight partial sums (lane l takes candidates
/// l, l + 8, ...) added up in lane order. m in [0, kMaxCandidates]; the arrays must hold
/// finite values up to the next multiple of 8 past m (the lanes past m are masked out).
void sum_portable(float xi, float yi, float zi, const float* cx, const float* cy, const float* cz, int m, float r,
                  float max_d, float half_k, float out[3]);

/// The same, eight candidates at a time with AVX2, in two passes: the first lists the
/// blocks of eight with a squared distance below skip_d2(r, max_d) (without a branch),
/// the second takes the square roots and divisions of those blocks only (about half the
/// blocks of the springs river at 100,000: the 27 cells' far corners). A branch per block
/// instead was slower than no skipping at all (mispredicted). Only where available().
void sum_avx2(float xi, float yi, float zi, const float* cx, const float* cy, const float* cz, int m, float r,
              float max_d, float half_k, float out[3]);

/// avx2_enabled() (core.h).
bool available();

/// A squared distance at or beyond which a candidate's term is 0 in float arithmetic:
/// (r + max_d)^2 with a margin of 0.2 %, far above the rounding of |d| - r (a few ulps of
/// r + max_d). Infinite when that overflows (nothing is skipped).
inline float skip_d2(float r, float max_d) {
    const double reach = double(r) + double(max_d);
    const double b = reach * reach * 1.002;
    return b > 3.0e38 ? __builtin_inff() : static_cast<float>(b);
}

}  // namespace mr::spring_kernel
