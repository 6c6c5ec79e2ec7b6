// The smoothing's feature-weight pass, eight vertices at a time (smoothing_simd.h). Each
// lane computes what SmoothingGround::height, FieldProbe::at and the weight's smoothstep
// compute for one vertex, with the same operations in the same order; the lanes that the
// scalar code sends down a branch (hidden, outside the grid) are masked out at the end,
// and their gathers read index 0. (The scalar probe's shortcut for blocks at or below the
// floor is left out: it changes no weight, see probe().)
#include "smoothing_simd.h"

#include <metariver/sparse_field.h>

#include <climits>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define METARIVER_SMOOTH_AVX2 1
#endif

namespace mr::smoothing_simd {

bool sizes_fit(const WeightPass& p, size_t n, size_t slots) {
    constexpr size_t kMax = size_t(INT_MAX) - 64;
    const size_t ground = size_t(std::max(p.columns, 0)) * size_t(std::max(p.rows, 0));
    const size_t blocks = size_t(std::max(p.bx, 0)) * size_t(std::max(p.by, 0)) *
                          (size_t(std::max(p.nz2, 0)) / size_t(SparseField::kBlock) + 2);
    return n <= kMax / 3 && ground <= kMax / 3 && slots <= kMax / size_t(SparseField::kBlockSamples) && blocks <= kMax;
}

#if METARIVER_SMOOTH_AVX2

bool available() { return avx2_enabled(); }

namespace {

// No "fma" in the target: the compiler must not contract a * b + c, or the lanes would
// differ from the scalar twin in the last bit.
#define MR_SMOOTH_AVX2 __attribute__((target("avx2")))

MR_SMOOTH_AVX2 inline __m256 gather(const float* base, __m256i idx) { return _mm256_i32gather_ps(base, idx, 4); }

/// x, y, z of the eight Vec3 at p (24 floats; Intel's AoS-to-SoA shuffle for 3-vectors).
MR_SMOOTH_AVX2 inline void load8(const float* p, __m256& x, __m256& y, __m256& z) {
    const __m256 m03 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p)), _mm_loadu_ps(p + 12), 1);
    const __m256 m14 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 4)), _mm_loadu_ps(p + 16), 1);
    const __m256 m25 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 8)), _mm_loadu_ps(p + 20), 1);
    const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));
    const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));
    x = _mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0));
    y = _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0));
    z = _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1));
}

MR_SMOOTH_AVX2 inline __m256 lerp(__m256 a, __m256 b, __m256 t) {
    return _mm256_add_ps(a, _mm256_mul_ps(t, _mm256_sub_ps(b, a)));
}

/// SmoothingGround::cell for eight coordinates: the cell index k and the fraction f.
MR_SMOOTH_AVX2 inline void ground_cell(__m256 u, int n, __m256i& k, __m256& f) {
    // !(u >= 0) (NaN too): 0; else min(u, n - 1).
    const __m256 ge0 = _mm256_cmp_ps(u, _mm256_setzero_ps(), _CMP_GE_OQ);
    u = _mm256_and_ps(ge0, _mm256_min_ps(_mm256_set1_ps(float(n - 1)), u));
    k = _mm256_min_epi32(_mm256_cvttps_epi32(u), _mm256_set1_epi32(n - 2));
    f = _mm256_min_ps(_mm256_set1_ps(1.0f), _mm256_sub_ps(u, _mm256_cvtepi32_ps(k)));
}

