// The paper's spring forces (section 2.3.1, eq. 3) as its code computes them:
// for each pair of active particles, v = p_i - p_j; when |v| - r < max_distance,
// a = 0.5 * k * (r * v/|v| - v) pushes i towards rest length r and j by the opposite
// amount, so every pair conserves momentum. The all-pairs loop is O(N^2) on purpose:
// it is the reference the neighbour-grid path is checked against.
#include <metariver/particles.h>

#include "simd_offsets.h"
#include "spring_kernel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define METARIVER_SPRINGS_AVX2 1
#endif

namespace mr {

std::string_view to_string(SpringMode m) {
    switch (m) {
        case SpringMode::Pairs: return "pairs";
        case SpringMode::Grid: return "grid";
    }
    return "?";
}

float spring_reach(const SpringDef& def) { return def.min_distance + def.max_distance; }

void add_spring_forces_pairs(Particles& p, const SpringDef& def) {
    if (def.stiffness == 0.0f) return;
    const size_t n = p.size();
    const float half_k = 0.5f * def.stiffness;
    const float r = def.min_distance;
    for (size_t i = 0; i < n; ++i) {
        if (!p.active[i]) continue;
        const Vec3 pi = p.position[i];
        Vec3 acc_i(0.0f);
        for (size_t j = i + 1; j < n; ++j) {
            if (!p.active[j]) continue;
            const Vec3 v = pi - p.position[j];
            const float len = glm::length(v);
            if (len <= 0.0f || len - r >= def.max_distance) continue;
            const Vec3 a = half_k * (r * (v / len) - v);
            acc_i += a;
            p.force[j] -= a;
        }
        p.force[i] += acc_i;
    }
}

namespace {

/// Candidates gathered per chunk; 3 x 512 floats stay on the stack (no heap at all).
constexpr int kChunk = spring_kernel::kMaxCandidates;

}  // namespace

namespace spring_kernel {

namespace {

/// The eight partial sums of each axis added up in lane order.
void add_lanes(const float ax[8], const float ay[8], const float az[8], float out[3]) {
    float sx = 0.0f, sy = 0.0f, sz = 0.0f;
    for (int l = 0; l < 8; ++l) {
        sx += ax[l];
        sy += ay[l];
        sz += az[l];
    }
    out[0] = sx;
    out[1] = sy;
    out[2] = sz;
}

}  // namespace

void sum_portable(float xi, float yi, float zi, const float* cx, const float* cy, const float* cz, int m, float r,
                  float max_d, float half_k, float out[3]) {
    // Eight independent lanes so the loop vectorises without reassociating the sum; a
    // candidate at distance 0 (the particle itself, or one exactly on top of it) adds
    // nothing, as in the pair loop.
    float ax[8] = {}, ay[8] = {}, az[8] = {};
    for (int k = 0; k < m; k += 8) {
        for (int l = 0; l < 8; ++l) {
            const float dx = xi - cx[k + l], dy = yi - cy[k + l], dz = zi - cz[k + l];
            const float d2 = dx * dx + dy * dy + dz * dz;
            const float len = std::sqrt(d2);
            // Branch-free (computed for every candidate, then masked) so the loop
            // vectorises; max(len, 1e-20) keeps the masked-out value finite (k r <= 5e9).
            const float s_all = half_k * (r / std::max(len, 1e-20f) - 1.0f);
            const float on = static_cast<float>((d2 > 0.0f) & (len - r < max_d) & (k + l < m));
            const float s = s_all * on;
            ax[l] += s * dx;
            ay[l] += s * dy;
            az[l] += s * dz;
        }
    }
    add_lanes(ax, ay, az, out);
}

#if METARIVER_SPRINGS_AVX2

bool available() { return avx2_enabled(); }

// The portable loop's operations in its order: (dx dx + dy dy) + dz dz without fusing,
// max(len, 1e-20) as std::max (both finite here), s = s_all masked. A masked lane adds
// +0 or -0 to its partial sum, which never changes it (a partial sum starts at +0 and
// +0 + -0 = +0), so a skipped block, whose lanes would all be masked, changes nothing.
[[gnu::target("avx2")]] void sum_avx2(float xi, float yi, float zi, const float* cx, const float* cy,
                                      const float* cz, int m, float r, float max_d, float half_k, float out[3]) {
    const __m256 X = _mm256_set1_ps(xi), Y = _mm256_set1_ps(yi), Z = _mm256_set1_ps(zi);
    const __m256 R = _mm256_set1_ps(r), MAXD = _mm256_set1_ps(max_d), HK = _mm256_set1_ps(half_k);
    const __m256 one = _mm256_set1_ps(1.0f), tiny = _mm256_set1_ps(1e-20f), zero = _mm256_setzero_ps();
    const __m256 skip = _mm256_set1_ps(skip_d2(r, max_d));
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    // First the blocks with a candidate within reach, listed without a branch; then the
    // square roots and divisions of those blocks only.
    int near[kMaxCandidates / 8];
    int n_near = 0;
    for (int k = 0; k < m; k += 8) {
        const simd::Offsets8 o = simd::offsets8(X, Y, Z, cx, cy, cz, size_t(k));
        near[n_near] = k;
        n_near += _mm256_movemask_ps(_mm256_cmp_ps(o.d2, skip, _CMP_LT_OQ)) != 0;
    }
    __m256 ax = zero, ay = zero, az = zero;
    for (int q = 0; q < n_near; ++q) {
        const int k = near[q];
        const auto [dx, dy, dz, d2] = simd::offsets8(X, Y, Z, cx, cy, cz, size_t(k));
        const __m256 len = _mm256_sqrt_ps(d2);
        const __m256 s_all = _mm256_mul_ps(HK, _mm256_sub_ps(_mm256_div_ps(R, _mm256_max_ps(len, tiny)), one));
        const __m256 inside = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(m - k), lane));
        const __m256 on = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(d2, zero, _CMP_GT_OQ),
                                                      _mm256_cmp_ps(_mm256_sub_ps(len, R), MAXD, _CMP_LT_OQ)),
                                        inside);
        const __m256 s = _mm256_and_ps(s_all, on);
        ax = _mm256_add_ps(ax, _mm256_mul_ps(s, dx));
        ay = _mm256_add_ps(ay, _mm256_mul_ps(s, dy));
        az = _mm256_add_ps(az, _mm256_mul_ps(s, dz));
    }
    // add_lanes with x, y and z side by side: v_l = (ax_l, ay_l, az_l, 0), added up in
    // lane order from +0, one vector add per lane instead of three scalar ones.
    const __m256 t0 = _mm256_unpacklo_ps(ax, ay), t1 = _mm256_unpackhi_ps(ax, ay);
    const __m256 t2 = _mm256_unpacklo_ps(az, zero), t3 = _mm256_unpackhi_ps(az, zero);
    const __m256 v04 = _mm256_shuffle_ps(t0, t2, 0x44), v15 = _mm256_shuffle_ps(t0, t2, 0xEE);
    const __m256 v26 = _mm256_shuffle_ps(t1, t3, 0x44), v37 = _mm256_shuffle_ps(t1, t3, 0xEE);
    __m128 sum = _mm_add_ps(_mm_setzero_ps(), _mm256_castps256_ps128(v04));
    sum = _mm_add_ps(sum, _mm256_castps256_ps128(v15));
    sum = _mm_add_ps(sum, _mm256_castps256_ps128(v26));
    sum = _mm_add_ps(sum, _mm256_castps256_ps128(v37));
    sum = _mm_add_ps(sum, _mm256_extractf128_ps(v04, 1));
    sum = _mm_add_ps(sum, _mm256_extractf128_ps(v15, 1));
    sum = _mm_add_ps(sum, _mm256_extractf128_ps(v26, 1));
    sum = _mm_add_ps(sum, _mm256_extractf128_ps(v37, 1));
    alignas(16) float s4[4];
    _mm_store_ps(s4, sum);
    out[0] = s4[0];
    out[1] = s4[1];
    out[2] = s4[2];
}

