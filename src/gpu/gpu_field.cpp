// The compact-kernel field on the GPU (gpu_field.h). Per build:
//
//   upload    the balls (vec4), into a buffer grown to the largest frame
//   bin       each ball's cell (clamped into the binning grid) and its count, then the
//             shared counting sort (gpu_compute.h: scan, scatter, each cell in ball
//             order) and the balls gathered in cell order
//   splat     one thread per sample: the sum of the kernel over the balls of the 27
//             cells around the sample's cell, written to its own slot (no atomics: the
//             same field for any schedule)
//
// The binning cells are the kernel radius, or larger where the grid's box would hold
// more than kMaxCells of them (a bigger cell still holds every ball within reach of the
// 27 cells around a sample, only more of the others).
#include <metariver/gpu_field.h>

#include "gpu_compute.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace mr::gpu {

namespace {

constexpr size_t kMaxCells = size_t{1} << 22;

// std140, uniform binding 1.
struct FieldParams {
    float sample_origin[4];  // xyz; w = spacing
    uint32_t sample_dim[4];  // nx, ny, nz; w = kernel type (0 poly6, 1 W1)
    float kernel[4];         // radius^2, amplitude (poly6) or strength (W1), subtract (W1), 1 / radius^2
};

constexpr const char* kFieldBlock = R"(
layout(std140, binding = 1) uniform FieldParams {
    vec4 sample_origin;
    uvec4 sample_dim;
    vec4 kernel;
};
)";

constexpr const char* kBallCells = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Buf0 { vec4 ball[]; };
layout(std430, binding = 1) writeonly buffer Buf1 { uint cell_of[]; };
layout(std430, binding = 2) buffer Buf2 { uint count[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counts.x) return;
    uint c = cell_index(ball[i].xyz);
    cell_of[i] = c;
    atomicAdd(count[c], 1u);
}
)";

constexpr const char* kBallGather = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Buf0 { uint order[]; };
layout(std430, binding = 1) readonly buffer Buf1 { vec4 ball[]; };
layout(std430, binding = 2) writeonly buffer Buf2 { vec4 ball_sorted[]; };
void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k < counts.x) ball_sorted[k] = ball[order[k]];
}
)";

constexpr const char* kSplat = R"(
layout(local_size_x = 8, local_size_y = 4, local_size_z = 4) in;
layout(std430, binding = 0) readonly buffer Buf0 { vec4 ball[]; };
layout(std430, binding = 1) readonly buffer Buf1 { uint start[]; };
layout(std430, binding = 2) writeonly buffer Buf2 { float value[]; };
void main() {
    uvec3 s = gl_GlobalInvocationID;
    if (any(greaterThanEqual(s, sample_dim.xyz))) return;
    vec3 p = sample_origin.xyz + sample_origin.w * vec3(s);
    float sum = 0.0;
    NEIGHBOURS_BEGIN(cell_index(p)) {
        vec3 d = p - ball[j].xyz;
        float r2 = dot(d, d);
        if (r2 < kernel.x) {
            if (sample_dim.w == 1u) {
                sum += max(0.0, kernel.y / (r2 + 1e-6) - kernel.z);
            } else {
                float q = 1.0 - r2 * kernel.w;
                sum += kernel.y * (q * q * q);
            }
        }
    } NEIGHBOURS_END
    value[s.x + sample_dim.x * (s.y + sample_dim.y * s.z)] = sum;
}
)";

}  // namespace

struct GpuField::Impl {
    GpuFieldDef def;
    Params params{};
    FieldParams field{};
    Binning bin;
    GLuint balls = 0, sorted = 0, cell_of = 0, values = 0, ubo = 0, field_ubo = 0, query = 0;
    size_t capacity = 0;
    bool query_pending = false;
    std::vector<float> packed;  // the balls as vec4s for the upload, kept between builds
    GLuint count_pass = 0, gather = 0, splat = 0;

    void reserve(size_t n) {
        if (balls && n <= capacity) return;
        for (GLuint* b : {&balls, &sorted, &cell_of})
            if (*b) glDeleteBuffers(1, b);
        capacity = std::max<size_t>({n, capacity + capacity / 2, 1024});
        balls = buffer(capacity * 16);
        sorted = buffer(capacity * 16);
        cell_of = buffer(capacity * 4);
        bin.reserve(capacity);
    }
};

