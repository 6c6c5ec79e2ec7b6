// The workloads of `metariver bench` (bench_scenarios.h).
#include "bench_scenarios.h"

#include "driver.h"

#include <metariver/export.h>
#include <metariver/gl_context.h>
#include <metariver/gpu_field.h>
#include <metariver/gpu_pbf.h>
#include <metariver/io.h>
#include <metariver/pbf_solver.h>
#include <metariver/sparse_field.h>
#include <metariver/spring_solver.h>
#include <metariver/surface.h>
#include <metariver/workloads.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <random>
#include <unistd.h>

namespace mr::app {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

}  // namespace

ScenarioResult bench_simulation(const std::string& name, const SceneDef& def, int warmup, int frames,
                                const std::string& note) {
    auto map = load_scene_heightmap(def);
    if (!map) return ScenarioResult{.name = name, .note = "skipped: " + map.error().message};
    return bench_simulation(name, def, map.value(), warmup, frames, note);
}

ScenarioResult bench_simulation(const std::string& name, const SceneDef& def, const Heightmap& map, int warmup,
                                int frames, const std::string& note) {
    ScenarioResult r;
    r.name = name;
    r.note = note;
    Driver d({.command = "bench", .frames = frames, .warmup = warmup, .quiet = true});  // 1/60 s per frame
    d.set_scene(def);
    if (!d.create(&map)) {
        r.note = "skipped: " + d.error();
        return r;
    }
    const Simulation& s = d.sim();
    d.warm_up();
    const uint64_t sunk_before = s.counters().sunk;
    OutletMeter outlets(s.terrain(), s.channel(), s.main_channel().back());
    float max_speed = 0.0f, density_max = 0.0f;
    (void)d.loop([&](long long f) {
        outlets.record(double(f + 1) / 60.0, s.last_exits());
        max_speed = std::max(max_speed, s.counters().max_speed);
        density_max = std::max(density_max, s.counters().density_error_max);
        const FrameTimings& t = s.last_timings();
        r.sample("simulate", t.simulate_ms);
        if (s.foam()) r.sample("foam", t.foam_ms);  // [foam]: diffuse particles (issue 11)
        r.sample("field", t.field_ms);
        r.sample("surface", t.surface_ms);
        // Part of surface, not added to total (issue 11: the smoothing's share of the stage).
        if (smoothing_on(s.def())) r.sample("smoothing", t.smoothing_ms);
        r.sample("total", t.simulate_ms + t.foam_ms + t.field_ms + t.surface_ms);
        return true;
    });
    r.particles = s.particles().active_count();
    r.triangles = s.surface().triangle_count();
    r.params = {{"scene", def.name},
                {"particles", s.def().spawn.count},  // the budget as sized (particles.count = "auto")
                {"springs", std::string(to_string(def.springs.mode))},
                {"collision", std::string(to_string(def.collision.mode))},
                {"field_kernel", std::string(to_string(def.field.kernel))},
                {"surface_smoothing", std::string(to_string(def.smoothing.method))},
                {"frames", frames},
                {"warmup", warmup}};
    if (const auto w = s.warnings(); !w.empty()) r.params["warnings"] = w;  // e.g. a flow rate the source capped
    if (s.field_overflows() > 0) r.params["field_overflows"] = s.field_overflows();  // frames with no surface
    // Plausibility (issues 5 and 9) beside the times: nothing through the ground (and how
    // often the guard had to lift a particle), outflow at the sinks over the measured
    // frames, water in the channel, density error, no explosion, no spray, settled speed.
    // Outflow over inflow: the main outlet's rate over the second half of the measured
    // frames over the source's nominal rate; coverage of the main channel at the end.
    const double inflow = s.def().spawn.total_particles_per_second();  // as sized, every source
    r.quality = {{"tunneled", s.counters().tunneled},
                 {"guarded", s.counters().guarded},
                 {"respawned", s.counters().respawned},
                 {"outflow_per_s", double(s.counters().sunk - sunk_before) * 60.0 / double(std::max(frames, 1))},
                 {"wet_channel_fraction", s.wet_fraction()},
                 {"density_error_max", density_max},
                 {"max_speed", max_speed},
                 {"final_speed_p95", percentiles(s.active_speeds()).p95},
                 {"spray_fraction", s.spray_fraction()},
                 {"outflow_over_inflow", inflow > 0.0 ? outlets.summary().main.rate / inflow : 0.0},
                 {"channel_coverage", s.channel_coverage()}};
    if (const FoamSystem* f = s.foam())
        r.quality["foam"] = {{"spray", f->stats().spray}, {"foam", f->stats().foam}, {"bubbles", f->stats().bubbles}};
    return r;
}

