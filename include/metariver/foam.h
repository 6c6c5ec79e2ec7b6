// metariver foam: diffuse spray, foam and bubble particles generated from the fluid,
// after Ihmsen, Akinci, Akinci and Teschner, "Unified spray, foam and air bubbles for
// particle-based fluids", The Visual Computer 28(6), 2012.
//
// Each frame, for every active fluid particle i with neighbours j within the kernel
// radius h (W~(r) = 1 - r/h, the paper's weighting):
//   trapped air  I_ta = sum_j |v_ij| (1 - v^_ij . x^_ij) W~(x_ij)     (m/s)
//   wave crest   I_wc = sum_j (1 - n^_i . n^_j) W~(x_ij) over j with x^_ji . n^_i < 0,
//                times 1 when v^_i . n^_i >= 0.6, else 0                (dimensionless)
//   kinetic      I_k  = 0.5 |v_i|^2                                    (J/kg: unit mass)
// with n_i = sum_j x_ij W~ (pointing out of the fluid, zero inside it), each clamped
// and mapped to [0, 1] by Phi(I, min, max) = (min(I, max) - min(I, min)) / (max - min).
// Particle i emits Phi_k (rate_ta Phi_ta + rate_wc Phi_wc) dt diffuse particles (the
// fraction by a counter-based random draw), in a disc of radius h/2 around it normal
// to its velocity, with its velocity and a lifetime drawn from [lifetime_min,
// lifetime_max]. A fluid particle at rest has Phi_k = 0: a still pool makes none.
//
// A diffuse particle with fewer than spray_neighbours fluid neighbours is spray
// (ballistic under gravity), with more than bubble_neighbours a bubble (fluid velocity
// plus buoyancy, dragged towards it), else foam (moves with the W~-averaged fluid
// velocity). Each step first moves the particles with the kind and fluid velocity found
// at the end of the previous step (explicit in the fluid velocity: one neighbour gather
// per particle and step instead of two), then emits, then counts every particle's
// neighbours again. All of them age; one is removed when its life ends, when it leaves
// the terrain's rectangle, or (spray) when it falls onto the ground (foam and bubbles
// are kept on it).
//
// Determinism: every pass is a per-particle gather written to the particle's own slot
// (tbb::parallel_for); the emission counts are prefix-summed serially, new particles
// are appended in fluid index order and the random numbers come from a hash of (frame,
// fluid id, draw): the same state for any thread count.
#pragma once

