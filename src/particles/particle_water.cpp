// The own solvers' water: the parts of solver_parts.h put together, and the sinks.
// After every step each particle is flagged: still on the terrain, out of its bounds
// (re-spawned at the source, the paper), in a sink box, or over an outlet edge (both
// recycled to the sources, or at once to the main one without a flow rate). Whatever
// draws random numbers runs serially in index order, so results do not depend on the
// thread count.
#include <metariver/solver_parts.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace mr {

bool outside_terrain(const Terrain& terrain, const Vec3& p) {
    return p.y < terrain.bounds().min.y || !terrain.contains_xz(p.x, p.z) || !std::isfinite(p.y);
}

Sinks::Sinks(const Terrain& terrain, SinkDef def, size_t n) : terrain_(terrain), def_(std::move(def)), flags_(n, 0) {}

Sinks::Exit Sinks::exit_of(const Vec3& p) const {
    if (def_.in_a_box(p)) return Box;
    if (!outside_terrain(terrain_, p)) return Stay;
    // Over an edge (not through the bottom): an outlet.
    if (def_.kind == SinkKind::Edges && std::isfinite(p.y) && p.y >= terrain_.bounds().min.y && std::isfinite(p.x) &&
        std::isfinite(p.z))
        return Edge;
    return Respawn;
}

void Sinks::flag_exits(const Particles& p, size_t count) {
    const auto flag = [&](size_t b, size_t e) {
        for (size_t i = b; i != e; ++i) flags_[i] = p.active[i] ? exit_of(p.position[i]) : Stay;
    };
    constexpr size_t kGrain = 1024;
    const size_t n = std::min(count, p.size());
    if (n <= kGrain) return flag(0, n);  // one block: no task
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kGrain), [&](const tbb::blocked_range<size_t>& r) { flag(r.begin(), r.end()); });
}

void Sinks::record_sunk(SolverCounters& counters, const Vec3& x, bool over_an_edge) {
    ++counters.sunk;
    if (over_an_edge) exits_.push_back(x);
}

EmitterDef ParticleWater::emitter_def(const SpawnDef& spawn, const CollisionDef& collision,
                                      const IntegratorDef& integrator, float lattice_spacing) {
    return EmitterDef{.spawn = spawn,
                      .lattice_spacing = lattice_spacing,
                      .on_ground = collision.mode != CollisionMode::None,
                      .ground_lift = collision.radius,
                      .ground_offset = collision.offset,
                      .gravity = integrator.gravity};
}

ParticleWater::ParticleWater(const Terrain& terrain, const Bvh& bvh, const SpawnDef& spawn,
                             const CollisionDef& collision, const IntegratorDef& integrator, uint32_t seed,
                             const SinkDef& sink, float lattice_spacing, bool fluid)
    : integrator(integrator),
      pool(static_cast<size_t>(std::max(spawn.count, 0)), spawn.center),
      emitters(terrain, emitter_def(spawn, collision, integrator, lattice_spacing), seed),
      sinks(terrain, sink, pool.size()),
      collider(terrain, bvh, collision, fluid) {}

bool ParticleWater::set_shared(const SpawnDef& spawn, const CollisionDef& collision, const IntegratorDef& integrator,
                               const SinkDef& sink, float lattice_spacing) {
    if (spawn.count != emitters.spawn_def().count) return false;
    emitters.set_def(emitter_def(spawn, collision, integrator, lattice_spacing));
    collider.set_def(collision);
    this->integrator = integrator;
    sinks.set_def(sink);
    return true;
}

void ParticleWater::finish_step(const ContactCounts& c) {
    SolverCounters& counters = pool.counters;
    counters.particle_steps += c.steps;
    counters.collisions += c.collisions;
    counters.guarded += c.guarded;
    counters.tunneled += c.tunneled;
    const Particles& p = pool.particles;
    const size_t n = pool.active();  // the flagged prefix (the slots past it are idle)
    const bool by_rate = emitters.by_rate();
    if (emitters.uses_lattice()) {
        // PBF: out of bounds or sunk, every particle goes back to the pool; without a
        // flow rate the source owes it back at once (it re-emits as slots free up).
        for (size_t i = n; i-- > 0;) {
            const Sinks::Exit e = sinks.flag(i);
            if (e == Sinks::Stay) continue;
            if (e == Sinks::Respawn) ++counters.respawned;
            else sinks.record_sunk(counters, p.position[i], e == Sinks::Edge);
            pool.deactivate(i);
            if (!by_rate) emitters.owe_one();
        }
        pool.record_max_speed();
        return;
    }
    // Serial, in index order: the RNG sequence does not depend on the thread count.
    for (size_t i = 0; i < n; ++i) {
        const Sinks::Exit e = sinks.flag(i);
        if (e == Sinks::Respawn) {
            ++counters.respawned;
            emitters.spawn(pool, i);
        } else if (e >= Sinks::Box && !by_rate) {
            sinks.record_sunk(counters, p.position[i], e == Sinks::Edge);  // no flow rate: straight back to the source
            emitters.spawn(pool, i);
        }
    }
    if (by_rate) {  // recycled into the pool, highest index first (swaps only move processed slots)
        for (size_t i = n; i-- > 0;)
            if (sinks.flag(i) >= Sinks::Box) {
                sinks.record_sunk(counters, p.position[i], sinks.flag(i) == Sinks::Edge);
                pool.deactivate(i);
            }
    }
    pool.record_max_speed();
}

}  // namespace mr
