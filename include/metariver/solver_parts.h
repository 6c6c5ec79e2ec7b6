// metariver solver parts: what the own particle solvers are made of. A solver HOLDS
// these (ParticleWater bundles them); none inherits them:
//  - ParticlePool: the particle arrays with the active prefix, the frame and the counters;
//  - Emitters: the spawn volume(s), the lattice sources, per-source credits and the one
//    RNG: every activation, respawn, placement and pour of SpringSolver, PbfSolver and
//    BulletSolver draws here, the same draws in the same order;
//  - Sinks: the exit flags after a step (left the terrain, a sink box, an outlet edge)
//    and where particles left over an edge;
//  - TerrainCollider: collision with the terrain under a response policy (the paper's,
//    the robust bounce, the fluid's slide), its guard and counts, and the one contact
//    loop both own solvers run;
//  - SortedGrid: the neighbour grid with the reordering of every array by cell.
// The force model (springs, PBF, Bullet's engine) stays with the solver.
#pragma once

#include <metariver/particles.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace mr {

/// Per-particle state a solver keeps beside Particles (PBF's sleep counters, Bullet's
/// bodies), told when a slot is (re)activated or pushed awake (reset), when two slots
/// swap (a deactivation), and when every array is reordered (new slot k = old perm[k]).
class SlotState {
public:
    virtual void reset(size_t i) = 0;
    virtual void swap(size_t i, size_t j) = 0;
    /// Slots [0, perm.size()) reordered (new slot k = old perm[k], perm a permutation of
    /// them); the slots past it keep their state.
    virtual void permute(std::span<const uint32_t> perm) = 0;

protected:
    ~SlotState() = default;
};

/// One solver's particles and their bookkeeping. Active particles form the prefix
/// [0, active()); a deactivated particle swaps with the last active one. `frame` stamps
/// births (Particles::birth_frame).
struct ParticlePool {
    /// `n` particles, all inactive at `at` (id = index).
    ParticlePool(size_t n, const Vec3& at);

    Particles particles;
    SolverCounters counters;
    uint64_t frame = 0;
    size_t next_to_activate = 0;  ///< active particles form the prefix [0, next_to_activate)
    uint32_t next_to_pour = 0;    ///< round-robin cursor over particle ids (Emitters::pour)
    SlotState* slots = nullptr;   ///< the solver's per-slot state, if any

    size_t size() const { return particles.size(); }
    /// The active prefix's length: per-slot passes stop there (the idle budget costs nothing).
    size_t active() const { return next_to_activate; }
    /// Inactive particles left.
    size_t free() const { return particles.size() - next_to_activate; }
    /// Particle i (re)starts at `x` with velocity `v`, born this frame.
    void activate(size_t i, const Vec3& x, const Vec3& v);
    /// Takes active particle i out (it joins the inactive pool; arrays stay a prefix).
    void deactivate(size_t i);
    /// The slot now holding particle `id` (size() when none).
    size_t slot_of_id(uint32_t id) const;
    /// Interaction: adds `velocity` x (1 - (d / radius)^2)^2 to every active particle
    /// within `radius` of `center` and wakes it. Returns how many it pushed.
    size_t push(const Vec3& center, float radius, const Vec3& velocity);
    /// counters.max_speed from the active particles' velocities.
    void record_max_speed();
};

/// How Emitters place water on their terrain.
struct EmitterDef {
    SpawnDef spawn;
    /// > 0: every activation goes through lattice sources of this spacing, metres (PBF);
    /// 0: random points of the source volumes (the paper's springs, Bullet).
    float lattice_spacing = 0.0f;
    /// A drawn point under the ground starts on it, at height + ground_lift +
    /// ground_offset (metres); the lattice keeps its slots that far above it too.
    bool on_ground = true;
    float ground_lift = 0.0f;
    float ground_offset = 0.0f;
    float gravity = 9.82f;  ///< m/s^2: how fast a lattice source with no inflow speed drains
};

/// The sources: spawn volumes, their lattices and credits, and the RNG of every draw.
class Emitters {
public:
    Emitters(const Terrain& terrain, EmitterDef def, uint32_t seed);

    /// Live edits: new def, the credits of the remaining sources kept. The lattices are
    /// not rebuilt (build_lattices()).
    void set_def(const EmitterDef& def);
    const SpawnDef& spawn_def() const { return def_.spawn; }
    /// Moves the main source (future activations and respawns start there).
    void set_center(const Vec3& center);
    /// The lattices of every source (def.lattice_spacing > 0).
    void build_lattices();

