// The PBF step as OpenGL 4.5 compute shaders (gpu_pbf.h): pbf.cpp's step without the
// terrain, pass for pass.
//
//   predict + bin      v += g dt; last = x; x += v dt; cell = the kernel-radius cell of x
//                      (clamped into the grid's box); count[cell]++ (atomic)
//   scan               exclusive prefix sum of the counts (1024 cells per work group, the
//                      group sums scanned by one group, added back): start[cell]
//   scatter            slot = start[cell] + cursor[cell]++ (atomic: any order), then
//                      each cell's slots sorted by the particle's previous slot: the
//                      order is (cell, previous order) whatever the atomics did, so the
//                      step is deterministic
//   gather             every array reordered into the new slots
//   iterations         density and lambda (eq. 1, 11; unilateral C), correction with
//                      s_corr (eq. 13, 14), clamped to half a spacing, written to the
//                      other position buffer; both over the 9 rows of 3 cells around the
//                      particle's binned cell (as the CPU's 27-cell twin)
//   velocity, XSPH     v = (x - last) / dt; v += c / rho0 sum (v_j - v_i) W
//   finish             slow-water damping, sleeping (with the drift average), counters
//                      (max density error, max speed, asleep: per work group, then one
//                      atomic per group)
//
// Every pass writes only its particle's (or cell's) own slots; passes are separated by
// glMemoryBarrier. Constants sit in one std140 uniform block (binding 0); each pass binds
// its buffers at storage bindings 0..7 (the least GL 4.3 guarantees).
#include <metariver/gpu_pbf.h>

#include "gpu_compute.h"

#include <epoxy/gl.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <string>
#include <utility>

namespace mr::gpu {

namespace {


constexpr const char* kPredict = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) buffer Buf0 { vec4 pos[]; };
layout(std430, binding = 1) writeonly buffer Buf1 { vec4 last[]; };
layout(std430, binding = 2) buffer Buf2 { vec4 vel[]; };
layout(std430, binding = 3) writeonly buffer Buf3 { uint cell_of[]; };
layout(std430, binding = 4) buffer Buf4 { uint count[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counts.x) return;
    vec3 v = vel[i].xyz;
    v.y -= motion.y * motion.x;
    vec3 x = pos[i].xyz;
    last[i] = vec4(x, 0.0);
    x += v * motion.x;
    pos[i] = vec4(x, 0.0);
    vel[i] = vec4(v, 0.0);
    uint c = cell_index(x);
    cell_of[i] = c;
    atomicAdd(count[c], 1u);
}
)";

// Three arrays reordered into the new slots (slot k takes particle order[k]'s values):
// the motion (position, last position, velocity) or the state (drift mean, slow steps,
// binned cell), by their element types.
std::string gather_source(const char* t1, const char* t2, const char* t3) {
    return fmt::format(R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Buf0 {{ uint order[]; }};
layout(std430, binding = 1) readonly buffer Buf1 {{ {0} a[]; }};
layout(std430, binding = 2) readonly buffer Buf2 {{ {1} b[]; }};
layout(std430, binding = 3) readonly buffer Buf3 {{ {2} c[]; }};
layout(std430, binding = 4) writeonly buffer Buf4 {{ {0} a_out[]; }};
layout(std430, binding = 5) writeonly buffer Buf5 {{ {1} b_out[]; }};
layout(std430, binding = 6) writeonly buffer Buf6 {{ {2} c_out[]; }};
void main() {{
    uint k = gl_GlobalInvocationID.x;
    if (k >= counts.x) return;
    uint i = order[k];
    a_out[k] = a[i];
    b_out[k] = b[i];
    c_out[k] = c[i];
}}
)",
                       t1, t2, t3);
}

constexpr const char* kDensity = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Buf0 { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Buf1 { uint cell[]; };
layout(std430, binding = 2) readonly buffer Buf2 { uint start[]; };
layout(std430, binding = 3) writeonly buffer Buf3 { float lambda[]; };
layout(std430, binding = 4) writeonly buffer Buf4 { float density[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counts.x) return;
    vec3 xi = pos[i].xyz;
    float rho = 0.0, sum_g2 = 0.0;
    vec3 gi = vec3(0.0);
    NEIGHBOURS_BEGIN(cell[i]) {
        vec3 d = xi - pos[j].xyz;
        float r2 = dot(d, d);
        if (r2 < kern.y) {
            rho += W(r2);
            vec3 gr = (grad_factor(sqrt(r2)) * d) * solve.x;
            gi += gr;
            sum_g2 += dot(gr, gr);
        }
    } NEIGHBOURS_END
    float C = rho * solve.x - 1.0;
    sum_g2 += dot(gi, gi);
    density[i] = C;
    lambda[i] = -max(C, 0.0) / (sum_g2 + solve.y);
}
)";

