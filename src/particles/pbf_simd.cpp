// AVX2 sums of the PBF solver's density and correction passes (pbf_simd.h): eight list
// entries at a time, the neighbours' positions gathered from the solver's array.
#include "pbf_simd.h"

#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define METARIVER_PBF_AVX2 1
#endif

namespace mr::pbf_simd {

#if METARIVER_PBF_AVX2

bool available() {
    static const bool yes = avx2_enabled() && __builtin_cpu_supports("fma");
    return yes;
}

namespace {

#define MR_AVX2 __attribute__((target("avx2,fma")))

/// Lanes [0, n) set (n in [0, 8]).
MR_AVX2 inline __m256i lanes_below(uint32_t n) {
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(int(n)), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}

/// The sum of the eight lanes, in a fixed order.
MR_AVX2 inline float sum8(__m256 v) {
    const __m128 s = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
    const __m128 t = _mm_add_ps(s, _mm_movehl_ps(s, s));
    return _mm_cvtss_f32(_mm_add_ss(t, _mm_shuffle_ps(t, t, 1)));
}

/// x, y, z of the eight Vec3 at base + 3 j (j: the lanes of `jv`, each < count), as if
/// gathered: one 16-byte load per lane (its x, y, z and the next float) and a 4 x 4
/// transpose per half. Three eight-wide gathers cost about 3.5 times as much on AMD Zen 4
/// (2.1 M entries: 1.7 -> 0.47 ms; not measured on Intel). A lane at the array's last
/// element would read one float past its end, so a batch holding it gathers instead.
MR_AVX2 inline void load_xyz(const float* base, __m256i jv, uint32_t count, __m256& x, __m256& y, __m256& z) {
    const __m256i last = _mm256_set1_epi32(int(count) - 1);
    if (!_mm256_testz_si256(_mm256_cmpeq_epi32(jv, last), _mm256_cmpeq_epi32(jv, last))) {
        const __m256i j3 = _mm256_add_epi32(jv, _mm256_add_epi32(jv, jv));
        x = _mm256_i32gather_ps(base, j3, 4);
        y = _mm256_i32gather_ps(base + 1, j3, 4);
        z = _mm256_i32gather_ps(base + 2, j3, 4);
        return;
    }
    alignas(32) uint32_t j[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(j), jv);
    const __m256 t0 = _mm256_loadu2_m128(base + 3 * size_t(j[4]), base + 3 * size_t(j[0]));
    const __m256 t1 = _mm256_loadu2_m128(base + 3 * size_t(j[5]), base + 3 * size_t(j[1]));
    const __m256 t2 = _mm256_loadu2_m128(base + 3 * size_t(j[6]), base + 3 * size_t(j[2]));
    const __m256 t3 = _mm256_loadu2_m128(base + 3 * size_t(j[7]), base + 3 * size_t(j[3]));
    const __m256 u0 = _mm256_unpacklo_ps(t0, t1);  // x0 x1 y0 y1 | x4 x5 y4 y5
    const __m256 u1 = _mm256_unpackhi_ps(t0, t1);  // z0 z1 .. .. | z4 z5 .. ..
    const __m256 u2 = _mm256_unpacklo_ps(t2, t3);  // x2 x3 y2 y3 | x6 x7 y6 y7
    const __m256 u3 = _mm256_unpackhi_ps(t2, t3);  // z2 z3 .. .. | z6 z7 .. ..
    x = _mm256_shuffle_ps(u0, u2, _MM_SHUFFLE(1, 0, 1, 0));
    y = _mm256_shuffle_ps(u0, u2, _MM_SHUFFLE(3, 2, 3, 2));
    z = _mm256_shuffle_ps(u1, u3, _MM_SHUFFLE(1, 0, 1, 0));
}

/// Eight list entries from q (the lanes beyond `valid` read index 0 and are masked by
/// the caller): their indices (index[q + lane], or q + lane without an index: a range of
/// the cell-ordered arrays) and the neighbours' x, y, z from `pos` (count Vec3).
struct Gathered {
    __m256i j;
    __m256 x, y, z;
};
MR_AVX2 inline Gathered gather(const uint32_t* index, uint32_t q, __m256i valid, const float* pos, uint32_t count) {
    Gathered g;
    g.j = index ? _mm256_maskload_epi32(reinterpret_cast<const int*>(index + q), valid)
                : _mm256_and_si256(valid, _mm256_add_epi32(_mm256_set1_epi32(int(q)),
                                                           _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)));
    load_xyz(pos, g.j, count, g.x, g.y, g.z);
    return g;
}

/// Eight values as 16-bit integers (rounded to nearest; saturating).
MR_AVX2 inline __m128i to_fixed(__m256 v) {
    const __m256i i = _mm256_cvtps_epi32(v);
    return _mm_packs_epi32(_mm256_castsi256_si128(i), _mm256_extracti128_si256(i, 1));
}
/// Eight 16-bit integers from p (all eight readable) as floats.
MR_AVX2 inline __m256 load_fixed(const int16_t* p) {
    return _mm256_cvtepi32_ps(_mm256_cvtepi16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))));
}

}  // namespace