ScenarioResult bench_w1(int n, int res, int frames) {
    ScenarioResult r;
    r.name = fmt::format("w1 N={} R={}", n, res);
    const std::vector<Vec3> balls = w1_balls(n);
    SparseFieldDef def;
    def.kernel = w1_kernel_for(n);
    def.domain = DomainMode::FixedBox;
    def.box = w1_grid(res);
    SparseField field;
    SurfaceMesh mesh;
    SurfaceWorkspace ws;
    for (int f = -2; f < frames; ++f) {  // two warm-up frames
        auto t0 = Clock::now();
        if (auto st = field.build(balls, def); !st) {
            r.note = "skipped: " + st.error().message;
            return r;
        }
        const double field_ms = ms_since(t0);
        t0 = Clock::now();
        extract_surface_sparse(field, kW1Iso, mesh, ws);
        const double surface_ms = ms_since(t0);
        if (f < 0) continue;
        r.sample("field", field_ms);
        r.sample("surface", surface_ms);
        r.sample("total", field_ms + surface_ms);
    }
    double coord_sum = 0.0;
    for (const Vec3& b : balls) coord_sum += double(b.x) + double(b.y) + double(b.z);
    r.particles = static_cast<size_t>(n);
    r.triangles = mesh.triangle_count();
    r.params = {{"N", n}, {"R", res}, {"rcoef", 0.3}, {"frames", frames}, {"coord_sum", coord_sum}};
    r.quality = {{"vertices", mesh.vertex_count()}};
    return r;
}

/// W1's field on the GPU (gpu_field.h): the same balls, kernel and grid as bench_w1,
/// the samples filled by compute shaders (llvmpipe here, the GPU where one is lent).
/// Stages: `field` the build enqueued and waited for (upload included, read-back not),
/// `gpu` the driver's timer for it (left out where it reads under 1 % of the wall time,
/// as llvmpipe's does). Quality: the largest difference from SparseField's samples
/// relative to the largest sample (the twin check, outside the timing).
ScenarioResult bench_w1_gpu(int n, int res, int frames) {
    ScenarioResult r;
    r.name = fmt::format("w1-gpu N={} R={}", n, res);
    auto ctx = gl::HeadlessContext::create();
    if (!ctx) {
        r.note = "skipped: " + ctx.error().message;
        return r;
    }
    const std::vector<Vec3> balls = w1_balls(n);
    const KernelDef kernel = w1_kernel_for(n);
    auto gpu = gpu::GpuField::create({.kernel = kernel, .grid = w1_grid(res)});
    if (!gpu) {
        r.note = "skipped: " + gpu.error().message;
        return r;
    }
    gpu::GpuField& g = *gpu.value();
    for (int f = -2; f < frames; ++f) {  // two warm-up frames, as bench_w1
        const auto t0 = Clock::now();
        if (auto st = g.build(balls); !st) {
            r.note = "failed: " + st.error().message;
            return r;
        }
        const double gpu_ms = g.last_build_gpu_ms();  // waits for the build
        const double wall = ms_since(t0);
        if (f < 0) continue;
        r.sample("field", wall);
        if (gpu_ms > 0.01 * wall) r.sample("gpu", gpu_ms);
    }
    ScalarGrid ours, twin;
    g.to_dense(ours);
    SparseField cpu;
    const SparseFieldDef twin_def{.kernel = kernel, .domain = DomainMode::FixedBox, .box = w1_grid(res)};
    if (auto st = cpu.build(balls, twin_def); !st) {
        r.note = "failed: the CPU twin: " + st.error().message;
        return r;
    }
    cpu.to_dense(twin);
    float diff = 0.0f, top = 1.0f;
    for (size_t i = 0; i < std::min(ours.values.size(), twin.values.size()); ++i) {
        diff = std::max(diff, std::abs(ours.values[i] - twin.values[i]));
        top = std::max(top, std::abs(twin.values[i]));
    }
    r.particles = static_cast<size_t>(n);
    r.params = {{"N", n}, {"R", res}, {"rcoef", 0.3}, {"frames", frames}, {"device", g.device()}};
    r.quality = {{"max_relative_difference_vs_cpu", diff / top}};
    return r;
}

