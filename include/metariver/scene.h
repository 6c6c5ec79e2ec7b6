// metariver scene: the full description of a run (SceneDef), its TOML file format,
// the built-in presets (the paper's scenes with their exact parameters), and the
// Simulation that owns terrain, particles, solver, field and surface.
#pragma once

#include <metariver/bodies.h>
#include <metariver/bullet_solver.h>
#include <metariver/core.h>
#include <metariver/drainage.h>
#include <metariver/field.h>
#include <metariver/foam.h>
#include <metariver/sparse_field.h>
#include <metariver/particles.h>
#include <metariver/scene_view.h>
#include <metariver/solver_registry.h>
#include <metariver/surface.h>
#include <metariver/hybrid_solver.h>
#include <metariver/swe_solver.h>
#include <metariver/terrain.h>

#include <array>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mr {

enum class TerrainSource {
    Valley,  ///< procedural valley with a winding river channel (the default scene)
    Strict,  ///< procedural equivalent of the paper's strict17.png
    Bowl,    ///< procedural equivalent of the paper's bowl.png
    Flat,    ///< all zero
    File,    ///< a PNG heightmap
    Waterfall,  ///< procedural: a channel over a cliff into a plunge pool (procedural_waterfall)
    Weir,       ///< procedural: a channel across a weir (procedural_weir)
    Alps,       ///< assets/heightmaps/real/alps.png, built into the library (108 x 61 samples)
};
std::string_view to_string(TerrainSource s);

struct TerrainSourceDef {
    TerrainSource kind = TerrainSource::Valley;
    std::string heightmap;  ///< PNG path when kind == File (relative paths: to the scene file)
    int width = 65;         ///< samples along x for procedural terrains, [2, kMaxHeightmapSide]
    int height = 65;        ///< samples along z for procedural terrains, [2, kMaxHeightmapSide]
    uint32_t seed = 1;      ///< procedural seed
};

/// [render]: how the scene asks to be drawn. Only the renderer reads it (render, view);
/// the simulation does not.
struct RenderLookDef {
    /// Realistic water: detail advected along the flow (docs/rendering.md, "Flow detail").
    bool flow_detail = true;
};

