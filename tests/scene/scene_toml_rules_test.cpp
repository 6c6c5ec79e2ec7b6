// Keys a scene's solver or another key's value makes irrelevant are errors naming the key
// (issue 13), split from scene_toml_test.cpp.
#include <metariver/scene.h>

#include "scene_toml_util.h"

#include <gtest/gtest.h>

#include <string>

namespace mr {
namespace {

using scene_test::expect_error;
using scene_test::parse;

TEST(SceneToml, OptionsBulletIgnoresAreErrorsAndItDoesNotInheritTheRiversSpawning) {
    // Issue 13: solver = "bullet" silently ignored flow_rate, source_shape, [sink],
    // springs.mode and [collision], and inherited the river's 420/s, interval 0 (all
    // 4000 spheres at frame 0).
    auto bare = parse("solver = \"bullet\"\n");
    ASSERT_TRUE(bare.ok()) << bare.error().message;
    EXPECT_EQ(bare->spawn.flow_rate, 0.0f);
    EXPECT_EQ(bare->sink.kind, SinkKind::None);
    EXPECT_EQ(bare->spawn.interval, preset("paper-engine")->spawn.interval);
    EXPECT_GT(bare->spawn.interval, 0);
    expect_error("solver = \"bullet\"\n[particles]\nflow_rate = 100.0\n", "particles.flow_rate: solver = \"bullet\" does not use it");
    expect_error("solver = \"bullet\"\n[particles]\nsource_shape = \"disc\"\n", "particles.source_shape");
    expect_error("solver = \"bullet\"\n[sink]\nkind = \"edges\"\n", "sink.kind");
    expect_error("solver = \"bullet\"\n[springs]\nmode = \"grid\"\n", "springs.mode");
    expect_error("solver = \"bullet\"\n[collision]\nmode = \"robust\"\n", "collision: solver = \"bullet\"");
    expect_error("solver = \"bullet\"\n[pbf]\nxsph = 0.1\n", "pbf: only solver = \"pbf\"");
    // What matches what Bullet does is fine (the docs/bullet scenes pin it).
    EXPECT_TRUE(parse("solver = \"bullet\"\n[particles]\nflow_rate = 0.0\n[sink]\nkind = \"none\"\n").ok());
}

TEST(SceneToml, OptionsTheSpringsAndPbfSolversIgnoreAreErrorsNamingTheKey) {
    // Issue 13: only Bullet scenes refused what they ignore; a springs scene took a
    // [pbf] or [bullet] table, a PBF scene [springs], [bullet] and collision.mode =
    // "paper" (it slides, never reflects), a Bullet scene integrator.substeps and
    // springs it does not apply, all without a word.
    const std::string springs = "solver = \"springs\"\n";
    expect_error(springs + "[pbf]\nxsph = 0.1\n", "pbf: only solver = \"pbf\" reads [pbf]");
    expect_error(springs + "[pbf]\nspacing = 0.25\n", "pbf: only solver = \"pbf\"");  // no carving: unused
    expect_error(springs + "[bullet]\nmass = 2.0\n", "bullet: only solver = \"bullet\" reads [bullet]");
    expect_error("solver = \"pbf\"\n[bullet]\nccd = true\n", "bullet: only solver = \"bullet\"");
    expect_error("[bullet]\nccd = true\n", "bullet: only solver = \"bullet\"");  // the default is PBF
    expect_error("solver = \"pbf\"\n[springs]\nstiffness = 2.0\n", "springs: solver = \"pbf\" does not use springs");
    expect_error("[springs]\nmode = \"grid\"\n", "springs: solver = \"pbf\"");
    expect_error("[collision]\nmode = \"paper\"\n", "collision.mode: solver = \"pbf\" slides");
    expect_error("solver = \"bullet\"\n[integrator]\nsubsteps = 4\n", "integrator.substeps: solver = \"bullet\"");
    expect_error("solver = \"bullet\"\n[springs]\nstiffness = 2.0\n", "springs.stiffness: solver = \"bullet\" applies springs only");
    expect_error("solver = \"bullet\"\n[springs]\nmin_distance = 2.0\n", "springs.min_distance");
    // A springs scene that carves a channel reads pbf.spacing (its depth), nothing else of [pbf].
    const std::string carve = springs + "[terrain]\ncondition = \"carve\"\n";
    auto c = parse(carve + "[pbf]\nspacing = 0.25\n");
    ASSERT_TRUE(c.ok()) << c.error().message;
    EXPECT_FLOAT_EQ(c->pbf.spacing, 0.25f);
    expect_error(carve + "[pbf]\nspacing = 0.25\niterations = 4\n", "pbf.iterations: only solver = \"pbf\" reads it");
    expect_error(carve + "[pbf]\nspacing = 0.0\n", "pbf.spacing: must be in [0.001, 1000]");
    // What each solver reads is accepted.
    for (const char* ok : {"solver = \"springs\"\n[springs]\nstiffness = 2.0\nmode = \"grid\"\n[collision]\nmode = \"paper\"\n"
                           "[integrator]\nsubsteps = 2\n",
                           "solver = \"pbf\"\n[pbf]\nxsph = 0.1\n[collision]\nmode = \"none\"\nradius = 0.1\n[integrator]\nsubsteps = 3\n",
                           "solver = \"bullet\"\n[springs]\nstiffness = 0.0\n",
                           "solver = \"bullet\"\n[bullet]\nsprings = true\n[springs]\nstiffness = 2.0\nmin_distance = 1.0\nmax_distance = 0.5\n"
                           "[integrator]\ndt = 0.02\n"}) {
        auto r = parse(ok);
        EXPECT_TRUE(r.ok()) << ok << (r.ok() ? "" : r.error().message);
    }
}

TEST(SceneToml, KeysAnotherKeysValueMakesIrrelevantAreErrorsNamingBoth) {
    // Issue 13, "no silent option": each of these keys was accepted and then never read,
    // because of the value of another key (written or inherited from the default scene).
    // The error names the ignored key, the key/value that makes it irrelevant and the way out.
    const std::string springs = "solver = \"springs\"\n";
    // The surface is off: no field is built (field.resolution stays, see EveryKeyIsRead).
    expect_error("surface = false\n[field]\nthreshold = 0.3\n",
                 "field.threshold: ignored when surface = false (no field or surface is built");
    expect_error("surface = false\n[field]\nresolution = 2\nkernel = \"poly6\"\n", "field.kernel: ignored when surface = false");
    expect_error(springs + "surface = false\n[field]\nbounds_offset = 1.0\n", "remove it or set surface = true");
    // A rate decides the activations; spawn_interval only schedules them without one.
    expect_error("[particles]\nflow_rate = 50.0\nspawn_interval = 4\n",
                 "particles.spawn_interval: ignored when particles.flow_rate > 0 (the source emits 50 particles per second): "
                 "remove it or set flow_rate = 0");
    expect_error(springs + "[particles]\nflow_rate = 5.0\nspawn_interval = 4\n", "particles.spawn_interval: ignored when");
    expect_error("[particles]\nspawn_interval = 4\n",  // the default river's rate is "auto": inherited, still a rate
                 "particles.spawn_interval: ignored when particles.flow_rate = \"auto\" (the default river's)");
    // ... and without a rate, its unit and "auto" (a PBF river's sizing) are not read.
    expect_error("[particles]\nflow_rate = 0.0\nlitres_per_particle = 2.0\n",
                 "particles.litres_per_particle: ignored when particles.flow_rate = 0");
    expect_error(springs + "[particles]\nlitres_per_particle = 2.0\n", "particles.litres_per_particle: ignored when");
    expect_error(springs + "[particles]\nflow_rate = \"auto\"\n", "particles.flow_rate: \"auto\" sizes a PBF river");
    // The source's placement and shape.
    expect_error("[particles]\nspawn_center = [10, 5, 80]\nauto_height = 2.0\n",
                 "particles.auto_height: ignored when particles.spawn_center is [x, y, z]");
    expect_error("[particles]\nsource_shape = \"point\"\nspawn_half_extent = [1, 1, 1]\n",
                 "particles.spawn_half_extent: ignored when particles.source_shape = \"point\"");
    expect_error("[sink]\nkind = \"edges\"\nmin = [0, 0, 0]\n", "sink.min: ignored when sink.kind = \"edges\"");
    expect_error(springs + "[particles]\nflow_rate = 0.0\n[sink]\nkind = \"none\"\nmax = [1, 1, 1]\n",
                 "sink.max: ignored when sink.kind = \"none\"");
    // Springs without a stiffness: no force, so no rest length, reach or pair search.
    for (const char* k : {"min_distance = 3.0", "max_distance = 5.0", "mode = \"grid\""})
        expect_error(springs + "[springs]\nstiffness = 0.0\n" + k + "\n",
                     "ignored when springs.stiffness = 0 (no spring force): remove it or give a stiffness");
    expect_error("solver = \"bullet\"\n[bullet]\nsprings = true\n[springs]\nstiffness = 0.0\nmax_distance = 5.0\n",
                 "springs.max_distance: ignored when springs.stiffness = 0");
    // Collision: no terrain contact with mode "none"; the paper's response has one query.
    expect_error(springs + "[collision]\nmode = \"none\"\ndamping = 0.5\n", "collision.damping: ignored when collision.mode = \"none\"");
    expect_error("[particles]\nprefill = false\n[collision]\nmode = \"none\"\noffset = 0.1\n",
                 "collision.offset: ignored when collision.mode = \"none\"");
    EXPECT_TRUE(parse("[collision]\nmode = \"none\"\noffset = 0.1\n").ok()) << "the river's prefill reads it";
    // The bed friction's law is PBF's: the springs' bounce has none.
    expect_error("[collision]\nmode = \"none\"\nfriction_speed = 3\n",
                 "collision.friction_speed: ignored when collision.mode = \"none\"");
    expect_error(springs + "[collision]\nfriction_speed = 3\n", "collision.friction_speed: ignored when solver = \"springs\"");
    expect_error(springs + "[collision]\nmode = \"paper\"\nquery = \"heightfield\"\n",
                 "collision.query: ignored when collision.mode = \"paper\"");
    // The terrain: a PNG has its own size and no procedure; only the valley is random.
    expect_error("[terrain]\nheightmap = \"h.png\"\nwidth = 33\n", "terrain.width: ignored when terrain.source = \"file\"");
    expect_error("[terrain]\nsource = \"file\"\nheightmap = \"h.png\"\nseed = 3\n", "terrain.seed: ignored when terrain.source = \"file\"");
    expect_error("[terrain]\nsource = \"bowl\"\nseed = 3\n", "terrain.seed: ignored when terrain.source = \"bowl\"");
    expect_error("[terrain]\nsource = \"valley\"\nheightmap = \"h.png\"\n",
                 "terrain.heightmap: ignored when terrain.source = \"valley\"");
    // The field's kernel: 1/r^2 has no radius.
    expect_error(springs + "[field]\nkernel = \"inverse_square\"\nradius = 2.0\n",
                 "field.radius: ignored when field.kernel = \"inverse_square\"");
    // PBF: the tensile correction's shape without its strength.
    expect_error("[pbf]\nscorr_k = 0.0\nscorr_n = 2\n", "pbf.scorr_n: ignored when pbf.scorr_k = 0");
    expect_error("[pbf]\nscorr_k = 0.0\nscorr_dq = 0.2\n", "pbf.scorr_dq: ignored when pbf.scorr_k = 0");
    // Bullet: no fixed step without substeps; spheres with springs never sleep.
    expect_error("solver = \"bullet\"\n[bullet]\nmax_substeps = 0\ndt = 0.01\n", "bullet.dt: ignored when bullet.max_substeps = 0");
    expect_error("solver = \"bullet\"\n[bullet]\nsprings = true\nsleep = true\n", "bullet.sleep: ignored when bullet.springs = true");
    // The surface's smoothing (issue 11's [surface]): what smooth_surface reads for the method.
    expect_error("[surface]\nenabled = false\nmethod = \"taubin\"\n", "surface.method: ignored when surface.enabled = false");
    expect_error("[surface]\nenabled = false\n[field]\nthreshold = 0.3\n",
                 "field.threshold: ignored when surface.enabled = false");
    expect_error("[surface]\nmethod = \"none\"\niterations = 4\n", "surface.iterations: ignored when surface.method = \"none\"");
    expect_error("[surface]\niterations = 0\nnormal_iterations = 2\n",
                 "surface.normal_iterations: ignored when surface.iterations = 0");
    expect_error("[surface]\nmethod = \"taubin\"\nkeep_volume = false\n", "surface.keep_volume: ignored when surface.method = \"taubin\"");
    expect_error("[surface]\nmethod = \"taubin\"\nsteps = \"uniform\"\n", "surface.steps: ignored when surface.method = \"taubin\"");
    expect_error("[surface]\nsteps = \"uniform\"\npass_band = 0.2\n", "surface.pass_band: ignored when surface.steps = \"uniform\"");
    expect_error("[surface]\nlambda = 0.5\n",  // the default scene's Chebyshev steps, inherited
                 "surface.lambda: ignored when surface.steps = \"chebyshev\"");
    expect_error(springs + "[field]\nkernel = \"inverse_square\"\n[surface]\nmethod = \"laplacian\"\nfeature_count = 4\n",
                 "surface.feature_count: ignored when field.kernel = \"inverse_square\"");
    // The spawn seed: PBF draws no random number (a solver scope, as fb17bfe's).
    expect_error("seed = 3\n", "seed: solver = \"pbf\" does not use it");
    expect_error("solver = \"pbf\"\nseed = 3\n", "seed: solver = \"pbf\"");

    // Inherited values never trigger it, and what each scene reads is accepted.
    for (const char* ok :
         {"[particles]\nflow_rate = 0.0\nspawn_interval = 4\n",  // PBF without a rate: the interval schedules
          "solver = \"springs\"\n[particles]\nspawn_interval = 4\n",  // "auto" is 0 outside PBF
          "solver = \"springs\"\n[particles]\nflow_rate = 5.0\nlitres_per_particle = 2.0\n",
          "[particles]\nlitres_per_particle = 2.0\n",  // the default river's "auto" rate in litres
          "[particles]\nflow_rate = 0.0\nlitres_per_particle = 0.0\n",  // 0 agrees: off
          "[particles]\nspawn_center = \"channel\"\nauto_height = 2.0\n",
          "[particles]\nsource_shape = \"point\"\n", "[sink]\nkind = \"box\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n",
          "surface = false\n", "solver = \"springs\"\nsurface = false\n",
          "solver = \"springs\"\nseed = 3\n[springs]\nstiffness = 0.0\n",
          "solver = \"springs\"\n[springs]\nstiffness = 2.0\nmin_distance = 3.0\nmax_distance = 5.0\nmode = \"grid\"\n",
          "solver = \"springs\"\n[collision]\nmode = \"paper\"\ndamping = 0.7\noffset = 0.07\nradius = 0.1\n",
          "[collision]\nmode = \"none\"\nradius = 0.1\n",  // the tunneled counter reads the radius
          "[collision]\nquery = \"tree\"\n", "[terrain]\nsource = \"valley\"\nseed = 3\nwidth = 33\n",
          "[terrain]\nsource = \"bowl\"\nwidth = 33\n",
          "solver = \"springs\"\n[field]\nkernel = \"radius_over_r\"\nradius = 2.0\n", "[field]\nradius = 2.0\n",
          "[pbf]\nscorr_k = 0.01\nscorr_n = 2\nscorr_dq = 0.2\n", "[pbf]\nscorr_k = 0.0\n",
          "solver = \"bullet\"\nseed = 3\n[bullet]\nmax_substeps = 0\n",
          "solver = \"bullet\"\n[bullet]\nmax_substeps = 2\ndt = 0.01\n",
          "solver = \"bullet\"\n[bullet]\nsprings = true\nsleep = false\n",
          "[surface]\nmethod = \"taubin\"\nlambda = 0.6\npass_band = 0.05\n", "[surface]\npass_band = 0.2\nkeep_volume = false\n",
          "[surface]\nmethod = \"none\"\n", "[surface]\nenabled = false\n", "[surface]\nenabled = false\n[field]\nresolution = 2\n",
          "solver = \"springs\"\n[field]\nkernel = \"inverse_square\"\n[surface]\nmethod = \"laplacian\"\nfeature_count = 0\n"}) {
        auto r = parse(ok);
        EXPECT_TRUE(r.ok()) << ok << (r.ok() ? "" : r.error().message);
    }
}

// Issue 42: which keys a scene reads comes from the key table alone. Keys the table said
// were not read but no hand-written rule refused are refused now; one the table says every
// scene reads (the AABB tree's leaf size: Bvh::build in every scene) is no longer refused
// with the rest of [collision] in a Bullet scene.
TEST(SceneToml, WhatTheKeyTableSaysIsNotReadIsRefused) {
    // The source follows the ground only as a PBF lattice emitting at a rate (Emitters::build_lattices).
    expect_error("solver = \"springs\"\n[particles]\nfollow_ground = true\n",
                 "particles.follow_ground: ignored when solver = \"springs\" (only PBF's lattice source follows the ground)");
    expect_error("[particles]\nflow_rate = 0\nfollow_ground = true\n",
                 "particles.follow_ground: ignored when particles.flow_rate = 0");
    EXPECT_TRUE(parse("solver = \"springs\"\n[particles]\nfollow_ground = false\n").ok()) << "false agrees: it does not";
    EXPECT_TRUE(parse("[particles]\nfollow_ground = true\n").ok()) << "the default river's";
    // Without terrain contact PBF counts no wall density and no contact band (pbf.cpp).
    for (const char* k : {"wall_density = 0.5", "contact_band = 1.0"})
        expect_error(std::string("[collision]\nmode = \"none\"\n[pbf]\n") + k + "\n",
                     "ignored when collision.mode = \"none\" (particles pass through the terrain)");
    // Every scene builds the tree; the rest of [collision] stays refused in Bullet.
    auto tree = parse("solver = \"bullet\"\n[collision]\nbvh_leaf_triangles = 16\n");
    ASSERT_TRUE(tree.ok()) << tree.error().message;
    EXPECT_EQ(tree->collision.leaf_triangles, 16);
    expect_error("solver = \"bullet\"\n[collision]\nbvh_leaf_triangles = 16\ndamping = 0.5\n",
                 "collision: solver = \"bullet\" does not use it");
    // A section a scene reads nothing of is refused as a table, even empty.
    expect_error("[bullet]\n", "bullet: only solver = \"bullet\" reads [bullet]");
    expect_error("solver = \"springs\"\n[pbf]\n", "pbf: only solver = \"pbf\" reads [pbf]");
    expect_error("[springs]\n", "springs: solver = \"pbf\" does not use springs");
    EXPECT_TRUE(parse("solver = \"springs\"\n[foam]\n").ok()) << "[foam]'s refusals are its keys'";
    // A Bullet scene reads no extra sources.
    expect_error("solver = \"bullet\"\n[[particles.source]]\ncenter = [1, 2, 3]\nhalf_extent = [1, 1, 1]\nflow_rate = 5.0\n",
                 "particles.source: ignored: only a scene with a particle rate reads it");
}

}  // namespace
}  // namespace mr
