// metariver PBF solver: Position Based Fluids (Macklin and Mueller 2013;
// src/particles/pbf.cpp) from the solver parts (solver_parts.h): the density constraint
// over per-particle neighbour lists, the fluid's sliding collision, XSPH, vorticity
// confinement, sleeping; emission through the lattice sources.
#pragma once

#include <metariver/bodies.h>
#include <metariver/particles.h>
#include <metariver/solver_parts.h>

#include <memory>
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

    /// Rigid bodies two-way coupled with the water (bodies.h; src/particles/pbf_bodies.cpp):
    /// the Simulation's add_body, remove_body, set_body_motion and bodies() (scene.h).
    Result<uint32_t> add_body(const BodyDef& def);
    Status remove_body(uint32_t id);
    Status set_body_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                           const Vec3& angular_velocity);
    std::span<const BodyState> bodies() const;

    /// One step of dt seconds (algorithm 1 of the paper; the stages in pbf.cpp).
    void step(float dt) override;
    ParticleWater& water() override { return water_; }
    const ParticleWater& water() const override { return water_; }

    PbfSolver(const PbfSolver&) = delete;
    PbfSolver& operator=(const PbfSolver&) = delete;
    ~PbfSolver() override;

    /// A step's constants (kernels, lattice, switches): pbf_stages.h.
    struct Stage;
    /// The solver's working arrays (per-particle step state, neighbour lists, the SIMD
    /// passes' caches, sleep counters): src/particles/pbf_state.h, not part of the API.
    struct State;

private:
    // The stages of step(), in order.
    void predict(const Stage& s);
    void bin();
    void measure_walls();
    void iterate(const Stage& s);
    void density_pass(const Stage& s, const NeighborLists* nl, bool simd);
    void correction_pass(const Stage& s, const NeighborLists* nl, bool simd);
    void bed_friction(const Stage& s);
    // The bodies' coupling (pbf_bodies.cpp).
    void assign_bodies(const Stage& s);
    void push_out_of_bodies(const Stage& s, bool into_velocity);
    void react_on_bodies(float dt, bool into_velocity);
    void drag_bodies(const Stage& s);
    void clear_body_volume(uint32_t id);
    void count_inside_bodies(const Stage& s);
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
    float list_skin() const;

    void init_pbf();

    ParticleWater water_;
    PbfDef pbf_;
    float rest_density_ = 1.0f;
    std::unique_ptr<State> st_;
};

}  // namespace mr
