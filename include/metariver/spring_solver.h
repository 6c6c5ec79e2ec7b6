// metariver spring solver: the paper's particles (section 2.3) from the solver parts
// (solver_parts.h): gravity plus Hooke springs between particles (eq. 3), semi-implicit
// Euler, and the terrain collider in the paper's mode or the robust one.
#pragma once

#include <metariver/particles.h>
#include <metariver/solver_parts.h>

namespace mr {

/// The paper's particles: springs (the all-pairs loop or its grid twin) on the water's
/// parts; random points of the spawn volume. Deterministic for a seed.
class SpringSolver final : public ParticleSolver {
public:
    SpringSolver(const Terrain& terrain, const Bvh& bvh, SpawnDef spawn, SpringDef springs, CollisionDef collision,
                 IntegratorDef integrator, uint32_t seed, SinkDef sink = {});
    /// Live edits (Simulation::apply): false, and nothing changed, when the budget changes.
    bool set_params(const SpawnDef& spawn, const SpringDef& springs, const CollisionDef& collision,
                    const IntegratorDef& integrator, const SinkDef& sink);

    /// One integration step of dt seconds (forces, integrate, collide, respawn).
    void step(float dt) override;
    ParticleWater& water() override { return water_; }
    const ParticleWater& water() const override { return water_; }

private:
    ParticleWater water_;
    SpringDef springs_;
};

}  // namespace mr
