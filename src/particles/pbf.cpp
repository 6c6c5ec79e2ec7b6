// Position Based Fluids: M. Macklin and M. Mueller, "Position Based Fluids", ACM
// Transactions on Graphics 32(4), SIGGRAPH 2013.
//
// One step of dt (algorithm 1 of the paper):
//   v += g dt; x* = x + v dt                                   (predict)
//   bin x* in the neighbour grid (cell = h), arrays reordered by cell
//   repeat `iterations` times:
//     rho_i = sum_j W_poly6(x*_i - x*_j)                        (number density)
//     C_i = max(rho_i / rho_0 - 1, 0)                          (eq. 1; unilateral: a free
//                                                               surface is not pulled together)
//     lambda_i = -C_i / (sum_k |grad_k C_i|^2 + eps)            (eq. 11)
//     dx_i = 1/rho_0 sum_j (lambda_i + lambda_j + s_corr) grad W_spiky(x*_i - x*_j)   (eq. 14)
//     s_corr = -k (W(r) / W(dq))^n                             (eq. 13, tensile instability)
//     x*_i += dx_i, kept above the terrain (heightfield, + radius)
//   v = (x* - x) / dt; swept robust terrain collision on x -> x* (the particle slides)
//   XSPH viscosity v_i += c sum_j (v_j - v_i) W(x_i - x_j) / rho_0 (eq. 17), optional
//   vorticity confinement (eq. 15, 16)
//   slow-water damping v *= exp(-damping s dt), s = 1 below damping_speed, 0 above twice it
//   sleeping (after NVIDIA FleX's sleepThreshold): a particle slower than
//   sleep_threshold for kSleepAfterSeconds, whose mean horizontal velocity
//   (sleep_drift) is slow too, is asleep; its slow steps are undone
//
// Wall density (PbfDef::wall_density): rho_i also counts the terrain as water at rest,
// rho_0 times the share of the kernel around x_i that lies under the heightfield, and
// grad C_i gains that share's gradient (static ground: only lambda_i moves the particle
// off it). Without it a particle at the bed sees half a neighbourhood (SPH's particle
// deficiency; Akinci et al. 2012 sample the boundary with particles, Koschier and Bender
// 2017 precompute its density). The share is a quadrature over the heightfield's
// triangles within the kernel (pbf_wall.cpp): each triangle is subdivided by its area
// (4 samples per h along it, so a steep face is sampled as densely as flat ground), each
// sample adds the vertical poly6 column below the surface there (closed form) times its
// projected area, and the gradient is -sum W n dS (the divergence theorem). So the
// ground below, a steep wall beside the particle and the crease at the wall's foot all
// count with one consistent share; it is computed once per step at the predicted
// position and extrapolated linearly through the iterations.
//
// rho_0 is the kernel sum of a cubic lattice of the rest spacing, so "number density"
// (no mass) and a perfect lattice has C = 0. eps and s_corr are scaled by a lattice
// particle's sum |grad C|^2 so they mean the same at any spacing.
//
// Every pass is a per-particle gather over the 27 cells around the particle's cell
// (the arrays are sorted by cell, so each neighbour cell row is one contiguous index
// range), written only to the particle's own slot: parallel, no atomics, and the same
// result for any thread count (each particle's sum runs in a fixed order). The fast
// path walks per-particle neighbour lists instead (NeighborLists: the pairs within
// h + skin, built once per step after binning, rebuilt before a pass when a particle
// has moved 0.45 skin), the same pairs in the same order, and the density pass keeps
// each pair's W and grad factor for the correction pass at the same positions: the
// same step bit for bit as the 27-cell twin (set_pbf_neighbor_lists(false); tested).
// Where the CPU has AVX2 and FMA the list passes (density, correction, XSPH without
// vorticity) sum eight entries at a time (pbf_simd.h; the density pass keeps the kernel
// gradient's three components, so the correction gathers no positions): the scalar list
// loops are their twin, equal to float rounding (PbfProbe::set_simd; tested).
//
// step() runs the stages in this order; the density iterations and the velocity passes
// (XSPH, vorticity) are in pbf_passes.cpp. The water's parts (solver_parts.h) do the
// rest: the emitters' lattice sources, the collider's contact loop (the fluid slides),
// the sinks and the respawns.
#include <metariver/pbf_solver.h>

#include "pbf_state.h"
#include "pbf_stages.h"

#include <algorithm>
#include <cmath>

