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
#include <metariver/particles.h>

#include "grid_runs.h"
#include "pbf_simd.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace mr {

namespace {

constexpr float kPi = 3.14159265358979f;

struct Kernels {
    float h, h2, poly6, spiky;
    explicit Kernels(float radius)
        : h(radius),
          h2(radius * radius),
          poly6(315.0f / (64.0f * kPi * std::pow(radius, 9.0f))),
          spiky(-45.0f / (kPi * std::pow(radius, 6.0f))) {}
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

/// Calls f(i, each) for every binned particle i, in parallel; each(g) calls g(j, e) for
/// i's candidates j: its neighbour list (`lists` set; e = the list entry) or the 27
/// cells around its cell run (e = 0). After the caller's own distance test both give
/// the same j in the same order.
template <class F>
void for_each_binned(const NeighborGrid& grid, const NeighborLists* lists, F&& f) {
    if (lists) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, lists->size(), 256),
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

}  // namespace

PbfSolver::PbfSolver(const Terrain& terrain, const Bvh& bvh, SpawnDef spawn, PbfDef pbf, CollisionDef collision,
                     IntegratorDef integrator, uint32_t seed, SinkDef sink)
    : ParticleSolver(terrain, bvh, spawn, collision, integrator, seed, sink, pbf.spacing), pbf_(pbf) {
    slow_steps_.assign(particles_.size(), 0);
    mean_velocity_.assign(particles_.size(), Vec3(0.0f));
    init_pbf();
}

bool PbfSolver::set_params(const SpawnDef& spawn, const PbfDef& pbf, const CollisionDef& collision,
                           const IntegratorDef& integrator, const SinkDef& sink) {
    if (!set_shared(spawn, collision, integrator, sink, pbf.spacing)) return false;
    pbf_ = pbf;
    init_pbf();  // rest density, lattice constants and the source's lattice
    return true;
}

void PbfSolver::permute_slots(std::span<const uint32_t> perm) {
    scratch_slow_.resize(perm.size());
    for (size_t k = 0; k < perm.size(); ++k) scratch_slow_[k] = slow_steps_[perm[k]];
    slow_steps_.swap(scratch_slow_);
    scratch_mean_.resize(perm.size());
    for (size_t k = 0; k < perm.size(); ++k) scratch_mean_[k] = mean_velocity_[perm[k]];
    mean_velocity_.swap(scratch_mean_);
}

PbfLattice pbf_lattice(const PbfDef& d) {
    const Kernels k(d.kernel_radius);
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
    const Kernels k(d.kernel_radius);
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

void PbfSolver::init_pbf() {
    const PbfLattice l = pbf_lattice(pbf_);
    rest_density_ = l.rest_density;
    build_lattice();
    lattice_grad_sum_ = l.grad_sum;
}

void PbfSolver::pbf_densities(std::vector<float>& out) {
    const Kernels k(pbf_.kernel_radius);
    sort_by_cell(pbf_.kernel_radius);
    const Particles& p = particles_;
    out.assign(p.size(), 0.0f);
    for_each_run(grid_, [&](uint32_t i, const Ranges& rg) {
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

void PbfSolver::pbf_densities_brute_force(std::vector<float>& out) const {
    const Kernels k(pbf_.kernel_radius);
    const Particles& p = particles_;
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

void PbfSolver::collide_fluid(size_t i, StepCounts& c) {
    Particles& p = particles_;
    const Vec3 lift(0.0f, collision_.radius, 0.0f);
    Vec3 from = p.last_position[i] - lift;
    Vec3 to = p.position[i] - lift;
    Vec3 v = p.velocity[i];
    constexpr int kMaxContacts = 4;
    for (int b = 0; b <= kMaxContacts; ++b) {
        const auto hit = robust_hit(from, to);
        if (!hit) break;
        ++c.collisions;
        if (b == kMaxContacts) {  // still sliding into a crease: stay at the last contact
            to = from;
            break;
        }
        const Vec3 n = hit->normal;
        // Slide: the rest of the motion loses its normal part (and the damping share).
        Vec3 rest = to - hit->point;
        rest -= std::min(glm::dot(rest, n), 0.0f) * n;
        const float vn = glm::dot(v, n);
        if (vn < 0.0f) v -= vn * n;
        v *= 1.0f - collision_.damping;
        from = hit->point + Vec3(0.0f, collision_.offset, 0.0f);
        to = from + rest * (1.0f - collision_.damping);
    }
    count_and_guard(to, v, c);
    p.velocity[i] = v;
    p.position[i] = to + lift;
}

// Out of the ground along the triangle's normal onto its plane lifted by radius +
// offset (a vertical lift on a steep wall would fling the particle up by the wall's
// height). The offset keeps resting particles strictly above the surface, so the
// next step's swept segment starts above it and rounding cannot hide a crossing. At a
// concave crease the new point can be under the neighbouring triangle: a few rounds,
// then the particle stays where it started the step (`fallback`, above the ground): a
// vertical lift out of a narrow pit or off a spike's flank would fling it. After a
// push, a point still on the triangle it was pushed out of and within half the offset
// of its target counts as out: on a plane the push lands exactly on the target, and
// float rounding lands it a hair below half the time; without the slack three such
// rounds sent a particle sliding down a steep face back to `fallback` every few steps,
// and it stuck to the wall. The slack is for that rounding only: a push along a steep
// wall's normal that lands on the floor at the wall's foot leaves the point up to the
// slack under the floor's plane, and accepting it there kept particles in the crease
// bobbing by the slack every few steps, never at rest (the box basin of
// tests/scene/sound_water_test.cpp); the floor's own push follows instead.
bool PbfSolver::push_out_of_terrain(Vec3& x, const Vec3& fallback) const {
    const float lift = collision_.radius + collision_.offset;
    const float slack = 0.5f * collision_.offset;
    constexpr uint32_t kNone = ~0u;
    uint32_t pushed_off = kNone;  // the triangle of the last push
    const auto tolerance = [&](const Vec3& p) {
        return pushed_off != kNone && terrain_.triangle_at(p.x, p.z) == pushed_off ? slack : 0.0f;
    };
    for (int round = 0; round < 3; ++round) {
        if (!terrain_.contains_xz(x.x, x.z)) return pushed_off != kNone;
        const float h = terrain_.height_mesh(x.x, x.z) + lift;
        if (x.y >= h - tolerance(x)) return pushed_off != kNone;
        // Deeper under the ground than the step moved it: it did not sink through the
        // surface it was on, it ran into a cliff face between two samples. Lifting it
        // onto the ground above would launch it up the cliff (tens of m/s): it stops at
        // the face. In every round, not only the first: a push off the face's steep
        // triangle (a small lift) can land under the terrace above, whose push then
        // lifted the whole cliff's height at once (0.48 m in a 1/120 s step: 45 m/s).
        const uint32_t tri = terrain_.triangle_at(x.x, x.z);
        const Vec3 nrm = terrain_.triangle_normal(tri);
        if ((h - x.y) * nrm.y > glm::length(x - fallback) + lift) {
            x = fallback;
            return true;
        }
        x += ((h - x.y) * nrm.y) * nrm;
        pushed_off = tri;
    }
    if (terrain_.contains_xz(x.x, x.z) && x.y < terrain_.height_mesh(x.x, x.z) + lift - tolerance(x)) x = fallback;
    return true;
}

void PbfSolver::step(float dt) {
    const PbfDef& d = pbf_;
    Particles& p = particles_;
    const size_t n = p.size();
    const Kernels k(d.kernel_radius);
    const Vec3 g(0.0f, -integrator_.gravity, 0.0f);
    const PbfStepConstants sc = pbf_step_constants(d, PbfLattice{rest_density_, lattice_grad_sum_});
    const float inv_rho0 = sc.inv_rho0, eps = sc.eps, inv_wdq = sc.inv_wdq, scorr_scale = sc.scorr_scale;
    const float max_move = sc.max_move;
    const bool terrain = collision_.mode != CollisionMode::None;
    const bool wall = terrain && d.wall_density > 0.0f;
    // The list passes eight entries at a time (pbf_simd.h) where the CPU has AVX2.
    const bool simd_on = pbf_simd_on_ && pbf_simd::available();
    const pbf_simd::KernelConsts kc{k.h, k.h2, k.poly6, k.spiky};

    // 1. Predict.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            respawn_flag_[i] = 0;
            if (!p.active[i]) continue;
            p.velocity[i] += g * dt;
            p.last_position[i] = p.position[i];
            p.position[i] += p.velocity[i] * dt;
        }
    });
    // 2. Bin the predicted positions (reorders every array by cell).
    sort_by_cell(d.kernel_radius);
    lambda_.assign(n, 0.0f);
    contact_.assign(n, 0);
    density_.assign(n, 0.0f);
    delta_.assign(n, Vec3(0.0f));
    // Neighbour lists of the binned positions. A stale list is rebuilt before a pass
    // when the new one serves `passes` >= 2 passes at these positions (a rebuild scans
    // the candidates twice); a single pass walks the 27 cells instead (the same pairs).
    const float skin = pbf_list_skin_ * d.kernel_radius;
    if (pbf_lists_on_) pbf_lists_.build(grid_, p.position, d.kernel_radius + skin);
    const auto lists = [&](int passes) -> const NeighborLists* {
        if (!pbf_lists_on_) return nullptr;
        if (pbf_lists_.stale(p.position, skin)) {
            if (passes < 2) return nullptr;
            pbf_lists_.build(grid_, p.position, d.kernel_radius + skin);
        }
        return &pbf_lists_;
    };

    // The terrain's share of each kernel at the predicted position (wall density).
    if (wall) {
        wall_share_.resize(n);
        wall_grad_.resize(n);
        wall_at_.resize(n);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                wall_at_[i] = p.position[i];
                wall_share_[i] = p.active[i] ? d.wall_density * wall_share(p.position[i], wall_grad_[i]) : 0.0f;
                wall_grad_[i] = p.active[i] ? d.wall_density * wall_grad_[i] : Vec3(0.0f);
            }
        });
    }