ScenarioResult bench_w2(int n) {
    ScenarioResult r;
    r.name = fmt::format("w2 spheres={}", n);
    auto terrain = Terrain::build(w2_heightmap(), w2_terrain_def());
    auto bvh = Bvh::build(terrain.value(), BvhDef{});
    const std::vector<Vec3> spheres = w2_spheres(n);
    // Spheres as particles: robust collision with the sphere radius; sphere-sphere
    // contact through the springs' minimum distance = 2 x radius with max_distance 0
    // (repulsion only while overlapping), as Bullet's spheres touch each other.
    SpawnDef spawn{.count = n, .center = Vec3(128, 20, 128), .half_extent = Vec3(0.0f), .interval = 1000000};
    SpringDef springs{.stiffness = 2000.0f, .min_distance = 2.0f * kW2Radius, .max_distance = 0.0f,
                      .mode = SpringMode::Grid};
    CollisionDef collision{.mode = CollisionMode::Robust, .damping = 0.5f, .offset = 0.0f, .leaf_triangles = 8,
                           .radius = kW2Radius, .query = CollisionQuery::Heightfield};
    IntegratorDef integrator{.gravity = 9.82f, .fixed_dt = 1.0f / 60.0f, .substeps = 2};
    SpringSolver solver(terrain.value(), bvh.value(), spawn, springs, collision, integrator, 12345u);
    solver.place(spheres);
    double fall_ms = 0.0;
    for (int step = 1; step <= 600; ++step) {
        const auto t0 = Clock::now();
        solver.step_frame(1.0f / 60.0f);
        const double ms = ms_since(t0);
        if (step <= 120)
            fall_ms += ms;
        else
            r.sample("step", ms);
    }
    // Quality after 600 steps, as the Bullet driver measures it.
    size_t below = 0, penetrating = 0, outside = 0;
    const Particles& p = solver.particles();
    for (size_t i = 0; i < p.size(); ++i) {
        const Vec3& c = p.position[i];
        if (c.x < 0 || c.x > 256 || c.z < 0 || c.z > 256) {
            ++outside;
            continue;
        }
        const float h = terrain->height_mesh(c.x, c.z);
        if (c.y < h) ++below;
        const Vec3 nrm = terrain->normal_mesh(c.x, c.z);
        const float dist = glm::dot(c - Vec3(c.x, h, c.z), nrm);  // signed distance to the triangle's plane
        if (kW2Radius - dist > 0.25f) ++penetrating;
    }
    r.particles = static_cast<size_t>(n);
    r.params = {{"spheres", n}, {"steps", 600}, {"substeps", integrator.substeps}, {"stiffness", springs.stiffness}};
    r.quality = {{"fall_ms_total", fall_ms},
                 {"tunneled", below},
                 {"tunneled_steps", solver.counters().tunneled},
                 {"guarded", solver.counters().guarded},
                 {"penetrating_0_25", penetrating},
                 {"outside", outside},
                 {"respawned", solver.counters().respawned}};
    return r;
}

