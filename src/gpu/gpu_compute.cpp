// The GPU compute stages' shared parts (gpu_compute.h).
#include "gpu_compute.h"

#include "gl_shader.h"

#include <fmt/format.h>

#include <algorithm>

namespace mr::gpu {

namespace {

constexpr const char* kScanBlocks = R"(
layout(local_size_x = 512) in;
layout(std430, binding = 0) readonly buffer Buf0 { uint count[]; };
layout(std430, binding = 1) writeonly buffer Buf1 { uint start[]; };
layout(std430, binding = 2) writeonly buffer Buf2 { uint sums[]; };
shared uint s[1024];
void main() {
    uint t = gl_LocalInvocationID.x, g = gl_WorkGroupID.x, cells = grid_dim.w;
    uint a = g * 1024u + 2u * t, b = a + 1u;
    s[2u * t] = a < cells ? count[a] : 0u;
    s[2u * t + 1u] = b < cells ? count[b] : 0u;
    uint offset = 1u;
    for (uint d = 512u; d > 0u; d >>= 1u) {  // up-sweep (Blelloch)
        memoryBarrierShared();
        barrier();
        if (t < d) s[offset * (2u * t + 2u) - 1u] += s[offset * (2u * t + 1u) - 1u];
        offset <<= 1u;
    }
    memoryBarrierShared();
    barrier();
    if (t == 0u) {
        sums[g] = s[1023];
        s[1023] = 0u;
    }
    for (uint d = 1u; d < 1024u; d <<= 1u) {  // down-sweep
        offset >>= 1u;
        memoryBarrierShared();
        barrier();
        if (t < d) {
            uint ai = offset * (2u * t + 1u) - 1u, bi = offset * (2u * t + 2u) - 1u;
            uint x = s[ai];
            s[ai] = s[bi];
            s[bi] += x;
        }
    }
    memoryBarrierShared();
    barrier();
    if (a < cells) start[a] = s[2u * t];
    if (b < cells) start[b] = s[2u * t + 1u];
}
)";

constexpr const char* kScanSums = R"(
layout(local_size_x = 256) in;
layout(std430, binding = 0) buffer Buf0 { uint sums[]; };
layout(std430, binding = 1) writeonly buffer Buf1 { uint start[]; };
shared uint part[256];
void main() {
    uint t = gl_LocalInvocationID.x, cells = grid_dim.w;
    uint groups = (cells + 1023u) / 1024u, per = (groups + 255u) / 256u;
    uint b = min(t * per, groups), e = min(b + per, groups);
    uint s = 0u;
    for (uint k = b; k < e; ++k) s += sums[k];
    part[t] = s;
    for (uint off = 1u; off < 256u; off <<= 1u) {  // inclusive scan (Hillis-Steele)
        memoryBarrierShared();
        barrier();
        uint v = t >= off ? part[t - off] : 0u;
        memoryBarrierShared();
        barrier();
        part[t] += v;
    }
    memoryBarrierShared();
    barrier();
    uint run = t > 0u ? part[t - 1u] : 0u;
    for (uint k = b; k < e; ++k) {
        uint v = sums[k];
        sums[k] = run;
        run += v;
    }
    if (t == 255u) start[cells] = part[255];
}
)";

constexpr const char* kScanAdd = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) buffer Buf0 { uint start[]; };
layout(std430, binding = 1) readonly buffer Buf1 { uint sums[]; };
void main() {
    uint c = gl_GlobalInvocationID.x;
    if (c < grid_dim.w) start[c] += sums[c / 1024u];
}
)";

constexpr const char* kScatter = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Buf0 { uint cell_of[]; };
layout(std430, binding = 1) readonly buffer Buf1 { uint start[]; };
layout(std430, binding = 2) buffer Buf2 { uint cursor[]; };
layout(std430, binding = 3) writeonly buffer Buf3 { uint order[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counts.x) return;
    uint c = cell_of[i];
    order[start[c] + atomicAdd(cursor[c], 1u)] = i;
}
)";