/// A scene. The member defaults ARE the built-in default scene (default_scene() returns
/// SceneDef{}): a PBF river down the procedural valley. A disc source (radius 2.5 m,
/// 1.5 m above the ground, inflow 3 m/s down: a lattice source that can deliver about
/// 600 particles per second) at the head of the valley's main channel; the budget and
/// the rate sized to the channel ("auto", docs/river.md, "Sizing"), the spacing sized to
/// the terrain (0.5 m at 1 m per sample); the carved channel starts full; bed friction
/// 0.002 per contact step, quadratic in speed; particles leaving over the terrain's
/// edges return to the source. Two substeps of 1/120 s with 3 density iterations; the
/// sparse poly6 field wraps them, the mesh is smoothed, foam is on. Code that means
/// another solver sets every table it relies on (the presets do: scene_def.cpp).
struct SceneDef {
    std::string name = "default";
    uint32_t seed = 1;  ///< particle spawn seed
    SolverKind solver = SolverKind::Pbf;  ///< a name in the SolverRegistry the Simulation is created with
    TerrainSourceDef source{.kind = TerrainSource::Valley, .heightmap = {}, .width = 65, .height = 97, .seed = 7};
    /// 1 m per sample (a small map stretched to 16 m: auto_area_scale), 24 m high; the
    /// river's channel carved from the source to the outlet (condition "auto": a scene
    /// without a continuous source and an edge sink keeps its heights; docs/river.md,
    /// "Depressions").
    TerrainDef terrain{.area_scale = 1.0f,
                       .height_scale = 24.0f,
                       .paper_row_orientation = true,
                       .condition = TerrainCondition::Auto,
                       .auto_area_scale = true};
    /// The carved channel starts full (prefill): the river runs from the first frame
    /// (docs/river.md, "Quadratic bed friction and a channel that starts full").
    SpawnDef spawn{.count = kAutoCount,
                   .center = Vec3(0.0f),
                   .half_extent = Vec3(2.5f, 0.5f, 2.5f),
                   .interval = 0,
                   .initial_velocity = Vec3(0.0f, -3.0f, 0.0f),
                   .auto_center = true,
                   .auto_height = 1.5f,
                   .auto_channel = true,
                   .shape = SourceShape::Disc,
                   .flow_rate = kAutoRate,
                   .litres_per_particle = 0.0f,
                   .prefill = true,
                   .follow_ground = true};
    /// Read by solver = springs only (the springs valley's soft springs).
    SpringDef springs{.stiffness = 4.0f, .min_distance = 1.0f, .max_distance = 0.5f, .mode = SpringMode::Pairs};
    /// Bed friction quadratic in speed (docs/river.md, "Quadratic bed friction ..."):
    /// friction_speed measured best of 0, 1, 2, 3, 4 m/s over the failing maps.
    CollisionDef collision{.mode = CollisionMode::Robust,
                           .damping = 0.002f,
                           .offset = 0.005f,
                           .leaf_triangles = 8,
                           .radius = 0.1f,
                           .query = CollisionQuery::Heightfield,
                           .friction_speed = 4.0f};
    IntegratorDef integrator{.gravity = 9.82f, .fixed_dt = 0.0f, .substeps = 2};
    BulletDef bullet;  ///< solver = bullet only
    SweDef swe;        ///< [swe]: solver = swe, hybrid
    HybridDef hybrid;  ///< [hybrid]: solver = hybrid only
    /// solver = pbf only. Sleeping, damping, the contact band and the wall density
    /// "auto": off for the river, on for still water; a pool levels out before it sleeps
    /// (a river does not sleep); the spacing sized to the terrain.
    PbfDef pbf{.sleep_threshold = kAutoSleep,
               .sleep_drift = kStillSleepDrift,
               .damping = kAutoDamping,
               .wall_density = kAutoWallDensity,
               .contact_band = kAutoContactBand,
               .auto_spacing = true};
    SinkDef sink{.kind = SinkKind::Edges};  ///< where water leaves (recycled to the source)
    FieldDef field{.kernel = FieldKernel::Poly6, .radius = 1.0f, .resolution = 3.0f, .bounds_offset = 1.0f, .threshold = 0.4f};
    bool surface = true;  ///< build the field and the surface every frame
    /// [surface]: how the extracted mesh is smoothed (none in the paper's presets). The
    /// default: as splashsurf does (feature-weighted Laplacian steps), in eight Chebyshev
    /// steps and with its volume given back: still water flat, drops kept
    /// (docs/rendering.md, "Surface smoothing").
    SmoothingDef smoothing{.method = SmoothingMethod::Laplacian};
    /// [foam]: diffuse spray, foam and bubbles (solver = pbf only; on in the default
    /// river where it is fast or broken: docs/rendering.md, "Foam and spray").
    FoamDef foam{.enabled = true};
    RenderLookDef render;    ///< [render]: drawing choices the renderer reads
    /// [[bodies]]: rigid bodies in the water (bodies.h), at most kMaxBodies; solver = pbf only.
    std::vector<BodyDef> bodies;
    /// Metres, > 0 or 0: the PBF spacing the carved channel and the source's basin are
    /// sized for (carve_def); 0 = pbf.spacing. Not a scene-file key: pbf_river_scene()
    /// sets it to keep the default river's terrain while it refines the spacing.
    float carve_spacing = 0.0f;
};

/// The built-in default scene: SceneDef{} (a PBF river on the procedural valley, source
/// at the head of its main channel, outlet edges recycled to the source).
SceneDef default_scene();
/// The default scene before the fluid solver: the paper's springs on the valley
/// (preset "springs-valley"; river_scene(n) builds on it).
SceneDef springs_valley_scene();
/// Names of the built-in presets ("default", "paper-full", "paper-nile", "paper-bowl", ...).
std::vector<std::string> preset_names();
/// A preset by name; an unknown name is an error listing the known ones. Presets whose
/// paper scene used a file keep source.kind == File with an empty path: the caller
/// supplies it (--heightmap); see resolve_heightmap().
Result<SceneDef> preset(std::string_view name);

/// Sizes above which the reference paths would not finish a frame in bounded time;
/// validate() refuses them and names the fast alternative.
inline constexpr int kMaxPairsParticles = 20'000;    ///< springs.mode = "pairs" (O(N^2), serial)
inline constexpr int kMaxDenseFieldBalls = 5'000;    ///< the paper's field kernels (O(balls x samples))
inline constexpr int kMaxBulletBodies = 200'000;     ///< solver = "bullet"
inline constexpr int kMaxFieldAxisSamples = 1'000'000;  ///< field.bounds = "terrain": samples along one axis