MR_AVX2 DensitySums density(const KernelConsts& k, float inv_rho0, const Vec3& xi, uint32_t i, const uint32_t* index,
                            uint32_t b, uint32_t e, const Vec3* pos, uint32_t count, float* cache_w,
                            int16_t* const cache_g[3]) {
    const float* const p = &pos[0].x;
    const __m256 px = _mm256_set1_ps(xi.x), py = _mm256_set1_ps(xi.y), pz = _mm256_set1_ps(xi.z);
    const __m256 h = _mm256_set1_ps(k.h), h2 = _mm256_set1_ps(k.h2), poly6 = _mm256_set1_ps(k.poly6);
    const __m256 spiky = _mm256_set1_ps(k.spiky), tiny = _mm256_set1_ps(1e-9f), inv = _mm256_set1_ps(inv_rho0);
    const __m256 minus1 = _mm256_set1_ps(-1.0f);
    const __m256i self = _mm256_set1_epi32(int(i));
    const __m256 g_fixed = _mm256_set1_ps(grad_fixed_scale(k));
    __m256 rho = _mm256_setzero_ps(), gx = rho, gy = rho, gz = rho, g2 = rho;
    for (uint32_t q = b; q < e; q += 8) {
        const __m256i valid = lanes_below(e - q);
        const Gathered n = gather(index, q, valid, p, count);
        const __m256 dx = _mm256_sub_ps(px, n.x), dy = _mm256_sub_ps(py, n.y), dz = _mm256_sub_ps(pz, n.z);
        const __m256 r2 = _mm256_fmadd_ps(dz, dz, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dx, dx)));
        const __m256 in = _mm256_and_ps(_mm256_cmp_ps(r2, h2, _CMP_LT_OQ), _mm256_castsi256_ps(valid));
        const __m256 d = _mm256_sub_ps(h2, r2);
        const __m256 w = _mm256_and_ps(in, _mm256_mul_ps(_mm256_mul_ps(poly6, d), _mm256_mul_ps(d, d)));
        const __m256 r = _mm256_sqrt_ps(r2);
        const __m256 a = _mm256_sub_ps(h, r);
        const __m256 grad_ok = _mm256_and_ps(in, _mm256_and_ps(_mm256_cmp_ps(r, tiny, _CMP_GT_OQ),
                                                                _mm256_cmp_ps(r, h, _CMP_LT_OQ)));
        const __m256 g = _mm256_and_ps(grad_ok, _mm256_div_ps(_mm256_mul_ps(spiky, _mm256_mul_ps(a, a)), r));
        // W for the correction: -1 beyond h and for i itself.
        const __m256 not_self = _mm256_castsi256_ps(
            _mm256_xor_si256(_mm256_cmpeq_epi32(n.j, self), _mm256_set1_epi32(-1)));
        const __m256 gdx = _mm256_mul_ps(g, dx), gdy = _mm256_mul_ps(g, dy), gdz = _mm256_mul_ps(g, dz);
        _mm256_maskstore_ps(cache_w + q, valid, _mm256_blendv_ps(minus1, w, _mm256_and_ps(in, not_self)));
        const __m128i fx = to_fixed(_mm256_mul_ps(gdx, g_fixed));
        const __m128i fy = to_fixed(_mm256_mul_ps(gdy, g_fixed));
        const __m128i fz = to_fixed(_mm256_mul_ps(gdz, g_fixed));
        if (e - q >= 8) {
            _mm_storeu_si128(reinterpret_cast<__m128i*>(cache_g[0] + q), fx);
            _mm_storeu_si128(reinterpret_cast<__m128i*>(cache_g[1] + q), fy);
            _mm_storeu_si128(reinterpret_cast<__m128i*>(cache_g[2] + q), fz);
        } else {  // past e lies the next particle's list, another thread's
            alignas(16) int16_t t[3][8];
            _mm_store_si128(reinterpret_cast<__m128i*>(t[0]), fx);
            _mm_store_si128(reinterpret_cast<__m128i*>(t[1]), fy);
            _mm_store_si128(reinterpret_cast<__m128i*>(t[2]), fz);
            for (int a = 0; a < 3; ++a) std::memcpy(cache_g[a] + q, t[a], (e - q) * sizeof(int16_t));
        }
        rho = _mm256_add_ps(rho, w);
        const __m256 grx = _mm256_mul_ps(gdx, inv), gry = _mm256_mul_ps(gdy, inv), grz = _mm256_mul_ps(gdz, inv);
        gx = _mm256_add_ps(gx, grx);
        gy = _mm256_add_ps(gy, gry);
        gz = _mm256_add_ps(gz, grz);
        g2 = _mm256_fmadd_ps(grz, grz, _mm256_fmadd_ps(gry, gry, _mm256_fmadd_ps(grx, grx, g2)));
    }
    DensitySums s;
    s.rho = sum8(rho);
    s.grad = Vec3(sum8(gx), sum8(gy), sum8(gz));
    s.grad2 = sum8(g2);
    return s;
}