constexpr const char* kCorrection = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Buf0 { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Buf1 { uint cell[]; };
layout(std430, binding = 2) readonly buffer Buf2 { uint start[]; };
layout(std430, binding = 3) readonly buffer Buf3 { float lambda[]; };
layout(std430, binding = 4) writeonly buffer Buf4 { vec4 pos_out[]; };
float scorr(float w) {
    int n = int(counts.z);
    if (n < 4) return pow(w, float(n));
    float w2 = w * w, sc = w2 * w2;
    for (int e = 4; e < n; ++e) sc *= w;
    return sc;
}
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counts.x) return;
    vec3 xi = pos[i].xyz;
    float li = lambda[i];
    vec3 dx = vec3(0.0);
    NEIGHBOURS_BEGIN(cell[i]) {
        if (j != i) {
            vec3 d = xi - pos[j].xyz;
            float r2 = dot(d, d);
            if (r2 < kern.y)
                dx += (li + lambda[j] - solve.z * scorr(W(r2) * solve.w)) * (grad_factor(sqrt(r2)) * d);
        }
    } NEIGHBOURS_END
    dx *= solve.x;
    float len = length(dx);
    if (len > motion.z) dx *= motion.z / len;
    pos_out[i] = vec4(xi + dx, 0.0);
}
)";

constexpr const char* kVelocity = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Buf0 { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Buf1 { vec4 last[]; };
layout(std430, binding = 2) writeonly buffer Buf2 { vec4 vel[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counts.x) return;
    vel[i] = vec4((pos[i].xyz - last[i].xyz) * (1.0 / motion.x), 0.0);
}
)";

constexpr const char* kXsph = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Buf0 { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Buf1 { vec4 vel[]; };
layout(std430, binding = 2) readonly buffer Buf2 { uint cell[]; };
layout(std430, binding = 3) readonly buffer Buf3 { uint start[]; };
layout(std430, binding = 4) writeonly buffer Buf4 { vec4 vel_out[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= counts.x) return;
    vec3 xi = pos[i].xyz, vi = vel[i].xyz, visc = vec3(0.0);
    NEIGHBOURS_BEGIN(cell[i]) {
        vec3 d = xi - pos[j].xyz;
        float r2 = dot(d, d);
        if (r2 < kern.y) visc += (vel[j].xyz - vi) * W(r2);
    } NEIGHBOURS_END
    vel_out[i] = vec4(vi + motion.w * solve.x * visc, 0.0);
}
)";

constexpr const char* kFinish = R"(
layout(local_size_x = 128) in;
layout(std430, binding = 0) buffer Buf0 { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Buf1 { vec4 last[]; };
layout(std430, binding = 2) buffer Buf2 { vec4 vel[]; };
layout(std430, binding = 3) buffer Buf3 { vec4 mean[]; };
layout(std430, binding = 4) buffer Buf4 { uint slow[]; };
layout(std430, binding = 5) readonly buffer Buf5 { float density[]; };
layout(std430, binding = 6) buffer Buf6 { uint stats[]; };
shared uint g_density, g_speed, g_asleep;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (gl_LocalInvocationID.x == 0u) {
        g_density = 0u;
        g_speed = 0u;
        g_asleep = 0u;
    }
    memoryBarrierShared();
    barrier();
    if (i < counts.x) {
        vec3 v = vel[i].xyz;
        if (rest.x > 0.0) {  // slow-water damping
            float sp = clamp(2.0 - length(v) * rest.y, 0.0, 1.0);
            if (sp > 0.0) v *= exp(-rest.x * sp * motion.x);
        }
        if (rest.z > 0.0) {  // sleeping
            uint s = slow[i];
            uint after = counts.y;
            bool asleep = s >= after, drifting = false;
            if (sleepv.y > 0.0 && !asleep) {
                vec3 m = mean[i].xyz;
                m += sleepv.x * (vec3(v.x, 0.0, v.z) - m);
                mean[i] = vec4(m, 0.0);
                drifting = dot(m, m) >= rest.w;
            }
            if (dot(v, v) >= rest.z || drifting) {
                s = 0u;
            } else if (s < after) {
                ++s;
            } else {
                pos[i] = last[i];
                v = vec3(0.0);
            }
            slow[i] = s;
            if (s >= after) atomicAdd(g_asleep, 1u);
        }
        vel[i] = vec4(v, 0.0);
        atomicMax(g_density, floatBitsToUint(max(density[i], 0.0)));
        atomicMax(g_speed, floatBitsToUint(length(v)));
    }
    memoryBarrierShared();
    barrier();
    if (gl_LocalInvocationID.x == 0u) {
        atomicMax(stats[0], g_density);
        atomicMax(stats[1], g_speed);
        atomicAdd(stats[2], g_asleep);
    }
}
)";

}  // namespace

