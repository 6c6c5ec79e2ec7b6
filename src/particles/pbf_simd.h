// metariver particles, private: the PBF solver's and the foam's per-particle sums over
// their neighbour lists (and the foam's classification over its grid's cell ranges),
// eight entries at a time with AVX2 (pbf_simd.cpp), picked at run time.
//
// The scalar loops in pbf.cpp and foam.cpp are their twins: the same pairs and formulas, but
// eight partial sums per particle (added up in a fixed order) and fused multiply-adds,
// so the results agree to float rounding, not bit for bit (pbf_test.cpp and foam_test.cpp
// compare them). Each particle's sums run in a fixed order, so a step is the same for
// any thread count.
#pragma once

#include <metariver/core.h>

#include <cstdint>

namespace mr::pbf_simd {

/// avx2_enabled() (core.h) and FMA (every function below).
bool available();

/// The kernels of pbf.cpp: poly6 W(r2) = poly6 (h2 - r2)^3 below h2, spiky gradient
/// factor spiky (h - r)^2 / r for 1e-9 < r < h.
struct KernelConsts {
    float h, h2, poly6, spiky;
};

struct DensitySums {
    float rho = 0.0f;     ///< sum of W over the entries within h (i itself included)
    Vec3 grad{0.0f};      ///< sum of grad W / rho0
    float grad2 = 0.0f;   ///< sum of |grad W / rho0|^2
};

/// The density pass keeps each entry's kernel gradient for the correction pass as 16-bit
/// fixed point: component times grad_fixed_scale, |grad W| <= spiky h^2 mapped to 32767.
/// Half the bytes of floats, and the correction pass is bound by reading them (W3 at
/// 48,668: 19.4-20.0 -> 16.8-17.1 ms a step). The error is at most 1.5e-5 of the largest
/// gradient a term; W stays a float: quantised too, it left still water jittering
/// (SoundWater's speed at 10 s 0.05 -> 0.22 m/s) through s_corr = (W / W(dq))^n.
inline float grad_fixed_scale(const KernelConsts& k) { return 32767.0f / (k.spiky * k.h2); }

/// The density pass of particle i (position xi) over its list entries [b, e) of `index`:
/// per entry, for the correction pass, cache_w[e] = W (or -1 beyond h and for i itself)
/// and cache_g[0..2][e] = the kernel gradient's x, y, z (grad factor times x_i - x_j) in
/// fixed point (grad_fixed_scale). `pos` holds `count` positions (every index below count).
DensitySums density(const KernelConsts& k, float inv_rho0, const Vec3& xi, uint32_t i, const uint32_t* index,
                    uint32_t b, uint32_t e, const Vec3* pos, uint32_t count, float* cache_w,
                    int16_t* const cache_g[3]);

/// The correction pass's sum of (li + lambda_j - scorr) grad W over the entries with
/// cache_w >= 0 (not yet divided by rho0), from the density pass's cache (the positions
/// have not moved since): scorr = scorr_scale (cache_w inv_wdq)^scorr_n. The gradient's
/// arrays hold 8 entries past the last list's end (read, multiplied by 0).
Vec3 correction(const KernelConsts& k, float li, const uint32_t* index, uint32_t b, uint32_t e, const float* lambda,
                const float* cache_w, const int16_t* const cache_g[3], float scorr_scale, float inv_wdq, int scorr_n);

/// XSPH's sum of (v_j - v_i) W over i's list entries [b, e) within h (not yet scaled);
/// without an index, over the particles [b, e) (a range of the cell-ordered arrays).
/// `pos` and `vel` hold `count` particles.
Vec3 viscosity(const KernelConsts& k, const Vec3& xi, const Vec3& vi, const uint32_t* index, uint32_t b, uint32_t e,
               const Vec3* pos, const Vec3* vel, uint32_t count);

/// Sorted (cell-ordered) copies of the fluid for the diffuse particles' classification
/// (foam.cpp): x, y, z, then the velocity's components.
struct FoamArrays {
    const float *x, *y, *z, *vx, *vy, *vz;
};

/// The foam's first pass for particle k over its list entries [b, e) (without an index:
/// the particles [b, e)): the sum of x^_kj W~ = (x_k - x_j) / r (1 - r / h) over j != k
/// with 1e-12 < r^2 < h^2. `pos` holds `count` particles in the lists' order.
Vec3 foam_normal_sum(const Vec3* pos, uint32_t count, uint32_t k, const uint32_t* index, uint32_t b, uint32_t e,
                     float h);

/// The foam's second pass for particle k (velocity v, normal n) over its list entries [b,
/// e), as foam_normal_sum: the trapped-air sum |v_kj| (1 - v^_kj . x^_kj) W~ (|v_kj| >
/// 1e-6) and the convex curvature sum (1 - n_k . n_j) W~ (x^_kj . n_k > 0), added to ta
/// and curv. `vel` and `nrm` hold the particles' velocities and first-pass normals.
void foam_potential_sums(const Vec3* pos, const Vec3* vel, const Vec3* nrm, uint32_t count, uint32_t k,
                         const Vec3& v, const Vec3& n, const uint32_t* index, uint32_t b, uint32_t e, float h,
                         float& ta, float& curv);

/// The diffuse particles' classification (foam.cpp) for one at p over fluid candidates
/// [s, e): the number within h (r^2 = (dx^2 + dy^2) + dz^2 < h^2, the scalar loop's test
/// and arithmetic, so the count is the same), and the sums of W~ = 1 - r / h and of W~ v_j
/// over them, added to count, wsum and vsum.
void foam_classify_sums(const FoamArrays& a, const Vec3& p, uint32_t s, uint32_t e, float h, int& count, float& wsum,
                        Vec3& vsum);

}  // namespace mr::pbf_simd