/// The default PBF river resolved with about n particles (pbf_river_scene), measured
/// after `warmup` frames of flow.
ScenarioResult bench_pbf_river(int n, int warmup, int frames) {
    const SceneDef def = pbf_river_scene(n);
    ScenarioResult r = bench_simulation(fmt::format("pbf {}", n), def, warmup, frames);
    r.params["target_particles"] = n;
    r.params["spacing"] = def.pbf.spacing;
    r.params["kernel_radius"] = def.pbf.kernel_radius;
    r.params["flow_rate"] = def.spawn.flow_rate;
    r.params["field_resolution"] = def.field.resolution;
    r.params["substeps"] = def.integrator.substeps;
    r.params["iterations"] = def.pbf.iterations;
    return r;
}

/// W3 (../shared/peers/pbf_anchor/README.md): nx * nx * nx/2 particles at 0.1 m with 1 %
/// jitter (std::mt19937 seed 1, the anchor's draws in its order), h = 0.2 m, 3
/// iterations, no gravity, run by our full PBF step (predict, grid and sort, 3
/// iterations, velocities, XSPH, sleeping; terrain collision off: the block floats 1 m
/// above a flat ground), 1/120 s per step. `warmup` steps, then `steps` timed.
ScenarioResult bench_w3(int nx, int warmup, int steps) {
    ScenarioResult r;
    r.name = fmt::format("w3 nx={}", nx);
    constexpr float d = kW3Spacing;
    const float margin = 2.0f;  // metres of ground around the block
    const std::vector<Vec3> block = w3_block(nx, Vec3(margin, 1.0f, margin));
    const float side = float(nx) * d + 2.0f * margin;
    auto terrain = Terrain::build(flat_heightmap(9, 9), TerrainDef{.area_scale = side / 8.0f, .height_scale = 1.0f});
    auto bvh = Bvh::build(terrain.value(), BvhDef{});
    const int n = int(block.size());
    SpawnDef spawn{.count = n, .center = Vec3(side / 2, 2, side / 2), .half_extent = Vec3(0.0f), .interval = 0};
    PbfDef pbf{.spacing = d, .kernel_radius = 2.0f * d, .iterations = 3};
    const float dt = 1.0f / 120.0f;
    PbfSolver solver(terrain.value(), bvh.value(), spawn, pbf, CollisionDef{.mode = CollisionMode::None},
                          IntegratorDef{.gravity = 0.0f, .fixed_dt = dt, .substeps = 1}, 1u, SinkDef{});
    solver.place(block);
    float density_max = 0.0f;
    for (int s = -warmup; s < steps; ++s) {
        const auto t0 = Clock::now();
        solver.step_frame(dt);
        const double ms = ms_since(t0);
        if (s < 0) continue;
        r.sample("step", ms);
        density_max = std::max(density_max, solver.counters().density_error_max);
    }
    r.particles = solver.particles().active_count();
    r.params = {{"nx", nx},         {"spacing", d},       {"kernel_radius", 2.0 * d}, {"iterations", pbf.iterations},
                {"gravity", 0.0},   {"dt", dt},           {"warmup", warmup},         {"steps", steps},
                {"particles", n}};
    r.quality = {{"density_error_max", density_max}, {"max_speed", solver.counters().max_speed}};
    return r;
}