MR_AVX2 Vec3 correction(const KernelConsts& k, float li, const uint32_t* index, uint32_t b, uint32_t e,
                        const float* lambda, const float* cache_w, const int16_t* const cache_g[3], float scorr_scale,
                        float inv_wdq, int scorr_n) {
    const __m256 l = _mm256_set1_ps(li), sk = _mm256_set1_ps(scorr_scale), iw = _mm256_set1_ps(inv_wdq);
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
    __m256 sx = zero, sy = zero, sz = zero;
    for (uint32_t q = b; q < e; q += 8) {
        const __m256i valid = lanes_below(e - q);
        const __m256 wc = _mm256_maskload_ps(cache_w + q, valid);
        const __m256 use = _mm256_and_ps(_mm256_cmp_ps(wc, zero, _CMP_GE_OQ), _mm256_castsi256_ps(valid));
        const __m256i j = _mm256_maskload_epi32(reinterpret_cast<const int*>(index + q), valid);
        // lambda_j by eight plain loads (the lanes not used read a valid index and are
        // masked out of c below): a one-float gather costs more on AMD Zen 4.
        alignas(32) uint32_t jj[8];
        _mm256_store_si256(reinterpret_cast<__m256i*>(jj), j);
        const __m256 lj = _mm256_setr_ps(lambda[jj[0]], lambda[jj[1]], lambda[jj[2]], lambda[jj[3]], lambda[jj[4]],
                                         lambda[jj[5]], lambda[jj[6]], lambda[jj[7]]);
        const __m256 x = _mm256_mul_ps(wc, iw);
        __m256 sc = one;
        for (int m = 0; m < scorr_n; ++m) sc = _mm256_mul_ps(sc, x);
        const __m256 c = _mm256_and_ps(use, _mm256_sub_ps(_mm256_add_ps(l, lj), _mm256_mul_ps(sk, sc)));
        // c is 0 in the lanes not used: the integers read there add nothing.
        sx = _mm256_fmadd_ps(c, load_fixed(cache_g[0] + q), sx);
        sy = _mm256_fmadd_ps(c, load_fixed(cache_g[1] + q), sy);
        sz = _mm256_fmadd_ps(c, load_fixed(cache_g[2] + q), sz);
    }
    return Vec3(sum8(sx), sum8(sy), sum8(sz)) / grad_fixed_scale(k);
}