#else

bool available() { return false; }
void sum_avx2(float xi, float yi, float zi, const float* cx, const float* cy, const float* cz, int m, float r,
              float max_d, float half_k, float out[3]) {
    sum_portable(xi, yi, zi, cx, cy, cz, m, r, max_d, half_k, out);
}

#endif

}  // namespace spring_kernel

// Each particle sums its own share of every pair it is in: a(i, j) = -a(j, i), so the
// totals equal the pair loop's, with no writes to other particles (no atomics). Work
// goes cell by cell: the candidates of the 27 cells around a cell are gathered once
// into contiguous arrays and every particle of the cell runs over them.
void add_spring_forces_grid(Particles& p, const NeighborGrid& grid, const SpringDef& def) {
    if (def.stiffness == 0.0f || spring_reach(def) <= 0.0f) return;
    const float half_k = 0.5f * def.stiffness;
    const float r = def.min_distance;
    const float max_d = def.max_distance;
    const auto order = grid.order();
    const auto sx = grid.sorted_x(), sy = grid.sorted_y(), sz = grid.sorted_z();
    const auto spring_sum = spring_kernel::available() ? spring_kernel::sum_avx2 : spring_kernel::sum_portable;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.run_count(), 16), [&](const tbb::blocked_range<size_t>& range) {
        alignas(32) float cx[kChunk + 8], cy[kChunk + 8], cz[kChunk + 8];
        for (size_t run = range.begin(); run != range.end(); ++run) {
            const uint32_t begin = grid.run_start(run), end = grid.run_start(run + 1);
            int fill = 0;
            bool first_chunk = true;
            const auto flush = [&] {
                for (int t = 0; t < 8; ++t) cx[fill + t] = cy[fill + t] = cz[fill + t] = 0.0f;  // finite padding
                for (uint32_t k = begin; k < end; ++k) {
                    const uint32_t i = order[k];
                    const Vec3 pi = p.position[i];
                    float a[3];
                    spring_sum(pi.x, pi.y, pi.z, cx, cy, cz, fill, r, max_d, half_k, a);
                    p.force[i] += Vec3(a[0], a[1], a[2]);
                }
                fill = 0;
                first_chunk = false;
            };
            grid.for_each_neighbor_range(run, [&](uint32_t s, uint32_t e) {
                if (fill + (e - s) <= uint32_t(kChunk)) {  // the common case: the range fits
                    // Blocks of four: the last one reads up to 3 past e (the grid's copies
                    // are padded) and writes as far past the fill (the buffers' slack), which
                    // the next range or the flush's padding overwrites.
                    float *dx = cx + fill, *dy = cy + fill, *dz = cz + fill;
#if defined(__SSE2__)
                    for (uint32_t t = s; t < e; t += 4, dx += 4, dy += 4, dz += 4) {
                        _mm_storeu_ps(dx, _mm_loadu_ps(sx.data() + t));
                        _mm_storeu_ps(dy, _mm_loadu_ps(sy.data() + t));
                        _mm_storeu_ps(dz, _mm_loadu_ps(sz.data() + t));
                    }
#else
                    for (uint32_t t = s; t < e; ++t) *dx++ = sx[t], *dy++ = sy[t], *dz++ = sz[t];
#endif
                    fill += static_cast<int>(e - s);
                    return;
                }
                while (s < e) {
                    if (fill == kChunk) flush();
                    const uint32_t take = std::min<uint32_t>(e - s, static_cast<uint32_t>(kChunk - fill));
                    // Ranges are short (a few cells): a plain loop beats memcpy calls.
                    for (uint32_t t = 0; t < take; ++t) {
                        cx[fill + int(t)] = sx[s + t];
                        cy[fill + int(t)] = sy[s + t];
                        cz[fill + int(t)] = sz[s + t];
                    }
                    fill += static_cast<int>(take);
                    s += take;
                }
            });
            if (fill > 0 || first_chunk) flush();
        }
    });
}

}  // namespace mr