namespace mr {

PbfLattice pbf_lattice(const PbfDef& d) {
    const PbfKernels k(d.kernel_radius);
    const int m = int(std::ceil(d.kernel_radius / d.spacing)) + 1;
    double rho = 0.0;
    Vec3 gsum(0.0f);
    double g2 = 0.0;
    for (int a = -m; a <= m; ++a)
        for (int b = -m; b <= m; ++b)
            for (int c = -m; c <= m; ++c) {
                const Vec3 x = d.spacing * Vec3(float(a), float(b), float(c));
                const float r = glm::length(x);
                rho += k.W(r * r);
                const Vec3 gr = k.grad(x, r);
                gsum += gr;
                g2 += double(glm::dot(gr, gr));
            }
    const double inv = 1.0 / rho;
    return PbfLattice{.rest_density = float(rho), .grad_sum = float(inv * inv * (g2 + double(glm::dot(gsum, gsum))))};
}

PbfStepConstants pbf_step_constants(const PbfDef& d, const PbfLattice& lattice) {
    const PbfKernels k(d.kernel_radius);
    const float dq = d.scorr_dq * d.kernel_radius;
    return PbfStepConstants{
        .h = k.h,
        .h2 = k.h2,
        .poly6 = k.poly6,
        .spiky = k.spiky,
        .inv_rho0 = 1.0f / lattice.rest_density,
        .eps = d.relaxation * lattice.grad_sum,
        .scorr_scale = d.scorr_k * lattice.grad_sum > 0.0f ? d.scorr_k / lattice.grad_sum : 0.0f,
        .inv_wdq = 1.0f / k.W(dq * dq),
        .max_move = 0.5f * d.spacing,  // per iteration: a spawn overlap never explodes
    };
}

PbfSleepStep pbf_sleep_step(const PbfDef& d, float gravity, float dt) {
    return PbfSleepStep{
        .threshold = gravity > 0.0f ? std::min(d.sleep_threshold, kSleepCapOfFallStep * gravity * dt) : d.sleep_threshold,
        .after = std::clamp(int(std::ceil(kSleepAfterSeconds / dt)), 1, 65535),
        .drift_alpha = std::min(1.0f, dt / kSleepDriftSeconds),
    };
}

PbfSolver::PbfSolver(const Terrain& terrain, const Bvh& bvh, SpawnDef spawn, PbfDef pbf, CollisionDef collision,
                     IntegratorDef integrator, uint32_t seed, SinkDef sink)
    : water_(terrain, bvh, spawn, collision, integrator, seed, sink, pbf.spacing, true),
      pbf_(pbf),
      st_(std::make_unique<State>()) {
    st_->sleep_.slow_steps.assign(water_.pool.size(), 0);
    st_->sleep_.mean_velocity.assign(water_.pool.size(), Vec3(0.0f));
    water_.pool.slots = &st_->sleep_;
    init_pbf();
}

bool PbfSolver::set_params(const SpawnDef& spawn, const PbfDef& pbf, const CollisionDef& collision,
                           const IntegratorDef& integrator, const SinkDef& sink) {
    if (!water_.set_shared(spawn, collision, integrator, sink, pbf.spacing)) return false;
    pbf_ = pbf;
    init_pbf();  // rest density, lattice constants and the sources' lattices
    return true;
}

void PbfSolver::init_pbf() {
    State& st = *st_;
    const PbfLattice l = pbf_lattice(pbf_);
    rest_density_ = l.rest_density;
    water_.emitters.build_lattices();
    st.lattice_grad_sum_ = l.grad_sum;
}

void PbfSolver::State::Sleep::swap(size_t i, size_t j) {
    std::swap(slow_steps[i], slow_steps[j]);
    std::swap(mean_velocity[i], mean_velocity[j]);
}

void PbfSolver::State::Sleep::permute(std::span<const uint32_t> perm) {
    const size_t n = perm.size();  // the prefix reordered; the slots past it keep theirs
    scratch_slow.resize(n);
    for (size_t k = 0; k < n; ++k) scratch_slow[k] = slow_steps[perm[k]];
    std::copy_n(scratch_slow.begin(), n, slow_steps.begin());
    scratch_mean.resize(n);
    for (size_t k = 0; k < n; ++k) scratch_mean[k] = mean_velocity[perm[k]];
    std::copy_n(scratch_mean.begin(), n, mean_velocity.begin());
}

PbfSolver::~PbfSolver() = default;

float PbfSolver::list_skin() const { return st_->pbf_list_skin_ * pbf_.kernel_radius; }

void pbf_densities(ParticleWater& water, float kernel_radius, std::vector<float>& out) {
    const PbfKernels k(kernel_radius);
    water.grid.sort(water.pool, kernel_radius);
    const Particles& p = water.pool.particles;
    out.assign(p.size(), 0.0f);
    for_each_run(water.grid.grid(), [&](uint32_t i, const Ranges& rg) {
        const Vec3 xi = p.position[i];
        float rho = 0.0f;
        for (int q = 0; q < rg.n; ++q)
            for (uint32_t j = rg.s[q]; j < rg.e[q]; ++j) {
                const Vec3 d = xi - p.position[j];
                rho += k.W(glm::dot(d, d));
            }
        out[i] = rho;
    });
}

void pbf_densities_brute_force(const ParticleWater& water, float kernel_radius, std::vector<float>& out) {
    const PbfKernels k(kernel_radius);
    const Particles& p = water.pool.particles;
    out.assign(p.size(), 0.0f);
    for (size_t i = 0; i < p.size(); ++i) {
        if (!p.active[i]) continue;
        double rho = 0.0;
        for (size_t j = 0; j < p.size(); ++j) {
            if (!p.active[j]) continue;
            const Vec3 d = p.position[i] - p.position[j];
            rho += k.W(glm::dot(d, d));
        }
        out[i] = float(rho);
    }
}

void PbfSolver::step(float dt) {
    State& st = *st_;
    const PbfKernels k(pbf_.kernel_radius);
    const bool terrain = water_.collider.response() != ContactResponse::None;
    const Stage s{.dt = dt,
                  .k = k,
                  .c = pbf_step_constants(pbf_, PbfLattice{rest_density_, st.lattice_grad_sum_}),
                  .kc = pbf_simd::KernelConsts{k.h, k.h2, k.poly6, k.spiky},
                  .terrain = terrain,
                  .wall = terrain && pbf_.wall_density > 0.0f,
                  .bodies = !st.bodies_.empty(),
                  .body_mass = 1000.0f * pbf_.spacing * pbf_.spacing * pbf_.spacing,
                  .simd = st.pbf_simd_on_ && pbf_simd::available()};
    predict(s);
    bin();
    if (s.bodies) assign_bodies(s);
    if (s.wall) measure_walls();
    for (int it = 0; it < pbf_.iterations; ++it) iterate(s);
    if (terrain && water_.collider.def().damping > 0.0f) bed_friction(s);
    if (s.bodies) {  // the bodies' contacts, the water out of them again, their velocities
        st.bodies_.contacts(water_.collider.terrain(), s.dt);
        st.bodies_.velocities(s.dt, water_.integrator.gravity);
    }
    const ContactCounts contacts = collide(s);
    if (s.bodies) {  // after the terrain's collision: the water it lifted into a body goes out again
        push_out_of_bodies(s, true);
        if (st.body_coupling_on_) drag_bodies(s);
    }
    if (pbf_.xsph > 0.0f || pbf_.vorticity > 0.0f) viscosity(s);
    if (pbf_.damping > 0.0f) damp(s);
    sleep(s);
    if (s.bodies) {
        count_inside_bodies(s);
        st.bodies_.update_states();
    }
    water_.sinks.flag_exits(water_.pool.particles, water_.pool.active());
    record_density_error();
    water_.finish_step(contacts);
}

// 1. Predict.
void PbfSolver::predict(const Stage& s) {
    Particles& p = water_.pool.particles;
    const Vec3 g(0.0f, -water_.integrator.gravity, 0.0f);
    if (s.bodies) st_->bodies_.predict(s.dt, water_.integrator.gravity);
    for_each_slot(water_.pool.active(), 1024, [&](size_t i) {
        if (!p.active[i]) return;
        p.velocity[i] += g * s.dt;
        p.last_position[i] = p.position[i];
        p.position[i] += p.velocity[i] * s.dt;
    });
}

// 2. Bin the predicted positions (reorders every array by cell), and the neighbour
// lists of the binned positions.
void PbfSolver::bin() {
    State& st = *st_;
    water_.grid.sort(water_.pool, pbf_.kernel_radius);
    // Sized for every slot; only the active prefix is read, so only it is cleared.
    const size_t size = water_.pool.size(), n = water_.pool.active();
    st.lambda_.resize(size);
    st.contact_.resize(size);
    st.density_.resize(size);
    st.delta_.resize(size);
    std::fill_n(st.lambda_.begin(), n, 0.0f);
    std::fill_n(st.contact_.begin(), n, uint8_t(0));
    std::fill_n(st.density_.begin(), n, 0.0f);
    std::fill_n(st.delta_.begin(), n, Vec3(0.0f));
    if (st.pbf_lists_on_) st.pbf_lists_.build(water_.grid.grid(), water_.pool.particles.position, pbf_.kernel_radius + list_skin());
}

// A stale list is rebuilt before a pass when the new one serves `passes` >= 2 passes at
// these positions (a rebuild scans the candidates twice); a single pass walks the 27
// cells instead (the same pairs).
const NeighborLists* PbfSolver::lists(int passes) {
    State& st = *st_;
    if (!st.pbf_lists_on_) return nullptr;
    const std::vector<Vec3>& x = water_.pool.particles.position;
    if (st.pbf_lists_.stale(x, list_skin())) {
        if (passes < 2) return nullptr;
        st.pbf_lists_.build(water_.grid.grid(), x, pbf_.kernel_radius + list_skin());
    }
    return &st.pbf_lists_;
}

// The terrain's share of each kernel at the predicted position (wall density).
void PbfSolver::measure_walls() {
    State& st = *st_;
    const Particles& p = water_.pool.particles;
    const Terrain& terrain = water_.collider.terrain();
    st.wall_share_.resize(p.size());  // sized for every slot, set for the active prefix (the one read)
    st.wall_grad_.resize(p.size());
    st.wall_at_.resize(p.size());
    for_each_slot(water_.pool.active(), 256, [&](size_t i) {
        st.wall_at_[i] = p.position[i];
        st.wall_share_[i] = p.active[i] ? pbf_.wall_density * pbf_terrain_share(terrain, pbf_.kernel_radius, p.position[i], st.wall_grad_[i]) : 0.0f;
        st.wall_grad_[i] = p.active[i] ? pbf_.wall_density * st.wall_grad_[i] : Vec3(0.0f);
    });
}

// Bed friction: a particle the terrain held this step (pushed out in an iteration)
// loses the `damping` share of its motion along the ground (linear drag at the
// bed). It takes the energy out of a pool's slosh; too much of it holds a shallow
// river on its bed (docs/river.md has the measured trade-off).
// With a contact band (PbfDef::contact_band) a particle that close to the ground
// under it counts as held too: with the wall density the bed layer is held off the
// ground by pressure and is rarely pushed out.
void PbfSolver::bed_friction(const Stage& s) {
    State& st = *st_;
    Particles& p = water_.pool.particles;
    const Terrain& terrain = water_.collider.terrain();
    const CollisionDef& col = water_.collider.def();
    if (pbf_.contact_band > 0.0f) {
        const float band = pbf_.contact_band * pbf_.spacing;
        for_each_slot(water_.pool.active(), 1024, [&](size_t i) {
            const Vec3 x = p.position[i];
            if (p.active[i] && !st.contact_[i] && terrain.contains_xz(x.x, x.z) && x.y - terrain.height_mesh(x.x, x.z) < band)
                st.contact_[i] = 1;
        });
    }
    // The law (CollisionDef::friction_speed): the share is damping, or damping x
    // |dx_t| / (dt friction_speed), the step's speed along the ground over the law's.
    const bool quadratic = col.friction_speed > 0.0f;
    const float per_speed = quadratic ? 1.0f / (s.dt * col.friction_speed) : 0.0f;
    for_each_slot(water_.pool.active(), 1024, [&](size_t i) {
        if (!st.contact_[i]) return;
        const Vec3 x = p.position[i];
        if (!terrain.contains_xz(x.x, x.z)) return;
        const Vec3 nrm = terrain.normal_mesh(x.x, x.z);
        const Vec3 dx = x - p.last_position[i];
        const Vec3 along = dx - glm::dot(dx, nrm) * nrm;
        const float share = quadratic ? std::min(0.5f, col.damping * glm::length(along) * per_speed) : col.damping;
        p.position[i] = x - share * along;
    });
}

// 4. Velocity from the motion, then the collider's contact loop (the fluid slides).
ContactCounts PbfSolver::collide(const Stage& s) {
    Particles& p = water_.pool.particles;
    const float inv_dt = 1.0f / s.dt;
    for_each_slot(water_.pool.active(), 1024, [&](size_t i) {
        if (p.active[i]) p.velocity[i] = (p.position[i] - p.last_position[i]) * inv_dt;
    });
    return water_.collider.collide_active(p, s.dt, water_.pool.active());
}

// 6. Slow-water damping: exp(-damping s dt), s = 1 below damping_speed, linearly to
// 0 at twice it. A pool's slosh dies out (e-folding 1/damping seconds) before its
// water falls asleep; faster water is not touched.
void PbfSolver::damp(const Stage& s) {
    Particles& p = water_.pool.particles;
    const float inv_speed = 1.0f / pbf_.damping_speed;
    for_each_slot(water_.pool.active(), 1024, [&](size_t i) {
        if (!p.active[i]) return;
        const float sp = std::clamp(2.0f - glm::length(p.velocity[i]) * inv_speed, 0.0f, 1.0f);
        if (sp > 0.0f) p.velocity[i] *= std::exp(-pbf_.damping * sp * s.dt);
    });
}

// 7. Sleeping: a particle slower than the threshold for kSleepAfterSeconds is
// asleep, and an asleep particle's slow step is undone (position kept, velocity
// zero); a faster step wakes it. Judged on the final velocity, after collision and
// viscosity: a particle at the top of a bounce is slow for a step or two, not for
// kSleepAfterSeconds. The threshold is capped below the speed gravity gives in one
// step, so an asleep particle whose support went away wakes with its first fall.
// The mean horizontal velocity (PbfDef::sleep_drift): an exponential average over
// kSleepDriftSeconds of the awake steps; a particle whose mean is not slow stays
// awake, so a slosh levels out instead of freezing at its slow turn. Only the
// horizontal part: a slosh moves the water sideways, while the vertical settling of a
// column (water still packing under its weight) kept the pools awake past 10 s when
// it counted (max speed 0.10-0.20 m/s at 10 s).
void PbfSolver::sleep(const Stage& s) {
    State& st = *st_;
    const PbfSleepStep rule = pbf_sleep_step(pbf_, water_.integrator.gravity, s.dt);
    if (!(rule.threshold > 0.0f)) return;
    Particles& p = water_.pool.particles;
    const float s2 = rule.threshold * rule.threshold;
    const int after = rule.after;
    const float drift2 = pbf_.sleep_drift * pbf_.sleep_drift;
    const float alpha = rule.drift_alpha;
    std::vector<uint16_t>& slow = st.sleep_.slow_steps;
    std::vector<Vec3>& mean = st.sleep_.mean_velocity;
    const bool near_bodies = s.bodies && !st.body_of_.empty();
    const auto covered = [&](int32_t b, const Vec3& x) {  // a body took its place
        return b >= 0 && st.bodies_.all()[size_t(b)].distance(x) < 0.0f;
    };
    for_each_slot(water_.pool.active(), 1024, [&](size_t i) {
        if (!p.active[i]) return;
        bool asleep = slow[i] >= after;
        if (asleep && near_bodies && (covered(st.body_of_[i], p.last_position[i]) || covered(st.body2_of_[i], p.last_position[i])))
            slow[i] = 0, asleep = false;  // awake
        bool drifting = false;
        if (pbf_.sleep_drift > 0.0f && !asleep) {
            mean[i] += alpha * (Vec3(p.velocity[i].x, 0.0f, p.velocity[i].z) - mean[i]);
            drifting = glm::dot(mean[i], mean[i]) >= drift2;
        }
        if (glm::dot(p.velocity[i], p.velocity[i]) >= s2 || drifting) {
            slow[i] = 0;  // moving (or woken)
        } else if (slow[i] < after) {
            ++slow[i];
        } else {  // asleep
            p.position[i] = p.last_position[i];
            p.velocity[i] = Vec3(0.0f);
        }
    });
}

// Density error of the last iteration (serial sum: deterministic).
void PbfSolver::record_density_error() {
    State& st = *st_;
    const Particles& p = water_.pool.particles;
    double sum = 0.0;
    float mx = 0.0f;
    size_t cnt = 0;
    for (size_t i = 0; i < water_.pool.active(); ++i) {
        if (!p.active[i]) continue;
        sum += std::max(st.density_[i], 0.0f);
        mx = std::max(mx, st.density_[i]);
        ++cnt;
    }
    SolverCounters& counters = water_.pool.counters;
    counters.density_error_mean = cnt ? float(sum / double(cnt)) : 0.0f;
    counters.density_error_max = mx;
}

}  // namespace mr
