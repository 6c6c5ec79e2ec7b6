// Eight candidates' offsets from one particle over contiguous x, y, z copies (AVX2), shared
// by the springs' kernel (springs.cpp) and the neighbour lists' build (neighbor_lists.cpp).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include <cstddef>

namespace mr::simd {

/// Candidates k .. k + 7 relative to the particle at (x, y, z): d = x_i - x_j and |d|^2 as
/// the scalar loops compute them, (dx dx + dy dy) + dz dz without fusing (no "fma" in the
/// target), so masks and sums built on it match the scalar twins bit for bit.
struct Offsets8 {
    __m256 dx, dy, dz, d2;
};
[[gnu::target("avx2")]] inline Offsets8 offsets8(__m256 x, __m256 y, __m256 z, const float* cx, const float* cy,
                                                 const float* cz, size_t k) {
    const __m256 dx = _mm256_sub_ps(x, _mm256_loadu_ps(cx + k));
    const __m256 dy = _mm256_sub_ps(y, _mm256_loadu_ps(cy + k));
    const __m256 dz = _mm256_sub_ps(z, _mm256_loadu_ps(cz + k));
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    return {dx, dy, dz, d2};
}

}  // namespace mr::simd

#endif