    /// Every activation goes through the sources' lattices (built).
    bool uses_lattice() const { return !sources_.empty() && sources_[0].lattice.has_value(); }
    /// The scene emits by rate (SpawnDef::has_rate).
    bool by_rate() const { return def_.spawn.has_rate(); }
    /// Sources: the main one and SpawnDef::sources.
    size_t source_count() const { return 1 + def_.spawn.sources.size(); }
    const LatticeSource* lattice_source(size_t k = 0) const;
    /// Particles per second source k emits: its rate, capped to what its lattice delivers.
    float emit_rate(size_t k = 0) const;
    /// Lattice sources that cannot emit or not at their rate, one line each.
    std::vector<std::string> warnings() const;

    /// Particle i at a random point of source k's volume, with the initial velocity.
    void spawn(ParticlePool& pool, size_t i, size_t k = 0);
    /// The paper's activation: when the frame is due (every spawn.interval frames), one
    /// particle (all of them for interval 0) at random points of the main volume.
    void activate_due(ParticlePool& pool);
    /// Activates particles at the given positions (velocities: the initial one where
    /// `velocities` is shorter), from the first inactive one; extra positions are ignored.
    void place(ParticlePool& pool, std::span<const Vec3> positions, std::span<const Vec3> velocities);
    /// Moves the main source to `center` and (re)spawns `count` particles there,
    /// inactive ones first, then the oldest-poured (lattice: as its slots free up).
    void pour(ParticlePool& pool, const Vec3& center, int count);
    /// Start of a frame: the activations due before its steps.
    void begin_frame(ParticlePool& pool);
    /// After each step of h seconds: the sources emit what they owe.
    void after_step(ParticlePool& pool, float h);
    /// A particle went back to the pool and the main source owes it (lattice, no rate).
    void owe_one() { sources_[0].credit += 1.0; }

private:
    /// Source k's volume: centre and half extent (0: the main source).
    std::pair<Vec3, Vec3> volume(size_t k) const;
    /// Particles per second source k asks for, before any cap.
    float asked_rate(size_t k) const;
    void emit(ParticlePool& pool, float dt);
    void emit_lattice(ParticlePool& pool, size_t k);

    const Terrain& terrain_;
    EmitterDef def_;
    Lcg rng_;
    /// Per source (0: the main one, then SpawnDef::sources): the particles it owes (a
    /// fraction carried over) and its lattice.
    struct Source {
        double credit = 0.0;
        std::optional<LatticeSource> lattice;
    };
    std::vector<Source> sources_;
    std::vector<Vec3> slots_;  ///< scratch of emit_lattice()
};

/// True when `p` has left the terrain: below its box, outside its x/z rectangle, or not finite.
bool outside_terrain(const Terrain& terrain, const Vec3& p);

/// Where particles leave: after a step each particle is flagged (Exit), and particles
/// that left over an outlet edge are recorded where they left.
class Sinks {
public:
    enum Exit : uint8_t {
        Stay = 0,
        Respawn = 1,  ///< left the terrain (not through a sink)
        Box = 2,      ///< in a sink box
        Edge = 3,     ///< over an outlet edge (SinkKind::Edges)
    };
    Sinks(const Terrain& terrain, SinkDef def, size_t n);
    void set_def(const SinkDef& def) { def_ = def; }
    Exit exit_of(const Vec3& p) const;
    /// Flags the first `count` particles (the active prefix; inactive ones Stay); parallel.
    /// Only those flags are read (ParticleWater::finish_step).
    void flag_exits(const Particles& p, size_t count);
    Exit flag(size_t i) const { return Exit(flags_[i]); }
    /// Counts a particle at `x` as sunk; one over an edge is recorded (last_exits).
    void record_sunk(SolverCounters& counters, const Vec3& x, bool over_an_edge);
    void clear_exits() { exits_.clear(); }
    std::span<const Vec3> last_exits() const { return exits_; }

private:
    const Terrain& terrain_;
    SinkDef def_;
    std::vector<uint8_t> flags_;
    std::vector<Vec3> exits_;  ///< reused, no allocation once warm
};