struct GpuPbf::Impl {
    GpuPbfDef def;
    uint32_t n = 0;
    size_t cells = 0;
    Params params{};
    // Particle arrays: [0] is the live one, [1] the other side of a ping-pong.
    std::array<GLuint, 2> pos{}, last{}, vel{}, mean{}, slow{};
    GLuint cell_of = 0, cell_sorted = 0, lambda = 0, density = 0, stats = 0, ubo = 0, query = 0;
    bool query_pending = false;
    Binning bin;
    GLuint predict = 0, gather_motion = 0, gather_state = 0, density_pass = 0, correction = 0, velocity = 0, xsph = 0,
           finish = 0;

    std::vector<GLuint*> all_buffers() {
        std::vector<GLuint*> b = {&cell_of, &cell_sorted, &lambda, &density, &stats, &ubo};
        for (auto* a : {&pos, &last, &vel, &mean, &slow})
            for (GLuint& id : *a) b.push_back(&id);
        return b;
    }
    std::vector<GLuint*> all_programs() {
        return {&predict, &gather_motion, &gather_state, &density_pass, &correction, &velocity, &xsph, &finish};
    }

    void set_dt(float dt) {
        const PbfSleepStep sleep = pbf_sleep_step(def.pbf, def.gravity, dt);
        params.motion[0] = dt;
        params.rest[2] = sleep.threshold > 0.0f ? sleep.threshold * sleep.threshold : 0.0f;
        params.counts[1] = uint32_t(sleep.after);
        params.sleepv[0] = sleep.drift_alpha;
        glNamedBufferSubData(ubo, 0, sizeof(Params), &params);
    }

    void step(float dt) {
        set_dt(dt);
        glBindBufferBase(GL_UNIFORM_BUFFER, 0, ubo);
        query_ms(query, query_pending);  // the last step's time, if unread: frees the query
        glBeginQuery(GL_TIME_ELAPSED, query);
        const uint32_t pg = groups(n, kGroup);
        clear(bin.count);
        run(predict, {pos[0], last[0], vel[0], cell_of, bin.count}, pg);
        bin.sort(cell_of, n);
        run(gather_motion, {bin.order, pos[0], last[0], vel[0], pos[1], last[1], vel[1]}, pg);
        std::swap(pos[0], pos[1]);
        std::swap(last[0], last[1]);
        std::swap(vel[0], vel[1]);
        run(gather_state, {bin.order, mean[0], slow[0], cell_of, mean[1], slow[1], cell_sorted}, pg);
        std::swap(mean[0], mean[1]);
        std::swap(slow[0], slow[1]);
        for (int it = 0; it < def.pbf.iterations; ++it) {
            run(density_pass, {pos[0], cell_sorted, bin.start, lambda, density}, pg);
            run(correction, {pos[0], cell_sorted, bin.start, lambda, pos[1]}, pg);
            std::swap(pos[0], pos[1]);
        }
        run(velocity, {pos[0], last[0], vel[0]}, pg);
        if (def.pbf.xsph > 0.0f) {
            run(xsph, {pos[0], vel[0], cell_sorted, bin.start, vel[1]}, pg);
            std::swap(vel[0], vel[1]);
        }
        clear(stats);
        run(finish, {pos[0], last[0], vel[0], mean[0], slow[0], density, stats}, pg);
        glEndQuery(GL_TIME_ELAPSED);
        query_pending = true;
    }

