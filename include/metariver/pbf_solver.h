// metariver PBF solver: Position Based Fluids (Macklin and Mueller 2013;
// src/particles/pbf.cpp) from the solver parts (solver_parts.h): the density constraint
// over per-particle neighbour lists, the fluid's sliding collision, XSPH, vorticity
// confinement, sleeping; emission through the lattice sources.
#pragma once

#include <metariver/particles.h>
#include <metariver/solver_parts.h>

#include <array>
#include <span>
#include <vector>

namespace mr {

class PbfSolver final : public ParticleSolver {
public:
    PbfSolver(const Terrain& terrain, const Bvh& bvh, SpawnDef spawn, PbfDef pbf, CollisionDef collision,
              IntegratorDef integrator, uint32_t seed, SinkDef sink = {});
    /// Live edits (Simulation::apply): the rest density and the sources' lattices are
    /// recomputed from the new values; false, and nothing changed, when the budget changes.
    bool set_params(const SpawnDef& spawn, const PbfDef& pbf, const CollisionDef& collision,
                    const IntegratorDef& integrator, const SinkDef& sink);
    const PbfDef& def() const { return pbf_; }
    /// Rest number density (lattice sum of the poly6 kernel).
    float pbf_rest_density() const { return rest_density_; }

    /// One step of dt seconds (algorithm 1 of the paper; the stages in pbf.cpp).
    void step(float dt) override;
    ParticleWater& water() override { return water_; }
    const ParticleWater& water() const override { return water_; }

    /// A step's constants (kernels, lattice, switches): pbf_stages.h.
    struct Stage;

private:
    friend struct PbfProbe;  ///< the twin tests' hooks (src/particles/pbf_probe.h)

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

    // The stages of step(), in order.
    void predict(const Stage& s);
    void bin();
    void measure_walls();
    void iterate(const Stage& s);
    void density_pass(const Stage& s, const NeighborLists* nl, bool simd);
    void correction_pass(const Stage& s, const NeighborLists* nl, bool simd);
    void bed_friction(const Stage& s);
    ContactCounts collide(const Stage& s);
    void viscosity(const Stage& s);
    void xsph_simd(const Stage& s, const NeighborLists* nl);
    void damp(const Stage& s);
    void sleep(const Stage& s);
    void record_density_error();
    /// The neighbour lists for `passes` passes at the current positions, rebuilt when
    /// stale and worth it (passes >= 2); null: walk the 27 cells.
    const NeighborLists* lists(int passes);
    /// The lists' reach beyond h, metres.
    float list_skin() const { return pbf_list_skin_ * pbf_.kernel_radius; }

    /// Number density of every particle through the grid (after the cell sort) and by
    /// brute force over all active pairs: the twin tests compare them.
    void pbf_densities(std::vector<float>& out);
    void pbf_densities_brute_force(std::vector<float>& out) const;
    /// The terrain's share of a kernel centred at `x` (PbfDef::wall_density: the
    /// heightfield quadrature), in [0, 1], and its gradient w.r.t. x (into `grad`); 0
    /// (and grad 0) where no terrain is within h.
    float wall_share(const Vec3& x, Vec3& grad) const;
    void init_pbf();

    ParticleWater water_;
    Sleep sleep_;
    PbfDef pbf_;
    float rest_density_ = 1.0f;
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
};

}  // namespace mr