MR_AVX2 Vec3 viscosity(const KernelConsts& k, const Vec3& xi, const Vec3& vi, const uint32_t* index, uint32_t b,
                       uint32_t e, const Vec3* pos, const Vec3* vel, uint32_t count) {
    const __m256 px = _mm256_set1_ps(xi.x), py = _mm256_set1_ps(xi.y), pz = _mm256_set1_ps(xi.z);
    const __m256 ux = _mm256_set1_ps(vi.x), uy = _mm256_set1_ps(vi.y), uz = _mm256_set1_ps(vi.z);
    const __m256 h2 = _mm256_set1_ps(k.h2), poly6 = _mm256_set1_ps(k.poly6);
    __m256 sx = _mm256_setzero_ps(), sy = sx, sz = sx;
    for (uint32_t q = b; q < e; q += 8) {
        const __m256i valid = lanes_below(e - q);
        const Gathered n = gather(index, q, valid, &pos[0].x, count);
        const __m256 dx = _mm256_sub_ps(px, n.x), dy = _mm256_sub_ps(py, n.y), dz = _mm256_sub_ps(pz, n.z);
        const __m256 r2 = _mm256_fmadd_ps(dz, dz, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dx, dx)));
        const __m256 in = _mm256_and_ps(_mm256_cmp_ps(r2, h2, _CMP_LT_OQ), _mm256_castsi256_ps(valid));
        const __m256 d = _mm256_sub_ps(h2, r2);
        const __m256 w = _mm256_and_ps(in, _mm256_mul_ps(_mm256_mul_ps(poly6, d), _mm256_mul_ps(d, d)));
        __m256 vx, vy, vz;
        load_xyz(&vel[0].x, n.j, count, vx, vy, vz);
        sx = _mm256_fmadd_ps(_mm256_sub_ps(vx, ux), w, sx);
        sy = _mm256_fmadd_ps(_mm256_sub_ps(vy, uy), w, sy);
        sz = _mm256_fmadd_ps(_mm256_sub_ps(vz, uz), w, sz);
    }
    return Vec3(sum8(sx), sum8(sy), sum8(sz));
}

namespace {

/// Per lane over eight list entries of particle k (neighbour j at x, y, z): the offset
/// x_k - x_j, r, W~ = 1 - r / h and the mask of 1e-12 < r^2 < h^2, j != k, in `valid`.
struct FoamPair {
    __m256 dx, dy, dz, r, w, ok;
};
MR_AVX2 inline FoamPair foam_pair(const Gathered& n, __m256 px, __m256 py, __m256 pz, uint32_t k, __m256i valid,
                                  __m256 h2, __m256 inv_h) {
    FoamPair q;
    const __m256i not_k = _mm256_xor_si256(_mm256_cmpeq_epi32(n.j, _mm256_set1_epi32(int(k))), _mm256_set1_epi32(-1));
    q.dx = _mm256_sub_ps(px, n.x);
    q.dy = _mm256_sub_ps(py, n.y);
    q.dz = _mm256_sub_ps(pz, n.z);
    const __m256 r2 = _mm256_fmadd_ps(q.dz, q.dz, _mm256_fmadd_ps(q.dy, q.dy, _mm256_mul_ps(q.dx, q.dx)));
    q.ok = _mm256_and_ps(_mm256_castsi256_ps(_mm256_and_si256(valid, not_k)),
                         _mm256_and_ps(_mm256_cmp_ps(r2, h2, _CMP_LT_OQ),
                                       _mm256_cmp_ps(r2, _mm256_set1_ps(1e-12f), _CMP_GT_OQ)));
    q.r = _mm256_sqrt_ps(r2);
    q.w = _mm256_fnmadd_ps(q.r, inv_h, _mm256_set1_ps(1.0f));
    return q;
}

}  // namespace

