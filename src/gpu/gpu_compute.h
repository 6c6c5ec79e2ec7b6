// The GPU compute stages' shared parts (gpu_pbf.cpp, gpu_field.cpp; private to
// mr_gpu): the std140 parameter block every shader sees at uniform binding 0 (the
// binning grid and the counts, then each stage's own constants), the common GLSL (the
// kernels, the cell of a point, the 27-cell walk), the counting sort that bins items
// into the grid's cells, and the small helpers every pass uses.
#pragma once

#include <metariver/core.h>

#include <epoxy/gl.h>

#include <cstdint>
#include <initializer_list>
#include <string>

namespace mr::gpu {

inline constexpr uint32_t kGroup = 128;       // item and cell passes
inline constexpr uint32_t kScanBlock = 1024;  // cells per scan work group (512 threads, 2 each)

// std140: every member a vec4 / uvec4.
struct Params {
    float grid_min[4];     // xyz; w = 1 / cell size
    uint32_t grid_dim[4];  // cells along x, y, z; w = cells in all
    float kern[4];         // h, h^2, poly6, spiky
    float solve[4];        // 1/rho0, eps, scorr_scale, 1/W(dq)
    float motion[4];       // dt, gravity, max_move, xsph
    float rest[4];         // damping, 1/damping_speed, sleep^2 (0: off), drift^2
    float sleepv[4];       // alpha, sleep_drift, 0, 0
    uint32_t counts[4];    // n, after, scorr_n, 0
};

inline constexpr const char* kCommon = R"(#version 450
layout(std140, binding = 0) uniform Params {
    vec4 grid_min;
    uvec4 grid_dim;
    vec4 kern;
    vec4 solve;
    vec4 motion;
    vec4 rest;
    vec4 sleepv;
    uvec4 counts;
};
float W(float r2) {
    if (r2 >= kern.y) return 0.0;
    float d = kern.y - r2;
    return kern.z * d * d * d;
}
float grad_factor(float r) {
    if (r >= kern.x || r <= 1e-9) return 0.0;
    float a = kern.x - r;
    return kern.w * a * a / r;
}
uint cell_index(vec3 x) {
    vec3 q = clamp(floor((x - grid_min.xyz) * grid_min.w), vec3(0.0), vec3(grid_dim.xyz) - 1.0);
    return uint(q.x) + grid_dim.x * (uint(q.y) + grid_dim.y * uint(q.z));
}
// The particles of the 3 x 3 x 3 cells around cell c: 9 rows of 3 cells, each one
// contiguous range of slots. NEIGHBOURS_BEGIN(c) { body using j } NEIGHBOURS_END
#define NEIGHBOURS_BEGIN(c)                                                      \
    uint cx_ = (c) % grid_dim.x, cyz_ = (c) / grid_dim.x;                        \
    int cy_ = int(cyz_ % grid_dim.y), cz_ = int(cyz_ / grid_dim.y);              \
    uint x0_ = cx_ > 0u ? cx_ - 1u : 0u, x1_ = min(cx_ + 1u, grid_dim.x - 1u);   \
    for (int z_ = max(cz_ - 1, 0); z_ <= min(cz_ + 1, int(grid_dim.z) - 1); ++z_) \
        for (int y_ = max(cy_ - 1, 0); y_ <= min(cy_ + 1, int(grid_dim.y) - 1); ++y_) { \
            uint row_ = grid_dim.x * (uint(y_) + grid_dim.y * uint(z_));         \
            uint e_ = start[row_ + x1_ + 1u];                                    \
            for (uint j = start[row_ + x0_]; j < e_; ++j)
#define NEIGHBOURS_END }
)";

/// A compute program from kCommon and `body`; errors name the stage and the shader and
/// carry the driver's log on one line.
Result<GLuint> compute_program(const std::string& body, const char* stage, const char* what);
/// One program for compute_programs: its slot, its body (after kCommon), its name in errors.
struct ProgramSource {
    GLuint* prog;
    std::string body;
    const char* what;
};
/// compute_program for each source, in order, into its slot; the first failure's error
/// (the programs made before it stay in their slots, for the caller to delete).
Status compute_programs(std::initializer_list<ProgramSource> sources, const char* stage);
inline uint32_t groups(size_t items, uint32_t per) { return uint32_t((items + per - 1) / per); }
/// An immutable storage buffer of `bytes` (at least 16), filled from `data` or zeroed.
GLuint buffer(size_t bytes, const void* data = nullptr);
/// Zeroes a buffer and orders it before the next pass.
void clear(GLuint id);
/// Binds `buffers` at storage bindings 0, 1, ... and dispatches `groups` work groups,
/// then a barrier so the next pass sees what this one wrote.
void run(GLuint prog, std::initializer_list<GLuint> buffers, uint32_t groups);

/// GL_RENDERER and GL_VERSION of the current context, for reports.
std::string device_string();
/// Waits for a GL_TIME_ELAPSED query when one is pending; its time, ms (0 when none).
double query_ms(GLuint query, bool& pending);

/// A counting sort of items into the cells of Params' grid. The caller clears `count`,
/// runs its own pass that writes each item's cell to a buffer and counts it
/// (atomicAdd(count[cell], 1)), then sort(): `start` (cells + 1 offsets) and `order`
/// (slot -> item, each cell's items in item order: deterministic whatever the atomics
/// did). Params at uniform binding 0 must hold the grid (grid_dim) and counts.x = items.
struct Binning {
    GLuint scan_blocks = 0, scan_sums = 0, scan_add = 0, scatter = 0, cell_sort = 0;
    GLuint count = 0, start = 0, sums = 0, order = 0;
    size_t cells = 0, capacity = 0;

    Status create(size_t cells, size_t items, const char* stage);
    /// Room for `items` in `order` (grows it; the contents are lost).
    void reserve(size_t items);
    void sort(GLuint cell_of, uint32_t items);
    void destroy();
};

}  // namespace mr::gpu