/// How the collider answers a hit.
enum class ContactResponse {
    None,    ///< no collision (CollisionMode::None): only the tunneled count
    Paper,   ///< the paper's leaf query and reflection (CollisionMode::Paper)
    Bounce,  ///< swept robust query, reflect and damp, re-checked (CollisionMode::Robust)
    Slide,   ///< swept robust query, the motion's normal part removed (the fluid's, PBF)
};
/// Springs follow CollisionDef::mode; a fluid slides whenever the mode collides.
ContactResponse contact_response(CollisionMode mode, bool fluid);

/// Particle-steps and what the collider did in them (summed over threads).
struct ContactCounts {
    uint64_t steps = 0;
    uint64_t collisions = 0;
    uint64_t guarded = 0;
    uint64_t tunneled = 0;
};

/// Terrain collision with a response policy. Runs on the particle's centre moved down
/// by CollisionDef::radius (the terrain lifted by it).
class TerrainCollider {
public:
    TerrainCollider(const Terrain& terrain, const Bvh& bvh, CollisionDef def, bool fluid);
    void set_def(const CollisionDef& def);
    const CollisionDef& def() const { return def_; }
    ContactResponse response() const { return response_; }
    const Terrain& terrain() const { return terrain_; }

    /// The one contact loop: collides every active particle of the first `count` (the
    /// solvers pass their active prefix; default: every slot) that moved last_position ->
    /// position in a step of dt (parallel; counts tunneled before any correction).
    ContactCounts collide_active(Particles& p, float dt, size_t count = SIZE_MAX) const;
    /// Collide particle i (touches only particle i).
    void collide(Particles& p, size_t i, float dt, ContactCounts& c) const;
    /// Moves a predicted position out of the lifted terrain along the triangle normal
    /// to `offset` above it (or back to `fallback` where that fails); true when it had to.
    bool push_out(Vec3& x, const Vec3& fallback) const;
    /// The swept robust query (with its contact skin): the segment's first hit.
    std::optional<RayHit> robust_hit(const Vec3& from, const Vec3& to) const;
    /// True when `lifted` (a centre moved down by the radius) is below the mesh.
    bool ends_below(const Vec3& lifted) const;

private:
    void collide_paper(Particles& p, size_t i, float dt, ContactCounts& c) const;
    void sweep(Particles& p, size_t i, float dt, ContactCounts& c) const;
    /// Counts a particle-step that ended below the mesh (`to` lifted) as tunneled, then
    /// lifts it onto the mesh (+ offset) and counts guarded.
    void count_and_guard(Vec3& to, Vec3& v, ContactCounts& c) const;

    const Terrain& terrain_;
    const Bvh& bvh_;
    CollisionDef def_;
    bool fluid_ = false;
    ContactResponse response_ = ContactResponse::Paper;
};

/// The neighbour grid over the active particles, with every array of the pool (and
/// its SlotState) reordered by cell for locality; Particles::id keeps identities.
class SortedGrid {
public:
    /// Bins the active particles (cell size at least 1 mm) and reorders by cell.
    void sort(ParticlePool& pool, float cell);
    const NeighborGrid& grid() const { return grid_; }

private:
    NeighborGrid grid_;
    // Reorder scratch (reused; no allocation once warm).
    std::vector<uint32_t> perm_;
    std::vector<Vec3> scratch_vec_;
    std::vector<uint32_t> scratch_id_;
};

/// What an own solver's water is made of: the parts above over one terrain, and the
/// frame loop that runs a force model's step between the emitters and the sinks.
/// Deterministic for a seed; not copyable (the terrain and tree are referenced).
struct ParticleWater {
    /// `lattice_spacing` > 0: activations through lattice sources (PbfSolver builds
    /// them: emitters.build_lattices()); `fluid`: the collider slides (PBF).
    ParticleWater(const Terrain& terrain, const Bvh& bvh, const SpawnDef& spawn, const CollisionDef& collision,
                  const IntegratorDef& integrator, uint32_t seed, const SinkDef& sink, float lattice_spacing,
                  bool fluid);
    ParticleWater(const ParticleWater&) = delete;
    ParticleWater& operator=(const ParticleWater&) = delete;

    /// Live edits; false, and nothing changed, when the budget (spawn.count) would change.
    bool set_shared(const SpawnDef& spawn, const CollisionDef& collision, const IntegratorDef& integrator,
                    const SinkDef& sink, float lattice_spacing);