/// Why `solver` does not use collision mode `mode`, or "" when it does: Bullet has its
/// own contacts ([bullet]); PBF slides along the terrain ("robust") or ignores it
/// ("none") but never reflects ("paper", the springs solver's response).
std::string collision_mode_unused(SolverKind solver, CollisionMode mode);

/// Why `solver` does not use the spawn seed (`seed`, `--seed`), or "" when it does:
/// PBF's lattice source places every particle it emits, nothing is random.
std::string seed_unused(SolverKind solver);

/// Checks every field against its documented range. The message names the field
/// ("particles.count: must be in [1, 10000000] (got 0)").
Status validate(const SceneDef& def);

/// Parses a scene from TOML text. `origin` names the file in messages and is the base
/// for relative heightmap paths. Unknown keys, wrong types and out-of-range values are
/// errors naming the key. Keys left out keep the value of `base` (default_scene()).
Result<SceneDef> parse_scene_toml(std::string_view text, const std::string& origin,
                                  const SceneDef& base);
/// Reads and parses a scene file. A `heightmap` replaces the file's terrain (source =
/// "file", that PNG; --heightmap), so a file whose PNG is left to fill in loads with it.
Result<SceneDef> load_scene_file(const std::string& path, const std::string& heightmap = {});

/// Checks a scene against its terrain (source inside the terrain's rectangle, sinks
/// that do not swallow the source); the message names the field.
Status validate_on_terrain(const SceneDef& def, const Terrain& terrain);

/// terrain.condition with Auto resolved: Carve for a PBF river (a continuous source,
/// sink = edges), None for everything else (a still pool keeps its basin).
TerrainCondition resolved_condition(const SceneDef& def);
/// A PBF river: a continuous source (or flow_rate "auto") and sink = edges.
bool is_river(const SceneDef& def);
/// The surface is built and smoothed: [surface] on, method not none, iterations > 0.
bool smoothing_on(const SceneDef& def);
/// pbf.sleep_threshold with "auto" resolved: 0 for a river (sleeping froze a slow river
/// on a gentle bed: docs/river.md, "A least slope of 2 % and no sleeping river"),
/// kSleepThreshold otherwise (still water comes to rest).
float resolved_sleep_threshold(const SceneDef& def);
/// pbf.damping with "auto" resolved: 0 for a river (its slow reaches must not be held),
/// kStillDamping otherwise (a pool's slosh dies out before it falls asleep).
float resolved_damping(const SceneDef& def);
/// pbf.contact_band with "auto" resolved: 0 for a river (its bed friction as tuned,
/// docs/river.md), kStillContactBand otherwise (a pool's first slosh stays in its bowl).
float resolved_contact_band(const SceneDef& def);
/// pbf.wall_density with "auto" resolved: 0 for a river, kStillWallDensity otherwise.
float resolved_wall_density(const SceneDef& def);
/// The terrain's rendered mesh as the ground of the surface smoothing (a view of its
/// heights: the water's bed below it stays as extracted, surface.smooth_hidden).
SmoothingGround smoothing_ground(const Terrain& t);
/// Neighbourhood radius, metres, for the velocities of a scene's surface vertices
/// (SceneView::flow_radius): the compact field's support (every surface vertex has a
/// particle within it), 2 x the metaball radius for the paper's kernels.
float flow_radius(const SceneDef& def);
/// The carved channel's cross-section for a scene (condition Carve): a flat bed
/// max(3 samples, 4 pbf.spacing) wide, walls max(1.5 samples, 2 pbf.spacing) wide on
/// each side, the bed 2 pbf.spacing deep (carve_spacing instead when it is set).
CarveDef carve_def(const SceneDef& def, float area_scale);

