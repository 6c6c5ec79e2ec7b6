// metariver particles: the particle set (structure of arrays), the paper's spring
// forces, semi-implicit Euler integration and terrain collision.
//
// Paper: "Real-time river simulation using metaballs", section 2.3: gravity, Hooke
// springs between particles (eq. 3), semi-implicit Euler, and collisions with the
// terrain through its AABB tree (2.3.3): reflect about the triangle normal, damp,
// place at hit + offset up + v dt.
#pragma once

#include <metariver/core.h>
#include <metariver/emitters.h>
#include <metariver/neighbor_grid.h>
#include <metariver/solver.h>
#include <metariver/terrain.h>

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mr {

/// Particles as structure of arrays. Hot data (position, velocity) lives in arrays
/// of its own so the force and integration loops stream through memory; `active`
/// marks particles that have spawned (the paper activates one every spawn_interval
/// frames). Active particles always form a prefix [0, active_count). The grid solver
/// reorders every array by neighbour-grid cell each step for locality; `id` is the
/// stable identity that survives the reordering (id == index while nothing reorders).
struct Particles {
    std::vector<Vec3> position;       ///< metres
    std::vector<Vec3> last_position;  ///< position before the latest integration, metres
    std::vector<Vec3> velocity;       ///< metres per second
    std::vector<Vec3> force;          ///< accumulated acceleration this step, m/s^2 (unit mass)
    std::vector<uint8_t> active;      ///< 1 once spawned
    std::vector<uint32_t> id;         ///< stable particle id
    /// Solver frame at the particle's latest emission (spawn, respawn or recycle), so
    /// exporters can give its age: (frame() - birth_frame) frames. Cold data, moved with
    /// the particle when the arrays are reordered.
    std::vector<uint32_t> birth_frame;

    size_t size() const { return position.size(); }
    void resize(size_t n);
    size_t active_count() const;
    /// Positions of the active particles, in index order, into `out` (cleared first).
    void gather_active_positions(std::vector<Vec3>& out) const;
};

/// How long a PBF particle must stay slower than `PbfDef::sleep_threshold` to fall asleep.
inline constexpr float kSleepAfterSeconds = 0.1f;
/// PBF sleep threshold cap, as a fraction of the speed gravity gives in one step: an
/// asleep particle with nothing under it moves faster than that in its first step.
inline constexpr float kSleepCapOfFallStep = 0.9f;

/// Skin of the PBF neighbour lists, as a fraction of h: the lists hold the pairs within
/// h (1 + skin) at the step's binning and are rebuilt once a particle has moved 0.45
/// skin since (NeighborLists::stale). 10 % of h: 1.33x the pairs within h, and a step's
/// density corrections rarely move a particle that far.
inline constexpr float kPbfListSkin = 0.1f;

/// Largest particle budget a scene may ask for.
inline constexpr int kMaxParticles = 10'000'000;
/// `SpawnDef::count` asking for a budget sized to the terrain (`particles.count = "auto"`).
inline constexpr int kAutoCount = 0;
/// `SpawnDef::flow_rate` asking for a rate sized to the terrain (`particles.flow_rate = "auto"`).
inline constexpr float kAutoRate = -1.0f;
/// PbfDef::sleep_threshold: the still-water default, and "auto" (resolved per scene).
inline constexpr float kSleepThreshold = 0.065f;
inline constexpr float kAutoSleep = -1.0f;
/// PbfDef::damping: the still-water default (1/s), and "auto" (resolved per scene).
inline constexpr float kStillDamping = 1.0f;
inline constexpr float kAutoDamping = -1.0f;
/// PbfDef::wall_density: the still-water default (weight), and "auto" (resolved per scene).
inline constexpr float kStillWallDensity = 1.0f;
inline constexpr float kAutoWallDensity = -1.0f;
/// PbfDef::contact_band: the still-water default (spacings), and "auto" (resolved per scene).
inline constexpr float kStillContactBand = 1.5f;
inline constexpr float kAutoContactBand = -1.0f;
/// Time constant (s) of the mean velocity PbfDef::sleep_drift is judged on, and the
/// default scene's sleep_drift (m/s).
inline constexpr float kSleepDriftSeconds = 0.5f;
inline constexpr float kStillSleepDrift = 0.015f;

/// Share of a poly6 kernel (support `h`) that lies beyond a plane at `distance` from its
/// centre, in [0, 1] (0.5 on the plane, 0 at h or farther, 1 at -h or deeper): the
/// closed form of what PbfDef::wall_density adds for flat ground (tests check the
/// heightfield quadrature against it).
float pbf_wall_share(float distance, float h);

struct SpawnDef {
    int count = 20;                          ///< particle budget, [1, kMaxParticles]; kAutoCount: sized to the terrain (PBF)
    Vec3 center{8.0f, 7.0f, 15.0f};          ///< spawn volume centre, metres
    Vec3 half_extent{2.0f, 1.0f, 0.2f};      ///< spawn volume half size, metres (>= 0)
    int interval = 80;                       ///< frames between two activations, [0, 1e6]; 0 = all at once
    Vec3 initial_velocity{0.0f};             ///< velocity given at (re)spawn, m/s
    /// When true, `center` is ignored and the spawn volume is placed `auto_height`
    /// metres above the lowest sample of the terrain's upstream band (the 10 % of rows
    /// with the highest z): the head of the valley for the procedural river.
    bool auto_center = false;
    float auto_height = 2.0f;                ///< metres above the ground for auto_center, [0, 1e4]
    /// With auto_center: place the source at the head of the terrain's main channel
    /// (ChannelMap::main_head) instead of the upstream band's lowest sample.
    bool auto_channel = false;
    SourceShape shape = SourceShape::Box;    ///< shape of the spawn volume
    /// Emission rate, particles per second, [0, 1e7]; 0 = the paper's activation of one
    /// particle every `interval` frames. With a rate, particles recycled by a sink wait
    /// in the pool until the source emits them again.
    float flow_rate = 0.0f;
    /// > 0: `flow_rate` is given in litres per second and each particle carries this
    /// many litres; 0: `flow_rate` is in particles per second.
    float litres_per_particle = 0.0f;
    /// `flow_rate == kAutoRate` (`particles.flow_rate = "auto"`, the default river's):
    /// derived from the terrain's main channel when a PBF simulation is created
    /// (size_river in scene.h); any other value is used as given.
    bool auto_rate() const { return flow_rate == kAutoRate; }
    /// The scene (Simulation, solver = pbf on a carved channel) fills the main channel
    /// with water at the start, so the river runs from the first frame; the solver
    /// itself ignores it. (particles.prefill; docs/river.md, "Quadratic bed friction and a channel that starts full".)
    bool prefill = false;
    /// PBF with a rate (the lattice source): each column of the source's slots is lowered
    /// until its lowest slot sits just above the ground under it, so water on a slope is
    /// born on the ground instead of falling from a flat disc metres above its downhill
    /// side (particles.follow_ground; strict17.png's spray 0.035 -> 0.003, docs/river.md).
    bool follow_ground = false;
    /// More sources (`[[particles.source]]`, at most kMaxMoreSources), emitting with
    /// the main one when the scene has a particle rate (has_rate()).
    std::vector<SourceDef> sources;
    /// Particles per second the (main) source emits.
    float particles_per_second() const {
        if (auto_rate()) return 0.0f;  // not known before the terrain is
        return per_second(flow_rate);
    }
    /// Particles per second more source k emits.
    float particles_per_second(size_t k) const { return per_second(sources[k].flow_rate); }
    /// The main source and every more source together, particles per second.
    float total_particles_per_second() const {
        float r = particles_per_second();
        for (size_t k = 0; k < sources.size(); ++k) r += particles_per_second(k);
        return r;
    }
    /// Emission by rate (the sources owe rate x time) rather than the paper's activation
    /// every `interval` frames: a rate on the main source or on any more source.
    bool has_rate() const { return total_particles_per_second() > 0.0f; }

private:
    float per_second(float rate) const { return litres_per_particle > 0.0f ? rate / litres_per_particle : rate; }
};

/// Position Based Fluids (Macklin and Mueller 2013). The rest density is the kernel
/// sum of a cubic lattice of `spacing` (so a perfect lattice has zero error); every
/// quantity below is in units of that number density.
struct PbfDef {
    float spacing = 0.5f;        ///< rest particle spacing d, metres, (0, 1e3]
    float kernel_radius = 1.0f;  ///< smoothing length h, metres, (spacing, 4 spacing]
    int iterations = 3;          ///< density-constraint iterations per step, [1, 100]
    float relaxation = 0.05f;    ///< constraint force mixing eps, relative to a lattice particle's sum |grad C|^2, (0, 1e3]
    float scorr_k = 0.01f;       ///< tensile correction strength k (relative to a lattice particle's lambda at C = 1), [0, 1]
    int scorr_n = 4;             ///< tensile correction exponent n, [1, 8]
    float scorr_dq = 0.3f;       ///< tensile correction reference distance, fraction of h, (0, 1)
    float xsph = 0.05f;          ///< XSPH viscosity c, [0, 1]
    float vorticity = 0.0f;      ///< vorticity confinement epsilon, m/s^2 scale, [0, 100]; 0 = off
    /// Sleeping (after NVIDIA FleX's sleepThreshold), m/s, [0, 1]; 0 = off: a particle
    /// slower than this for kSleepAfterSeconds falls asleep, and while asleep a step
    /// that would move it slower than this is undone (position kept, velocity zero); a
    /// faster step wakes it. Still water comes to rest instead of creeping; anything
    /// moving faster is untouched. Capped at kSleepCapOfFallStep x gravity x the step
    /// (0.074 m/s at 120 steps/s under 9.82): an unsupported particle never stays asleep.
    /// 0.065: at 0.05 a last particle or two on a settled pool's surface still rolled at
    /// 0.1-0.25 m/s after 10 s in 3 of 5 pools of 2300-2700 particles; at 0.065 none of 8.
    /// kAutoSleep (`pbf.sleep_threshold = "auto"`, the default scene's): Simulation::create
    /// resolves it to 0 for a river and kSleepThreshold otherwise (resolved_sleep_threshold).
    float sleep_threshold = kSleepThreshold;
    bool auto_sleep() const { return sleep_threshold == kAutoSleep; }
    /// Sleeping also asks for a small mean horizontal velocity, m/s, [0, 1]; 0 = off: a
    /// particle falls asleep only while the exponential average of its horizontal
    /// velocity (time constant kSleepDriftSeconds) is slower than this. A slosh's turn
    /// is slow for a moment, its average is not: without it a pool froze mid-slosh,
    /// tilted (docs/rendering.md, "Still water that is level"). The default scene's is kStillSleepDrift; 0 in a
    /// bare PbfDef.
    float sleep_drift = 0.0f;
    /// Slow-water damping, 1/s, [0, 100]; 0 = off: every step a particle's velocity is
    /// scaled by exp(-damping s dt), s = 1 below `damping_speed`, falling linearly to 0
    /// at twice it (faster water is never damped): a pool's slosh dies out before it
    /// falls asleep. kAutoDamping (the default scene's): 0 for a river, kStillDamping
    /// otherwise (resolved_damping in scene.h). 0 in a bare PbfDef.
    float damping = 0.0f;
    bool auto_damping() const { return damping == kAutoDamping; }
    float damping_speed = 1.0f;  ///< m/s, (0, 1000]: full damping below, none above twice it
    /// The terrain counts in each particle's density: the share of its kernel that lies
    /// under the terrain (a quadrature over the heightfield around the particle, so a
    /// steep wall beside it and the crease at a wall's foot count as well as the ground
    /// below), with its gradient in the constraint. Water at the bed and banks is then
    /// held at the rest spacing by pressure, and a pool is level to its shore (0:
    /// SPH's particle deficiency at a wall; the still pool's surface rose 4-7 cm to the
    /// banks). A weight in [0, 1] on the share (1: the terrain is water at rest).
    /// kAutoWallDensity (the default scene's): 0 for a river (its flow as tuned, and
    /// rain on the spikes map was thrown faster than free fall with it: docs/rendering.md),
    /// kStillWallDensity otherwise (resolved_wall_density). 0 in a bare PbfDef.
    float wall_density = 0.0f;
    bool auto_wall_density() const { return wall_density == kAutoWallDensity; }
    /// Bed friction band, in spacings, [0, 10]: a particle whose distance to the ground
    /// under it is below this many spacings counts as touching it (the bed friction,
    /// CollisionDef::damping); 0: only particles the collision pushed out of the terrain.
    /// With wall_density the bed layer is held off the ground by pressure and is rarely
    /// pushed out, so without a band the bed loses its friction. kAutoContactBand (the
    /// default scene's): 0 for a river, kStillContactBand otherwise (resolved_contact_band).
    /// 0 in a bare PbfDef.
    float contact_band = 0.0f;
    bool auto_contact_band() const { return contact_band == kAutoContactBand; }
    /// `spacing = "auto"` (the default scene's): a self-sized river (count or flow_rate
    /// "auto") is resolved at auto_spacing() (scene.h), `spacing` being its value at 1 m
    /// per sample; the lengths sized in spacings scale with it. A number clears it.
    bool auto_spacing = false;
};

/// A PbfDef's lattice constants: the rest density (the kernel sum of a cubic lattice of
/// the rest spacing: "number density", so a perfect lattice has C = 0) and a lattice
/// particle's sum |grad C|^2 (eps and s_corr are scaled by it, so they mean the same at
/// any spacing). Shared by the CPU solver and the GPU step (gpu_pbf.h).
struct PbfLattice {
    float rest_density = 1.0f;
    float grad_sum = 1.0f;
};
PbfLattice pbf_lattice(const PbfDef& def);

/// The constants a PBF step uses, from the def and its lattice: the kernels' coefficients
/// (poly6 W(r^2) = poly6 (h^2 - r^2)^3, spiky grad factor spiky (h - r)^2 / r), 1 / rest
/// density, eps, the s_corr scale and 1 / W(dq), and the largest move per iteration. One
/// function for the CPU solver and the GPU step (gpu_pbf.h), so the twins use the same floats.
struct PbfStepConstants {
    float h = 1.0f, h2 = 1.0f, poly6 = 0.0f, spiky = 0.0f;
    float inv_rho0 = 1.0f, eps = 0.0f, scorr_scale = 0.0f, inv_wdq = 0.0f, max_move = 0.0f;
};
PbfStepConstants pbf_step_constants(const PbfDef& def, const PbfLattice& lattice);

/// Sleeping's constants for a step of dt under `gravity` (PbfDef::sleep_threshold):
/// the threshold, capped at kSleepCapOfFallStep x gravity x dt (0: off), the slow steps
/// after which a particle is asleep (kSleepAfterSeconds, in [1, 65535]) and the weight of
/// one step in the drift average (dt / kSleepDriftSeconds, at most 1).
struct PbfSleepStep {
    float threshold = 0.0f;
    int after = 1;
    float drift_alpha = 1.0f;
};
PbfSleepStep pbf_sleep_step(const PbfDef& def, float gravity, float dt);

enum class SpringMode {
    Pairs,  ///< the paper's all-pairs loop, O(N^2), serial: the reference
    Grid,   ///< neighbour grid, O(N), parallel per-particle gather: same forces
};
std::string_view to_string(SpringMode m);

/// The paper's eq. 3: for each pair (i, j) with v = p_i - p_j, if |v| - r < max_distance
/// the acceleration a = 0.5 * k * (r * v/|v| - v) is added to i and subtracted from j.
struct SpringDef {
    float stiffness = 0.0f;      ///< k, 1/s^2, [0, 1e6]; 0 turns springs off
    float min_distance = 3.0f;   ///< r, metres, rest length, [0, 1e4]
    float max_distance = 5.0f;   ///< metres, cut-off beyond r, [0, 1e4]
    SpringMode mode = SpringMode::Pairs;
};

enum class CollisionMode {
    Paper,   ///< leaf holding the new position, eq. 4 ray test (particles slip through seams)
    Robust,  ///< swept segment through the whole tree, watertight test, heightfield guard
    None,    ///< no terrain collision
};
std::string_view to_string(CollisionMode m);

/// How the robust mode finds the segment's hit (both give the same hits; tests check).
enum class CollisionQuery {
    Tree,         ///< the AABB tree, every leaf the segment crosses
    Heightfield,  ///< walk the heightfield cells under the segment (fast; tree for long segments)
};
std::string_view to_string(CollisionQuery q);

struct CollisionDef {
    CollisionMode mode = CollisionMode::Paper;
    float damping = 0.7f;        ///< fraction of speed lost at a bounce, [0, 1]
    float offset = 0.07f;        ///< metres the particle is placed above the hit point, [0, 10]
    int leaf_triangles = 8;      ///< AABB tree leaf size, [2, 4096]
    /// Particle radius, metres, [0, 100]: the centre is kept `radius` above the terrain
    /// (the terrain is offset vertically by it: exact on flat ground, conservative by
    /// r(1 - cos(slope)) on slopes). 0 = points, as the paper.
    float radius = 0.0f;
    CollisionQuery query = CollisionQuery::Tree;
    /// PBF bed friction law, m/s, [0, 1000]. 0: a particle the terrain holds loses the
    /// share `damping` of its motion along the ground each step (drag linear in speed).
    /// > 0: it loses min(0.5, damping x speed / friction_speed): drag quadratic in speed,
    /// as a river bed's (Manning), the same as the linear law at this speed, weaker
    /// below it (a slow sheet on a flat runs on), stronger above (a chute is held).
    float friction_speed = 0.0f;
};

struct IntegratorDef {
    float gravity = 9.82f;       ///< m/s^2, downwards (-y), [-1000, 1000]
    float fixed_dt = 0.0f;       ///< seconds; 0 = use the frame time given to step(); else (0, 1]
    int substeps = 1;            ///< integration steps per frame, [1, 1000]
};

/// Depth below the mesh (metres) that tests and the Bullet solver tolerate for a
/// particle found at the end of a frame (Bullet's contacts rest a hair inside the
/// mesh). The own solvers count any depth > 0 as tunneled, before correcting it.
inline constexpr float kTunnelEpsilon = 1e-3f;

/// Spring accelerations (eq. 3) for the active particles, all pairs, added to p.force.
void add_spring_forces_pairs(Particles& p, const SpringDef& def);
/// The same forces through a neighbour grid built over p with cell size >=
/// min_distance + max_distance; parallel, each particle gathers its own sum.
void add_spring_forces_grid(Particles& p, const NeighborGrid& grid, const SpringDef& def);
/// Cell size the grid needs for these springs (their reach), metres.
float spring_reach(const SpringDef& def);

}  // namespace mr