    std::vector<Vec3> read_vec(GLuint id) const {
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        std::vector<float> raw(size_t(n) * 4);
        if (n) glGetNamedBufferSubData(id, 0, GLsizeiptr(raw.size() * sizeof(float)), raw.data());
        std::vector<Vec3> out(n);
        for (size_t i = 0; i < n; ++i) out[i] = Vec3(raw[4 * i], raw[4 * i + 1], raw[4 * i + 2]);
        return out;
    }
};

Result<std::unique_ptr<GpuPbf>> GpuPbf::create(const GpuPbfDef& def, std::span<const Vec3> positions) {
    const PbfDef& d = def.pbf;
    if (d.vorticity != 0.0f) return Error{"GPU PBF: pbf.vorticity must be 0 on the GPU path (got a non-zero value)"};
    if (d.wall_density != 0.0f || d.contact_band != 0.0f)
        return Error{"GPU PBF: pbf.wall_density and pbf.contact_band need the terrain, which the GPU path does not have: "
                     "both must be 0"};
    if (!(d.spacing > 0.0f && d.spacing <= 1e3f) || !(d.kernel_radius > d.spacing && d.kernel_radius <= 4.0f * d.spacing))
        return Error{fmt::format("GPU PBF: pbf.spacing must be in (0, 1000] and pbf.kernel_radius in (spacing, 4 spacing] "
                                 "(got {} and {})",
                                 d.spacing, d.kernel_radius)};
    if (d.iterations < 1 || d.iterations > 100)
        return Error{fmt::format("GPU PBF: pbf.iterations must be in [1, 100] (got {})", d.iterations)};
    if (d.scorr_n < 1 || d.scorr_n > 8)
        return Error{fmt::format("GPU PBF: pbf.scorr_n must be in [1, 8] (got {})", d.scorr_n)};
    if (!(d.sleep_threshold >= 0.0f && d.sleep_threshold <= 1.0f))
        return Error{fmt::format("GPU PBF: pbf.sleep_threshold must be in [0, 1] (got {}; resolve \"auto\" first)",
                                 d.sleep_threshold)};
    if (!(d.damping >= 0.0f && d.damping <= 100.0f) || !(d.damping_speed > 0.0f))
        return Error{fmt::format("GPU PBF: pbf.damping must be in [0, 100] and pbf.damping_speed > 0 (got {} and {}; "
                                 "resolve \"auto\" first)",
                                 d.damping, d.damping_speed)};
    if (!(def.gravity >= 0.0f && def.gravity <= 1000.0f))
        return Error{fmt::format("GPU PBF: gravity must be in [0, 1000] (got {})", def.gravity)};
    if (positions.size() > kGpuPbfMaxParticles)
        return Error{fmt::format("GPU PBF: {} particles, at most {}", positions.size(), kGpuPbfMaxParticles)};
    const Vec3 extent = def.domain_max - def.domain_min;
    if (!(extent.x >= 0.0f && extent.y >= 0.0f && extent.z >= 0.0f) || !std::isfinite(extent.x + extent.y + extent.z))
        return Error{"GPU PBF: domain_max must be at or above domain_min on every axis"};
    std::array<uint32_t, 3> dim{};
    double cells = 1.0;
    for (int a = 0; a < 3; ++a) {
        const double c = std::floor(double(extent[a]) / double(d.kernel_radius)) + 1.0;
        cells *= c;
        dim[size_t(a)] = c > 1e9 ? 0u : uint32_t(c);
    }
    if (cells > double(kGpuPbfMaxCells))
        return Error{fmt::format("GPU PBF: the domain holds {:.0f} cells of pbf.kernel_radius, at most {}: shrink "
                                 "domain_min..domain_max or grow the kernel radius",
                                 cells, kGpuPbfMaxCells)};
    for (const Vec3& p : positions)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return Error{"GPU PBF: a particle position is not finite"};
    if (epoxy_gl_version() < 43 && !epoxy_has_gl_extension("GL_ARB_compute_shader"))
        return Error{"GPU PBF: the OpenGL context has no compute shaders (needs 4.3 or GL_ARB_compute_shader)"};

    auto m = std::make_unique<Impl>();
    m->def = def;
    m->n = uint32_t(positions.size());
    m->cells = size_t(cells);
    const PbfStepConstants c = pbf_step_constants(d, pbf_lattice(d));
    Params& p = m->params;
    p = Params{.grid_min = {def.domain_min.x, def.domain_min.y, def.domain_min.z, 1.0f / c.h},
               .grid_dim = {dim[0], dim[1], dim[2], uint32_t(m->cells)},
               .kern = {c.h, c.h2, c.poly6, c.spiky},
               .solve = {c.inv_rho0, c.eps, c.scorr_scale, c.inv_wdq},
               .motion = {1.0f / 120.0f, def.gravity, c.max_move, d.xsph},
               .rest = {d.damping, 1.0f / d.damping_speed, 0.0f, d.sleep_drift * d.sleep_drift},
               .sleepv = {0.0f, d.sleep_drift, 0.0f, 0.0f},
               .counts = {m->n, 1u, uint32_t(d.scorr_n), 0u}};

    auto out = std::unique_ptr<GpuPbf>(new GpuPbf(std::move(m)));
    Impl& im = *out->impl_;
    // On a failure the destructor deletes what was made.
    if (auto st = compute_programs({{&im.predict, kPredict, "predict"},
                                    {&im.gather_motion, gather_source("vec4", "vec4", "vec4"), "gather"},
                                    {&im.gather_state, gather_source("vec4", "uint", "uint"), "gather state"},
                                    {&im.density_pass, kDensity, "density"},
                                    {&im.correction, kCorrection, "correction"},
                                    {&im.velocity, kVelocity, "velocity"},
                                    {&im.xsph, kXsph, "XSPH"},
                                    {&im.finish, kFinish, "finish"}},
                                   "GPU PBF");
        !st)
        return st.error();
    const size_t n = im.n;
    std::vector<float> packed(n * 4, 0.0f);
    for (size_t i = 0; i < n; ++i) {
        packed[4 * i] = positions[i].x;
        packed[4 * i + 1] = positions[i].y;
        packed[4 * i + 2] = positions[i].z;
    }
    const size_t v4 = n * 16, u1 = n * 4;
    im.pos = {buffer(v4, packed.data()), buffer(v4)};
    im.last = {buffer(v4, packed.data()), buffer(v4)};
    im.vel = {buffer(v4), buffer(v4)};
    im.mean = {buffer(v4), buffer(v4)};
    im.slow = {buffer(u1), buffer(u1)};
    im.cell_of = buffer(u1);
    im.cell_sorted = buffer(u1);
    im.lambda = buffer(u1);
    im.density = buffer(u1);
    if (auto st = im.bin.create(im.cells, n, "GPU PBF"); !st) return st.error();
    im.stats = buffer(16);
    im.ubo = buffer(sizeof(Params), &im.params);
    glGenQueries(1, &im.query);
    if (const GLenum e = glGetError(); e != GL_NO_ERROR)
        return Error{fmt::format("GPU PBF: OpenGL error 0x{:x} while allocating {} particles' buffers", e, n)};
    return out;
}