/// W3 run by the GPU step (gpu_pbf.h; OpenGL 4.5 compute on whatever the headless
/// context finds: llvmpipe here, the GPU where one is lent): the same block, parameters
/// and step as bench_w3, no terrain (the grid's box is the block and 2 h around it).
/// Stages: `step` one step enqueued and waited for (wall clock, as the CPU's `step`),
/// `gpu` the GPU's own time for it (a GL_TIME_ELAPSED query; absent where the driver's
/// queries read next to nothing, as llvmpipe's do).
ScenarioResult bench_w3_gpu(int nx, int warmup, int steps) {
    ScenarioResult r;
    r.name = fmt::format("w3-gpu nx={}", nx);
    auto ctx = gl::HeadlessContext::create();
    if (!ctx) {
        r.note = "skipped: " + ctx.error().message;
        return r;
    }
    constexpr float d = kW3Spacing;
    const std::vector<Vec3> block = w3_block(nx, Vec3(0.0f));
    gpu::GpuPbfDef def{.pbf = PbfDef{.spacing = d, .kernel_radius = 2.0f * d, .iterations = 3}, .gravity = 0.0f};
    const float pad = 2.0f * def.pbf.kernel_radius;
    def.domain_min = Vec3(-pad);
    def.domain_max = Vec3(float(nx) * d, float(nx / 2) * d, float(nx) * d) + Vec3(pad);
    auto gpu = gpu::GpuPbf::create(def, block);
    if (!gpu) {
        r.note = "skipped: " + gpu.error().message;
        return r;
    }
    gpu::GpuPbf& g = *gpu.value();
    const float dt = 1.0f / 120.0f;
    float density_max = 0.0f;
    for (int s = -warmup; s < steps; ++s) {
        const auto t0 = Clock::now();
        g.step(dt);
        const double gpu_ms = g.last_step_gpu_ms();  // waits for the step
        const double wall = ms_since(t0);
        if (s < 0) continue;
        r.sample("step", wall);
        // A query that reads under 1 % of the wall time did not time the work (llvmpipe's).
        if (gpu_ms > 0.01 * wall) r.sample("gpu", gpu_ms);
        density_max = std::max(density_max, g.counters().density_error_max);
    }
    r.particles = g.size();
    r.params = {{"nx", nx},       {"spacing", d},     {"kernel_radius", 2.0 * d}, {"iterations", def.pbf.iterations},
                {"gravity", 0.0}, {"dt", dt},         {"warmup", warmup},         {"steps", steps},
                {"particles", g.size()}, {"device", g.device()}};
    const gpu::GpuPbfCounters c = g.counters();
    r.quality = {{"density_error_max", density_max}, {"max_speed", c.max_speed}, {"asleep", c.asleep}};
    return r;
}

/// Export cost by format: the default river (or `particles` of it) after `warmup` frames,
/// then every frame written in every format (water + particles, encode + write) into a
/// temporary folder that the unfinished export removes again. Stages: ms per frame by
/// format; quality: MB per frame by format.
ScenarioResult bench_export(int particles, int warmup, int frames) {
    ScenarioResult r;
    r.name = "export (default river)";
    SceneDef def = default_scene();
    if (particles) def.spawn.count = particles;
    Driver d({.command = "bench", .frames = frames, .warmup = warmup, .quiet = true});  // 1/60 s per frame
    d.set_scene(def);
    if (!d.create()) {
        r.note = "skipped: " + d.error();
        return r;
    }
    const Simulation& s = d.sim();
    const fs::path dir = fs::temp_directory_path() / fmt::format("metariver-bench-export-{}", ::getpid());
    auto e = Exporter::begin(ExportDef{.dir = dir.string(),
                                       .formats = {ExportFormat::Obj, ExportFormat::Ply, ExportFormat::Glb, ExportFormat::Vdb},
                                       .voxel_size = 1.0f / def.field.resolution,
                                       .scene = def.name});
    if (!e) {
        r.note = "skipped: " + e.error().message;
        return r;
    }
    d.warm_up();
    const bool written = d.loop([&](long long f) {
        auto st = e.value()->write_frame(f, double(warmup + f + 1) / 60.0, s.surface(), s.particles(), s.frame());
        return st ? true : d.stop(kExitFailure, st.error().message);
    });
    if (!written) {
        r.note = "failed: " + d.error();
        return r;
    }
    json bytes = json::object();
    for (const ExportFormatStats& st : e.value()->stats()) {
        for (double ms : st.ms) r.sample(std::string(to_string(st.format)), ms);
        bytes[std::string(to_string(st.format))] = double(st.bytes) / double(std::max(frames, 1)) / 1e6;
    }
    r.particles = s.particles().active_count();
    r.triangles = s.surface().triangle_count();
    r.params = {{"scene", def.name}, {"particles", s.def().spawn.count}, {"warmup", warmup}, {"frames", frames},
                {"voxel_size", 1.0 / def.field.resolution}};
    r.quality = {{"mb_per_frame", bytes}};
    return r;  // the export is not finished: its files go with it
}

}  // namespace mr::app
