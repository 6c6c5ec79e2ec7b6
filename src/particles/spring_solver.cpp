// The paper's particles (section 2.3) on the solver parts: gravity plus springs
// (springs.cpp), semi-implicit Euler (v += a dt; last = p; p += v dt), then the terrain
// collider's contact loop (the paper's mode or the robust one), the sinks' exit flags
// and the emitters' respawns (ParticleWater::finish_step).
#include <metariver/spring_solver.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace mr {

SpringSolver::SpringSolver(const Terrain& terrain, const Bvh& bvh, SpawnDef spawn, SpringDef springs,
                           CollisionDef collision, IntegratorDef integrator, uint32_t seed, SinkDef sink)
    : water_(terrain, bvh, spawn, collision, integrator, seed, sink, 0.0f, false), springs_(springs) {}

bool SpringSolver::set_params(const SpawnDef& spawn, const SpringDef& springs, const CollisionDef& collision,
                              const IntegratorDef& integrator, const SinkDef& sink) {
    if (!water_.set_shared(spawn, collision, integrator, sink, 0.0f)) return false;
    springs_ = springs;
    return true;
}

void SpringSolver::step(float dt) {
    Particles& p = water_.pool.particles;
    const bool grid_springs = springs_.mode == SpringMode::Grid;
    if (grid_springs) water_.grid.sort(water_.pool, spring_reach(springs_));

    const Vec3 g(0.0f, -water_.integrator.gravity, 0.0f);
    std::fill(p.force.begin(), p.force.end(), g);
    if (springs_.stiffness != 0.0f) {
        if (grid_springs)
            add_spring_forces_grid(p, water_.grid.grid(), springs_);
        else
            add_spring_forces_pairs(p, springs_);
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            if (!p.active[i]) continue;
            p.velocity[i] += p.force[i] * dt;
            p.last_position[i] = p.position[i];
            p.position[i] += p.velocity[i] * dt;
        }
    });
    const ContactCounts c = water_.collider.collide_active(p, dt, water_.pool.active());
    water_.sinks.flag_exits(p, water_.pool.active());
    water_.finish_step(c);
}

}  // namespace mr
