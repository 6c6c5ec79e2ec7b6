// The PBF step on the GPU: OpenGL 4.5 compute shaders (src/gpu/gpu_pbf.cpp), the
// CPU solver's step (PbfSolver::step, pbf.cpp) without the terrain, for blocks of fluid
// in free space: W3 of ../shared/peers/pbf_anchor and the brief's "millions on a GPU".
// Each step: predict, bin by a counting sort into a dense grid of kernel-radius cells
// (every array reordered by cell, each cell's particles kept in their previous order, so
// the step is deterministic), `iterations` density / correction passes over the 27 cells
// (as the CPU's 27-cell twin), velocities, XSPH, slow-water damping and sleeping. The
// CPU solver is its twin (tests/gpu/gpu_pbf_test.cpp); it runs on llvmpipe in CI and
// is timed on a real GPU when one is lent (`metariver bench --scenario w3 --gpu`).
#pragma once

#include <metariver/core.h>
#include <metariver/particles.h>

#include <memory>
#include <span>
#include <string>
#include <vector>

namespace mr::gpu {

struct GpuPbfDef {
    /// The CPU solver's parameters. Not on the GPU (create() refuses them, naming the
    /// field): vorticity, wall_density, contact_band (they need the terrain or a second
    /// gather pass that this path does not have yet).
    PbfDef pbf;
    float gravity = 9.82f;  ///< m/s^2 along -y, [0, 1000]
    /// The neighbour grid's box, metres: cells of kernel_radius, at most kGpuPbfMaxCells.
    /// A particle outside it is binned in the nearest border cell: the same neighbours,
    /// found more slowly.
    Vec3 domain_min{0.0f}, domain_max{0.0f};
};

inline constexpr size_t kGpuPbfMaxCells = size_t{1} << 26;       // 64 M cells: 512 MB of cell arrays
inline constexpr size_t kGpuPbfMaxParticles = size_t{1} << 25;   // 33 M particles

struct GpuPbfCounters {
    float density_error_max = 0.0f;  ///< max(C, 0) of the last iteration, over the last step
    float max_speed = 0.0f;          ///< m/s, after the last step
    uint32_t asleep = 0;             ///< particles asleep after the last step
};

/// Needs a current OpenGL 4.5 core context (gl::HeadlessContext or a window's) for its whole
/// life; every call enqueues work and returns, except the read-backs.
class GpuPbf {
public:
    /// Fails (one line naming the field and its range) on a parameter this path cannot
    /// run, a domain of too many cells, or a driver without compute shaders.
    static Result<std::unique_ptr<GpuPbf>> create(const GpuPbfDef& def, std::span<const Vec3> positions);
    ~GpuPbf();
    GpuPbf(const GpuPbf&) = delete;
    GpuPbf& operator=(const GpuPbf&) = delete;

    /// One step of dt seconds (0, 1].
    void step(float dt);
    /// Waits for the queued steps; the GPU time of the last step, ms (a timer query).
    double last_step_gpu_ms();
    /// Read-backs, in the GPU's current (cell-sorted) order.
    std::vector<Vec3> positions() const;
    std::vector<Vec3> velocities() const;
    GpuPbfCounters counters() const;
    size_t size() const;
    /// GL_RENDERER and GL_VERSION of the context, for reports.
    std::string device() const;

private:
    struct Impl;
    explicit GpuPbf(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace mr::gpu