    // 3. Density constraint iterations. With lists, the density pass keeps each pair's
    // W and grad factor (positions do not change before the correction pass reads
    // them); W = -1 marks a pair the correction skips (beyond h, or i itself).
    for (int it = 0; it < d.iterations; ++it) {
        const NeighborLists* const nl = lists(2);  // the density and correction passes
        const bool simd = nl && simd_on;
        if (nl) {
            pair_w_.resize(nl->entries());
            if (simd) {  // the SIMD passes keep the gradient's components (fixed point, + 8 read past)
                for (auto& c : pair_fixed_) c.resize(nl->entries() + 8);
            } else {
                pair_g_.resize(nl->entries());
            }
        }
        float* const cache_w = nl ? pair_w_.data() : nullptr;
        float* const cache_g = nl ? pair_g_.data() : nullptr;
        int16_t* const cache_grad[3] = {pair_fixed_[0].data(), pair_fixed_[1].data(), pair_fixed_[2].data()};
        for_each_binned(grid_, nl, [&](uint32_t i, auto&& each) {
            const Vec3 xi = p.position[i];
            float rho = 0.0f, sum_g2 = 0.0f;
            Vec3 gi(0.0f);
            if (simd) {
                const pbf_simd::DensitySums s =
                    pbf_simd::density(kc, inv_rho0, xi, i, nl->index(), nl->first(i), nl->first(i + 1),
                                      p.position.data(), uint32_t(n), cache_w, cache_grad);
                rho = s.rho, gi = s.grad, sum_g2 = s.grad2;
            } else {
                each([&](uint32_t j, uint32_t e) {
                    const Vec3 dd = xi - p.position[j];
                    const float r2 = glm::dot(dd, dd);
                    if (r2 >= k.h2) {
                        if (cache_w) cache_w[e] = -1.0f;
                        return;
                    }
                    const float w = k.W(r2), g = k.grad_factor(std::sqrt(r2));
                    if (cache_w) {
                        cache_w[e] = j == i ? -1.0f : w;
                        cache_g[e] = g;
                    }
                    rho += w;
                    const Vec3 gr = (g * dd) * inv_rho0;
                    gi += gr;
                    sum_g2 += glm::dot(gr, gr);
                });
            }
            float C = rho * inv_rho0 - 1.0f;
            if (wall && (wall_share_[i] > 0.0f || wall_grad_[i] != Vec3(0.0f))) {  // the terrain's share, extrapolated
                C += std::clamp(wall_share_[i] + glm::dot(wall_grad_[i], xi - wall_at_[i]), 0.0f, 1.0f);
                gi += wall_grad_[i];
            }
            sum_g2 += glm::dot(gi, gi);
            density_[i] = C;
            lambda_[i] = -std::max(C, 0.0f) / (sum_g2 + eps);
        });
        const auto scorr = [&](float w) {
            const float w2 = w * w;
            float sc = w2 * w2;  // n = 4
            for (int e = 4; e < d.scorr_n; ++e) sc *= w;
            if (d.scorr_n < 4) sc = std::pow(w, float(d.scorr_n));
            return sc;
        };
        for_each_binned(grid_, nl, [&](uint32_t i, auto&& each) {
            const Vec3 xi = p.position[i];
            const float li = lambda_[i];
            Vec3 dx(0.0f);
            if (simd) {
                dx = pbf_simd::correction(kc, li, nl->index(), nl->first(i), nl->first(i + 1), lambda_.data(),
                                          cache_w, cache_grad, scorr_scale, inv_wdq, d.scorr_n);
            } else if (cache_w) {  // the density pass's W and grad factor, the same values
                each([&](uint32_t j, uint32_t e) {
                    const float wc = cache_w[e];
                    if (wc < 0.0f) return;
                    const Vec3 dd = xi - p.position[j];
                    dx += (li + lambda_[j] - scorr_scale * scorr(wc * inv_wdq)) * (cache_g[e] * dd);
                });
            } else {
                each([&](uint32_t j, uint32_t) {
                    if (j == i) return;
                    const Vec3 dd = xi - p.position[j];
                    const float r2 = glm::dot(dd, dd);
                    if (r2 >= k.h2) return;
                    dx += (li + lambda_[j] - scorr_scale * scorr(k.W(r2) * inv_wdq)) * k.grad(dd, std::sqrt(r2));
                });
            }
            dx *= inv_rho0;
            if (wall) dx += li * wall_grad_[i];  // off the terrain (lambda < 0 when compressed)
            const float len = glm::length(dx);
            if (len > max_move) dx *= max_move / len;
            delta_[i] = dx;
        });
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                if (!p.active[i]) continue;
                Vec3 x = p.position[i] + delta_[i];
                if (terrain && push_out_of_terrain(x, p.last_position[i])) contact_[i] = 1;
                p.position[i] = x;
            }
        });
    }

    // Bed friction: a particle the terrain held this step (pushed out in an iteration)
    // loses the `damping` share of its motion along the ground (linear drag at the
    // bed). It takes the energy out of a pool's slosh; too much of it holds a shallow
    // river on its bed (docs/river.md has the measured trade-off).
    // With a contact band (PbfDef::contact_band) a particle that close to the ground
    // under it counts as held too: with the wall density the bed layer is held off the
    // ground by pressure and is rarely pushed out.
    if (terrain && collision_.damping > 0.0f && d.contact_band > 0.0f) {
        const float band = d.contact_band * d.spacing;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                const Vec3 x = p.position[i];
                if (p.active[i] && !contact_[i] && terrain_.contains_xz(x.x, x.z) &&
                    x.y - terrain_.height_mesh(x.x, x.z) < band)
                    contact_[i] = 1;
            }
        });
    }
    if (terrain && collision_.damping > 0.0f) {
        // The law (CollisionDef::friction_speed): the share is damping, or damping x
        // |dx_t| / (dt friction_speed), the step's speed along the ground over the law's.
        const bool quadratic = collision_.friction_speed > 0.0f;
        const float per_speed = quadratic ? 1.0f / (dt * collision_.friction_speed) : 0.0f;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                if (!contact_[i]) continue;
                const Vec3 x = p.position[i];
                if (!terrain_.contains_xz(x.x, x.z)) continue;
                const Vec3 nrm = terrain_.normal_mesh(x.x, x.z);
                const Vec3 dx = x - p.last_position[i];
                const Vec3 along = dx - glm::dot(dx, nrm) * nrm;
                const float share = quadratic ? std::min(0.5f, collision_.damping * glm::length(along) * per_speed)
                                              : collision_.damping;
                p.position[i] = x - share * along;
            }
        });
    }

    // 4. Velocity from the motion, swept terrain collision (sliding), exits.
    std::atomic<uint64_t> steps{0}, collisions{0}, guarded{0}, tunneled{0};
    const float inv_dt = 1.0f / dt;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 512), [&](const tbb::blocked_range<size_t>& range) {
        StepCounts c;
        uint64_t local = 0;
        for (size_t i = range.begin(); i != range.end(); ++i) {
            if (!p.active[i]) continue;
            ++local;
            p.velocity[i] = (p.position[i] - p.last_position[i]) * inv_dt;
            if (terrain) collide_fluid(i, c);  // counts tunneled before its guard
            else if (ends_below_terrain(p.position[i] - Vec3(0.0f, collision_.radius, 0.0f))) ++c.tunneled;
        }
        steps += local;
        collisions += c.collisions;
        guarded += c.guarded;
        tunneled += c.tunneled;
    });

    // 5. XSPH viscosity and vorticity confinement (gathers of the velocities).
    if (d.xsph > 0.0f || d.vorticity > 0.0f) {
        const NeighborLists* const nl = lists(d.vorticity > 0.0f ? 2 : 1);
        if (d.vorticity > 0.0f) {
            omega_.assign(n, Vec3(0.0f));
            for_each_binned(grid_, nl, [&](uint32_t i, auto&& each) {
                Vec3 w(0.0f);
                each([&](uint32_t j, uint32_t) {
                    const Vec3 dd = p.position[i] - p.position[j];
                    const float r = glm::length(dd);
                    if (r >= k.h) return;  // grad is 0 there: the same sum
                    w += glm::cross(p.velocity[j] - p.velocity[i], -k.grad(dd, r));
                });
                omega_[i] = w * inv_rho0;
            });
        }
        if (simd_on && d.vorticity <= 0.0f) {
            // XSPH alone, eight entries at a time: over the lists, or over the 27 cells'
            // ranges when they went stale after collision.
            const Vec3 *x = p.position.data(), *v = p.velocity.data();
            const auto put = [&](uint32_t i, const Vec3& visc) { delta_[i] = v[i] + d.xsph * inv_rho0 * visc; };
            if (nl) {
                for_each_binned(grid_, nl, [&](uint32_t i, auto&&) {
                    put(i, pbf_simd::viscosity(kc, x[i], v[i], nl->index(), nl->first(i), nl->first(i + 1), x, v,
                                               uint32_t(n)));
                });
            } else {
                for_each_run(grid_, [&](uint32_t i, const Ranges& rg) {
                    Vec3 visc(0.0f);
                    for (int q = 0; q < rg.n; ++q)
                        visc += pbf_simd::viscosity(kc, x[i], v[i], nullptr, rg.s[q], rg.e[q], x, v, uint32_t(n));
                    put(i, visc);
                });
            }
        } else {
            for_each_binned(grid_, nl, [&](uint32_t i, auto&& each) {
                const Vec3 xi = p.position[i], vi = p.velocity[i];
                Vec3 visc(0.0f), eta(0.0f);
                each([&](uint32_t j, uint32_t) {
                    const Vec3 dd = xi - p.position[j];
                    const float r2 = glm::dot(dd, dd);
                    if (r2 >= k.h2) return;
                    visc += (p.velocity[j] - vi) * k.W(r2);
                    if (d.vorticity > 0.0f) eta += glm::length(omega_[j]) * k.grad(dd, std::sqrt(r2));
                });
                Vec3 v = vi + d.xsph * inv_rho0 * visc;
                if (d.vorticity > 0.0f) {
                    const float el = glm::length(eta);
                    if (el > 1e-12f) v += dt * d.vorticity * glm::cross(eta / el, omega_[i]);
                }
                delta_[i] = v;
            });
        }
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i)
                if (p.active[i]) p.velocity[i] = delta_[i];
        });
    }
    // 6. Slow-water damping: exp(-damping s dt), s = 1 below damping_speed, linearly to
    // 0 at twice it. A pool's slosh dies out (e-folding 1/damping seconds) before its
    // water falls asleep; faster water is not touched.
    if (d.damping > 0.0f) {
        const float inv_speed = 1.0f / d.damping_speed;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                if (!p.active[i]) continue;
                const float sp = std::clamp(2.0f - glm::length(p.velocity[i]) * inv_speed, 0.0f, 1.0f);
                if (sp > 0.0f) p.velocity[i] *= std::exp(-d.damping * sp * dt);
            }
        });
    }
    // 7. Sleeping: a particle slower than the threshold for kSleepAfterSeconds is
    // asleep, and an asleep particle's slow step is undone (position kept, velocity
    // zero); a faster step wakes it. Judged on the final velocity, after collision and
    // viscosity: a particle at the top of a bounce is slow for a step or two, not for
    // kSleepAfterSeconds. The threshold is capped below the speed gravity gives in one
    // step, so an asleep particle whose support went away wakes with its first fall.
    const PbfSleepStep sleep_step = pbf_sleep_step(d, integrator_.gravity, dt);
    const float sleep = sleep_step.threshold;
    if (sleep > 0.0f) {
        const float s2 = sleep * sleep;
        const int after = sleep_step.after;
        // The mean horizontal velocity (PbfDef::sleep_drift): an exponential average
        // over kSleepDriftSeconds of the awake steps; a particle whose mean is not slow
        // stays awake, so a slosh levels out instead of freezing at its slow turn. Only
        // the horizontal part: a slosh moves the water sideways, while the vertical
        // settling of a column (water still packing under its weight) kept the pools
        // awake past 10 s when it counted (max speed 0.10-0.20 m/s at 10 s).
        const float drift2 = d.sleep_drift * d.sleep_drift;
        const float alpha = sleep_step.drift_alpha;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                if (!p.active[i]) continue;
                const bool asleep = slow_steps_[i] >= after;
                bool drifting = false;
                if (d.sleep_drift > 0.0f && !asleep) {
                    mean_velocity_[i] += alpha * (Vec3(p.velocity[i].x, 0.0f, p.velocity[i].z) - mean_velocity_[i]);
                    drifting = glm::dot(mean_velocity_[i], mean_velocity_[i]) >= drift2;
                }
                if (glm::dot(p.velocity[i], p.velocity[i]) >= s2 || drifting) {
                    slow_steps_[i] = 0;  // moving (or woken)
                } else if (slow_steps_[i] < after) {
                    ++slow_steps_[i];
                } else {  // asleep
                    p.position[i] = p.last_position[i];
                    p.velocity[i] = Vec3(0.0f);
                }
            }
        });
    }
    for (size_t i = 0; i < n; ++i)
        if (p.active[i]) respawn_flag_[i] = exit_flag(p.position[i]);

    // Density error of the last iteration (serial sum: deterministic).
    double sum = 0.0;
    float mx = 0.0f;
    size_t cnt = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!p.active[i]) continue;
        sum += std::max(density_[i], 0.0f);
        mx = std::max(mx, density_[i]);
        ++cnt;
    }
    counters_.density_error_mean = cnt ? float(sum / double(cnt)) : 0.0f;
    counters_.density_error_max = mx;
    finish_step(steps, StepCounts{.collisions = collisions, .guarded = guarded, .tunneled = tunneled});
}

}  // namespace mr