/// The self-sized river (docs/river.md, "Sizing"): `particles.count = "auto"` and
/// `particles.flow_rate = "auto"` are derived from the carved channel's section and the
/// main channel's length. The rate fills kRiverFill of the section at kRiverSpeed; the
/// budget covers the rate over the time a particle spends on the channel at the slower
/// kRiverTransitSpeed (the measured median), kRiverBudgetMargin times, plus the source's
/// pile; above kRiverMaxCount the rate drops so that the budget still covers it.
inline constexpr float kRiverSpeed = 1.5f;          ///< m/s, the flow speed the section is sized for
/// The speed the section is sized for on a gentle channel: kRiverSpeedPerRootSlope x
/// sqrt(mean slope) within [kRiverTransitSpeed, kRiverSpeed] (the quadratic bed friction's
/// terminal speed grows with the root of the slope; measured median speeds: 0.73 m/s on
/// the procedural flat's 2 % bed, 0.89 on western_usa, 1.3-1.6 on alps, andes_peru and
/// random_100x61). A rate sized at 1.5 m/s on a channel that runs at 0.8 overfills it and
/// the prefilled channel drains slower than the source fills it.
inline constexpr float kRiverSpeedPerRootSlope = 5.3f;
inline constexpr float kRiverTransitSpeed = 0.75f;  ///< m/s, the speed the budget's transit time assumes
inline constexpr float kRiverFill = 0.75f;          ///< share of the carved section the flow fills
inline constexpr float kRiverBudgetMargin = 2.0f;   ///< budget over rate x transit time
inline constexpr double kRiverSourcePile = 300.0;   ///< particles the source's basin holds
inline constexpr float kRiverMinRate = 0.5f, kRiverMaxRate = 2000.0f;  ///< particles per second
inline constexpr int kRiverMinCount = 500, kRiverMaxCount = 12000;     ///< particle budget
inline constexpr int kFixedDefaultCount = 4000;  ///< `count = "auto"` for a solver that does not size itself
struct RiverSize {
    int count = 0;              ///< particle budget
    float rate = 0.0f;          ///< particles per second
    float channel_length_m = 0; ///< the main channel's length from the source to its outlet
    float channel_slope = 1.0f; ///< its mean ground slope (head minus outlet over the length)
    float speed = kRiverSpeed;  ///< m/s, the speed the rate is sized for (river_speed)
    bool capped = false;        ///< the budget hit kRiverMaxCount (the rate was lowered)
};
RiverSize size_river(const SceneDef& def, float area_scale, float channel_length_m, float channel_slope = 1.0f);
/// The speed a river's rate is sized for on a channel of mean slope `slope` (above).
float river_speed(float slope);

/// `pbf.spacing = "auto"` (the default scene's; docs/river.md, "Spacing"): the spacing a
/// self-sized river on terrain `t` is resolved at: pbf.spacing (0.5 m) per metre of
/// area_scale (two particles per sample: the carved bed, three samples wide, holds six
/// across at any scale, and the budget of a map does not depend on its scale), at most
/// the terrain's shorter side over kAutoSpacingAcross, within [kAutoSpacingMin,
/// kAutoSpacingMax]. Not coarsened for a long channel's budget: measured worse
/// (docs/river.md, "Spacing").
inline constexpr float kAutoSpacingAcross = 32.0f;
inline constexpr float kAutoSpacingMin = 0.01f, kAutoSpacingMax = 1000.0f;  ///< metres
float auto_spacing(const SceneDef& def, const Terrain& t);
/// Scales a river scene to particle spacing `spacing`: the lengths sized in spacings
/// (pbf.kernel_radius, collision.radius and offset, field.radius and bounds_offset) by
/// spacing / pbf.spacing, field.resolution divided by it (at most
/// max_field_resolution), and, unless carve_spacing keeps the channel, the source's
/// half extents and auto_height.
void scale_river_lengths(SceneDef& d, float spacing, float max_field_resolution = 64.0f);

/// The path a river's channel is carved along: `path` (cells (row, column), source to
/// outlet, 8-connected) with every cell but the first and the last moved at least
/// `margin` cells in from the grid's edges (at most a quarter of each side), and the
/// cells rejoined by straight 8-connected steps. A channel hugging the edge of the map
/// has no bank there (the grid ends inside its section) and loses its water over it
/// (andes_peru: 3.7 particles/s over the east edge); moved in, it keeps its banks and
/// turns to the edge at its outlet.
std::vector<std::pair<int, int>> keep_off_edges(std::span<const std::pair<int, int>> path, int rows, int columns,
                                                int margin);