GpuPbf::GpuPbf(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

GpuPbf::~GpuPbf() {
    for (GLuint* b : impl_->all_buffers())
        if (*b) glDeleteBuffers(1, b);
    for (GLuint* p : impl_->all_programs())
        if (*p) glDeleteProgram(*p);
    impl_->bin.destroy();
    if (impl_->query) glDeleteQueries(1, &impl_->query);
}

void GpuPbf::step(float dt) { impl_->step(std::clamp(dt, 1e-6f, 1.0f)); }

double GpuPbf::last_step_gpu_ms() { return query_ms(impl_->query, impl_->query_pending); }

std::vector<Vec3> GpuPbf::positions() const { return impl_->read_vec(impl_->pos[0]); }
std::vector<Vec3> GpuPbf::velocities() const { return impl_->read_vec(impl_->vel[0]); }

GpuPbfCounters GpuPbf::counters() const {
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    uint32_t s[4] = {};
    glGetNamedBufferSubData(impl_->stats, 0, sizeof(s), s);
    GpuPbfCounters c;
    std::memcpy(&c.density_error_max, &s[0], 4);
    std::memcpy(&c.max_speed, &s[1], 4);
    c.asleep = s[2];
    return c;
}

size_t GpuPbf::size() const { return impl_->n; }

std::string GpuPbf::device() const { return device_string(); }

}  // namespace mr::gpu