Result<std::unique_ptr<GpuField>> GpuField::create(const GpuFieldDef& def) {
    if (auto st = validate(def.kernel); !st) return Error{"GPU field: " + st.error().message};
    const SampleGrid& g = def.grid;
    if (!(g.spacing > 0.0f) || !std::isfinite(g.spacing) || !std::isfinite(g.origin.x + g.origin.y + g.origin.z))
        return Error{fmt::format("GPU field: grid.spacing must be finite and > 0 and grid.origin finite (got {})",
                                 g.spacing)};
    if (g.nx < 1 || g.ny < 1 || g.nz < 1 || g.samples() > kGpuFieldMaxSamples)
        return Error{fmt::format("GPU field: the grid must hold 1 to {} samples (got {} x {} x {})", kGpuFieldMaxSamples,
                                 g.nx, g.ny, g.nz)};
    if (epoxy_gl_version() < 43 && !epoxy_has_gl_extension("GL_ARB_compute_shader"))
        return Error{"GPU field: the OpenGL context has no compute shaders (needs 4.3 or GL_ARB_compute_shader)"};

    auto m = std::make_unique<Impl>();
    m->def = def;
    const KernelDef& k = def.kernel;
    // Binning cells: the kernel radius, or the size that keeps them under kMaxCells.
    const Vec3 extent = g.spacing * Vec3(float(g.nx - 1), float(g.ny - 1), float(g.nz - 1));
    float cell = k.radius;
    const auto cells_for = [&](float c) {
        double n = 1.0;
        for (int a = 0; a < 3; ++a) n *= std::floor(double(extent[a]) / double(c)) + 1.0;
        return n;
    };
    while (cells_for(cell) > double(kMaxCells)) cell *= 1.25f;
    uint32_t dim[3];
    for (int a = 0; a < 3; ++a) dim[a] = uint32_t(std::floor(double(extent[a]) / double(cell)) + 1.0);
    const size_t cells = size_t(dim[0]) * dim[1] * dim[2];
    m->params.grid_min[0] = g.origin.x;
    m->params.grid_min[1] = g.origin.y;
    m->params.grid_min[2] = g.origin.z;
    m->params.grid_min[3] = 1.0f / cell;
    m->params.grid_dim[0] = dim[0];
    m->params.grid_dim[1] = dim[1];
    m->params.grid_dim[2] = dim[2];
    m->params.grid_dim[3] = uint32_t(cells);
    const float r2 = k.radius * k.radius;
    const bool w1 = k.type == FieldKernel::W1;
    m->field = FieldParams{.sample_origin = {g.origin.x, g.origin.y, g.origin.z, g.spacing},
                           .sample_dim = {uint32_t(g.nx), uint32_t(g.ny), uint32_t(g.nz), w1 ? 1u : 0u},
                           .kernel = {r2, w1 ? k.strength : k.amplitude, w1 ? k.subtract : 0.0f, 1.0f / r2}};

    auto out = std::unique_ptr<GpuField>(new GpuField(std::move(m)));
    Impl& im = *out->impl_;
    const std::string block = kFieldBlock;
    if (auto st = compute_programs({{&im.count_pass, block + kBallCells, "ball cells"},
                                    {&im.gather, block + kBallGather, "ball gather"},
                                    {&im.splat, block + kSplat, "splat"}},
                                   "GPU field");
        !st)
        return st.error();
    if (auto st = im.bin.create(cells, 1024, "GPU field"); !st) return st.error();
    im.reserve(1024);
    im.values = buffer(g.samples() * 4);
    im.ubo = buffer(sizeof(Params), &im.params);
    im.field_ubo = buffer(sizeof(FieldParams), &im.field);
    glGenQueries(1, &im.query);
    if (const GLenum e = glGetError(); e != GL_NO_ERROR)
        return Error{fmt::format("GPU field: OpenGL error 0x{:x} while allocating {} samples", e, g.samples())};
    return out;
}

GpuField::GpuField(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

GpuField::~GpuField() {
    Impl& m = *impl_;
    for (GLuint* b : {&m.balls, &m.sorted, &m.cell_of, &m.values, &m.ubo, &m.field_ubo})
        if (*b) glDeleteBuffers(1, b);
    for (GLuint* p : {&m.count_pass, &m.gather, &m.splat})
        if (*p) glDeleteProgram(*p);
    m.bin.destroy();
    if (m.query) glDeleteQueries(1, &m.query);
}

Status GpuField::build(std::span<const Vec3> balls) {
    Impl& m = *impl_;
    if (balls.size() > kGpuFieldMaxBalls)
        return Error{fmt::format("GPU field: {} balls, at most {}", balls.size(), kGpuFieldMaxBalls)};
    std::vector<float>& packed = m.packed;  // no allocation once it has grown to the ball count
    packed.assign(balls.size() * 4, 0.0f);
    for (size_t i = 0; i < balls.size(); ++i) {
        const Vec3& b = balls[i];
        if (!std::isfinite(b.x) || !std::isfinite(b.y) || !std::isfinite(b.z))
            return Error{fmt::format("GPU field: ball {} is not finite", i)};
        packed[4 * i] = b.x;
        packed[4 * i + 1] = b.y;
        packed[4 * i + 2] = b.z;
    }
    m.reserve(balls.size());
    const auto n = uint32_t(balls.size());
    m.params.counts[0] = n;
    glNamedBufferSubData(m.ubo, 0, sizeof(Params), &m.params);
    if (n) glNamedBufferSubData(m.balls, 0, GLsizeiptr(packed.size() * sizeof(float)), packed.data());
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, m.ubo);
    glBindBufferBase(GL_UNIFORM_BUFFER, 1, m.field_ubo);
    query_ms(m.query, m.query_pending);  // an unread time: frees the query
    glBeginQuery(GL_TIME_ELAPSED, m.query);
    clear(m.bin.count);
    run(m.count_pass, {m.balls, m.cell_of, m.bin.count}, groups(n, kGroup));
    m.bin.sort(m.cell_of, n);
    run(m.gather, {m.bin.order, m.balls, m.sorted}, groups(n, kGroup));
    const SampleGrid& g = m.def.grid;
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, m.sorted);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, m.bin.start);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, m.values);
    glUseProgram(m.splat);
    glDispatchCompute(groups(size_t(g.nx), 8), groups(size_t(g.ny), 4), groups(size_t(g.nz), 4));
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    glEndQuery(GL_TIME_ELAPSED);
    m.query_pending = true;
    return Ok{};
}

double GpuField::last_build_gpu_ms() { return query_ms(impl_->query, impl_->query_pending); }

void GpuField::to_dense(ScalarGrid& out) const {
    const SampleGrid& g = impl_->def.grid;
    out.reset(g.nx, g.ny, g.nz, g.origin, g.spacing);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(impl_->values, 0, GLsizeiptr(out.values.size() * sizeof(float)), out.values.data());
}

const SampleGrid& GpuField::grid() const { return impl_->def.grid; }

std::string GpuField::device() const { return device_string(); }

}  // namespace mr::gpu