/// How fill_channel fills a carved channel (particles.prefill).
struct ChannelFillDef {
    float spacing = 0.5f;      ///< particle spacing, metres, > 0
    float floor_m = 3.0f;      ///< the bed's width (CarveDef::floor_m): floor / spacing - 1 particles across
    float depth_m = 0.75f;     ///< water depth: round(depth / spacing) layers (at least one)
    float clearance_m = 0.0f;  ///< gap between the ground and the lowest layer's bottom (collision radius + offset)
    float speed = 0.0f;        ///< m/s along the channel's horizontal tangent
    Vec3 skip_center{0.0f};    ///< stations within skip_radius_m of it (x, z) stay empty: the source's basin
    float skip_radius_m = 0.0f;
    size_t most = 0;           ///< particles at most
    /// Share of the positions kept, (0, 1]: evenly spread (every 1/share-th), for a
    /// river thinner than its channel's section (a capped budget's lowered rate).
    float share = 1.0f;
};
/// Positions (and velocities) filling the channel along `path` (cells: row, column)
/// from its first cell to its last: a station every spacing along the path, particles
/// across the bed and layers above the mesh, none nearer than 0.9 spacing to another.
struct ChannelFill {
    std::vector<Vec3> position, velocity;
};
ChannelFill fill_channel(const Terrain& t, std::span<const std::pair<int, int>> path, const ChannelFillDef& def);
/// Non-fatal advice about a valid scene (e.g. a flow rate the particle budget cannot
/// sustain for long), one line each, naming the field.
std::vector<std::string> scene_warnings(const SceneDef& def);

/// Loads or generates the heightmap a scene describes.
Result<Heightmap> load_scene_heightmap(const SceneDef& def);

/// A particle with fewer than this many neighbours within the kernel radius is isolated.
inline constexpr int kSprayNeighbours = 3;

/// Spray: the share of the active particles that are isolated AND airborne. Isolated:
/// fewer than kSprayNeighbours other active particles at a distance < kernel_radius.
/// Airborne: more than 2 * spacing above the terrain mesh (height_mesh at the particle's
/// x, z); a particle outside the terrain's rectangle counts as airborne. 0 when no
/// particle is active. O(N) through a neighbour grid of cell kernel_radius (> 0).
float spray_fraction(const Terrain& terrain, std::span<const Vec3> positions, std::span<const uint8_t> active,
                     float kernel_radius, float spacing);

/// Water over the main channel (issue 10): the share of a path's cells (e.g. the main
/// channel from the source to its outlet) with water over them. A cell is covered when
/// an active particle lies within `radius_samples` samples horizontally of the cell's
/// centre and at most `depth` metres above the ground sample there. O(active + cells):
/// each particle visits the 5 x 5 cells around it through a cell -> path index grid.
class ChannelCoverage {
public:
    ChannelCoverage() = default;
    ChannelCoverage(const Terrain& t, std::span<const std::pair<int, int>> cells, float radius_samples = 1.5f,
                    float depth = 3.0f);
    size_t cells() const { return ground_.size(); }
    /// Covered cells / cells (0 for an empty path).
    float measure(std::span<const Vec3> positions, std::span<const uint8_t> active) const;
    /// The same for a heightfield solver's water (its grid is the terrain's): a path cell
    /// is covered when a cell deeper than `wet_depth` lies within the radius.
    float measure(const HeightfieldWater& water, float wet_depth) const;

private:
    int rows_ = 0, columns_ = 0;
    float scale_ = 1.0f, radius_ = 1.5f, depth_ = 3.0f;
    Vec3 origin_{0.0f};  ///< the terrain's (min x, 0, min z)
    std::vector<std::pair<int, int>> cells_;
    std::vector<float> ground_;    ///< ground height at each path cell, metres
    std::vector<int32_t> index_;   ///< grid cell -> path index, -1 off the path
};