/// Whether each lane's point lies below the ground (SmoothingGround::height).
MR_SMOOTH_AVX2 inline __m256 below_ground(const WeightPass& p, __m256 x, __m256 y, __m256 z) {
    const __m256 s = _mm256_set1_ps(p.spacing);
    __m256i j, i;
    __m256 u, v;
    ground_cell(_mm256_div_ps(x, s), p.columns, j, u);
    ground_cell(_mm256_div_ps(z, s), p.rows, i, v);
    const __m256i cell = _mm256_add_epi32(_mm256_mullo_epi32(i, _mm256_set1_epi32(p.columns)), j);
    const __m256i b = _mm256_add_epi32(_mm256_mullo_epi32(cell, _mm256_set1_epi32(3)), _mm256_set1_epi32(1));
    const __m256i row = _mm256_set1_epi32(3 * p.columns);
    const __m256 h00 = gather(p.ground, b);
    const __m256 h01 = gather(p.ground, _mm256_add_epi32(b, _mm256_set1_epi32(3)));
    const __m256 h10 = gather(p.ground, _mm256_add_epi32(b, row));
    const __m256 h11 = gather(p.ground, _mm256_add_epi32(_mm256_add_epi32(b, row), _mm256_set1_epi32(3)));
    const __m256 one = _mm256_set1_ps(1.0f);
    const __m256 lower = _mm256_cmp_ps(_mm256_add_ps(u, v), one, _CMP_LE_OQ);
    const __m256 hl = _mm256_add_ps(_mm256_add_ps(h00, _mm256_mul_ps(u, _mm256_sub_ps(h01, h00))),
                                    _mm256_mul_ps(v, _mm256_sub_ps(h10, h00)));
    const __m256 hu = _mm256_add_ps(_mm256_add_ps(h11, _mm256_mul_ps(_mm256_sub_ps(one, u), _mm256_sub_ps(h10, h11))),
                                    _mm256_mul_ps(_mm256_sub_ps(one, v), _mm256_sub_ps(h01, h11)));
    return _mm256_cmp_ps(y, _mm256_blendv_ps(hu, hl, lower), _CMP_LT_OQ);
}

/// FieldProbe::at for eight points (lanes outside `active` read index 0 and return 0).
MR_SMOOTH_AVX2 inline __m256 probe(const WeightPass& p, __m256 px, __m256 py, __m256 pz, __m256 active) {
    const __m256 inv = _mm256_set1_ps(p.inv);
    const __m256 qx = _mm256_mul_ps(_mm256_sub_ps(px, _mm256_set1_ps(p.origin.x)), inv);
    const __m256 qy = _mm256_mul_ps(_mm256_sub_ps(py, _mm256_set1_ps(p.origin.y)), inv);
    const __m256 qz = _mm256_mul_ps(_mm256_sub_ps(pz, _mm256_set1_ps(p.origin.z)), inv);
    const __m256 zero = _mm256_setzero_ps();
    __m256 in = active;
    in = _mm256_and_ps(in, _mm256_cmp_ps(qx, zero, _CMP_GE_OQ));
    in = _mm256_and_ps(in, _mm256_cmp_ps(qy, zero, _CMP_GE_OQ));
    in = _mm256_and_ps(in, _mm256_cmp_ps(qz, zero, _CMP_GE_OQ));
    in = _mm256_and_ps(in, _mm256_cmp_ps(qx, _mm256_set1_ps(p.hi.x), _CMP_LE_OQ));
    in = _mm256_and_ps(in, _mm256_cmp_ps(qy, _mm256_set1_ps(p.hi.y), _CMP_LE_OQ));
    in = _mm256_and_ps(in, _mm256_cmp_ps(qz, _mm256_set1_ps(p.hi.z), _CMP_LE_OQ));
    if (_mm256_testz_ps(in, in)) return zero;
    const __m256i inm = _mm256_castps_si256(in);
    // Lanes not in: cell 0 (their gathers read the first block's first samples).
    const __m256 sx = _mm256_and_ps(in, qx), sy = _mm256_and_ps(in, qy), sz = _mm256_and_ps(in, qz);
    const __m256i i = _mm256_min_epi32(_mm256_cvttps_epi32(sx), _mm256_set1_epi32(p.nx2));
    const __m256i j = _mm256_min_epi32(_mm256_cvttps_epi32(sy), _mm256_set1_epi32(p.ny2));
    const __m256i k = _mm256_min_epi32(_mm256_cvttps_epi32(sz), _mm256_set1_epi32(p.nz2));
    const __m256 tx = _mm256_sub_ps(sx, _mm256_cvtepi32_ps(i));
    const __m256 ty = _mm256_sub_ps(sy, _mm256_cvtepi32_ps(j));
    const __m256 tz = _mm256_sub_ps(sz, _mm256_cvtepi32_ps(k));
    const __m256i seven = _mm256_set1_epi32(7), none = _mm256_set1_epi32(SparseField::kNoBlock);
    const __m256i bx = _mm256_set1_epi32(p.bx), by = _mm256_set1_epi32(p.by);
    // FieldProbe::at returns the floor, not the samples, where no block holding them rises
    // above it; the samples then lie at or below the floor too, and either way the weight
    // is 0 (smoothstep of at most 0, or a hair above it, far under min_weight). So this
    // pass reads the samples of every lane in the grid and does not gather the blocks'
    // maxima: the weight is the same.
    __m256 c[8];
    for (int n = 0; n < 8; ++n) {
        const __m256i x = _mm256_add_epi32(i, _mm256_set1_epi32(n & 1));
        const __m256i y = _mm256_add_epi32(j, _mm256_set1_epi32((n >> 1) & 1));
        const __m256i z = _mm256_add_epi32(k, _mm256_set1_epi32(n >> 2));
        const __m256i blk = _mm256_add_epi32(
            _mm256_srli_epi32(x, 3),
            _mm256_mullo_epi32(bx, _mm256_add_epi32(_mm256_srli_epi32(y, 3), _mm256_mullo_epi32(by, _mm256_srli_epi32(z, 3)))));
        const __m256i slot = _mm256_i32gather_epi32(p.dir, _mm256_and_si256(inm, blk), 4);
        const __m256i use = _mm256_andnot_si256(_mm256_cmpeq_epi32(slot, none), inm);
        const __m256i o = _mm256_add_epi32(
            _mm256_and_si256(x, seven),
            _mm256_slli_epi32(_mm256_add_epi32(_mm256_and_si256(y, seven), _mm256_slli_epi32(_mm256_and_si256(z, seven), 3)), 3));
        const __m256i at = _mm256_and_si256(use, _mm256_add_epi32(_mm256_slli_epi32(slot, 9), o));
        c[n] = _mm256_mask_i32gather_ps(zero, p.pool, at, _mm256_castsi256_ps(use), 4);  // no block: 0
    }
    const __m256 y0 = lerp(lerp(c[0], c[1], tx), lerp(c[2], c[3], tx), ty);
    const __m256 y1 = lerp(lerp(c[4], c[5], tx), lerp(c[6], c[7], tx), ty);
    return _mm256_and_ps(in, lerp(y0, y1, tz));
}

}  // namespace

