// The table of scene keys (include/metariver/scene_keys.h): every key a scene file can
// hold, with its type, unit, range, who reads it (scene_key_readers.h: the conditions and
// the reader's messages where they fail), what a live edit of it needs and its help. The
// TOML reader (which keys a file may set), validate(), Simulation::apply, the viewer's
// panel, the CLI's choices, the reference in docs/scene-format.md and `metariver scene
// --preset` all take keys from here.
#include <metariver/scene_keys.h>

#include "scene_key_readers.h"

#include <fmt/format.h>

#include <cmath>
#include <type_traits>

namespace mr {

namespace {

template <class T>
    requires(!std::is_enum_v<T>)
FieldRef field_ref(T* p) {
    return p;
}
template <class E>
    requires std::is_enum_v<E>
FieldRef field_ref(E* p) {
    return EnumRef{p, [](const void* f) { return static_cast<int>(*static_cast<const E*>(f)); },
                   [](void* f, int i) { *static_cast<E*>(f) = static_cast<E>(i); },
                   [](const void* f) { return to_string(*static_cast<const E*>(f)); }};
}
// The solver: a name, seen as its index among the built-in solvers (the key's choices).
FieldRef field_ref(SolverKind* p) {
    return EnumRef{p, [](const void* f) { return builtin_solver_index(*static_cast<const SolverKind*>(f)); },
                   [](void* f, int i) {
                       if (i >= 0 && size_t(i) < std::size(kBuiltinSolverNames))
                           *static_cast<SolverKind*>(f) = SolverKind{kBuiltinSolverNames[size_t(i)]};
                   },
                   [](const void* f) { return static_cast<const SolverKind*>(f)->name; }};
}
// A body's shape: its name in the scene file ([[bodies]] shape), in BodyShape's order.
constexpr std::string_view kBodyShapes[] = {"box", "sphere", "capsule", "convex_mesh", "triangle_mesh"};
FieldRef field_ref(BodyShape* p) {
    return EnumRef{p, [](const void* f) { return static_cast<int>(*static_cast<const BodyShape*>(f)); },
                   [](void* f, int i) { *static_cast<BodyShape*>(f) = static_cast<BodyShape>(i); },
                   [](const void* f) { return kBodyShapes[static_cast<size_t>(*static_cast<const BodyShape*>(f))]; }};
}
// Where a key lives: `d.<expr>`.
#define MR_FIELD(expr) [](SceneDef& d) { return field_ref(&d.expr); }

constexpr KeyRange closed(double lo, double hi) { return {.lo = lo, .hi = hi}; }
constexpr KeyRange above(double lo, double hi) { return {.lo = lo, .hi = hi, .lo_open = true}; }  // (lo, hi]
constexpr KeyRange big_vec(double lo) { return {.lo = lo, .hi = 1e6}; }

// Who reads a key, and what the reader says to a file that sets it elsewhere.
using namespace key_readers;

constexpr std::string_view kSources[] = {"valley", "strict", "bowl", "flat", "file", "waterfall", "weir", "alps"};
constexpr std::string_view kConditions[] = {"none", "fill", "breach", "carve", "auto"};
constexpr std::string_view kShapes[] = {"box", "disc", "point"};
constexpr std::string_view kSinks[] = {"none", "box", "edges"};
constexpr std::string_view kSpringModes[] = {"pairs", "grid"};
constexpr std::string_view kCollisionModes[] = {"paper", "robust", "none"};
constexpr std::string_view kQueries[] = {"tree", "heightfield"};
constexpr std::string_view kKernels[] = {"inverse_square", "radius_over_r", "poly6"};
constexpr std::string_view kBounds[] = {"particles", "terrain"};
constexpr std::string_view kMethods[] = {"none", "laplacian", "taubin"};
constexpr std::string_view kSteps[] = {"uniform", "chebyshev"};
constexpr std::string_view kBulletTerrains[] = {"mesh", "heightfield"};

constexpr std::string_view kAuto[] = {"auto"};
constexpr std::string_view kCentres[] = {"auto", "channel"};
constexpr KeyWords kCountWords{kAuto, [](S d) { return d.spawn.count == kAutoCount ? 0 : -1; },
                               [](SceneDef& d, int i) {
                                   if (i == 0) d.spawn.count = kAutoCount;
                               }};
constexpr KeyWords kRateWords{kAuto, [](S d) { return d.spawn.auto_rate() ? 0 : -1; },
                              [](SceneDef& d, int i) {
                                  if (i == 0) d.spawn.flow_rate = kAutoRate;
                              }};
/// "auto" for a PBF number whose value `Auto` stands for it (resolved per scene).
/// (The value by address: clang 15 takes no float template argument.)
template <float PbfDef::*F, const float* Auto>
constexpr KeyWords kPbfAutoWords{kAuto, [](S d) { return d.pbf.*F == *Auto ? 0 : -1; },
                                 [](SceneDef& d, int i) {
                                     if (i == 0) d.pbf.*F = *Auto;
                                 }};
constexpr KeyWords kSleepWords = kPbfAutoWords<&PbfDef::sleep_threshold, &kAutoSleep>;
constexpr KeyWords kDampingWords = kPbfAutoWords<&PbfDef::damping, &kAutoDamping>;
constexpr KeyWords kWallDensityWords = kPbfAutoWords<&PbfDef::wall_density, &kAutoWallDensity>;
constexpr KeyWords kContactBandWords = kPbfAutoWords<&PbfDef::contact_band, &kAutoContactBand>;
constexpr KeyWords kAreaScaleWords{kAuto, [](S d) { return d.terrain.auto_area_scale ? 0 : -1; },
                                   [](SceneDef& d, int i) {
                                       d.terrain.auto_area_scale = i == 0;
                                       if (i == 0) d.terrain.area_scale = 1.0f;
                                   }};
constexpr KeyWords kSpacingWords{kAuto, [](S d) { return d.pbf.auto_spacing ? 0 : -1; },
                                 [](SceneDef& d, int i) {
                                     d.pbf.auto_spacing = i == 0;
                                     if (i == 0) d.pbf.spacing = PbfDef{}.spacing;
                                 }};
// A centre given as [x, y, z] turns both automatic placements off.
constexpr KeyWords kCentreWords{kCentres, [](S d) { return d.spawn.auto_center ? (d.spawn.auto_channel ? 1 : 0) : -1; },
                                [](SceneDef& d, int i) {
                                    d.spawn.auto_center = i >= 0;
                                    d.spawn.auto_channel = i == 1;
                                }};

// [swe]: the source at the particle source's centre ("auto"), and no initial lake ("none").
constexpr KeyWords kSweSourceWords{kAuto, [](S d) { return d.swe.auto_source ? 0 : -1; },
                                   [](SceneDef& d, int i) { d.swe.auto_source = i == 0; }};
constexpr std::string_view kNone[] = {"none"};
constexpr KeyWords kDamWords{kNone, [](S d) { return std::isnan(d.swe.dam_z) ? 0 : -1; },
                             [](SceneDef& d, int i) {
                                 if (i == 0) d.swe.dam_z = std::nanf("");
                             }};
constexpr KeyWords kSweDischargeWords{kAuto, [](S d) { return d.swe.discharge == kSweAuto ? 0 : -1; },
                                      [](SceneDef& d, int i) {
                                          if (i == 0) d.swe.discharge = kSweAuto;
                                      }};
constexpr KeyWords kSweTimeScaleWords{kAuto, [](S d) { return d.swe.time_scale == kSweAuto ? 0 : -1; },
                                      [](SceneDef& d, int i) {
                                          if (i == 0) d.swe.time_scale = kSweAuto;
                                      }};
constexpr KeyWords kSweInitTimeWords{kAuto, [](S d) { return d.swe.init_max_time == kSweAuto ? 0 : -1; },
                                     [](SceneDef& d, int i) {
                                         if (i == 0) d.swe.init_max_time = kSweAuto;
                                     }};
constexpr KeyWords kSeaWords{kNone, [](S d) { return std::isnan(d.swe.sea_level) ? 0 : -1; },
                             [](SceneDef& d, int i) {
                                 if (i == 0) d.swe.sea_level = std::nanf("");
                             }};
constexpr std::string_view kSweInits[] = {"dry", "steady"};
constexpr std::string_view kSweEdges[] = {"open", "outfall"};
constexpr std::string_view kSweShapes[] = {"point", "line"};
constexpr KeyWords kLevelWords{kNone, [](S d) { return std::isnan(d.swe.initial_level) ? 0 : -1; },
                               [](SceneDef& d, int i) {
                                   if (i == 0) d.swe.initial_level = std::nanf("");
                               }};

using K = KeyType;
using E = KeyEdit;
const SceneKey kKeys[] = {
    // root
    {.name = "name", .type = K::String, .readers = kAll, .edit = E::Live, .help = "Shown in reports.", .field = MR_FIELD(name)},
    {.name = "solver", .type = K::Choice, .choices = kBuiltinSolverNames, .readers = kAll, .edit = E::Rebuild,
     .help = "pbf: Position Based Fluids (the default river, docs/river.md); springs: the paper's own physics; bullet: its "
             "engine physics (rigid spheres on Bullet, [bullet], docs/bullet.md); swe: shallow water on the terrain's grid, depth "
             "and velocity per sample ([swe], docs/shallow-water.md); hybrid: that grid, turned into PBF particles where it "
             "falls over a drop and back ([hybrid], docs/waterfalls.md).",
     .field = MR_FIELD(solver)},
    {.name = "seed", .type = K::Seed, .range = closed(0, 4294967295.0), .readers = kSeed, .edit = E::Rebuild,
     .help = "Particle spawn RNG seed (refused with solver = \"pbf\", as --seed is: its lattice source places every "
             "particle, nothing is random).",
     .field = MR_FIELD(seed)},
    // [terrain]
    {.name = "terrain.source", .type = K::Choice, .choices = kSources, .readers = kAll, .edit = E::Rebuild,
     .help = "valley: procedural valley with a winding river channel; strict, bowl: procedural equivalents of the paper's "
             "strict17.png and bowl.png; flat; file: the PNG of terrain.heightmap; waterfall, weir: a straight channel over a "
             "cliff into a plunge pool, or across a weir (the hybrid solver's scenes, docs/waterfalls.md); alps: the ETOPO5 Alps "
             "crop assets/heightmaps/real/alps.png (108 x 61 samples), built into the library so that a preset can use it.",
     .field = MR_FIELD(source.kind)},
    {.name = "terrain.heightmap", .type = K::String, .readers = kFile, .edit = E::Rebuild,
     .help = "PNG (8/16-bit gray, gray+alpha, RGB, RGBA; red channel), relative to the scene file; setting it implies "
             "source = \"file\" (--heightmap).",
     .field = MR_FIELD(source.heightmap)},
    {.name = "terrain.width", .type = K::Int, .unit = "samples", .range = closed(2, kMaxHeightmapSide),
     .readers = kProcedural, .edit = E::Rebuild,
     .help = "Samples along x.", .field = MR_FIELD(source.width)},
    {.name = "terrain.height", .type = K::Int, .unit = "samples", .range = closed(2, kMaxHeightmapSide),
     .readers = kProcedural, .edit = E::Rebuild,
     .help = "Samples along z.", .field = MR_FIELD(source.height)},
    {.name = "terrain.seed", .type = K::Seed, .range = closed(0, 4294967295.0), .readers = kValley, .edit = E::Rebuild,
     .help = "Procedural seed (only the valley is random).", .field = MR_FIELD(source.seed)},
    {.name = "terrain.area_scale", .type = K::Float, .unit = "m", .range = above(0, 1e4), .words = kAreaScaleWords,
     .readers = kAll, .edit = E::Rebuild,
     .help = "Metres between neighbouring samples (--area-scale; \"Heightmap scale\" below); \"auto\": 1 m, raised so that the "
             "terrain's shorter side is at least 16 m (a 2 x 2 map at 1 m is a 1 m terrain).", .field = MR_FIELD(terrain.area_scale)},
    {.name = "terrain.height_scale", .type = K::Float, .unit = "m", .range = above(0, 1e5), .readers = kAll, .edit = E::Rebuild,
     .help = "Metres for a normalised height of 1 (--height-scale).", .field = MR_FIELD(terrain.height_scale)},
    {.name = "terrain.paper_row_orientation", .type = K::Bool, .readers = kAll, .edit = E::Rebuild,
     .help = "Image row r -> z = (H-1-r) area_scale (the paper, Unity); false: z = r area_scale.",
     .field = MR_FIELD(terrain.paper_row_orientation)},
    {.name = "terrain.condition", .type = K::Choice, .choices = kConditions, .readers = kAll, .edit = E::Rebuild,
     .help = "Drainage conditioning before the mesh is built. fill: priority-flood filling with a 0.1 % slope; breach: a "
             "channel carved from each depression through its rim; carve: breach, then the river's main channel (source to "
             "outlet) cut in: a flat bed max(3 samples, 4 pbf.spacing) wide and 2 pbf.spacing deep that never rises (least slope 2 %), "
             "parabolic walls, levees where the ground beside is lower, a basin under the source; auto: carve for a PBF "
             "river (a flow rate and sink.kind = \"edges\"), none otherwise (a still pool keeps its basin). `run --stats` "
             "reports what it changed (docs/river.md).",
     .field = MR_FIELD(terrain.condition)},
    // [particles]
    {.name = "particles.count", .type = K::Int, .range = closed(1, kMaxParticles), .words = kCountWords,
     .readers = kParticleSource, .edit = E::Rebuild,
     .help = "Particle budget, or \"auto\": a PBF river sizes it to its main channel (docs/river.md, \"Sizing\"); other "
             "solvers take 4000.",
     .field = MR_FIELD(spawn.count)},
    {.name = "particles.spawn_center", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .words = kCentreWords, .readers = kAll,
     .help = "Centre of the source; \"auto\": above the lowest point of the upstream band (the 10 % of rows with the "
             "highest z); \"channel\": the head of the terrain's main channel.",
     .field = MR_FIELD(spawn.center)},
    {.name = "particles.spawn_half_extent", .type = K::Vec3, .unit = "m", .range = big_vec(0), .readers = kNotPoint,
     .help = "Half size of the source (a disc: radius .x, half height .y).", .field = MR_FIELD(spawn.half_extent)},
    {.name = "particles.spawn_interval", .type = K::Int, .unit = "frames", .range = closed(0, 1e6), .readers = kNoRate,
     .help = "Frames between two activations without a particle rate; 0 = all at once.", .field = MR_FIELD(spawn.interval)},
    {.name = "particles.initial_velocity", .type = K::Vec3, .unit = "m/s", .range = closed(-1e4, 1e4), .readers = kParticleSource,
     .help = "Velocity given at (re)spawn.", .field = MR_FIELD(spawn.initial_velocity)},
    {.name = "particles.auto_height", .type = K::Float, .unit = "m", .range = closed(0, 1e4),
     .readers = kAutoCentre, .edit = E::Rebuild,
     .help = "Height of an \"auto\" or \"channel\" centre above the ground; the source is moved inward until its "
             "footprint is inside the terrain and raised until half of the ground under it is 0.5 m below its bottom.",
     .field = MR_FIELD(spawn.auto_height)},
    {.name = "particles.source_shape", .type = K::Choice, .choices = kShapes, .readers = kShape,
     .help = "box | disc (radius spawn_half_extent.x) | point.", .field = MR_FIELD(spawn.shape)},
    {.name = "particles.flow_rate", .type = K::Float, .unit = "1/s", .range = closed(0, 1e7), .words = kRateWords, .readers = kFlowRate,
     .help = "Particles (or litres, with litres_per_particle) per second; 0: one every spawn_interval frames; \"auto\": a "
             "PBF river sizes it to its carved channel (`run` prints the values it chose; a number here keeps count "
             "\"auto\" sized to it). Above particles.count per second: a warning; PBF: above what the lattice source can "
             "deliver, a warning and capped (docs/river.md, \"Lattice sources\").",
     .field = MR_FIELD(spawn.flow_rate)},
    {.name = "particles.litres_per_particle", .type = K::Float, .unit = "l", .range = closed(0, 1e9), .readers = kRate,
     .help = "> 0: flow_rate is in litres per second, each particle this many litres.", .field = MR_FIELD(spawn.litres_per_particle)},
    {.name = "particles.prefill", .type = K::Bool, .readers = kPbfCarved, .edit = E::Rebuild,
     .help = "Fill the carved main channel with water at the start (three quarters of its depth, moving down it at "
             "0.75 m/s, at most half the budget), so the river runs from the first frame instead of after its front "
             "crossed the channel (docs/river.md, \"Quadratic bed friction and a channel that starts full\").",
     .field = MR_FIELD(spawn.prefill)},
    {.name = "particles.follow_ground", .type = K::Bool, .readers = kPbfRate,
     .help = "Lower each column of the source's lattice slots until its lowest slot sits just above the ground under "
             "it, so water on a slope is born on the ground instead of falling from a flat disc above its downhill "
             "side (docs/river.md, \"A source that follows the ground\").",
     .field = MR_FIELD(spawn.follow_ground)},
    // [pbf]
    {.name = "pbf.spacing", .type = K::Float, .unit = "m", .range = closed(1e-3, 1e3), .words = kSpacingWords,
     .readers = kPbfOrCarve, .edit = E::Rebuild,
     .help = "Rest spacing (below 1 mm the kernel constants overflow); a carved channel's depth and width. \"auto\": a "
             "self-sized river's spacing from its terrain (docs/river.md, \"Spacing and scale\"): 0.5 m per metre of "
             "area_scale, at most the shorter side / 32; the kernel, collision and field lengths and the source scale with "
             "it.", .field = MR_FIELD(pbf.spacing)},
    {.name = "pbf.kernel_radius", .type = K::Float, .unit = "m", .range = {.lo = 0, .hi = 4e3, .lo_open = true, .text = "(pbf.spacing, 4 pbf.spacing]"},
     .readers = kPbf, .help = "Smoothing length h.", .field = MR_FIELD(pbf.kernel_radius)},
    {.name = "pbf.iterations", .type = K::Int, .range = closed(1, 100), .readers = kPbf,
     .help = "Density-constraint iterations per step.", .field = MR_FIELD(pbf.iterations)},
    {.name = "pbf.relaxation", .type = K::Float, .range = above(0, 1e3), .readers = kPbf,
     .help = "Constraint force mixing, relative to a lattice particle's sum |grad C|^2.", .field = MR_FIELD(pbf.relaxation)},
    {.name = "pbf.scorr_k", .type = K::Float, .range = closed(0, 1), .readers = kPbf,
     .help = "Tensile-instability correction strength; 0 = off.", .field = MR_FIELD(pbf.scorr_k)},
    {.name = "pbf.scorr_n", .type = K::Int, .range = closed(1, 8), .readers = kScorr, .help = "Its exponent.", .field = MR_FIELD(pbf.scorr_n)},
    {.name = "pbf.scorr_dq", .type = K::Float, .unit = "h", .range = closed(1e-3, 0.999), .readers = kScorr,
     .help = "Its reference distance, a fraction of h.", .field = MR_FIELD(pbf.scorr_dq)},
    {.name = "pbf.xsph", .type = K::Float, .range = closed(0, 1), .readers = kPbf, .help = "XSPH viscosity.", .field = MR_FIELD(pbf.xsph)},
    {.name = "pbf.vorticity", .type = K::Float, .range = closed(0, 100), .readers = kPbf,
     .help = "Vorticity confinement; 0 = off.", .field = MR_FIELD(pbf.vorticity)},
    {.name = "pbf.sleep_threshold", .type = K::Float, .unit = "m/s", .range = closed(0, 1), .words = kSleepWords, .readers = kPbf,
     .help = "0 = off. A particle slower than this for 0.1 s sleeps (its slow steps are undone) until a step moves it "
             "faster (docs/river.md, \"Sleeping\"); capped at 0.9 x gravity x the step so nothing sleeps in mid-air. "
             "\"auto\": 0 for a river (a flow rate and sink.kind = \"edges\": a slow river on a gentle bed fell asleep "
             "and stopped), 0.065 otherwise (still water comes to rest).",
     .field = MR_FIELD(pbf.sleep_threshold)},
    {.name = "pbf.sleep_drift", .type = K::Float, .unit = "m/s", .range = closed(0, 1), .readers = kPbf,
     .help = "0 = off. Sleeping also asks that the particle's mean horizontal velocity (an exponential average over "
             "0.5 s) be slower than this: a slosh's turn is slow for a moment, its mean is not, so a pool levels out "
             "before it falls asleep instead of freezing tilted (docs/rendering.md, \"Still water that is level\").",
     .field = MR_FIELD(pbf.sleep_drift)},
    {.name = "pbf.damping", .type = K::Float, .unit = "1/s", .range = closed(0, 100), .words = kDampingWords, .readers = kPbf,
     .help = "Slow-water damping; 0 = off. Each step a particle's velocity is scaled by exp(-damping s dt), s = 1 below "
             "damping_speed and falling to 0 at twice it: a pool's slosh dies out before it falls asleep, faster water "
             "is untouched. \"auto\": 0 for a river (a flow rate and sink.kind = \"edges\"), 1 otherwise.",
     .field = MR_FIELD(pbf.damping)},
    {.name = "pbf.damping_speed", .type = K::Float, .unit = "m/s", .range = above(0, 1e3), .readers = kPbf,
     .help = "Speed below which pbf.damping acts fully; none at twice it.", .field = MR_FIELD(pbf.damping_speed)},
    {.name = "pbf.wall_density", .type = K::Float, .range = closed(0, 1), .words = kWallDensityWords, .readers = kPbfContact,
     .help = "Weight of the terrain in each particle's density: the share of its kernel under the terrain (a quadrature "
             "over the heightfield around it: the ground below, a steep wall beside it and the crease at the wall's "
             "foot) counts as water at rest and pushes back through the constraint, so water at the bed and banks "
             "keeps the rest spacing and a pool is level to its shore (0: the ground adds nothing; the still pool's "
             "surface rose 4-7 cm towards the banks). \"auto\": 0 for a river (its flow as tuned), 1 otherwise.",
     .field = MR_FIELD(pbf.wall_density)},
    {.name = "pbf.contact_band", .type = K::Float, .unit = "spacings", .range = closed(0, 10), .words = kContactBandWords,
     .readers = kPbfContact,
     .help = "A particle closer than this to the ground under it counts as touching it for the bed friction "
             "(collision.damping); 0: only particles the collision pushed out of the terrain (with pbf.wall_density "
             "the bed is held off the ground by pressure and rarely pushed out). \"auto\": 0 for a river (its "
             "friction as tuned), 1.5 otherwise (a pool's first slosh stays in its bowl).",
     .field = MR_FIELD(pbf.contact_band)},
    // [sink]
    {.name = "sink.kind", .type = K::Choice, .choices = kSinks, .readers = kSinkKind,
     .help = "none: particles respawn only when they leave the terrain's box | box: entering [min, max] | edges: leaving "
             "the terrain's rectangle over an edge (its outlets). Sunk particles are recycled to the source.",
     .field = MR_FIELD(sink.kind)},
    {.name = "sink.min", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .readers = kSinkBox, .help = "Box corner.", .field = MR_FIELD(sink.min)},
    {.name = "sink.max", .type = K::Vec3, .unit = "m", .range = {.lo = -1e6, .hi = 1e6, .text = "[sink.min, 1000000]"},
     .readers = kSinkBox, .help = "The opposite corner.", .field = MR_FIELD(sink.max)},
    // [forces]
    {.name = "forces.gravity", .type = K::Float, .unit = "m/s^2", .range = closed(-1000, 1000), .readers = kAll,
     .help = "Downwards.", .field = MR_FIELD(integrator.gravity)},
    // [springs]
    {.name = "springs.stiffness", .type = K::Float, .unit = "1/s^2", .range = closed(0, 1e6), .readers = kSpringsK,
     .help = "k; 0 = off.", .field = MR_FIELD(springs.stiffness)},
    {.name = "springs.min_distance", .type = K::Float, .unit = "m", .range = closed(0, 1e4), .readers = kSpringsOn,
     .help = "r, the rest length.", .field = MR_FIELD(springs.min_distance)},
    {.name = "springs.max_distance", .type = K::Float, .unit = "m", .range = closed(0, 1e4), .readers = kSpringsOn,
     .help = "Pairs with |v| - r >= max_distance are skipped.", .field = MR_FIELD(springs.max_distance)},
    {.name = "springs.mode", .type = K::Choice, .choices = kSpringModes, .readers = kSpringMode,
     .help = "pairs: the paper's all-pairs loop (the serial reference; refused above 20,000 particles); grid: the "
             "neighbour grid, parallel, the same forces (tested).",
     .field = MR_FIELD(springs.mode)},
    // [collision]
    {.name = "collision.mode", .type = K::Choice, .choices = kCollisionModes, .readers = kCollision,
     .help = "paper: the leaf of the new position, eq. 4 | robust: the swept segment through the whole tree, watertight, "
             "a guard (0 tunneling) | none. solver = \"pbf\": robust or none (it slides, never reflects).",
     .field = MR_FIELD(collision.mode)},
    {.name = "collision.damping", .type = K::Float, .range = closed(0, 1), .readers = kContact,
     .help = "Fraction of speed lost at a bounce; solver = \"pbf\": the bed friction, the share of a particle's motion "
             "along the ground it loses in each step the terrain holds it (still water 0.02: docs/river.md, \"Bed friction\").",
     .field = MR_FIELD(collision.damping)},
    {.name = "collision.friction_speed", .type = K::Float, .unit = "m/s", .range = closed(0, 1e3), .readers = kBedFriction,
     .help = "The bed friction's law: 0 = the share damping at every speed (linear drag); > 0 = the share damping x "
             "speed / friction_speed, at most 0.5 (quadratic drag, as a river bed's: slow sheets spread, fast chutes "
             "are held; docs/river.md, \"Quadratic bed friction and a channel that starts full\").",
     .field = MR_FIELD(collision.friction_speed)},
    {.name = "collision.offset", .type = K::Float, .unit = "m", .range = closed(0, 10), .readers = kOffset,
     .help = "Placed above the hit point.", .field = MR_FIELD(collision.offset)},
    {.name = "collision.bvh_leaf_triangles", .type = K::Int, .range = closed(2, 4096), .readers = kAll, .edit = E::Rebuild,
     .help = "AABB tree leaf size (every scene builds the tree; the viewer draws it).", .field = MR_FIELD(collision.leaf_triangles)},
    {.name = "collision.radius", .type = K::Float, .unit = "m", .range = closed(0, 100), .readers = kCollision,
     .help = "Particle radius: the centre stays this far above the ground (the terrain lifted vertically; exact on flat "
             "ground); the tunneled counter reads it.",
     .field = MR_FIELD(collision.radius)},
    {.name = "collision.query", .type = K::Choice, .choices = kQueries, .readers = kRobust,
     .help = "Robust mode's segment query: tree (the AABB tree) | heightfield (walk the cells under the segment: the same "
             "hits, faster).",
     .field = MR_FIELD(collision.query)},
    // [integrator]
    {.name = "integrator.dt", .type = K::Float, .unit = "s", .range = {.lo = 0, .hi = 1, .lo_open = true, .zero_too = true},
     .readers = kAll, .help = "Fixed step; 0: the frame time (the paper).", .field = MR_FIELD(integrator.fixed_dt)},
    {.name = "integrator.substeps", .type = K::Int, .range = closed(1, 1000), .readers = kSubsteps,
     .help = "Solver steps per frame (Bullet: bullet.dt, max_substeps).", .field = MR_FIELD(integrator.substeps)},
    // [field]
    {.name = "field.kernel", .type = K::Choice, .choices = kKernels, .readers = kSurface, .edit = E::Live,
     .help = "inverse_square: eq. 2, 1/r^2 | radius_over_r: the paper's code (both reach every grid sample: refused "
             "above 5,000 balls) | poly6: compact, sparse blocks, parallel.",
     .field = MR_FIELD(field.kernel)},
    {.name = "field.bounds", .type = K::Choice, .choices = kBounds, .readers = kSurface, .edit = E::Live,
     .help = "particles: the particles' box grown by bounds_offset (the paper) | terrain: the terrain's box, fixed "
             "(poly6 only).",
     .field = MR_FIELD(field.bounds)},
    {.name = "field.radius", .type = K::Float, .unit = "m", .range = above(0, 1e4), .readers = kRadius, .edit = E::Live,
     .help = "Metaball radius (radius_over_r); poly6: the support radius.", .field = MR_FIELD(field.radius)},
    {.name = "field.resolution", .type = K::Float, .unit = "1/m", .range = above(0, 64), .readers = kAll, .edit = E::Live,
     .help = "Grid cells per metre; also the default voxel size of --export --format vdb.", .field = MR_FIELD(field.resolution)},
    {.name = "field.bounds_offset", .type = K::Float, .unit = "m", .range = closed(0, 1e4), .readers = kSurface, .edit = E::Live,
     .help = "The particles' box grows by this on every side.", .field = MR_FIELD(field.bounds_offset)},
    {.name = "field.threshold", .type = K::Float, .range = above(0, 1e9), .readers = kSurface, .edit = E::Live,
     .help = "Iso value: inside where the field is above it.", .field = MR_FIELD(field.threshold)},
    // [surface]
    {.name = "surface.enabled", .type = K::Bool, .readers = kAll, .edit = E::Live,
     .help = "Build the field and the marching-cubes surface every frame; the root key `surface = true/false` is the same "
             "switch (a file has one or the other: TOML allows a name once).",
     .field = MR_FIELD(surface)},
    {.name = "surface.method", .type = K::Choice, .choices = kMethods, .readers = kSmoothingMethod, .edit = E::Live,
     .help = "none: the mesh as extracted | laplacian: feature-weighted Laplacian steps as splashsurf does (Loeschner et "
             "al. 2023), then the volume given back | taubin: lambda|mu steps (Taubin 1995), keep the volume, flatten less.",
     .field = MR_FIELD(smoothing.method)},
    {.name = "surface.steps", .type = K::Choice, .choices = kSteps, .readers = kLaplacian, .edit = E::Live,
     .help = "chebyshev: step sizes that damp the band [pass_band, 2] of mesh frequencies evenly (Taubin, Zhang, Golub "
             "1996: 8 steps damp it to 0.05, 16 uniform steps of 1 leave 0.19) | uniform: every step lambda.",
     .field = MR_FIELD(smoothing.steps)},
    {.name = "surface.iterations", .type = K::Int, .range = closed(0, 100), .readers = kSmoothing, .edit = E::Live,
     .help = "Steps (each a pass over the moving vertices).", .field = MR_FIELD(smoothing.iterations)},
    {.name = "surface.lambda", .type = K::Float, .range = above(0, 1), .readers = kLambda, .edit = E::Live,
     .help = "Share of the way to the neighbours' mean per step.", .field = MR_FIELD(smoothing.lambda)},
    {.name = "surface.pass_band", .type = K::Float, .range = {.lo = 0, .hi = 1, .lo_open = true, .hi_open = true},
     .readers = kPassBand, .edit = E::Live,
     .help = "Mesh frequency (0 to 2) below which shapes are kept: taubin's k_PB (mu = 1 / (k_PB - 1 / lambda)), "
             "chebyshev's band [pass_band, 2].",
     .field = MR_FIELD(smoothing.pass_band)},
    {.name = "surface.feature_count", .type = K::Float, .range = {.lo = 2, .hi = 1000, .zero_too = true},
     .readers = kFeatures, .edit = E::Live,
     .help = "0: off (every vertex moves fully). The poly6 field one lone particle's iso distance inside the surface is "
             "about the number of particles behind a vertex (a lone drop 1, a touching pair 1.4, still water 2 to 4): at "
             "or below feature_count / 2 a vertex does not move, from feature_count on it moves fully (smoothstep between).",
     .field = MR_FIELD(smoothing.feature_count)},
    {.name = "surface.keep_volume", .type = K::Bool, .readers = kLaplacian, .edit = E::Live,
     .help = "Move the smoothed vertices along their normals by what the steps took from the enclosed volume.",
     .field = MR_FIELD(smoothing.keep_volume)},
    {.name = "surface.normal_iterations", .type = K::Int, .range = closed(0, 100), .readers = kSmoothingOn, .edit = E::Live,
     .help = "Passes that average each recomputed normal with its neighbours'.", .field = MR_FIELD(smoothing.normal_iterations)},
    {.name = "surface.smooth_hidden", .type = K::Bool, .readers = kSmoothingOn, .edit = E::Live,
     .help = "Smooth the vertices below the terrain too (the river's bed, about half of its mesh, hidden by the "
             "ground); false: they stay as extracted.",
     .field = MR_FIELD(smoothing.smooth_hidden)},
    // [foam]
    {.name = "foam.enabled", .type = K::Bool, .readers = kFoamSwitch,
     .help = "Make diffuse particles (on in the default scene, off in the other presets; enabled = false is accepted in "
             "any scene).",
     .field = MR_FIELD(foam.enabled)},
    {.name = "foam.max_particles", .type = K::Int, .range = closed(0, 1e6), .readers = kFoam,
     .help = "Live diffuse particles at most (emission beyond is dropped, counted).", .field = MR_FIELD(foam.max_particles)},
    {.name = "foam.trapped_air_min", .type = K::Float, .unit = "m/s", .range = closed(0, 1e3), .readers = kFoam,
     .help = "I_ta below this traps no air.", .field = MR_FIELD(foam.trapped_air_min)},
    {.name = "foam.trapped_air_max", .type = K::Float, .unit = "m/s", .range = {.lo = 0, .hi = 1e3, .lo_open = true, .text = "(foam.trapped_air_min, 1000]"},
     .readers = kFoam, .help = "I_ta from here on counts fully.", .field = MR_FIELD(foam.trapped_air_max)},
    {.name = "foam.wave_crest_min", .type = K::Float, .range = closed(0, 1e3), .readers = kFoam,
     .help = "I_wc below this makes no crest foam.", .field = MR_FIELD(foam.wave_crest_min)},
    {.name = "foam.wave_crest_max", .type = K::Float, .range = {.lo = 0, .hi = 1e3, .lo_open = true, .text = "(foam.wave_crest_min, 1000]"},
     .readers = kFoam, .help = "I_wc from here on counts fully.", .field = MR_FIELD(foam.wave_crest_max)},
    {.name = "foam.energy_min", .type = K::Float, .unit = "J/kg", .range = closed(0, 1e6), .readers = kFoam,
     .help = "I_k below this emits nothing (0.5: slower than 1 m/s, a pool at rest makes none).", .field = MR_FIELD(foam.energy_min)},
    {.name = "foam.energy_max", .type = K::Float, .unit = "J/kg", .range = {.lo = 0, .hi = 1e6, .lo_open = true, .text = "(foam.energy_min, 1000000]"},
     .readers = kFoam, .help = "I_k from here on counts fully (8: 4 m/s).", .field = MR_FIELD(foam.energy_max)},
    {.name = "foam.trapped_air_rate", .type = K::Float, .unit = "1/s", .range = closed(0, 1e4), .readers = kFoam,
     .help = "Diffuse particles per fluid particle per second at Phi_ta = Phi_k = 1.", .field = MR_FIELD(foam.trapped_air_rate)},
    {.name = "foam.wave_crest_rate", .type = K::Float, .unit = "1/s", .range = closed(0, 1e4), .readers = kFoam,
     .help = "The same for the wave crest.", .field = MR_FIELD(foam.wave_crest_rate)},
    {.name = "foam.lifetime_min", .type = K::Float, .unit = "s", .range = closed(0.01, 1e3), .readers = kFoam,
     .help = "Each particle draws its life from [lifetime_min, lifetime_max].", .field = MR_FIELD(foam.lifetime_min)},
    {.name = "foam.lifetime_max", .type = K::Float, .unit = "s", .range = {.lo = 0.01, .hi = 1e3, .text = "[foam.lifetime_min, 1000]"},
     .readers = kFoam, .help = "See lifetime_min.", .field = MR_FIELD(foam.lifetime_max)},
    {.name = "foam.spray_neighbours", .type = K::Int, .range = closed(0, 1000), .readers = kFoam,
     .help = "Fewer fluid neighbours within h: spray (ballistic under gravity).", .field = MR_FIELD(foam.spray_neighbours)},
    {.name = "foam.bubble_neighbours", .type = K::Int, .range = {.lo = 0, .hi = 1000, .text = "[foam.spray_neighbours, 1000]"},
     .readers = kFoam,
     .help = "More: a bubble (buoyant, dragged to the fluid's velocity); between: foam (moves with the W~-averaged fluid "
             "velocity).",
     .field = MR_FIELD(foam.bubble_neighbours)},
    {.name = "foam.buoyancy", .type = K::Float, .unit = "g", .range = closed(0, 100), .readers = kFoam,
     .help = "Bubbles' upward acceleration in units of gravity.", .field = MR_FIELD(foam.buoyancy)},
    {.name = "foam.drag", .type = K::Float, .range = closed(0, 1), .readers = kFoam,
     .help = "Share of a bubble's velocity difference to the fluid removed per frame.", .field = MR_FIELD(foam.drag)},
    // [render]
    {.name = "render.flow_detail", .type = K::Bool, .readers = kAll, .edit = E::Live,
     .help = "Realistic water: ripples and foam streaks advected along the flow, stronger where it is fast, none on "
             "still water (docs/rendering.md, \"Flow detail\"); render --no-flow and the viewer's key L turn it off.",
     .field = MR_FIELD(render.flow_detail)},
    // [bullet]
    {.name = "bullet.terrain", .type = K::Choice, .choices = kBulletTerrains, .readers = kBullet, .edit = E::Rebuild,
     .help = "mesh: btBvhTriangleMeshShape of the terrain's triangles (the paper's mesh collider) | heightfield: "
             "btHeightfieldTerrainShape (the same samples, the same diagonal split).",
     .field = MR_FIELD(bullet.terrain)},
    {.name = "bullet.sphere_radius", .type = K::Float, .unit = "m", .range = above(0, 1e3), .readers = kBullet, .edit = E::Rebuild,
     .help = "Collider radius of every particle.", .field = MR_FIELD(bullet.sphere_radius)},
    {.name = "bullet.mass", .type = K::Float, .unit = "kg", .range = above(0, 1e6), .readers = kBullet, .edit = E::Rebuild,
     .help = "Per sphere.", .field = MR_FIELD(bullet.mass)},
    {.name = "bullet.friction", .type = K::Float, .range = closed(0, 100), .readers = kBullet, .edit = E::Rebuild,
     .help = "Contact friction (Bullet's default 0.5).", .field = MR_FIELD(bullet.friction)},
    {.name = "bullet.restitution", .type = K::Float, .range = closed(0, 1), .readers = kBullet, .edit = E::Rebuild,
     .help = "Bounciness.",
     .field = MR_FIELD(bullet.restitution)},
    {.name = "bullet.particle_collisions", .type = K::Bool, .readers = kBullet, .edit = E::Rebuild,
     .help = "Spheres collide with each other (the paper: no).", .field = MR_FIELD(bullet.particle_collisions)},
    {.name = "bullet.dt", .type = K::Float, .unit = "s", .range = above(0, 1), .readers = kBulletSubsteps, .edit = E::Rebuild,
     .help = "Bullet's fixed internal step.", .field = MR_FIELD(bullet.fixed_dt)},
    {.name = "bullet.max_substeps", .type = K::Int, .range = closed(0, 1000), .readers = kBullet, .edit = E::Rebuild,
     .help = "Internal steps per frame at most; 0 = one step of the frame time.", .field = MR_FIELD(bullet.max_substeps)},
    {.name = "bullet.solver_iterations", .type = K::Int, .range = closed(1, 1000), .readers = kBullet, .edit = E::Rebuild,
     .help = "Sequential-impulse iterations.", .field = MR_FIELD(bullet.solver_iterations)},
    {.name = "bullet.ccd", .type = K::Bool, .readers = kBullet, .edit = E::Rebuild,
     .help = "Continuous collision detection (a sphere moving more than half its radius in a step is swept).",
     .field = MR_FIELD(bullet.ccd)},
    {.name = "bullet.sleep", .type = K::Bool, .readers = kBulletSleep, .edit = E::Rebuild,
     .help = "Bullet's deactivation of resting spheres (spheres with springs never sleep).", .field = MR_FIELD(bullet.sleep)},
    {.name = "bullet.springs", .type = K::Bool, .readers = kBullet, .edit = E::Rebuild,
     .help = "The paper's eq. 3 ([springs]) as external forces: its future work.", .field = MR_FIELD(bullet.springs)},
    // [swe]
    {.name = "swe.manning", .type = K::Float, .unit = "s/m^(1/3)", .range = closed(0, 1), .readers = kSwe, .edit = E::Solver,
     .help = "Manning's n of the bed (0.03: a natural channel; 0: frictionless), applied implicitly.", .field = MR_FIELD(swe.manning)},
    {.name = "swe.cfl", .type = K::Float, .range = above(0, 0.5), .readers = kSwe, .edit = E::Solver,
     .help = "Courant number of the adaptive time step (substeps per frame follow it).", .field = MR_FIELD(swe.cfl)},
    {.name = "swe.dry_depth", .type = K::Float, .unit = "m", .range = closed(0, 1), .readers = kSwe, .edit = E::Solver,
     .help = "Water shallower than this has no velocity (wetting and drying).", .field = MR_FIELD(swe.dry_depth)},
    {.name = "swe.second_order", .type = K::Bool, .readers = kSwe, .edit = E::Solver,
     .help = "MUSCL slopes with Heun's two stages; false: first order at half the cost.", .field = MR_FIELD(swe.second_order)},
    {.name = "swe.discharge", .type = K::Float, .unit = "m^3/s", .range = closed(0, 1e6), .words = kSweDischargeWords,
     .readers = kSwe, .edit = E::Solver,
     .help = "The source's discharge at swe.source_center; 0: no source; auto: a river at least a cell wide at any scale "
             "(uniform Manning flow 0.3 m deep over one cell's width on the main channel's mean slope), 0 when the scene "
             "has swe.initial_level or [[swe.sources]].",
     .field = MR_FIELD(swe.discharge)},
    {.name = "swe.source_center", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .words = kSweSourceWords, .readers = kSwe,
     .edit = E::Solver, .help = "Where the source pours (x, z; y unused); auto: particles.spawn_center's resolved place.",
     .field = MR_FIELD(swe.source_center)},
    {.name = "swe.rain", .type = K::Float, .unit = "mm/h", .range = closed(0, 1e4), .readers = kSwe, .edit = E::Solver,
     .help = "Rain over the whole map, or within swe.rain_radius of swe.rain_center, or weighed by swe.rain_mask.",
     .field = MR_FIELD(swe.rain)},
    {.name = "swe.rain_center", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .readers = kSwe, .edit = E::Solver,
     .help = "The centre (x, z; y unused) of the circle swe.rain falls in when swe.rain_radius > 0.", .field = MR_FIELD(swe.rain_center)},
    {.name = "swe.rain_radius", .type = K::Float, .unit = "m", .range = closed(0, 1e7), .readers = kSwe, .edit = E::Solver,
     .help = "Rain only on the cells within this distance of swe.rain_center; 0: over the whole map.", .field = MR_FIELD(swe.rain_radius)},
    {.name = "swe.rain_mask", .type = K::String, .readers = kSwe, .edit = E::Solver,
     .help = "A grayscale PNG over the whole map, relative to the scene file: each cell's rain is swe.rain times the "
             "image's value there (black 0, white 1; the first channel), the image stretched over the grid (bilinear) "
             "when its size differs; with swe.rain_radius the circle applies too. \"\": none.",
     .field = MR_FIELD(swe.rain_mask)},
    {.name = "swe.sea_level", .type = K::Float, .unit = "m", .range = closed(-1e6, 1e6), .words = kSeaWords, .readers = kSwe,
     .edit = E::Solver,
     .help = "Cells whose bed lies below this height are the sea: a sink taking all the water that reaches them (counted as "
             "sunk); none: no sea. On a DEM at --real-scale the sea is at minus the sidecar's metres_min.",
     .field = MR_FIELD(swe.sea_level)},
    {.name = "swe.time_scale", .type = K::Float, .range = closed(1e-3, 1e6), .words = kSweTimeScaleWords, .readers = kSwe,
     .edit = E::Solver,
     .help = "Simulated seconds per second of frame time (substeps follow); auto: terrain.area_scale (1 at 1 m per sample, "
             "9266 on a 5 arc-minute DEM at --real-scale, where the water crosses about a cell a second at 1 m/s).",
     .field = MR_FIELD(swe.time_scale)},
    {.name = "swe.init", .type = K::Choice, .choices = kSweInits, .readers = kSwe, .edit = E::Rebuild,
     .help = "dry: the map starts dry (or holds swe.initial_level's lake); steady: spun up before frame 0 (first order, CFL "
             "0.5) until what leaves the map matches what comes in within swe.init_tolerance, or swe.init_max_time: frame 0 "
             "is the river.",
     .field = MR_FIELD(swe.init)},
    {.name = "swe.edges", .type = K::Choice, .choices = kSweEdges, .readers = kSwe, .edit = E::Solver,
     .help = "The map's four edges. open: transmissive (the state outside copies the edge cell; a slow river over a flat "
             "floor running off the map drains slowly and pools); outfall: a free overfall (the map ends in a drop: the "
             "water leaves at its critical depth, (8/27) sqrt(g) h^1.5 per metre of edge from a lake at rest, and "
             "nothing comes in).",
     .field = MR_FIELD(swe.edges)},
    {.name = "swe.init_tolerance", .type = K::Float, .range = closed(1e-6, 1), .readers = kSwe, .edit = E::Rebuild,
     .help = "swe.init = \"steady\": the spin-up stops when, over two windows of a fortieth of its time cap running, "
             "outflow + sinks differ from inflow + rain, and the stored volume changes, by at most this share of the inflow.",
     .field = MR_FIELD(swe.init_tolerance)},
    {.name = "swe.init_max_time", .type = K::Float, .unit = "s", .range = closed(1e-3, 1e10), .words = kSweInitTimeWords,
     .readers = kSwe, .edit = E::Rebuild,
     .help = "swe.init = \"steady\": simulated seconds the spin-up runs at most; auto: the larger of 8 times the main channel's "
             "length (at least half the map's diagonal) over 0.5 m/s and 20 residence times (the volume the map holds over the "
             "inflow per second, measured as it fills). Whatever it says, the work stops at swe.init_max_work.",
     .field = MR_FIELD(swe.init_max_time)},
    {.name = "swe.init_max_work", .type = K::Float, .unit = "cell updates", .range = closed(1e3, 1e13), .readers = kSwe,
     .edit = E::Rebuild,
     .help = "swe.init = \"steady\": cell updates the spin-up spends at most (its wall time: 6e9 is about a minute on two "
             "cores), and one substep per 5000 of them, whatever swe.init_max_time says.",
     .field = MR_FIELD(swe.init_max_work)},
    {.name = "swe.initial_level", .type = K::Float, .unit = "m", .range = closed(-1e6, 1e6), .words = kLevelWords, .readers = kSwe,
     .edit = E::Rebuild, .help = "A still lake up to this height at the start (every sample below it wet); none: the map starts dry.",
     .field = MR_FIELD(swe.initial_level)},
    {.name = "swe.dam_z", .type = K::Float, .unit = "m", .range = closed(-1e6, 1e6), .words = kDamWords, .readers = kSwe,
     .edit = E::Rebuild, .help = "With swe.initial_level: the lake only where z >= dam_z, held by a dam across the map that is "
                                 "gone at the start (a dam break); none: the lake everywhere below the level.",
     .field = MR_FIELD(swe.dam_z)},
    // [hybrid]
    {.name = "hybrid.drop", .type = K::Float, .unit = "m", .range = above(0, 1e4), .readers = kHybrid, .edit = E::Solver,
     .help = "A wet cell whose bed lies more than this above its neighbour's, with the flow towards it, sheds the volume "
             "that flows over that face as particles, where the face is as steep as hybrid.min_grade or the flow "
             "launches (hybrid.launch).", .field = MR_FIELD(hybrid.drop)},
    {.name = "hybrid.min_grade", .type = K::Float, .range = closed(0, 1000), .readers = kHybrid, .edit = E::Solver,
     .help = "Drop over cell size: a face that drops more than hybrid.drop at least this steeply (1: 45 degrees) is a "
             "cliff and sheds at any speed; on km cells a gentle reach drops metres between cells and sheds nothing.",
     .field = MR_FIELD(hybrid.min_grade)},
    {.name = "hybrid.launch", .type = K::Float, .range = closed(0, 1000), .readers = kHybrid, .edit = E::Solver,
     .help = "A gentler face (convex, dropping more than hybrid.drop) sheds where 2 u^2 (grade - the grade upstream) >= "
             "this x g x cell size: water thrown at the cell's speed u falls less than the bed (1); 0: cliffs only.",
     .field = MR_FIELD(hybrid.launch)},
    {.name = "hybrid.min_depth", .type = K::Float, .unit = "m", .range = closed(0, 100), .readers = kHybrid, .edit = E::Solver,
     .help = "Shallower cells shed nothing.", .field = MR_FIELD(hybrid.min_depth)},
    {.name = "hybrid.min_speed", .type = K::Float, .unit = "m/s", .range = closed(0, 100), .readers = kHybrid, .edit = E::Solver,
     .help = "Slower flow over the edge sheds nothing.", .field = MR_FIELD(hybrid.min_speed)},
    {.name = "hybrid.absorb_age", .type = K::Float, .unit = "s", .range = closed(0, 100), .readers = kHybrid, .edit = E::Solver,
     .help = "A particle younger than this is not absorbed by the water it lands on.", .field = MR_FIELD(hybrid.absorb_age)},
    {.name = "hybrid.absorb_depth", .type = K::Float, .unit = "m", .range = closed(0, 100), .readers = kHybrid, .edit = E::Solver,
     .help = "A cell at least this deep absorbs the particles at or below its surface.", .field = MR_FIELD(hybrid.absorb_depth)},
    {.name = "hybrid.rest_speed", .type = K::Float, .unit = "m/s", .range = closed(0, 100), .readers = kHybrid, .edit = E::Solver,
     .help = "A particle on the ground slower than this is at rest.", .field = MR_FIELD(hybrid.rest_speed)},
    {.name = "hybrid.rest_time", .type = K::Float, .unit = "s", .range = closed(0, 1e4), .readers = kHybrid, .edit = E::Solver,
     .help = "Seconds at rest on the ground after which a particle goes into the cell under it, wet or dry.",
     .field = MR_FIELD(hybrid.rest_time)},
    {.name = "hybrid.max_particles", .type = K::Int, .range = closed(1, 10000000), .readers = kHybrid, .edit = E::Rebuild,
     .help = "The particle budget; while it is spent the grid keeps its water.", .field = MR_FIELD(hybrid.max_particles)},
    {.name = "hybrid.pump_rate", .type = K::Float, .unit = "m^3/s", .range = closed(0, 1e6), .readers = kHybrid,
     .edit = E::Solver, .help = "A pump (0: none): each frame this rate x dt (at most what they hold) is taken from the "
                                "cells around hybrid.pump_from (hybrid.pump_radius) and put into the cell under "
                                "hybrid.pump_to, so the falls of a closed scene keep running and its total water stays "
                                "the same (docs/waterfalls.md).",
     .field = MR_FIELD(hybrid.pump_rate)},
    {.name = "hybrid.pump_radius", .type = K::Float, .unit = "m", .range = closed(0, 1e6), .readers = kHybrid,
     .edit = E::Solver, .help = "The pump takes from every cell whose centre lies within this of hybrid.pump_from (the "
                                "cell under it at least), in proportion to the water each holds.",
     .field = MR_FIELD(hybrid.pump_radius)},
    {.name = "hybrid.pump_from", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .readers = kHybrid, .edit = E::Solver,
     .help = "Where the pump takes its water (x and z; y unused): the cell under it, e.g. in the plunge pool.",
     .field = MR_FIELD(hybrid.pump_from)},
    {.name = "hybrid.pump_to", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .readers = kHybrid, .edit = E::Solver,
     .help = "Where the pump puts the water (x and z; y unused), at rest: the cell under it, e.g. above the falls.",
     .field = MR_FIELD(hybrid.pump_to)},
};
#undef MR_FIELD

const SceneSection kSections[] = {
    {"", "Keys at the top of the file."},
    {"terrain", "The heightmap and how its samples become metres (\"Heightmap scale\" below)."},
    {"particles", "The source: where, how many and how fast particles enter."},
    {"pbf", "Position Based Fluids (Macklin and Mueller 2013; docs/river.md): solver = \"pbf\" only; the other solvers "
            "read pbf.spacing only with terrain.condition = \"carve\" (the carved channel's size)."},
    {"sink", "Where water leaves: sunk particles are recycled to the source. Not with solver = \"bullet\"."},
    {"forces", "Forces on every particle."},
    {"springs", "The paper's eq. 3: a = 0.5 k (r v/|v| - v) to each particle of a pair. Read by solver = \"springs\", "
                "and by Bullet with bullet.springs = true (not mode); an error in a PBF scene."},
    {"collision", "Terrain contact of solver = \"springs\" and \"pbf\"; an error in a Bullet scene (it has [bullet]) but for "
                  "bvh_leaf_triangles (the tree every scene builds)."},
    {"integrator", "The time step."},
    {"field", "The metaball scalar field the surface is extracted from."},
    {"surface", "The marching-cubes surface and its smoothing (docs/rendering.md, \"Surface smoothing\"); the paper "
                "presets and springs-valley have method = \"none\"."},
    {"foam", "Diffuse spray, foam and bubbles (Ihmsen et al. 2012; docs/rendering.md, \"Foam and spray\"); solver = "
             "\"pbf\", \"swe\" from its grid's velocity (docs/shallow-water.md), and \"hybrid\" both: its particles' spray where "
             "the water falls, its grid's foam on the reaches and pools (docs/waterfalls.md). Per fluid particle i and frame, over its neighbours j within h (W~ = 1 - r/h): trapped air "
             "I_ta = sum |v_ij| (1 - v^_ij . x^_ij) W~ (m/s), wave crest I_wc = sum (1 - n^_i . n^_j) W~ over convex j "
             "where v^_i . n^_i >= 0.6, kinetic energy I_k = 0.5 |v_i|^2 (J/kg); each mapped to [0, 1] by "
             "(min(I, max) - min(I, min)) / (max - min); i emits Phi_k (trapped_air_rate Phi_ta + wave_crest_rate "
             "Phi_wc) dt particles."},
    {"render", "How the renderer draws the scene (render, view); the simulation ignores it."},
    {"bullet", "The paper's engine physics on Bullet (docs/bullet.md): solver = \"bullet\" only, at most 200,000 "
               "bodies; gravity from [forces], the frame time from [integrator]. A Bullet scene refuses what it does "
               "not do: a flow rate, litres_per_particle, a source_shape other than box, a sink, springs.mode, springs.* "
               "without bullet.springs (stiffness 0 is fine), integrator.substeps, [collision] (but its "
               "bvh_leaf_triangles), [pbf]; left out, the "
               "flow rate and sink are off and spawn_interval is the paper-engine preset's."},
    {"swe", "Shallow water on the terrain's grid (docs/shallow-water.md): solver = \"swe\" and the hybrid's grid; the "
            "terrain's edges are open (water leaves the map). Nothing is carved for it (terrain.condition = \"auto\" "
            "keeps the heights)."},
    {"hybrid", "The grid's water as PBF particles where it falls over a drop, and back where they land (docs/waterfalls.md): "
               "solver = \"hybrid\" only; its particles take [pbf] and [collision], its grid [swe]."},
};

// [[particles.source]] and [[sink.box]]: the entries' keys (the name is the leaf).
#define MR_ITEM(list, member) [](SceneDef& d, size_t i) { return field_ref(&d.list[i].member); }
const SceneListKey kSourceKeys[] = {
    {{.name = "center", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .help = "Centre of this source's volume."},
     MR_ITEM(spawn.sources, center)},
    {{.name = "half_extent", .type = K::Vec3, .unit = "m", .range = closed(0, 1e4),
      .help = "Half size of this source (a disc: radius .x, half height .y; a point: not read)."},
     MR_ITEM(spawn.sources, half_extent)},
    {{.name = "flow_rate", .type = K::Float, .unit = "particles/s or L/s", .range = closed(0, 1e7),
      .help = "This source's rate, in the unit of particles.flow_rate (litres per second with "
              "particles.litres_per_particle); 0: off."},
     MR_ITEM(spawn.sources, flow_rate)},
};
const SceneListKey kSinkBoxKeys[] = {
    {{.name = "min", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .help = "Box corner."}, MR_ITEM(sink.boxes, min)},
    {{.name = "max", .type = K::Vec3, .unit = "m", .range = {.lo = -1e6, .hi = 1e6, .text = "[min, 1000000]"},
      .help = "The opposite corner."},
     MR_ITEM(sink.boxes, max)},
};
// [[bodies]]: BodyDef's fields (bodies.h).
const SceneListKey kBodyKeys[] = {
    {{.name = "shape", .type = K::Choice, .choices = kBodyShapes,
      .help = "box; sphere; capsule (a cylinder with round caps along the body's x); convex_mesh (the convex hull of an "
              "OBJ's vertices); triangle_mesh (a closed OBJ triangle mesh)."},
     MR_ITEM(bodies, shape)},
    {{.name = "size", .type = K::Vec3, .unit = "m", .range = {.lo = 0, .hi = 1000, .text = "(0, 1000] (the components the shape reads)"},
      .help = "box: full extents along x, y, z; sphere: radius .x; capsule: radius .x, length .y of the cylinder between "
              "the caps; convex_mesh, triangle_mesh: scale .x of the OBJ's coordinates. The components a shape does not "
              "read may be 0."},
     MR_ITEM(bodies, size)},
    {{.name = "mesh", .type = K::String,
      .help = "convex_mesh, triangle_mesh only (required there): the OBJ file, relative to the scene file."},
     MR_ITEM(bodies, mesh)},
    {{.name = "density", .type = K::Float, .unit = "kg/m^3", .range = above(0, 100000),
      .help = "The body's density; water is 1000 (below floats, above sinks)."},
     MR_ITEM(bodies, density)},
    {{.name = "position", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .help = "Centre of mass at the start."},
     MR_ITEM(bodies, position)},
    {{.name = "rotation", .type = K::Vec3, .unit = "deg", .range = closed(-360, 360),
      .help = "Orientation at the start: rotations about the world's x, then y, then z."},
     MR_ITEM(bodies, rotation)},
    {{.name = "velocity", .type = K::Vec3, .unit = "m/s", .range = closed(-100, 100), .help = "Velocity at the start."},
     MR_ITEM(bodies, velocity)},
    {{.name = "angular_velocity", .type = K::Vec3, .unit = "rad/s", .range = closed(-100, 100),
      .help = "Angular velocity at the start (world axes)."},
     MR_ITEM(bodies, angular_velocity)},
    {{.name = "friction", .type = K::Float, .range = closed(0, 2),
      .help = "Coulomb friction coefficient against the terrain and the other bodies."},
     MR_ITEM(bodies, friction)},
};
// [[swe.sources]] and [[swe.sinks]].
const SceneListKey kSweSourceKeys[] = {
    {{.name = "shape", .type = K::Choice, .choices = kSweShapes,
      .help = "point: the discharge into the cell under start; line: spread evenly over the cells from start to end."},
     MR_ITEM(swe.sources, shape)},
    {{.name = "start", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .help = "The point, or the line's first end (x, z; y unused)."},
     MR_ITEM(swe.sources, start)},
    {{.name = "end", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .help = "The line's other end (shape = \"line\")."},
     MR_ITEM(swe.sources, end)},
    {{.name = "discharge", .type = K::Float, .unit = "m^3/s", .range = closed(0, 1e7), .help = "What this source pours."},
     MR_ITEM(swe.sources, discharge)},
};
const SceneListKey kSweSinkKeys[] = {
    {{.name = "center", .type = K::Vec3, .unit = "m", .range = big_vec(-1e6), .help = "The sink's centre (x, z; y unused)."},
     MR_ITEM(swe.sinks, center)},
    {{.name = "radius", .type = K::Float, .unit = "m", .range = closed(0, 1e7),
      .help = "The cells within this distance of the centre; 0: the one cell under it."},
     MR_ITEM(swe.sinks, radius)},
    {{.name = "discharge", .type = K::Float, .unit = "m^3/s", .range = closed(0, 1e7),
      .help = "What it removes at most, spread evenly over its cells; a cell never gives more than it holds (counted as "
              "sunk in the mass balance)."},
     MR_ITEM(swe.sinks, discharge)},
};
#undef MR_ITEM

const SceneList kLists[] = {
    {.name = "particles.source",
     .help = "More sources besides the main one (particles.spawn_*), each `[[particles.source]]` a volume of the main "
             "source's shape, inflow velocity and ground following at its own centre, size and rate. Read in a scene "
             "with a particle rate (on the main source or on any of these); every source draws on the one particle "
             "budget (particles.count), and sunk particles return to whichever source emits next.",
     .readers = kRate,
     .max = kMaxMoreSources,
     .size = [](S d) { return d.spawn.sources.size(); },
     .resize = [](SceneDef& d, size_t n) { d.spawn.sources.resize(n); },
     .keys = kSourceKeys},
    {.name = "sink.box",
     .help = "More box sinks, each `[[sink.box]]` taking the particles inside it back to the sources, whatever "
             "sink.kind is.",
     .readers = kNotBullet,
     .max = kMaxMoreSinks,
     .size = [](S d) { return d.sink.boxes.size(); },
     .resize = [](SceneDef& d, size_t n) { d.sink.boxes.resize(n); },
     .keys = kSinkBoxKeys},
    {.name = "bodies",
     .help = "Rigid bodies in the water (logs, boats, crates, debris; docs/bodies.md), each `[[bodies]]` one body, "
             "two-way coupled with the PBF water (the water carries and lifts it, it pushes the water aside) or, on the "
             "grid's water (swe, hybrid), floated and carried by it one way; it collides with the terrain and the other "
             "bodies.",
     .readers = kBodies,
     .max = kMaxBodies,
     .size = [](S d) { return d.bodies.size(); },
     .resize = [](SceneDef& d, size_t n) { d.bodies.resize(n); },
     .keys = kBodyKeys},
    {.name = "swe.sources",
     .help = "More shallow-water sources besides swe.discharge, each `[[swe.sources]]` a discharge at a point or along a "
             "line. With any of them swe.discharge = \"auto\" pours nothing.",
     .readers = kSwe,
     .max = kMaxSweSources,
     .size = [](S d) { return d.swe.sources.size(); },
     .resize = [](SceneDef& d, size_t n) { d.swe.sources.resize(n); },
     .keys = kSweSourceKeys},
    {.name = "swe.sinks",
     .help = "Shallow-water sinks, each `[[swe.sinks]]` removing water from a disc of cells (a drain, a pump, a lake's "
             "outlet pipe).",
     .readers = kSwe,
     .max = kMaxSweSources,
     .size = [](S d) { return d.swe.sinks.size(); },
     .resize = [](SceneDef& d, size_t n) { d.swe.sinks.resize(n); },
     .keys = kSweSinkKeys},
};

}  // namespace

std::string_view SceneKey::section() const {
    const size_t dot = name.find('.');
    return dot == std::string_view::npos ? std::string_view{} : name.substr(0, dot);
}

std::string_view SceneKey::leaf() const {
    const size_t dot = name.find('.');
    return dot == std::string_view::npos ? name : name.substr(dot + 1);
}

std::span<const SceneKey> scene_keys() { return kKeys; }
std::span<const SceneList> scene_lists() { return kLists; }

// A list at the top level ([[bodies]]) has no section: its name is its leaf.
std::string_view SceneList::section() const {
    const size_t dot = name.find('.');
    return dot == std::string_view::npos ? std::string_view{} : name.substr(0, dot);
}
std::string_view SceneList::leaf() const {
    const size_t dot = name.find('.');
    return dot == std::string_view::npos ? name : name.substr(dot + 1);
}
std::string SceneList::entry_key(size_t i, const SceneListKey& k) const {
    return fmt::format("{}[{}].{}", name, i + 1, k.key.name);
}
std::span<const SceneSection> scene_sections() { return kSections; }

const SceneKey* find_scene_key(std::string_view name) {
    for (const SceneKey& k : kKeys)
        if (k.name == name) return &k;
    return nullptr;
}

}  // namespace mr
