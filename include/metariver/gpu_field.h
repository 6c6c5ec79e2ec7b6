// The compact-kernel field on the GPU: OpenGL 4.5 compute shaders (src/gpu/gpu_field.cpp)
// that fill a dense sample grid with the sum of every ball's kernel (poly6 or W1, as
// SparseField). The balls are binned by the GPU PBF step's counting sort into cells of
// the kernel radius (or larger, to keep the cell count bounded) over the grid's box; each
// sample sums the balls of the 27 cells around it. SparseField (sparse_field.h) is its
// twin (tests/gpu/gpu_field_test.cpp): the same samples to float rounding.
#pragma once

#include <metariver/core.h>
#include <metariver/field.h>
#include <metariver/sparse_field.h>

#include <memory>
#include <span>
#include <string>

namespace mr::gpu {

struct GpuFieldDef {
    KernelDef kernel;  ///< poly6 or W1 (validate() in sparse_field.h)
    SampleGrid grid;   ///< the samples: spacing > 0, 1 to kGpuFieldMaxSamples of them
};

inline constexpr size_t kGpuFieldMaxSamples = size_t{1} << 28;  // 1 GiB of floats
inline constexpr size_t kGpuFieldMaxBalls = size_t{1} << 25;

/// Needs a current OpenGL 4.5 core context for its whole life.
class GpuField {
public:
    /// Fails (one line naming the field) on a kernel or grid this path cannot run.
    static Result<std::unique_ptr<GpuField>> create(const GpuFieldDef& def);
    ~GpuField();
    GpuField(const GpuField&) = delete;
    GpuField& operator=(const GpuField&) = delete;

    /// Uploads the balls and fills every sample (enqueued; balls outside the grid add
    /// where they reach in). Fails, leaving the last field, on a non-finite ball or
    /// more than kGpuFieldMaxBalls.
    Status build(std::span<const Vec3> balls);
    /// Waits for the last build; its GPU time, ms (a timer query; 0 when none is pending).
    double last_build_gpu_ms();
    /// Reads the samples back into a dense grid (the def's grid).
    void to_dense(ScalarGrid& out) const;
    const SampleGrid& grid() const;
    /// GL_RENDERER and GL_VERSION of the context, for reports.
    std::string device() const;

private:
    struct Impl;
    explicit GpuField(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace mr::gpu
