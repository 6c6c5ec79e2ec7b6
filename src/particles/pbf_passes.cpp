// The PBF step's neighbour passes (the method in pbf.cpp's header comment): the density
// constraint iterations (eq. 1, 11, 13, 14) and the velocity passes, XSPH viscosity
// (eq. 17) and vorticity confinement (eq. 15, 16). Each pass is a per-particle gather
// over the neighbour lists or the 27 cells around the particle's cell, written only to
// the particle's own slot; with AVX2 the list passes sum eight entries at a time
// (pbf_simd.h).
#include "pbf_state.h"
#include "pbf_stages.h"

#include <algorithm>
#include <cmath>

namespace mr {

// 3. One density constraint iteration. With lists, the density pass keeps each pair's
// W and grad factor (positions do not change before the correction pass reads them);
// W = -1 marks a pair the correction skips (beyond h, or i itself).
void PbfSolver::iterate(const Stage& s) {
    State& st = *st_;
    const NeighborLists* const nl = lists(2);  // the density and correction passes
    const bool simd = nl && s.simd;
    if (nl) {
        st.pair_w_.resize(nl->entries());
        if (simd) {  // the SIMD passes keep the gradient's components (fixed point, + 8 read past)
            for (auto& c : st.pair_fixed_) c.resize(nl->entries() + 8);
        } else {
            st.pair_g_.resize(nl->entries());
        }
    }
    density_pass(s, nl, simd);
    correction_pass(s, nl, simd);
    Particles& p = water_.pool.particles;
    const TerrainCollider& collider = water_.collider;
    for_each_slot(water_.pool.active(), 128, [&](size_t i) {  // a terrain query each: small blocks
        if (!p.active[i]) return;
        Vec3 x = p.position[i] + st.delta_[i];
        if (s.terrain && collider.push_out(x, p.last_position[i])) st.contact_[i] = 1;
        p.position[i] = x;
    });
    if (s.bodies) push_out_of_bodies(s, false);
}

// rho_i, C_i (with the terrain's extrapolated share) and lambda_i.
void PbfSolver::density_pass(const Stage& s, const NeighborLists* nl, bool simd) {
    State& st = *st_;
    const Particles& p = water_.pool.particles;
    const PbfKernels& k = s.k;
    const float inv_rho0 = s.c.inv_rho0, eps = s.c.eps;
    float* const cache_w = nl ? st.pair_w_.data() : nullptr;
    float* const cache_g = nl ? st.pair_g_.data() : nullptr;
    int16_t* const cache_grad[3] = {st.pair_fixed_[0].data(), st.pair_fixed_[1].data(), st.pair_fixed_[2].data()};
    const BodyShare body_share(k.h);
    for_each_binned(water_.grid.grid(), nl, [&](uint32_t i, auto&& each) {
        const Vec3 xi = p.position[i];
        float rho = 0.0f, sum_g2 = 0.0f;
        Vec3 gi(0.0f);
        if (simd) {
            const pbf_simd::DensitySums d = pbf_simd::density(s.kc, inv_rho0, xi, i, nl->index(), nl->first(i), nl->first(i + 1),
                                                              p.position.data(), uint32_t(p.size()), cache_w, cache_grad);
            rho = d.rho, gi = d.grad, sum_g2 = d.grad2;
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
        if (s.wall && (st.wall_share_[i] > 0.0f || st.wall_grad_[i] != Vec3(0.0f))) {  // the terrain's share, extrapolated
            C += std::clamp(st.wall_share_[i] + glm::dot(st.wall_grad_[i], xi - st.wall_at_[i]), 0.0f, 1.0f);
            gi += st.wall_grad_[i];
        }
        if (s.bodies && st.body_of_[i] >= 0) {  // the body's share (pbf_bodies.cpp)
            Vec3 gb;
            C += pbf_body_share(st.bodies_.all()[size_t(st.body_of_[i])], body_share, xi, gb);
            gi += gb;
            st.body_grad_[i] = gb;
        }
        sum_g2 += glm::dot(gi, gi);
        st.density_[i] = C;
        st.lambda_[i] = -std::max(C, 0.0f) / (sum_g2 + eps);
    });
}

// dx_i (eq. 14 with s_corr, eq. 13), capped at max_move, into delta_.
void PbfSolver::correction_pass(const Stage& s, const NeighborLists* nl, bool simd) {
    State& st = *st_;
    const Particles& p = water_.pool.particles;
    const PbfKernels& k = s.k;
    const float inv_rho0 = s.c.inv_rho0, inv_wdq = s.c.inv_wdq, scorr_scale = s.c.scorr_scale, max_move = s.c.max_move;
    const int scorr_n = pbf_.scorr_n;
    const float* const cache_w = nl ? st.pair_w_.data() : nullptr;
    const float* const cache_g = nl ? st.pair_g_.data() : nullptr;
    const int16_t* const cache_grad[3] = {st.pair_fixed_[0].data(), st.pair_fixed_[1].data(), st.pair_fixed_[2].data()};
    const auto scorr = [&](float w) {
        const float w2 = w * w;
        float sc = w2 * w2;  // n = 4
        for (int e = 4; e < scorr_n; ++e) sc *= w;
        if (scorr_n < 4) sc = std::pow(w, float(scorr_n));
        return sc;
    };
    for_each_binned(water_.grid.grid(), nl, [&](uint32_t i, auto&& each) {
        const Vec3 xi = p.position[i];
        const float li = st.lambda_[i];
        Vec3 dx(0.0f);
        if (simd) {
            dx = pbf_simd::correction(s.kc, li, nl->index(), nl->first(i), nl->first(i + 1), st.lambda_.data(), cache_w,
                                      cache_grad, scorr_scale, inv_wdq, scorr_n);
        } else if (cache_w) {  // the density pass's W and grad factor, the same values
            each([&](uint32_t j, uint32_t e) {
                const float wc = cache_w[e];
                if (wc < 0.0f) return;
                const Vec3 dd = xi - p.position[j];
                dx += (li + st.lambda_[j] - scorr_scale * scorr(wc * inv_wdq)) * (cache_g[e] * dd);
            });
        } else {
            each([&](uint32_t j, uint32_t) {
                if (j == i) return;
                const Vec3 dd = xi - p.position[j];
                const float r2 = glm::dot(dd, dd);
                if (r2 >= k.h2) return;
                dx += (li + st.lambda_[j] - scorr_scale * scorr(k.W(r2) * inv_wdq)) * k.grad(dd, std::sqrt(r2));
            });
        }
        dx *= inv_rho0;
        if (s.wall) dx += li * st.wall_grad_[i];  // off the terrain (lambda < 0 when compressed)
        Vec3 off_body(0.0f);
        if (s.bodies && st.body_of_[i] >= 0) {
            off_body = li * st.body_grad_[i];
            dx += off_body;
        }
        const float len = glm::length(dx);
        const float cap = len > max_move ? max_move / len : 1.0f;
        dx *= cap;
        if (s.bodies) st.body_dx_[i] = cap * off_body;  // its reaction on the body
        st.delta_[i] = dx;
    });
}

// 5. XSPH viscosity and vorticity confinement (gathers of the velocities).
void PbfSolver::viscosity(const Stage& s) {
    State& st = *st_;
    Particles& p = water_.pool.particles;
    const PbfKernels& k = s.k;
    const float inv_rho0 = s.c.inv_rho0;
    const PbfDef& d = pbf_;
    const NeighborLists* const nl = lists(d.vorticity > 0.0f ? 2 : 1);
    if (d.vorticity > 0.0f) {
        st.omega_.resize(p.size());  // sized for every slot; the active prefix is read
        std::fill_n(st.omega_.begin(), water_.pool.active(), Vec3(0.0f));
        for_each_binned(water_.grid.grid(), nl, [&](uint32_t i, auto&& each) {
            Vec3 w(0.0f);
            each([&](uint32_t j, uint32_t) {
                const Vec3 dd = p.position[i] - p.position[j];
                const float r = glm::length(dd);
                if (r >= k.h) return;  // grad is 0 there: the same sum
                w += glm::cross(p.velocity[j] - p.velocity[i], -k.grad(dd, r));
            });
            st.omega_[i] = w * inv_rho0;
        });
    }
    if (s.simd && d.vorticity <= 0.0f) {
        xsph_simd(s, nl);
    } else {
        for_each_binned(water_.grid.grid(), nl, [&](uint32_t i, auto&& each) {
            const Vec3 xi = p.position[i], vi = p.velocity[i];
            Vec3 visc(0.0f), eta(0.0f);
            each([&](uint32_t j, uint32_t) {
                const Vec3 dd = xi - p.position[j];
                const float r2 = glm::dot(dd, dd);
                if (r2 >= k.h2) return;
                visc += (p.velocity[j] - vi) * k.W(r2);
                if (d.vorticity > 0.0f) eta += glm::length(st.omega_[j]) * k.grad(dd, std::sqrt(r2));
            });
            Vec3 v = vi + d.xsph * inv_rho0 * visc;
            if (d.vorticity > 0.0f) {
                const float el = glm::length(eta);
                if (el > 1e-12f) v += s.dt * d.vorticity * glm::cross(eta / el, st.omega_[i]);
            }
            st.delta_[i] = v;
        });
    }
    for_each_slot(water_.pool.active(), 1024, [&](size_t i) {
        if (p.active[i]) p.velocity[i] = st.delta_[i];
    });
}

// XSPH alone, eight entries at a time: over the lists, or over the 27 cells' ranges
// when they went stale after collision.
void PbfSolver::xsph_simd(const Stage& s, const NeighborLists* nl) {
    State& st = *st_;
    const Particles& p = water_.pool.particles;
    const uint32_t n = uint32_t(p.size());
    const Vec3 *x = p.position.data(), *v = p.velocity.data();
    const auto put = [&](uint32_t i, const Vec3& visc) { st.delta_[i] = v[i] + pbf_.xsph * s.c.inv_rho0 * visc; };
    if (nl) {
        for_each_binned(water_.grid.grid(), nl, [&](uint32_t i, auto&&) {
            put(i, pbf_simd::viscosity(s.kc, x[i], v[i], nl->index(), nl->first(i), nl->first(i + 1), x, v, n));
        });
        return;
    }
    for_each_run(water_.grid.grid(), [&](uint32_t i, const Ranges& rg) {
        Vec3 visc(0.0f);
        for (int q = 0; q < rg.n; ++q) visc += pbf_simd::viscosity(s.kc, x[i], v[i], nullptr, rg.s[q], rg.e[q], x, v, n);
        put(i, visc);
    });
}

}  // namespace mr
