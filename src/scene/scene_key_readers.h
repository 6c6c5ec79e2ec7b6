// Who reads each scene key (KeyReaders in include/metariver/scene_keys.h), for the table
// in scene_keys.cpp (its only includer): each reader is a list of conditions, each with
// what the TOML reader says to a file that sets the key where the condition fails. So the
// one table decides what validate() checks, what the viewer's panel shows, what the
// reference says and what a scene file may set. Checked against the code that reads each
// key (src/particles/solver.cpp, pbf.cpp, bullet_solver.cpp, src/scene/simulation.cpp,
// src/surface/smoothing.cpp) and by tests/scene/scene_keys_test.cpp, which sets every key
// in every preset and compares what the reader accepts with these conditions.
#pragma once

#include <metariver/scene_keys.h>

#include <fmt/format.h>

#include <string>
#include <string_view>

namespace mr::key_readers {

using S = const SceneDef&;
using F = const SceneFileView&;

inline std::string solver_is(S d) { return fmt::format("solver = \"{}\"", to_string(d.solver)); }
/// A key another key's value makes irrelevant: "ignored when WHEN: FIX".
inline std::string ignored(std::string_view when, std::string_view fix) { return fmt::format("ignored when {}: {}", when, fix); }
/// A key the Bullet solver does not use (issue 13: it ignored them silently).
inline std::string not_bullet(std::string_view fix = {}) {
    return fmt::format("solver = \"bullet\" does not use it (spheres spawn in the box every particles.spawn_interval frames, "
                       "collide through Bullet and respawn below or outside the terrain){}",
                       fix);
}
/// The source emits at a rate: flow_rate > 0, or "auto" in a PBF river (sized from its channel).
inline bool with_rate(S d) { return d.spawn.auto_rate() ? d.solver == SolverKind::Pbf : d.spawn.has_rate(); }
inline bool springs_on(S d) { return d.solver == SolverKind::Springs || (d.solver == SolverKind::Bullet && d.bullet.springs); }

// ---- The solver's scope: what a solver does not read at all ----

/// [pbf]: PBF, and the other solvers' carve (pbf.spacing is the carved channel's depth and width).
constexpr ReadIf kPbfSection{
    .holds = [](S d) {
        return d.solver == SolverKind::Pbf || d.solver == SolverKind::Hybrid || d.terrain.condition == TerrainCondition::Carve;
    },
    .refusal = [](F f) {
        return fmt::format("only solver = \"pbf\" reads [pbf] ({} reads pbf.spacing only to carve a channel, "
                           "terrain.condition = \"carve\")",
                           solver_is(f.def));
    },
    .scope = ReadScope::Section};
constexpr ReadIf kPbfOnly{.holds = [](S d) { return d.solver == SolverKind::Pbf || d.solver == SolverKind::Hybrid; }, .refusal = [](F f) {
                              return fmt::format("only solver = \"pbf\" reads it ({} reads pbf.spacing only, the carved "
                                                 "channel's depth)",
                                                 solver_is(f.def));
                          },
                             .scope = ReadScope::Solver};
constexpr ReadIf kBulletSection{
    .holds = [](S d) { return d.solver == SolverKind::Bullet; },
    .refusal = [](F f) { return fmt::format("only solver = \"bullet\" reads [bullet] (this scene has {})", solver_is(f.def)); },
    .scope = ReadScope::Section};
constexpr ReadIf kSweSection{
    .holds = [](S d) { return d.solver == SolverKind::Swe || d.solver == SolverKind::Hybrid; },
    .refusal = [](F f) { return fmt::format("only solver = \"swe\" or \"hybrid\" reads [swe] (this scene has {})", solver_is(f.def)); },
    .scope = ReadScope::Section};
constexpr ReadIf kHybridSection{
    .holds = [](S d) { return d.solver == SolverKind::Hybrid; },
    .refusal = [](F f) { return fmt::format("only solver = \"hybrid\" reads [hybrid] (this scene has {})", solver_is(f.def)); },
    .scope = ReadScope::Section};
constexpr ReadIf kSpringsSection{.holds = [](S d) { return d.solver != SolverKind::Pbf; },
                                 .refusal = [](F) -> std::string {
                                     return "solver = \"pbf\" does not use springs (its density constraint keeps the "
                                            "particles apart: [pbf]); remove [springs]";
                                 },
                                 .scope = ReadScope::Section};
constexpr ReadIf kCollisionSection{
    .holds = [](S d) { return d.solver != SolverKind::Bullet; },
    .refusal = [](F f) { return collision_mode_unused(f.def.solver, f.def.collision.mode); },
    .scope = ReadScope::Section};
// PBF draws no random number: its lattice source places every particle it emits.
constexpr ReadIf kSeedSolver{.holds = [](S d) { return d.solver != SolverKind::Pbf && d.solver != SolverKind::Hybrid; },
                             .refusal = [](F f) { return seed_unused(f.def.solver); },
                             .scope = ReadScope::Solver};
/// Diffuse particles need the fluid's kernel neighbourhoods (PBF) or its velocity on a
/// grid (swe: heightfield_foam.h).
constexpr std::string (*kFoamSolverRefusal)(F) = [](F f) {
    return fmt::format("only solver = \"pbf\", \"swe\" or \"hybrid\" makes foam (diffuse particles need the fluid's kernel "
                       "neighbourhoods or its velocity on a grid; {} has neither): remove [foam]",
                       solver_is(f.def));
};
inline bool makes_foam(S d) { return d.solver == SolverKind::Pbf || d.solver == SolverKind::Swe || d.solver == SolverKind::Hybrid; }
constexpr ReadIf kFoamSolver{.holds = makes_foam, .refusal = kFoamSolverRefusal,
                             .scope = ReadScope::Solver};
constexpr ReadIf kFoamSwitchSolver{.holds = makes_foam,
                                   .refusal = kFoamSolverRefusal,
                                   .scope = ReadScope::Solver,
                             .agrees = [](S d) { return !d.foam.enabled; }};
constexpr ReadIf kSubstepsSolver{.holds = [](S d) { return d.solver != SolverKind::Bullet; }, .refusal = [](F) -> std::string {
                                     return "solver = \"bullet\" substeps with its own fixed step (bullet.dt, "
                                            "bullet.max_substeps); remove it";
                                 },
                             .scope = ReadScope::Solver};

// What Bullet does not do (its spheres spawn in the box and respawn; [bullet] springs).
constexpr ReadIf kFlowSolver{.holds = [](S d) { return d.solver != SolverKind::Bullet; },
                             .refusal = [](F) { return not_bullet("; remove it or set 0"); },
                             .scope = ReadScope::Solver,
                             .agrees = [](S d) { return !(d.spawn.flow_rate > 0.0f || d.spawn.auto_rate()); }};
constexpr ReadIf kLitresSolver{.holds = [](S d) { return d.solver != SolverKind::Bullet; },
                               .refusal = [](F) { return not_bullet(); },
                               .scope = ReadScope::Solver,
                             .agrees = [](S d) { return !(d.spawn.litres_per_particle > 0.0f); }};
constexpr ReadIf kShapeSolver{.holds = [](S d) { return d.solver != SolverKind::Bullet; },
                              .refusal = [](F) { return not_bullet("; only \"box\""); },
                              .scope = ReadScope::Solver,
                             .agrees = [](S d) { return d.spawn.shape == SourceShape::Box; }};
constexpr ReadIf kSinkSolver{.holds = [](S d) { return d.solver != SolverKind::Bullet; },
                             .refusal = [](F) { return not_bullet("; only \"none\""); },
                             .scope = ReadScope::Solver,
                             .agrees = [](S d) { return d.sink.kind == SinkKind::None; }};
constexpr ReadIf kSinkBoxSolver{.holds = [](S d) { return d.solver != SolverKind::Bullet; }, .refusal = [](F) { return not_bullet(); },
                             .scope = ReadScope::Solver};
// Bodies are coupled with PBF's particles (their density constraint) or pushed by the grid's
// water (swe, hybrid: rigid_bodies_grid.h); the others have none.
constexpr ReadIf kBodiesSolver{.holds = [](S d) {
                                   return d.solver == SolverKind::Pbf || d.solver == SolverKind::Swe ||
                                          d.solver == SolverKind::Hybrid;
                               }, .refusal = [](F f) {
                                   return fmt::format("only solver = \"pbf\", \"swe\" or \"hybrid\" moves bodies (the "
                                                      "water's coupling with them; {} has none): remove [[bodies]]",
                                                      solver_is(f.def));
                               },
                               .scope = ReadScope::Solver};
constexpr ReadIf kSpringModeSolver{.holds = [](S d) { return d.solver == SolverKind::Springs; }, .refusal = [](F) -> std::string {
                                       return "solver = \"bullet\" applies the springs itself (bullet.springs); remove "
                                              "springs.mode";
                                   },
                             .scope = ReadScope::Solver};
constexpr ReadIf kStiffnessBullet{.holds = springs_on, .refusal = [](F) -> std::string {
                                      return "solver = \"bullet\" applies springs only with bullet.springs = true; set 0 or "
                                             "turn them on";
                                  },
                                  .scope = ReadScope::Solver,
                             .agrees = [](S d) { return d.springs.stiffness == 0.0f; }};
constexpr ReadIf kDistanceBullet{.holds = springs_on, .refusal = [](F) -> std::string {
                                     return "solver = \"bullet\" applies springs only with bullet.springs = true";
                                 },
                             .scope = ReadScope::Solver};

// The hybrid's particles all come from its grid where the water falls (hybrid_solver.h): no
// particle source; of [particles] it reads spawn_center (and auto_height) only, as
// swe.source_center = "auto".
constexpr ReadIf kParticleSourceSolver{.holds = [](S d) { return d.solver != SolverKind::Hybrid; }, .refusal = [](F) -> std::string {
                                           return "solver = \"hybrid\" has no particle source: its particles come from the "
                                                  "grid where the water falls (hybrid.max_particles is their budget, [pbf] "
                                                  "their physics; docs/waterfalls.md); remove it";
                                       },
                                       .scope = ReadScope::Solver};

// ---- Keys another key's value makes irrelevant (issue 13, "no silent option") ----

// The surface is off: Simulation::step builds no field (field.resolution stays: the
// default --voxel-size of --export --format vdb, export_options.cpp).
constexpr ReadIf kFieldSurfaceOn{.holds = [](S d) { return d.surface; }, .refusal = [](F f) {
                                     const bool table = f.wrote("surface");
                                     return ignored(fmt::format("{} (no field or surface is built; field.resolution "
                                                                "stays, the default voxel size of --export --format vdb)",
                                                                table ? "surface.enabled = false" : "surface = false"),
                                                    fmt::format("remove it or set {} = true", table ? "surface.enabled" : "surface"));
                                 }};
// 1/r^2 has no radius (paper_field.cpp).
constexpr ReadIf kRadiusKernel{.holds = [](S d) { return d.field.kernel != FieldKernel::InverseSquare; }, .refusal = [](F) {
                                   return ignored("field.kernel = \"inverse_square\" (1/r^2 has no radius)",
                                                  "remove it or use field.kernel = \"radius_over_r\" or \"poly6\"");
                               }};
// The smoothing: smooth_surface (src/surface/smoothing.cpp) returns at once for method
// "none" or 0 iterations; Taubin steps lambda|mu and never restores the volume;
// Laplacian's uniform steps are lambda, its Chebyshev steps come from pass_band; feature
// weights read a poly6 field (Simulation::step passes none else).
constexpr ReadIf kSmoothSurfaceOn{.holds = [](S d) { return d.surface; }, .refusal = [](F) {
                                      return ignored("surface.enabled = false (nothing is smoothed)", "remove it or set enabled = true");
                                  }};
constexpr ReadIf kSmoothMethod{.holds = [](S d) { return d.smoothing.method != SmoothingMethod::None; }, .refusal = [](F) {
                                   return ignored("surface.method = \"none\" (the mesh as extracted)", "remove it or choose a method");
                               }};
constexpr ReadIf kSmoothIterations{.holds = [](S d) { return d.smoothing.iterations > 0; }, .refusal = [](F) {
                                       return ignored("surface.iterations = 0 (no smoothing step)", "remove it or give iterations");
                                   }};
constexpr ReadIf kSmoothLaplacian{.holds = [](S d) { return d.smoothing.method == SmoothingMethod::Laplacian; }, .refusal = [](F) {
                                      return ignored("surface.method = \"taubin\" (lambda|mu steps, which keep the volume themselves)",
                                                     "remove it or use method = \"laplacian\"");
                                  }};
constexpr ReadIf kSmoothLambda{
    .holds = [](S d) { return d.smoothing.method == SmoothingMethod::Taubin || d.smoothing.steps == SmoothingSteps::Uniform; },
    .refusal = [](F) {
        return ignored("surface.steps = \"chebyshev\" (the step sizes come from pass_band)", "remove it or use steps = \"uniform\"");
    }};
constexpr ReadIf kSmoothPassBand{
    .holds = [](S d) { return d.smoothing.method == SmoothingMethod::Taubin || d.smoothing.steps == SmoothingSteps::Chebyshev; },
    .refusal = [](F) { return ignored("surface.steps = \"uniform\" (every step is lambda)", "remove it or use steps = \"chebyshev\""); }};
constexpr ReadIf kSmoothFeatures{.holds = [](S d) { return d.field.kernel == FieldKernel::Poly6; },
                                 .refusal = [](F f) {
                                     return ignored(fmt::format("field.kernel = \"{}\" (feature weights read a poly6 field)",
                                                                to_string(f.def.field.kernel)),
                                                    "remove it or use field.kernel = \"poly6\"");
                                 },
                                 .agrees = [](S d) { return d.smoothing.feature_count == 0.0f; }};

// The source: a rate (flow_rate > 0, or "auto" sized for a PBF river) or one activation
// every spawn_interval frames (ParticleSolver::step_frame).
constexpr ReadIf kIntervalNoRate{.holds = [](S d) { return !with_rate(d); }, .refusal = [](F f) {
                                     const SceneDef& d = f.def;
                                     const std::string rate =
                                         d.spawn.auto_rate()
                                             ? fmt::format("particles.flow_rate = \"auto\"{} (the source emits at the river's sized rate)",
                                                           f.wrote("particles.flow_rate") ? "" : " (the default river's)")
                                             : fmt::format("particles.flow_rate > 0 (the source emits {} {} per second)", d.spawn.flow_rate,
                                                           d.spawn.litres_per_particle > 0.0f ? "litres" : "particles");
                                     return ignored(rate, "remove it or set flow_rate = 0");
                                 }};
/// "particles.flow_rate = 0" or "is 0 (solver = ... without a flow_rate": the source has no rate.
inline std::string no_rate(F f, std::string_view why) {
    return f.wrote("particles.flow_rate")
               ? fmt::format("particles.flow_rate = 0 ({})", why)
               : fmt::format("particles.flow_rate is 0 ({} without a flow_rate; {})", solver_is(f.def), why);
}
constexpr ReadIf kLitresRate{.holds = with_rate,
                             .refusal = [](F f) { return ignored(no_rate(f, "it is flow_rate's unit"), "remove it or give a flow_rate"); },
                             .agrees = [](S d) { return !(d.spawn.litres_per_particle > 0.0f); }};
constexpr ReadIf kAutoCentreOn{.holds = [](S d) { return d.spawn.auto_center; }, .refusal = [](F) {
                                   return ignored("particles.spawn_center is [x, y, z] (it places an \"auto\" or \"channel\" centre)",
                                                  "remove it or set spawn_center = \"auto\"");
                               }};
constexpr ReadIf kNotPointShape{.holds = [](S d) { return d.spawn.shape != SourceShape::Point; }, .refusal = [](F) {
                                    return ignored("particles.source_shape = \"point\" (every particle starts at the centre)",
                                                   "remove it or use source_shape = \"box\" or \"disc\"");
                                }};
constexpr ReadIf kBoxSink{.holds = [](S d) { return d.sink.kind == SinkKind::Box; }, .refusal = [](F f) {
                              return ignored(fmt::format("sink.kind = \"{}\" (only a box sink has corners)", to_string(f.def.sink.kind)),
                                             "remove it or set kind = \"box\"");
                          }};
// The channel's prefill needs PBF water and a carved channel to fill.
constexpr ReadIf kPrefillPbf{.holds = [](S d) { return d.solver == SolverKind::Pbf; }, .refusal = [](F f) {
                                 return ignored(fmt::format("{} (only PBF water fills the carved channel)", solver_is(f.def)),
                                                "remove it or use solver = \"pbf\"");
                             }};
constexpr ReadIf kPrefillCarved{.holds = [](S d) { return resolved_condition(d) == TerrainCondition::Carve; }, .refusal = [](F f) {
                                    return ignored(fmt::format("terrain.condition resolves to \"{}\" (no carved channel to fill)",
                                                               to_string(resolved_condition(f.def))),
                                                   "remove it or set terrain.condition = \"carve\"");
                                }};
// A PBF lattice source follows the ground only while it emits at a rate (particle_emitters.cpp:
// follow_ground && by_rate()); false is what the others do.
constexpr ReadIf kFollowPbf{.holds = [](S d) { return d.solver == SolverKind::Pbf; },
                            .refusal = [](F f) {
                                return ignored(fmt::format("{} (only PBF's lattice source follows the ground)", solver_is(f.def)),
                                               "remove it or use solver = \"pbf\"");
                            },
                            .agrees = [](S d) { return !d.spawn.follow_ground; }};
constexpr ReadIf kFollowRate{.holds = with_rate,
                             .refusal = [](F f) {
                                 return ignored(no_rate(f, "the source follows the ground as it emits"), "remove it or give a flow_rate");
                             },
                             .agrees = [](S d) { return !d.spawn.follow_ground; }};
constexpr ReadIf kStiffnessOn{.holds = [](S d) { return d.springs.stiffness > 0.0f; }, .refusal = [](F) {
                                  return ignored("springs.stiffness = 0 (no spring force)", "remove it or give a stiffness");
                              }};
// Collision: no terrain contact with mode "none" (collision.radius stays: the tunneled
// counter reads it); the paper's response walks the AABB tree; the bed friction's law is PBF's.
constexpr ReadIf kContactOn{.holds = [](S d) { return d.collision.mode != CollisionMode::None; }, .refusal = [](F) {
                                return ignored("collision.mode = \"none\" (particles pass through the terrain)",
                                               "remove it or set mode = \"robust\"");
                            }};
// The prefill keeps its water radius + offset above the carved bed, with or without a contact.
constexpr ReadIf kOffsetContactOn{
    .holds = [](S d) {
        return d.collision.mode != CollisionMode::None ||
               (d.solver == SolverKind::Pbf && d.spawn.prefill && resolved_condition(d) == TerrainCondition::Carve);
    },
    .refusal = kContactOn.refusal};
constexpr ReadIf kNotPaperContact{.holds = [](S d) { return d.collision.mode != CollisionMode::Paper; }, .refusal = [](F) {
                                      return ignored("collision.mode = \"paper\" (the paper's response walks the AABB tree; query "
                                                     "picks robust mode's)",
                                                     "remove it or set mode = \"robust\"");
                                  }};
// The hybrid's particles are PBF's (hybrid_solver.h): their bed friction reads the law too.
constexpr ReadIf kFrictionPbf{.holds = [](S d) { return d.solver == SolverKind::Pbf || d.solver == SolverKind::Hybrid; }, .refusal = [](F) {
                                  return ignored("solver = \"springs\" (a bounce's damping has no law; only PBF's bed friction)",
                                                 "remove it or use solver = \"pbf\"");
                              }};
// The terrain: a PNG has its own size and no procedure; only the valley is random.
inline std::string source_is(F f) { return fmt::format("terrain.source = \"{}\"", to_string(f.def.source.kind)); }
constexpr ReadIf kProceduralSource{.holds = [](S d) { return d.source.kind != TerrainSource::File && d.source.kind != TerrainSource::Alps; }, .refusal = [](F f) {
                                       return ignored(source_is(f) + " (the PNG gives the size; nothing is generated)",
                                                      "remove it or use a procedural source");
                                   }};
constexpr ReadIf kFileSource{.holds = [](S d) { return d.source.kind == TerrainSource::File; }, .refusal = [](F f) {
                                 return ignored(source_is(f) + " (a procedural terrain)", "remove it or set source = \"file\"");
                             }};
constexpr ReadIf kValleySource{.holds = [](S d) { return d.source.kind == TerrainSource::Valley; }, .refusal = [](F f) {
                                   return ignored(source_is(f) + " (only \"valley\" is random)", "remove it or use source = \"valley\"");
                               }};
// Simulation makes no FoamSystem; pbf.cpp has no tensile correction without its strength.
constexpr ReadIf kFoamOn{.holds = [](S d) { return d.foam.enabled; }, .refusal = [](F) {
                             return ignored("foam.enabled = false (no diffuse particles are made)", "remove it or set foam.enabled = true");
                         }};
constexpr ReadIf kScorrOn{.holds = [](S d) { return d.pbf.scorr_k > 0.0f; }, .refusal = [](F) {
                              return ignored("pbf.scorr_k = 0 (no tensile-instability correction)", "remove it or give a scorr_k");
                          }};
// Bullet: no fixed step without substeps; spheres with springs never sleep.
constexpr ReadIf kBulletSubstepsOn{.holds = [](S d) { return d.bullet.max_substeps > 0; }, .refusal = [](F) {
                                       return ignored("bullet.max_substeps = 0 (one Bullet step of the frame's time)",
                                                      "remove it or allow substeps (max_substeps >= 1)");
                                   }};
constexpr ReadIf kSleepNoSprings{.holds = [](S d) { return !d.bullet.springs; },
                                 .refusal = [](F) {
                                     return ignored("bullet.springs = true (spheres with springs never sleep)", "remove it or set sleep = false");
                                 },
                                 .agrees = [](S d) { return !d.bullet.sleep; }};

// ---- The readers of the table's keys: the text the reference shows, the conditions ----

/// KeyReaders{text, the conditions in the order the reader checks them}.
#define MR_READERS(name, text, ...)                 \
    constexpr ReadIf name##If[] = {__VA_ARGS__};    \
    constexpr KeyReaders name{text, name##If}

constexpr KeyReaders kAll{"every scene"};
MR_READERS(kSeed, "solver = springs, bullet", kSeedSolver);
MR_READERS(kNotBullet, "solver = springs, pbf", kSinkBoxSolver);  // [[sink.box]]
MR_READERS(kBodies, "solver = pbf, swe, hybrid", kBodiesSolver);    // [[bodies]]
MR_READERS(kPbf, "solver = pbf", kPbfSection, kPbfOnly);
MR_READERS(kBullet, "solver = bullet", kBulletSection);
MR_READERS(kSwe, "solver = swe, hybrid", kSweSection);
MR_READERS(kHybrid, "solver = hybrid", kHybridSection);
MR_READERS(kFile, "terrain.source = file", kFileSource);
MR_READERS(kProcedural, "a procedural terrain.source", kProceduralSource);
MR_READERS(kValley, "terrain.source = valley", kProceduralSource, kValleySource);
MR_READERS(kAutoCentre, "spawn_center auto, channel", kAutoCentreOn);
MR_READERS(kNotPoint, "source_shape box, disc; not solver = hybrid", kParticleSourceSolver, kNotPointShape);
MR_READERS(kNoRate, "a scene without a particle rate; not solver = hybrid", kParticleSourceSolver, kIntervalNoRate);
MR_READERS(kRate, "a scene with a particle rate", kParticleSourceSolver, kLitresSolver, kLitresRate);
MR_READERS(kShape, "solver = springs, pbf", kParticleSourceSolver, kShapeSolver);
MR_READERS(kFlowRate, "solver = springs, pbf", kParticleSourceSolver, kFlowSolver);
MR_READERS(kParticleSource, "every scene but solver = hybrid", kParticleSourceSolver);
MR_READERS(kPbfRate, "solver = pbf with a particle rate", kFollowPbf, kFollowRate);
MR_READERS(kPbfOrCarve, "solver = pbf; terrain.condition = carve", kPbfSection);
MR_READERS(kScorr, "solver = pbf, scorr_k > 0", kPbfSection, kPbfOnly, kScorrOn);
MR_READERS(kSinkKind, "solver = springs, pbf", kSinkSolver);
MR_READERS(kSinkBox, "sink.kind = box", kBoxSink, kSinkBoxSolver);
MR_READERS(kSpringsK, "solver = springs; bullet with bullet.springs", kSpringsSection, kStiffnessBullet);
MR_READERS(kSpringsOn, "springs.stiffness's readers, with stiffness > 0", kSpringsSection, kDistanceBullet, kStiffnessOn);
MR_READERS(kSpringMode, "solver = springs, stiffness > 0", kSpringsSection, kSpringModeSolver, kStiffnessOn);
MR_READERS(kCollision, "solver = springs, pbf", kCollisionSection);
MR_READERS(kContact, "solver = springs, pbf; collision.mode paper, robust", kCollisionSection, kContactOn);
MR_READERS(kOffset, "solver = springs, pbf; collision.mode paper, robust; a prefilled channel", kCollisionSection, kOffsetContactOn);
MR_READERS(kBedFriction, "solver = pbf, hybrid; collision.mode = robust", kCollisionSection, kContactOn, kFrictionPbf);
MR_READERS(kPbfContact, "solver = pbf, collision.mode = robust", kPbfSection, kPbfOnly, kContactOn);
MR_READERS(kRobust, "solver = springs, pbf; collision.mode = robust", kCollisionSection, kContactOn, kNotPaperContact);
MR_READERS(kPbfCarved, "solver = pbf with terrain.condition carve (auto: carve for a river)", kPrefillPbf, kPrefillCarved);
MR_READERS(kSubsteps, "solver = springs, pbf", kSubstepsSolver);
MR_READERS(kSurface, "a scene with the surface on", kFieldSurfaceOn);
MR_READERS(kRadius, "the surface with field.kernel radius_over_r, poly6", kFieldSurfaceOn, kRadiusKernel);
MR_READERS(kSmoothingMethod, "a scene with the surface on", kSmoothSurfaceOn);
MR_READERS(kSmoothing, "surface.method laplacian, taubin", kSmoothSurfaceOn, kSmoothMethod);
MR_READERS(kSmoothingOn, "smoothing (method not none, iterations > 0)", kSmoothSurfaceOn, kSmoothMethod, kSmoothIterations);
MR_READERS(kLaplacian, "surface.method = laplacian", kSmoothSurfaceOn, kSmoothMethod, kSmoothIterations, kSmoothLaplacian);
MR_READERS(kLambda, "surface.method taubin; laplacian with steps = uniform", kSmoothSurfaceOn, kSmoothMethod, kSmoothIterations,
           kSmoothLambda);
MR_READERS(kPassBand, "surface.method taubin; laplacian with steps = chebyshev", kSmoothSurfaceOn, kSmoothMethod,
           kSmoothIterations, kSmoothPassBand);
MR_READERS(kFeatures, "smoothing with field.kernel = poly6", kSmoothSurfaceOn, kSmoothMethod, kSmoothIterations, kSmoothFeatures);
MR_READERS(kFoamSwitch, "solver = pbf or swe", kFoamSwitchSolver);
MR_READERS(kFoam, "solver = pbf or swe, foam.enabled", kFoamSolver, kFoamOn);
MR_READERS(kBulletSubsteps, "solver = bullet, max_substeps > 0", kBulletSection, kBulletSubstepsOn);
MR_READERS(kBulletSleep, "solver = bullet without bullet.springs", kBulletSection, kSleepNoSprings);

#undef MR_READERS

}  // namespace mr::key_readers