constexpr const char* kCellSort = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Buf0 { uint start[]; };
layout(std430, binding = 1) buffer Buf1 { uint order[]; };
void main() {
    uint c = gl_GlobalInvocationID.x;
    if (c >= grid_dim.w) return;
    uint b = start[c], e = start[c + 1u];
    for (uint k = b + 1u; k < e; ++k) {  // insertion sort: a cell holds a few particles
        uint v = order[k], m = k;
        while (m > b && order[m - 1u] > v) {
            order[m] = order[m - 1u];
            --m;
        }
        order[m] = v;
    }
}
)";

}  // namespace

Result<GLuint> compute_program(const std::string& body, const char* stage, const char* what) {
    auto sh = gl::compile_shader(GL_COMPUTE_SHADER, {kCommon, body.c_str()});
    if (!sh) return Error{fmt::format("{}: the {} shader does not compile: {}", stage, what, sh.error().message)};
    auto prog = gl::link_program({sh.value()});
    if (!prog) return Error{fmt::format("{}: the {} shader does not link: {}", stage, what, prog.error().message)};
    return prog.value();
}

Status compute_programs(std::initializer_list<ProgramSource> sources, const char* stage) {
    for (const ProgramSource& s : sources) {
        auto prog = compute_program(s.body, stage, s.what);
        if (!prog) return prog.error();
        *s.prog = prog.value();
    }
    return Ok{};
}

namespace {

void zero_fill(GLuint id) {
    const uint32_t zero = 0;
    glClearNamedBufferData(id, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
}

}  // namespace

GLuint buffer(size_t bytes, const void* data) {
    GLuint id = 0;
    glCreateBuffers(1, &id);
    glNamedBufferStorage(id, GLsizeiptr(std::max<size_t>(bytes, 16)), data, GL_DYNAMIC_STORAGE_BIT);
    if (!data) zero_fill(id);
    return id;
}

void clear(GLuint id) {
    zero_fill(id);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

void run(GLuint prog, std::initializer_list<GLuint> buffers, uint32_t groups) {
    GLuint b = 0;
    for (GLuint id : buffers) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b++, id);
    glUseProgram(prog);
    if (groups) glDispatchCompute(groups, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

std::string device_string() { return gl::gl_string(GL_RENDERER) + ", OpenGL " + gl::gl_string(GL_VERSION); }

double query_ms(GLuint query, bool& pending) {
    if (!pending) return 0.0;
    GLuint64 ns = 0;
    glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
    pending = false;
    return double(ns) * 1e-6;
}

Status Binning::create(size_t cells_, size_t items, const char* stage) {
    cells = cells_;
    if (auto st = compute_programs({{&scan_blocks, kScanBlocks, "scan"},
                                    {&scan_sums, kScanSums, "scan sums"},
                                    {&scan_add, kScanAdd, "scan add"},
                                    {&scatter, kScatter, "scatter"},
                                    {&cell_sort, kCellSort, "cell sort"}},
                                   stage);
        !st)
        return st;
    count = buffer(cells * 4);
    start = buffer((cells + 1) * 4);
    sums = buffer(size_t(groups(cells, kScanBlock)) * 4);
    reserve(items);
    return Ok{};
}

void Binning::reserve(size_t items) {
    if (order && items <= capacity) return;
    if (order) glDeleteBuffers(1, &order);
    capacity = std::max<size_t>(items, 4);
    order = buffer(capacity * 4);
}

void Binning::sort(GLuint cell_of, uint32_t items) {
    const uint32_t cg = groups(cells, kGroup);
    run(scan_blocks, {count, start, sums}, groups(cells, kScanBlock));
    run(scan_sums, {sums, start}, 1);
    run(scan_add, {start, sums}, cg);
    clear(count);  // the scatter's cursors
    run(scatter, {cell_of, start, count, order}, groups(items, kGroup));
    run(cell_sort, {start, order}, cg);
}

void Binning::destroy() {
    for (GLuint* b : {&count, &start, &sums, &order})
        if (*b) glDeleteBuffers(1, b), *b = 0;
    for (GLuint* p : {&scan_blocks, &scan_sums, &scan_add, &scatter, &cell_sort})
        if (*p) glDeleteProgram(*p), *p = 0;
}

}  // namespace mr::gpu
