// metariver solver: what the Simulation drives. A solver advances its water one frame at a
// time and shows it as particles (the paper's springs, PBF, Bullet's spheres), as a
// heightfield over the terrain's grid (water depth per sample), or both; the Simulation
// builds the one surface mesh from whichever it gets (scene.h). Solvers are registered by
// name in a SolverRegistry (solver_registry.h) with their factory and live-edit rule.
#pragma once

#include <metariver/core.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace mr {

class Terrain;  // terrain.h

struct Particles;  // particles.h

/// Counters a solver accumulates; tests and --stats read them.
struct SolverCounters {
    uint64_t particle_steps = 0;  ///< active particle integrations
    uint64_t collisions = 0;      ///< terrain hits handled
    uint64_t tunneled = 0;        ///< particle-steps ending below the mesh (lifted by the radius) after the collision response, before any guard
    uint64_t respawned = 0;       ///< particles re-spawned after leaving the terrain bounds
    uint64_t guarded = 0;         ///< robust mode: particle-steps the heightfield guard had to lift (each one also tunneled)
    uint64_t emitted = 0;         ///< particles emitted by a flow-rate source (activations and recycles)
    uint64_t sunk = 0;            ///< particles taken out by a sink (recycled to the source)
    /// Particle-steps ending inside a rigid body (bodies.h), counted after the coupling's
    /// response and before any correction pushes them out (as tunneled is for the terrain).
    uint64_t inside_bodies = 0;
    uint64_t substeps = 0;      ///< heightfield solvers (swe): time steps taken under the CFL limit
    uint64_t cell_updates = 0;  ///< heightfield solvers (swe): cells updated (wet spans, both stages), summed over steps
    // Latest step's state (not cumulative):
    float density_error_mean = 0.0f;  ///< PBF: mean over active particles of max(rho/rho0 - 1, 0)
    float density_error_max = 0.0f;   ///< PBF: max of rho/rho0 - 1
    float max_speed = 0.0f;           ///< fastest active particle, m/s
};

/// Water as a heightfield on the terrain's grid: plain data a solver fills and keeps
/// between frames. Sample (i, j) (row i along z, column j along x) lies at
/// x = origin.x + j spacing, z = origin.z + i spacing, over the terrain's sample (i, j);
/// arrays are row-major, index i * columns + j, like Terrain::vertices().
struct HeightfieldWater {
    int rows = 0, columns = 0;  ///< samples along z and x (the terrain's)
    Vec3 origin{0.0f};          ///< metres: sample (0, 0)'s x and z (y unused)
    float spacing = 1.0f;       ///< metres between neighbouring samples (Terrain::area_scale)
    std::vector<float> depth;   ///< metres of water above the bed per sample, >= 0; 0: dry
    std::vector<Vec3> velocity; ///< depth-averaged velocity per sample, m/s; empty: at rest
    /// Optional, one per row (empty: not known): row i's samples outside columns
    /// wet_first[i]..wet_last[i] have depth 0 and velocity 0 (wet_first > wet_last: the
    /// whole row). A solver that keeps them (swe) lets the readers that use them (the
    /// mesh, the foam) cost the wet cells, not the grid. Whoever changes depth keeps them true.
    std::vector<int> wet_first, wet_last;

    size_t size() const { return static_cast<size_t>(rows) * static_cast<size_t>(columns); }
    /// Row i's columns [first, second] outside which it is dry, within [0, columns - 1]
    /// (first > second: all dry): the spans where they are there, else the whole row.
    std::pair<int, int> wet_columns(int i) const {
        if (wet_first.size() != static_cast<size_t>(rows) || wet_last.size() != static_cast<size_t>(rows))
            return {0, columns - 1};
        return {std::max(wet_first[size_t(i)], 0), std::min(wet_last[size_t(i)], columns - 1)};
    }
};

/// What the Simulation drives: one implementation per `solver` scene value (the paper's
/// springs and PBF in particles.h, Bullet in bullet_solver.h, and whatever a registry
/// adds). A solver shows its water through water_particles(), water_heightfield() or
/// both (at least one non-null after construction). The interaction hooks below are
/// optional: their defaults do nothing, and the Simulation asks the solver's registry
/// entry (SolverEntry) whether to offer them.
class Solver {
public:
    virtual ~Solver() = default;
    /// Advances one rendered frame (spawning, substeps, collision, respawn).
    virtual void step_frame(float frame_dt) = 0;
    virtual const SolverCounters& counters() const = 0;
    virtual uint64_t frame() const = 0;

    /// The water as particles (read-only views for the field, the exporters, stats);
    /// null when the solver's water is not particles.
    virtual const Particles* water_particles() const { return nullptr; }
    /// The same particles for the Simulation's terrain edits (lifting the ones the ground
    /// rose over); null when there are none the Simulation may move.
    virtual Particles* editable_particles() { return nullptr; }
    /// The water as a heightfield over the terrain's grid; null when it is not.
    virtual const HeightfieldWater* water_heightfield() const { return nullptr; }

    /// Moves the spawn volume's centre (future activations and respawns start there).
    virtual void set_spawn_center(const Vec3& /*center*/) {}
    /// Pours water: moves the spawn centre to `center` and (re)spawns `count` particles
    /// there at once, taking inactive particles first, then the oldest-poured ones.
    virtual void pour(const Vec3& /*center*/, int /*count*/) {}
    /// Interaction: adds `velocity` x (1 - (d / radius)^2)^2 to the water within
    /// `radius` of `center` (d: the 3D distance), waking what slept. Returns how many
    /// particles it pushed (0: none, or a solver without pushable water).
    virtual size_t push(const Vec3& /*center*/, float /*radius*/, const Vec3& /*velocity*/) { return 0; }
    /// Activates particles at the given positions with the given velocities (as long
    /// as `positions`), in order, from the first inactive one; extras are ignored.
    virtual void place(std::span<const Vec3> /*positions*/, std::span<const Vec3> /*velocities*/) {}
    /// Non-fatal advice about the scene as this solver runs it on its terrain (e.g. a
    /// flow rate the source cannot deliver), one line each, naming the field.
    virtual std::vector<std::string> warnings() const { return {}; }
    /// Where the outlet-edge sink (SinkKind::Edges) took particles during the latest
    /// step_frame: each one's position at exit (just past the terrain's edge), in the
    /// solver's deterministic order. Empty for solvers without sinks.
    virtual std::span<const Vec3> last_exits() const { return {}; }
    /// The terrain's heights changed over samples rows i0..i1 (z), columns j0..j1 (x)
    /// (Simulation::sculpt / restore): a solver with its own copy of the bed reads them.
    virtual void terrain_edited(const Terrain& /*terrain*/, int /*i0*/, int /*i1*/, int /*j0*/, int /*j1*/) {}
};

}  // namespace mr