/// Outflow per outlet (issue 10): each exit position a solver reports (Solver::last_exits)
/// goes to an outlet (ChannelMap::outlets(), plus the main channel's outlet cell if it is
/// not one of them): the exit projected onto the terrain's rectangle, within max(3
/// samples, 3 m) of the outlet cell's centre: the main outlet when it is within that
/// radius (a river's mouth spans several outlet cells), else the nearest; else to
/// "other" (spray over an edge, ...).
class OutletMeter {
public:
    struct Outlet {
        int row = 0, column = 0;
        float x = 0.0f, z = 0.0f;   ///< the cell's centre, metres
        uint32_t accumulation = 0;  ///< drainage cells (ChannelMap)
        bool main = false;          ///< the main channel's outlet
    };
    OutletMeter(const Terrain& t, const ChannelMap& m, std::pair<int, int> main_outlet);
    std::span<const Outlet> outlets() const { return outlets_; }
    /// Index into outlets() of the outlet an exit belongs to, -1 for other.
    int assign(const Vec3& exit) const;
    /// Feed after every frame: its end time and its exits. Constant memory
    /// (kOutletRecords checkpoints of the running counts): exact for runs of up to
    /// kOutletRecords frames; beyond, the second half starts within a checkpoint stride
    /// of its exact frame.
    void record(double time_s, std::span<const Vec3> exits);
    static constexpr size_t kOutletRecords = 2048;
    struct Count {
        uint64_t particles = 0;   ///< over the whole run
        double rate = 0.0;        ///< particles per second over the second half (FlowMeter's window; 0 under 8 frames)
        double first_s = -1.0;    ///< end time of the frame of the first exit, seconds (-1: none)
    };
    struct Summary {
        std::vector<Count> outlets;  ///< parallel to outlets()
        Count other;
        Count main;  ///< the main outlet's (zero when there is none)
    };
    Summary summary() const;

private:
    std::vector<Outlet> outlets_;
    float x0_ = 0, x1_ = 0, z0_ = 0, z1_ = 0, radius_ = 3.0f;
    Checkpoints records_;          ///< (time, running exits per outlet..., other) per frame
    std::vector<double> total_;    ///< running exits per outlet, "other" last
    std::vector<double> first_s_;  ///< end time of the frame of the first exit, per outlet, other last
    std::vector<double> row_;      ///< scratch for one record
};

/// Per-frame times of the three stages, milliseconds.
struct FrameTimings {
    double simulate_ms = 0.0;
    double field_ms = 0.0;
    double surface_ms = 0.0;  ///< marching cubes and the smoothing ([surface])
    double smoothing_ms = 0.0;  ///< the smoothing alone (part of surface_ms; 0 with method none)
    double foam_ms = 0.0;     ///< diffuse particles ([foam]; 0 when off)
};

/// What Simulation::apply did with an edited scene.
struct ApplyResult {
    /// The edit was applied in place (the particles kept), or it changes what the
    /// terrain, the tree, the budget or an automatic value was built from: nothing was
    /// changed and the caller creates a new Simulation from the edited scene.
    bool applied = false;
    std::vector<std::string> keys;  ///< the scene keys whose values changed, table order
    std::string rebuild_key;        ///< when not applied: the first key that needs a rebuild
};

/// Owns one scene's terrain, tree, solver, field and surface.
/// step(dt) advances one frame and rebuilds the surface from the solver's water:
/// particles -> field -> marching cubes -> smoothing, and a heightfield -> a triangle
/// grid over its wet cells (append_heightfield_surface), in one mesh. Views are read-only.
class Simulation {
public:
    /// Validates the scene, loads/generates the heightmap, builds terrain and tree, and
    /// the solver `solvers` registers under def.solver (an unknown name is an error
    /// naming `solver` and the known ones). The Simulation keeps a copy of the entry.
    static Result<std::unique_ptr<Simulation>> create(const SceneDef& def,
                                                      const SolverRegistry& solvers = SolverRegistry::builtin());
    /// The same with a heightmap the caller already has.
    static Result<std::unique_ptr<Simulation>> create(const SceneDef& def, const Heightmap& map,
                                                      const SolverRegistry& solvers = SolverRegistry::builtin());
    /// The solver and the tree refer to this object's own terrain: a copy or a move
    /// would leave them pointing at the old one.
    Simulation(const Simulation&) = delete;
    Simulation& operator=(const Simulation&) = delete;
    ~Simulation();

    /// Bounds the threads this Simulation's work uses (step, apply, sculpt, restore,
    /// push, pour, move_source and the channel measures): it all runs in a thread arena
    /// of `n` threads that the Simulation owns (the calling thread is one of them; at
    /// most the machine's cores); 0 (the default) = every core. The state after a frame does not depend on it
    /// (state_hash() is the same at every count). Error naming `threads` outside
    /// [0, kMaxThreads]; nothing changed then. Not to be called from inside step().
    Status set_threads(int n);
    /// The count set_threads() set (0: every core).
    int threads() const;
    static constexpr int kMaxThreads = 1024;