    /// One rendered frame: the activations due, then `substeps` calls of step(h)
    /// (h = dt / substeps, dt = fixed_dt when set, else frame_dt), the sources emitting
    /// after each.
    template <class Step>
    void step_frame(float frame_dt, Step&& step) {
        sinks.clear_exits();
        emitters.begin_frame(pool);
        const float dt = integrator.fixed_dt > 0.0f ? integrator.fixed_dt : frame_dt;
        const int sub = integrator.substeps > 1 ? integrator.substeps : 1;
        const float h = dt / static_cast<float>(sub);
        for (int s = 0; s < sub; ++s) {
            // Emit after the step: particles a sink took out this step are back at once
            // when the rate allows, so the budget stays in the river.
            step(h);
            emitters.after_step(pool, h);
        }
        ++pool.frame;
    }
    /// End of a step whose exits are flagged (sinks.flag_exits): the counts added, the
    /// particles that left respawned or returned to the pool, the max speed.
    void finish_step(const ContactCounts& c);

    IntegratorDef integrator;
    ParticlePool pool;
    Emitters emitters;
    Sinks sinks;
    TerrainCollider collider;
    SortedGrid grid;

private:
    static EmitterDef emitter_def(const SpawnDef& spawn, const CollisionDef& collision,
                                  const IntegratorDef& integrator, float lattice_spacing);
};

/// The Solver interface answered from a ParticleWater that the derived solver holds
/// (SpringSolver, PbfSolver): no state and no physics of its own, only the frame loop
/// around the derived force model's step() and the interface forwarded to the parts,
/// written once for both solvers.
class ParticleSolver : public Solver {
public:
    /// Advances one rendered frame: the activations due, then `substeps` steps.
    void step_frame(float frame_dt) final {
        water().step_frame(frame_dt, [this](float h) { step(h); });
    }
    /// One step of dt seconds of the force model (forces, integrate, collide, exits).
    virtual void step(float dt) = 0;
    /// The parts this solver runs on.
    virtual ParticleWater& water() = 0;
    virtual const ParticleWater& water() const = 0;

    const Particles& particles() const { return water().pool.particles; }
    Particles& particles_mut() { return water().pool.particles; }
    const Particles* water_particles() const final { return &water().pool.particles; }
    Particles* editable_particles() final { return &water().pool.particles; }
    const SolverCounters& counters() const final { return water().pool.counters; }
    uint64_t frame() const final { return water().pool.frame; }
    void set_spawn_center(const Vec3& center) final { water().emitters.set_center(center); }
    void pour(const Vec3& center, int count) final { water().emitters.pour(water().pool, center, count); }
    std::vector<std::string> warnings() const final { return water().emitters.warnings(); }
    /// step_frame clears the list; every step() (substep) appends its exits.
    std::span<const Vec3> last_exits() const final { return water().sinks.last_exits(); }
    /// Adds `velocity` x (1 - (d / radius)^2)^2 to every active particle within `radius`
    /// of `center` (d: the 3D distance) and wakes it if it slept. Returns how many it pushed.
    size_t push(const Vec3& center, float radius, const Vec3& velocity) final {
        return water().pool.push(center, radius, velocity);
    }
    /// Activates particles at the given positions (with `velocities`, or the initial
    /// velocity past its end), in order, from the first inactive one; extras are ignored.
    void place(std::span<const Vec3> positions, std::span<const Vec3> velocities) final {
        water().emitters.place(water().pool, positions, velocities);
    }
    void place(std::span<const Vec3> positions) { place(positions, {}); }
    /// Places particle i at a random point of source k's volume (0: the main source).
    void spawn(size_t i, size_t k = 0) { water().emitters.spawn(water().pool, i, k); }
    /// Takes active particle i out (it joins the inactive pool; arrays stay a prefix).
    void deactivate(size_t i) { water().pool.deactivate(i); }
    /// The lattice source k (PBF; 0: the main one, k >= 1: SpawnDef::sources[k - 1]).
    const LatticeSource* lattice_source(size_t k = 0) const { return water().emitters.lattice_source(k); }
    /// Particles per second source k emits: its rate, capped to what its lattice delivers.
    float emit_rate(size_t k = 0) const { return water().emitters.emit_rate(k); }
    size_t source_count() const { return water().emitters.source_count(); }
    /// The neighbour grid of the latest step (grid spring mode, PBF).
    const NeighborGrid& grid() const { return water().grid.grid(); }
};

}  // namespace mr
