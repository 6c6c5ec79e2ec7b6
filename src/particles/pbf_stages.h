// The PBF step's shared pieces (pbf.cpp, pbf_passes.cpp): the SPH kernels, the loop over
// binned particles' candidates, and the constants one step's stages read.
#pragma once

#include <metariver/pbf_solver.h>

#include "grid_runs.h"
#include "parallel_blocks.h"
#include "pbf_simd.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace mr {

inline constexpr float kPbfPi = 3.14159265358979f;

/// poly6 for densities, spiky's gradient for the corrections (Mueller et al. 2003).
struct PbfKernels {
    float h, h2, poly6, spiky;
    explicit PbfKernels(float radius)
        : h(radius),
          h2(radius * radius),
          poly6(315.0f / (64.0f * kPbfPi * std::pow(radius, 9.0f))),
          spiky(-45.0f / (kPbfPi * std::pow(radius, 6.0f))) {}
    float W(float r2) const {
        if (r2 >= h2) return 0.0f;
        const float d = h2 - r2;
        return poly6 * d * d * d;
    }
    /// grad W_spiky at d = x_i - x_j (w.r.t. x_i) is grad_factor(|d|) * d.
    float grad_factor(float r) const {
        if (r >= h || r <= 1e-9f) return 0.0f;
        const float a = h - r;
        return spiky * a * a / r;
    }
    Vec3 grad(const Vec3& d, float r) const { return grad_factor(r) * d; }
};

/// One step's constants: the kernels, the lattice's step constants, and what is on.
struct PbfSolver::Stage {
    float dt;
    PbfKernels k;
    PbfStepConstants c;
    pbf_simd::KernelConsts kc;
    bool terrain;  ///< the terrain collides (CollisionMode other than None)
    bool wall;     ///< wall density (PbfDef::wall_density > 0, with a terrain)
    bool bodies;   ///< rigid bodies are coupled (pbf_bodies.cpp)
    float body_mass;  ///< kg of water a particle stands for (the bodies' reactions)
    bool simd;     ///< the list passes eight entries at a time (pbf_simd.h) where the CPU has AVX2
};

/// Calls f(i, each) for every binned particle i, in parallel; each(g) calls g(j, e) for
/// i's candidates j: its neighbour list (`lists` set; e = the list entry) or the 27
/// cells around its cell run (e = 0). After the caller's own distance test both give
/// the same j in the same order. Blocks of 64 particles: a few hundred (the hybrid's
/// falling water) still spread over the threads, with room to balance dense and sparse ones.
template <class F>
void for_each_binned(const NeighborGrid& grid, const NeighborLists* lists, F&& f) {
    if (lists) {
        parallel_pass(tbb::blocked_range<size_t>(0, lists->size(), 64), lists->size(),
                          [&](const tbb::blocked_range<size_t>& r) {
                              const uint32_t* const index = lists->index();
                              for (uint32_t i = uint32_t(r.begin()); i != uint32_t(r.end()); ++i) {
                                  const uint32_t b = lists->first(i), e = lists->first(i + 1);
                                  f(i, [&](auto&& g) {
                                      for (uint32_t q = b; q < e; ++q) g(index[q], q);
                                  });
                              }
                          });
        return;
    }
    for_each_run(grid, [&](uint32_t i, const Ranges& rg) {
        f(i, [&](auto&& g) {
            for (int q = 0; q < rg.n; ++q)
                for (uint32_t j = rg.s[q]; j < rg.e[q]; ++j) g(j, 0u);
        });
    });
}

/// Every slot i in [0, n), in parallel blocks of `grain`; one block (the hybrid's few
/// hundred particles) runs here, without a task: a parallel_for of one block still costs a
/// task and a wait.
template <class F>
void for_each_slot(size_t n, size_t grain, F&& f) {
    if (n <= grain) {
        for (size_t i = 0; i < n; ++i) f(i);
        return;
    }
    parallel_pass(tbb::blocked_range<size_t>(0, n, grain), n, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
}

}  // namespace mr