    /// One frame: spawning and `substeps` solver steps, then field and surface.
    void step(float frame_dt);
    /// Live edit: `next` is the scene this Simulation was created from (requested(),
    /// "auto" values unresolved) with some keys changed. Keys the running solver, the
    /// field, the surface, the foam and the renderer read are applied in place: the
    /// water keeps flowing (the foam's diffuse particles restart when a foam key
    /// changes). A change of the terrain, the solver, the seed, the budget
    /// (particles.count), the prefill, pbf.spacing (it sizes the carved channel), the
    /// tree's leaves, any Bullet key, or to or from an "auto" word needs a new
    /// Simulation: then nothing is changed (ApplyResult::applied false). An invalid
    /// scene is an error and changes nothing.
    Result<ApplyResult> apply(const SceneDef& next);
    /// Sculpts the terrain under the running water (one brush stroke, Terrain::sculpt):
    /// the tree's boxes, the drainage network, the main channel and the source's lattice
    /// follow, and particles the ground rose over are lifted onto it (counted in
    /// terrain_lifts(), not as tunneled). Error for a solver whose entry refuses it
    /// (SolverEntry::no_sculpt: Bullet's world holds its own copy of the terrain) or a
    /// bad brush; nothing changed then. The renderer
    /// shows it after Renderer::set_scene(sim, true).
    Result<TerrainEdit> sculpt(const Brush& brush);
    /// Undoes a stroke of sculpt() (newest first), with the same updates.
    void restore(const TerrainEdit& edit);
    /// Particles sculpt() or restore() lifted because the ground rose over them.
    uint64_t terrain_lifts() const;
    /// The scene as given to create(), "auto" values unresolved (def() has them resolved).
    const SceneDef& requested() const;
    /// Interaction: pour `count` particles at `center` (the source moves there).
    void pour(const Vec3& center, int count);
    /// Interaction: moves the source to `center` (its volume's centre; the automatic
    /// placement is off from then on: requested() says the centre too), the main channel
    /// and its coverage measured from there. Error (nothing moved) when the source's
    /// footprint would leave the terrain's rectangle, naming particles.spawn_center.
    Status move_source(const Vec3& center);
    /// Interaction: pushes the water within `radius` metres of `center` with `velocity`
    /// (m/s at the centre, falling to 0 at the rim: Solver::push), waking any that
    /// slept. Error for a solver whose entry refuses it (SolverEntry::no_push: Bullet),
    /// or a radius that is not finite and > 0,
    /// or a velocity that is not finite. Returns how many particles it pushed.
    Result<size_t> push(const Vec3& center, float radius, const Vec3& velocity);
    /// Bodies (bodies.h): adds one body live; its id is stable for this Simulation. Error
    /// naming the BodyDef field (as its scene key, "bodies.density", ...) for a bad value,
    /// a mesh file that cannot be read, more than kMaxBodies, or a solver without bodies.
    Result<uint32_t> add_body(const BodyDef& body);
    /// Removes a body; error naming `id` when there is none.
    Status remove_body(uint32_t id);
    /// Moves a body (a drag, a throw): its centre of mass to `position`, its orientation,
    /// and its velocity and angular velocity; error naming `id` or the non-finite value.
    Status set_body_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                           const Vec3& angular_velocity);
    /// The bodies after the latest frame, in the order they were added.
    std::span<const BodyState> bodies() const;

    const SceneDef& def() const;
    const Terrain& terrain() const;
    const Bvh& bvh() const;
    /// The solver's particles; empty for a solver whose water is a heightfield only.
    const Particles& particles() const;
    /// The solver's heightfield water; null for a solver whose water is particles only.
    const HeightfieldWater* heightfield() const;
    /// The shallow-water grid: the solver itself (solver "swe") or the hybrid's; null for
    /// a solver whose water is particles only. Its balance() are the grid's volumes.
    const SweSolver* grid() const;
    /// Rain per cell over the grid in mm/h (SweSolver::set_rain: rows x columns values in
    /// [0, 1e4], row-major; empty: the scene's swe.rain keys again). Error naming `solver`
    /// for a solver without a grid, or `mm_per_h`; nothing changed then.
    Status set_rain(std::span<const float> mm_per_h);
    /// The registry entry of this scene's solver (a copy, taken at create()).
    const SolverEntry& solver_entry() const;
    /// The solver itself (read-only: a solver's own measurements, e.g. SweSolver::balance()).
    const Solver& solver() const;
    const SolverCounters& counters() const;
    /// Non-fatal advice: scene_warnings(def) plus the solver's on this terrain (e.g. a
    /// flow rate its source cannot deliver, and what it was capped to).
    std::vector<std::string> warnings() const;
    /// The dense field (paper kernels); empty when the scene uses a compact kernel.
    const ScalarGrid& field() const;
    /// The sparse field (compact kernels); empty for the paper's kernels.
    const SparseField& sparse_field() const;
    /// Samples per axis of the latest field, whichever kind.
    std::array<int, 3> field_dims() const;
    const SurfaceMesh& surface() const;
    /// Numbers of the latest frame's smoothing (all 0 with surface.method = "none").
    const SmoothingStats& smoothing_stats() const;
    const FrameTimings& last_timings() const;
    /// The diffuse particles ([foam]); null when foam is off or the solver is not PBF.
    const FoamSystem* foam() const;
    uint64_t frame() const;
    /// The latest frame as plain views (what the renderer reads): valid until the next
    /// step, edit or destruction of this Simulation.
    SceneView view() const;
    /// Frames whose field could not be built (its grid over kMaxFieldSamples, or the
    /// sparse field's kMaxSparseFieldSamples): no surface that frame.
    uint64_t field_overflows() const;
    /// Why the last such frame's field was refused; empty when none was.
    const std::string& field_overflow_message() const;
    /// Frames whose particles spread wider than the sparse field's cap: its field was built
    /// around the most of them (keep_balls_within_cap), the others not drawn that frame.
    uint64_t field_windows() const;
    /// The most particles such a frame left out of the field.
    size_t field_left_out() const;
    /// FNV-1a hash of the particles' positions, velocities and activity, then of the
    /// heightfield's depths and velocities when the solver has one (determinism checks).
    uint64_t state_hash() const;
    /// The terrain's drainage network (automatic source, wet-channel measure). After a
    /// sculpt() or restore() it is updated when it is next read (here, by main_channel(),
    /// wet_fraction() or channel_coverage()), over the rectangle of samples the edits since
    /// changed (ChannelMap::update: only the cells the change reaches), so a drag of many
    /// strokes updates it once.
    const ChannelMap& channel() const;
    /// Fraction of the active particles inside the wet channel (WetChannelDef defaults
    /// scaled to the terrain: width max(3 m, 3 samples), depth 3 m).
    float wet_fraction() const;
    /// spray_fraction() of the current particles at the scene's scale
    /// (SolverEntry::spray_scale): pbf: pbf.spacing and pbf.kernel_radius; springs:
    /// spacing springs.min_distance (1 m when 0); bullet: spacing 2 * bullet.sphere_radius;
    /// kernel radius 2 * spacing for both.
    float spray_fraction() const;
    /// |velocity| of every active particle, m/s, in index order.
    std::vector<double> active_speeds() const;
    /// Where the outlet-edge sink took particles during the latest frame (Solver::last_exits).
    std::span<const Vec3> last_exits() const;
    /// The main channel: ChannelMap::path_from the source's channel cell (the main head
    /// for the automatic channel source on terrain that is not carved, else the channel
    /// cell nearest the source's centre: on a carved terrain the automatic source stays
    /// at the head the carve was cut from) to the border cell where it leaves the
    /// terrain (back()). Valid until the next sculpt(), restore() or move_source(), after
    /// which the channel is measured again (copy it to keep it across them).
    std::span<const std::pair<int, int>> main_channel() const;
    /// ChannelCoverage of the main channel by the current particles (1.5 samples, 3 m).
    float channel_coverage() const;
    /// How the river sized itself (particles.count / flow_rate = "auto"); empty when
    /// neither was automatic.
    const std::optional<RiverSize>& sizing() const;
    /// Particles particles.prefill placed in the carved channel at the start (0: none).
    size_t prefilled() const;

private:
    /// Everything the Simulation owns (scene, terrain, solver, the per-frame scratch and
    /// caches, the thread arena): src/scene/simulation_impl.h.
    struct Impl;
    explicit Simulation(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace mr