MR_SMOOTH_AVX2 size_t weights(const WeightPass& p, size_t lo, size_t hi, float* w, size_t& moving, size_t& hidden) {
    const size_t end = lo + (hi - lo) / 8 * 8;
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    const __m256 all = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    size_t mv = 0, hid = 0;
    for (size_t v = lo; v < end; v += 8) {
        __m256 x, y, z;
        load8(p.pos + 3 * v, x, y, z);
        const __m256 under = p.ground ? below_ground(p, x, y, z) : zero;
        __m256 wt = one;
        if (p.dir) {
            const __m256 d = _mm256_set1_ps(p.depth);
            __m256 nx, ny, nz;
            load8(p.nrm + 3 * v, nx, ny, nz);
            const __m256 ax = _mm256_sub_ps(x, _mm256_mul_ps(d, nx));
            const __m256 ay = _mm256_sub_ps(y, _mm256_mul_ps(d, ny));
            const __m256 az = _mm256_sub_ps(z, _mm256_mul_ps(d, nz));
            const __m256 active = _mm256_andnot_ps(under, all);
            const __m256 value = probe(p, ax, ay, az, active);
            // smoothstep01((value / unit - half) * inv_span), 0 below min_weight.
            __m256 s = _mm256_mul_ps(_mm256_sub_ps(_mm256_div_ps(value, _mm256_set1_ps(p.unit)), _mm256_set1_ps(p.half)),
                                     _mm256_set1_ps(p.inv_span));
            s = _mm256_blendv_ps(s, zero, _mm256_cmp_ps(s, zero, _CMP_LT_OQ));  // std::clamp: x < lo ? lo
            s = _mm256_blendv_ps(s, one, _mm256_cmp_ps(one, s, _CMP_LT_OQ));    //             : hi < x ? hi : x
            wt = _mm256_mul_ps(_mm256_mul_ps(s, s), _mm256_sub_ps(_mm256_set1_ps(3.0f), _mm256_mul_ps(_mm256_set1_ps(2.0f), s)));
            wt = _mm256_andnot_ps(_mm256_cmp_ps(wt, _mm256_set1_ps(p.min_weight), _CMP_LT_OQ), wt);
        }
        wt = _mm256_andnot_ps(under, wt);
        _mm256_storeu_ps(w + v, wt);
        mv += unsigned(__builtin_popcount(unsigned(_mm256_movemask_ps(_mm256_cmp_ps(wt, zero, _CMP_GT_OQ)))));
        hid += unsigned(__builtin_popcount(unsigned(_mm256_movemask_ps(under))));
    }
    moving += mv, hidden += hid;
    return end;
}

#else

bool available() { return false; }
size_t weights(const WeightPass&, size_t lo, size_t, float*, size_t&, size_t&) { return lo; }

#endif

}  // namespace mr::smoothing_simd
