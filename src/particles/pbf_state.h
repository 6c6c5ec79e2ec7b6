// The PBF solver's working state (include/metariver/pbf_solver.h declares it opaque):
// the per-particle arrays of one step, the neighbour lists with the SIMD passes' caches,
// the sleep counters, and the switches the twin tests turn (pbf_probe.h). Not part of
// the library's API.
#pragma once

#include <metariver/pbf_solver.h>

#include "body_cells.h"
#include "rigid_bodies.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace mr {

struct PbfSolver::State {
    /// Sleeping, per slot: consecutive slow steps (saturating; asleep at
    /// kSleepAfterSeconds' worth) and the exponential average of the velocity
    /// (PbfDef::sleep_drift); reset when a slot is (re)activated or pushed awake.
    struct Sleep final : SlotState {
        std::vector<uint16_t> slow_steps, scratch_slow;
        std::vector<Vec3> mean_velocity, scratch_mean;
        void reset(size_t i) override {
            slow_steps[i] = 0;
            mean_velocity[i] = Vec3(0.0f);
        }
        void swap(size_t i, size_t j) override;
        void permute(std::span<const uint32_t> perm) override;
    };

    Sleep sleep_;
    float lattice_grad_sum_ = 1.0f;
    std::vector<float> lambda_, density_;
    std::vector<uint8_t> contact_;  ///< held by the terrain this step
    /// Wall density, per particle of the step: the terrain's share and its gradient at
    /// the predicted position `wall_at_` (each iteration extrapolates them linearly).
    std::vector<float> wall_share_;
    std::vector<Vec3> wall_grad_, wall_at_;
    std::vector<Vec3> delta_, omega_;
    NeighborLists pbf_lists_;
    bool pbf_lists_on_ = true;
    float pbf_list_skin_ = kPbfListSkin;
    bool pbf_simd_on_ = true;  ///< the list passes with AVX2 where the CPU has it (pbf_simd.h)
    /// Per list entry, W and the grad factor of the density pass (SIMD: W and the
    /// gradient's x, y, z in 16-bit fixed point, pbf_simd.h).
    std::vector<float> pair_w_, pair_g_;
    std::array<std::vector<int16_t>, 3> pair_fixed_;

    /// Rigid bodies (pbf_bodies.cpp): per particle of the step, the body it meets (-1:
    /// none) and the position corrections the body's terms gave it this iteration; the
    /// second nearest body within reach (-1: none) and the corrections its push-out gave
    /// (water between two bodies that touch).
    RigidBodies bodies_;
    std::vector<int32_t> body_of_, body2_of_;
    std::vector<Vec3> body_grad_, body_dx_, body2_dx_;
    std::vector<uint32_t> body_near_;  ///< the particles with a body (body_of_ >= 0), in slot order
    std::vector<glm::vec4> body_reach_;  ///< per body: its centre and (bound + reach)^2, for the broad phase
    BodyCells body_cells_;               ///< body_reach_ binned (the broad phase's cells)
    bool body_coupling_on_ = true;  ///< off (test probe): the water does not see the bodies

    /// A solver's state (for the test probe, pbf_probe.h: a member type reaches the
    /// solver's private members).
    static State& of(PbfSolver& s) { return *s.st_; }
    static const State& of(const PbfSolver& s) { return *s.st_; }
};

/// The terrain's share of a kernel of radius `h` centred at `x` (PbfDef::wall_density:
/// the heightfield quadrature), in [0, 1], and its gradient w.r.t. x (into `grad`); 0
/// (and grad 0) where no terrain is within h.
float pbf_terrain_share(const Terrain& terrain, float h, const Vec3& x, Vec3& grad);

/// The poly6 kernel's share beyond a plane at signed distance d, and d share / dd.
struct BodyShare {
    float h, h2, k;
    explicit BodyShare(float radius) : h(radius), h2(radius * radius), k(315.0f / (256.0f * std::pow(radius, 9.0f))) {}
    float F(float z) const {  // antiderivative of (h^2 - z^2)^4
        const float z2 = z * z, h4 = h2 * h2;
        return z * (h4 * h4 - z2 * (4.0f / 3.0f * h4 * h2 - z2 * (1.2f * h4 - z2 * (4.0f / 7.0f * h2 - z2 / 9.0f))));
    }
    float share(float d) const {
        if (d >= h) return 0.0f;
        if (d <= -h) return 1.0f;
        return k * (F(h) - F(d));
    }
    float slope(float d) const {
        if (d >= h || d <= -h) return 0.0f;
        const float a = h2 - d * d;
        return -k * (a * a) * (a * a);
    }
};

/// A body's share of a kernel of radius `bs.h` centred at `x` (pbf_bodies.cpp), in [0, 1],
/// and its gradient w.r.t. x (into `grad`).
float pbf_body_share(const RigidBody& body, const BodyShare& bs, const Vec3& x, Vec3& grad);

/// Number density of every particle through the grid (after the cell sort: it reorders
/// the particles) and by brute force over all active pairs: the twin tests compare them.
void pbf_densities(ParticleWater& water, float kernel_radius, std::vector<float>& out);
void pbf_densities_brute_force(const ParticleWater& water, float kernel_radius, std::vector<float>& out);

}  // namespace mr