MR_AVX2 Vec3 foam_normal_sum(const Vec3* pos, uint32_t count, uint32_t k, const uint32_t* index, uint32_t b, uint32_t e,
                             float h) {
    const float* const p = &pos[0].x;
    const __m256 px = _mm256_set1_ps(pos[k].x), py = _mm256_set1_ps(pos[k].y), pz = _mm256_set1_ps(pos[k].z);
    const __m256 h2 = _mm256_set1_ps(h * h), inv_h = _mm256_set1_ps(1.0f / h);
    __m256 sx = _mm256_setzero_ps(), sy = sx, sz = sx;
    for (uint32_t q0 = b; q0 < e; q0 += 8) {
        const __m256i valid = lanes_below(e - q0);
        const FoamPair q = foam_pair(gather(index, q0, valid, p, count), px, py, pz, k, valid, h2, inv_h);
        const __m256 f = _mm256_and_ps(q.ok, _mm256_div_ps(q.w, q.r));  // W~ / r
        sx = _mm256_fmadd_ps(q.dx, f, sx);
        sy = _mm256_fmadd_ps(q.dy, f, sy);
        sz = _mm256_fmadd_ps(q.dz, f, sz);
    }
    return Vec3(sum8(sx), sum8(sy), sum8(sz));
}

MR_AVX2 void foam_potential_sums(const Vec3* pos, const Vec3* vel, const Vec3* nrm, uint32_t count, uint32_t k,
                                 const Vec3& v, const Vec3& n, const uint32_t* index, uint32_t b, uint32_t e, float h,
                                 float& ta, float& curv) {
    const float* const p = &pos[0].x;
    const __m256 px = _mm256_set1_ps(pos[k].x), py = _mm256_set1_ps(pos[k].y), pz = _mm256_set1_ps(pos[k].z);
    const __m256 ux = _mm256_set1_ps(v.x), uy = _mm256_set1_ps(v.y), uz = _mm256_set1_ps(v.z);
    const __m256 nx = _mm256_set1_ps(n.x), ny = _mm256_set1_ps(n.y), nz = _mm256_set1_ps(n.z);
    const __m256 h2 = _mm256_set1_ps(h * h), inv_h = _mm256_set1_ps(1.0f / h), zero = _mm256_setzero_ps();
    const __m256 one = _mm256_set1_ps(1.0f), tiny = _mm256_set1_ps(1e-6f);
    __m256 t = zero, c = zero;
    for (uint32_t q0 = b; q0 < e; q0 += 8) {
        const __m256i valid = lanes_below(e - q0);
        const Gathered g = gather(index, q0, valid, p, count);
        const FoamPair q = foam_pair(g, px, py, pz, k, valid, h2, inv_h);
        if (_mm256_testz_ps(q.ok, q.ok)) continue;
        const __m256 inv_r = _mm256_div_ps(one, q.r);
        const __m256 xx = _mm256_mul_ps(q.dx, inv_r), xy = _mm256_mul_ps(q.dy, inv_r), xz = _mm256_mul_ps(q.dz, inv_r);
        // Trapped air: |v_kj| - v_kj . x^_kj = |v_kj| (1 - v^_kj . x^_kj).
        __m256 jx, jy, jz;
        load_xyz(&vel[0].x, g.j, count, jx, jy, jz);
        const __m256 vx = _mm256_sub_ps(ux, jx), vy = _mm256_sub_ps(uy, jy), vz = _mm256_sub_ps(uz, jz);
        const __m256 vl = _mm256_sqrt_ps(_mm256_fmadd_ps(vz, vz, _mm256_fmadd_ps(vy, vy, _mm256_mul_ps(vx, vx))));
        const __m256 along = _mm256_fmadd_ps(vz, xz, _mm256_fmadd_ps(vy, xy, _mm256_mul_ps(vx, xx)));
        const __m256 ta_ok = _mm256_and_ps(q.ok, _mm256_cmp_ps(vl, tiny, _CMP_GT_OQ));
        t = _mm256_add_ps(t, _mm256_and_ps(ta_ok, _mm256_mul_ps(_mm256_sub_ps(vl, along), q.w)));
        // Convex curvature: the neighbour lies behind k along k's normal.
        const __m256 behind = _mm256_fmadd_ps(xz, nz, _mm256_fmadd_ps(xy, ny, _mm256_mul_ps(xx, nx)));
        const __m256 cv_ok = _mm256_and_ps(q.ok, _mm256_cmp_ps(behind, zero, _CMP_GT_OQ));
        load_xyz(&nrm[0].x, g.j, count, jx, jy, jz);
        const __m256 nn = _mm256_fmadd_ps(nz, jz, _mm256_fmadd_ps(ny, jy, _mm256_mul_ps(nx, jx)));
        c = _mm256_add_ps(c, _mm256_and_ps(cv_ok, _mm256_mul_ps(_mm256_sub_ps(one, nn), q.w)));
    }
    ta += sum8(t);
    curv += sum8(c);
}

