// Foam on a heightfield's water (a HeightfieldWater, e.g. solver = "swe"): the diffuse
// particles of [foam] (foam.h) seeded from the grid's velocity instead of the particles'
// neighbourhoods, with Ihmsen et al.'s potentials read on the cells:
//   kinetic      I_k  = 0.5 |v|^2                                   (J/kg)
//   trapped air  I_ta = sum over the 4 neighbours n of max((v - v_n) . e_n, 0), e_n the
//                unit step to n (m/s: the flow converging, a jump; not the banks' shear)
//   wave crest   I_wc = |grad (bed + depth)|                         (the surface's slope)
// mapped by the same Phi(I, min, max) and [foam] thresholds; a wet cell emits
// Phi_k (rate_ta Phi_ta + rate_wc Phi_wc) dt (spacing / 0.5 m)^2 foam particles (the
// rates are per particle of the default river's 0.5 m spacing), at random places in the
// cell, on the surface. Each lives [lifetime_min, lifetime_max] seconds, rides the water's
// surface with the bilinear velocity and is removed when its life ends, it leaves the
// grid or its water is gone. Serial, counter-based random draws: deterministic.
#pragma once

#include <metariver/foam.h>
#include <metariver/solver.h>

#include <cstdint>
#include <span>

namespace mr {

class HeightfieldFoam {
public:
    explicit HeightfieldFoam(const FoamDef& def) : def_(def) {}

    /// Moves, ages and removes the foam, then emits from the water's current state.
    /// `bed`: the terrain's vertices (w.rows x w.columns).
    void step(const HeightfieldWater& w, std::span<const Vec3> bed, float dt, uint64_t frame);

    /// The hybrid: the particles' diffuse particles (`from`) under this water's surface,
    /// over water at least 5 cm deep (spray that fell into the pool), become foam on it at
    /// that place, with their life left (up to [foam] max_particles); returns how many.
    size_t take_landed(FoamSystem& from, const HeightfieldWater& w, std::span<const Vec3> bed);
    uint64_t landed_total() const { return landed_total_; }

    const DiffuseParticles& particles() const { return p_; }
    uint64_t generated_total() const { return generated_total_; }
    /// Particles per second that a wet sample emits now (before the random draw).
    float emission_rate(const HeightfieldWater& w, std::span<const Vec3> bed, int i, int j) const;

private:
    void advect(const HeightfieldWater& w, std::span<const Vec3> bed, float dt);
    void emit(const HeightfieldWater& w, std::span<const Vec3> bed, float dt, uint64_t frame);
    void push(const Vec3& position, const Vec3& velocity, float life);

    FoamDef def_;
    DiffuseParticles p_;
    uint64_t generated_total_ = 0, landed_total_ = 0;
    DiffuseParticles landed_;  ///< take_landed's
};

}  // namespace mr