#include <metariver/core.h>
#include <metariver/neighbor_grid.h>
#include <metariver/particles.h>
#include <metariver/terrain.h>

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace mr {

/// [foam]: diffuse particles (see the top of this file). Thresholds are in the units of
/// the potentials above; docs/scene-format.md gives the ranges and how they were scaled
/// to the default river's 0.5 m spacing.
struct FoamDef {
    bool enabled = false;
    int max_particles = 20000;        ///< cap on live diffuse particles, [0, 1e6]
    float trapped_air_min = 1.0f;     ///< I_ta below this emits nothing, m/s, [0, 1e3]
    float trapped_air_max = 6.0f;     ///< I_ta at or above this counts fully, m/s, (trapped_air_min, 1e3]
    float wave_crest_min = 0.5f;      ///< I_wc below this emits nothing, [0, 1e3]
    float wave_crest_max = 3.0f;      ///< (wave_crest_min, 1e3]
    float energy_min = 0.5f;          ///< I_k below this emits nothing, J/kg, [0, 1e6]
    float energy_max = 8.0f;          ///< (energy_min, 1e6]
    float trapped_air_rate = 6.0f;    ///< diffuse particles per fluid particle per second at Phi_ta = Phi_k = 1, [0, 1e4]
    float wave_crest_rate = 6.0f;     ///< the same for the wave crest, [0, 1e4]
    float lifetime_min = 1.0f;        ///< seconds, [0.01, 1e3]
    float lifetime_max = 2.5f;        ///< seconds, [lifetime_min, 1e3]
    int spray_neighbours = 6;         ///< fewer fluid neighbours: spray, [0, 1000]
    int bubble_neighbours = 20;       ///< more fluid neighbours: bubble, [spray_neighbours, 1000]
    float buoyancy = 2.0f;            ///< bubbles: upward acceleration in units of gravity, [0, 100]
    float drag = 0.5f;                ///< bubbles: share of the velocity difference to the fluid removed per step, [0, 1]
};

enum class DiffuseKind : uint8_t { Spray = 0, Foam = 1, Bubble = 2 };

/// The diffuse particles, structure of arrays; all entries are live.
struct DiffuseParticles {
    std::vector<Vec3> position;   ///< metres
    std::vector<Vec3> velocity;   ///< metres per second
    std::vector<float> life;      ///< seconds left
    std::vector<uint8_t> kind;    ///< DiffuseKind from `neighbours`
    std::vector<uint16_t> neighbours;  ///< fluid particles within h of the particle's current position (the fluid of the latest step)
    /// The fluid's velocity there, averaged with W~, m/s (0 without neighbours): what
    /// foam and bubbles follow in the next step.
    std::vector<Vec3> fluid_velocity;
    size_t size() const { return position.size(); }
};

/// Counts after the latest step.
struct FoamStats {
    size_t spray = 0, foam = 0, bubbles = 0;
    size_t generated = 0;        ///< made in the latest step
    size_t expired = 0;          ///< removed in the latest step: life ended
    size_t left = 0;             ///< removed in the latest step: left the terrain or hit the ground (spray)
    size_t handed_over = 0;      ///< taken out after the latest step by hand_over() (the hybrid: onto its grid's water)
    uint64_t generated_total = 0;
    uint64_t capped_total = 0;   ///< emissions dropped because the cap was reached
    size_t total() const { return spray + foam + bubbles; }
};

class FoamSystem {
public:
    /// `kernel_radius`: the fluid's h, metres (> 0); `gravity`: m/s^2 downwards.
    FoamSystem(const FoamDef& def, float kernel_radius, float gravity);

    /// Advances the diffuse particles by dt (classify, advect, age, remove), then emits
    /// new ones from the fluid's current state. `frame` seeds the random draws.
    void step(const Particles& fluid, const Terrain& terrain, float dt, uint64_t frame);

    const FoamDef& def() const { return def_; }
    const DiffuseParticles& particles() const { return p_; }
    const FoamStats& stats() const { return stats_; }
    /// The latest step's potentials per fluid slot, unclamped (0 for inactive slots;
    /// trapped air and wave crest 0 too where kinetic_energy <= energy_min: not computed).
    std::span<const float> trapped_air() const { return ta_; }
    std::span<const float> wave_crest() const { return wc_; }
    std::span<const float> kinetic_energy() const { return ek_; }
    /// FNV-1a of the diffuse particles' positions, velocities, lives and kinds.
    uint64_t state_hash() const;
    /// Removes the diffuse particles for which `leave(position)` is true (the others keep
    /// their order) and appends them, every array, to `out`; returns how many. The hybrid
    /// hands the spray that fell into its grid's water to the grid's foam this way.
    size_t hand_over(const std::function<bool(const Vec3&)>& leave, DiffuseParticles& out);

    /// Classification rule (exposed for tests).
    static DiffuseKind classify(int neighbours, const FoamDef& def);
    /// The potentials' neighbour sums eight at a time with AVX2 where the CPU has it
    /// (true, the default) or one at a time (false: the twin; equal to float rounding).
    void set_simd(bool on) { simd_ = on; }

private:
    void potentials(const Particles& fluid);
    void potentials_simd(const Particles& fluid);
    void advect(const Terrain& terrain, float dt);
    void emit(const Particles& fluid, float dt, uint64_t frame);
    /// Every diffuse particle's fluid neighbours within h, kind and averaged fluid velocity.
    void classify_all(const Particles& fluid);
    void resize(size_t n);
    /// Calls f on each array of the diffuse particles.
    template <class F>
    void each_array(F&& f) {
        f(p_.position);
        f(p_.velocity);
        f(p_.life);
        f(p_.kind);
        f(p_.neighbours);
        f(p_.fluid_velocity);
    }

    FoamDef def_;
    float h_ = 1.0f, gravity_ = 9.82f;
    NeighborGrid grid_;
    DiffuseParticles p_;
    FoamStats stats_;
    std::vector<Vec3> normal_;  ///< potentials (scalar passes): each fluid slot's surface normal
    std::vector<float> ta_, wc_, ek_;
    std::vector<float> sorted_;  ///< potentials_simd: velocities in the grid's order (SoA, for classify_all)
    std::vector<Vec3> sorted_pos_, sorted_vel_, sorted_nrm_;  ///< potentials_simd: the fluid in the grid's order
    NeighborLists lists_;        ///< potentials_simd: each sorted particle's fluid within h
    bool simd_ = true;
    std::vector<uint32_t> emit_count_, emit_first_;
    std::vector<uint8_t> keep_;
};

}  // namespace mr