MR_AVX2 void foam_classify_sums(const FoamArrays& a, const Vec3& p, uint32_t s, uint32_t e, float h, int& count,
                                float& wsum, Vec3& vsum) {
    const __m256 px = _mm256_set1_ps(p.x), py = _mm256_set1_ps(p.y), pz = _mm256_set1_ps(p.z);
    const __m256 h2 = _mm256_set1_ps(h * h), hv = _mm256_set1_ps(h), one = _mm256_set1_ps(1.0f);
    __m256 ws = _mm256_setzero_ps(), vx = ws, vy = ws, vz = ws;
    int c = 0;
    for (uint32_t j0 = s; j0 < e; j0 += 8) {
        const __m256i valid = lanes_below(e - j0);
        const __m256 dx = _mm256_sub_ps(px, _mm256_maskload_ps(a.x + j0, valid));
        const __m256 dy = _mm256_sub_ps(py, _mm256_maskload_ps(a.y + j0, valid));
        const __m256 dz = _mm256_sub_ps(pz, _mm256_maskload_ps(a.z + j0, valid));
        // No fused multiply-add: the scalar loop's r^2 bit for bit, so the same count.
        const __m256 r2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                        _mm256_mul_ps(dz, dz));
        const __m256 in = _mm256_and_ps(_mm256_cmp_ps(r2, h2, _CMP_LT_OQ), _mm256_castsi256_ps(valid));
        const int m = _mm256_movemask_ps(in);
        if (m == 0) continue;
        c += __builtin_popcount(unsigned(m));
        const __m256 w = _mm256_and_ps(in, _mm256_sub_ps(one, _mm256_div_ps(_mm256_sqrt_ps(r2), hv)));
        ws = _mm256_add_ps(ws, w);
        vx = _mm256_fmadd_ps(w, _mm256_maskload_ps(a.vx + j0, valid), vx);
        vy = _mm256_fmadd_ps(w, _mm256_maskload_ps(a.vy + j0, valid), vy);
        vz = _mm256_fmadd_ps(w, _mm256_maskload_ps(a.vz + j0, valid), vz);
    }
    count += c;
    wsum += sum8(ws);
    vsum += Vec3(sum8(vx), sum8(vy), sum8(vz));
}

#else

bool available() { return false; }
DensitySums density(const KernelConsts&, float, const Vec3&, uint32_t, const uint32_t*, uint32_t, uint32_t, const Vec3*,
                    uint32_t, float*, int16_t* const*) {
    return {};
}
Vec3 correction(const KernelConsts&, float, const uint32_t*, uint32_t, uint32_t, const float*, const float*,
                const int16_t* const*, float, float, int) {
    return Vec3(0.0f);
}
Vec3 viscosity(const KernelConsts&, const Vec3&, const Vec3&, const uint32_t*, uint32_t, uint32_t, const Vec3*,
               const Vec3*, uint32_t) {
    return Vec3(0.0f);
}
Vec3 foam_normal_sum(const Vec3*, uint32_t, uint32_t, const uint32_t*, uint32_t, uint32_t, float) { return Vec3(0.0f); }
void foam_potential_sums(const Vec3*, const Vec3*, const Vec3*, uint32_t, uint32_t, const Vec3&, const Vec3&,
                         const uint32_t*, uint32_t, uint32_t, float, float&, float&) {}
void foam_classify_sums(const FoamArrays&, const Vec3&, uint32_t, uint32_t, float, int&, float&, Vec3&) {}

#endif

}  // namespace mr::pbf_simd
