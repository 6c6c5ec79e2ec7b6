#include <metariver/scene.h>

#include "scene_toml_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace mr {
namespace {

using scene_test::expect_error;
using scene_test::parse;

TEST(SceneToml, EmptyFileIsTheDefaultScene) {
    auto r = parse("");
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_EQ(r->spawn.count, default_scene().spawn.count);
    EXPECT_EQ(r->source.kind, TerrainSource::Valley);
}

TEST(SceneToml, EveryKeyIsRead) {
    // One scene where every key is read (issue 13: a key another key's value makes
    // irrelevant is an error, so the file source, the automatic centre's height and
    // the surface's absence are checked on their own below).
    auto r = parse(R"(
name = "mine"
solver = "springs"
seed = 42
surface = true
[terrain]
source = "valley"
width = 10
height = 12
seed = 3
area_scale = 2.5
height_scale = 9
paper_row_orientation = false
condition = "breach"
[particles]
count = 77
spawn_center = [1, 2, 3]
spawn_half_extent = [0.5, 0.25, 1]
spawn_interval = 4
initial_velocity = [0, -1, 2]
[forces]
gravity = 3.5
[springs]
stiffness = 12
min_distance = 1.5
max_distance = 2
mode = "pairs"
[collision]
mode = "robust"
damping = 0.25
offset = 0.1
bvh_leaf_triangles = 16
[integrator]
dt = 0.01
substeps = 3
[field]
kernel = "radius_over_r"
radius = 1.25
resolution = 3
bounds_offset = 2.5
threshold = 0.4
)");
    ASSERT_TRUE(r.ok()) << r.error().message;
    const SceneDef& d = r.value();
    EXPECT_EQ(d.name, "mine");
    EXPECT_EQ(d.seed, 42u);
    EXPECT_TRUE(d.surface);
    EXPECT_EQ(d.source.kind, TerrainSource::Valley);
    EXPECT_EQ(d.source.width, 10);
    EXPECT_EQ(d.source.height, 12);
    EXPECT_EQ(d.source.seed, 3u);
    EXPECT_FLOAT_EQ(d.terrain.area_scale, 2.5f);
    EXPECT_FLOAT_EQ(d.terrain.height_scale, 9.0f);
    EXPECT_FALSE(d.terrain.paper_row_orientation);
    EXPECT_EQ(d.terrain.condition, TerrainCondition::Breach);
    EXPECT_EQ(d.spawn.count, 77);
    EXPECT_EQ(d.spawn.center, Vec3(1, 2, 3));
    EXPECT_FALSE(d.spawn.auto_center);
    EXPECT_FALSE(d.spawn.auto_channel);
    EXPECT_EQ(d.spawn.half_extent, Vec3(0.5f, 0.25f, 1));
    EXPECT_EQ(d.spawn.interval, 4);
    EXPECT_EQ(d.spawn.initial_velocity, Vec3(0, -1, 2));
    EXPECT_FLOAT_EQ(d.integrator.gravity, 3.5f);
    EXPECT_FLOAT_EQ(d.springs.stiffness, 12.0f);
    EXPECT_FLOAT_EQ(d.springs.min_distance, 1.5f);
    EXPECT_FLOAT_EQ(d.springs.max_distance, 2.0f);
    EXPECT_EQ(d.collision.mode, CollisionMode::Robust);
    EXPECT_FLOAT_EQ(d.collision.damping, 0.25f);
    EXPECT_FLOAT_EQ(d.collision.offset, 0.1f);
    EXPECT_EQ(d.collision.leaf_triangles, 16);
    EXPECT_FLOAT_EQ(d.integrator.fixed_dt, 0.01f);
    EXPECT_EQ(d.integrator.substeps, 3);
    EXPECT_EQ(d.field.kernel, FieldKernel::RadiusOverR);
    EXPECT_FLOAT_EQ(d.field.radius, 1.25f);
    EXPECT_FLOAT_EQ(d.field.resolution, 3.0f);
    EXPECT_FLOAT_EQ(d.field.bounds_offset, 2.5f);
    EXPECT_FLOAT_EQ(d.field.threshold, 0.4f);

    // The PBF river's own keys, its source and its sink (a scene of the default's solver;
    // SceneKeys.EveryKeyInTheTableIsReadIntoItsField covers every key of the table).
    auto pbf = parse(R"(
[particles]
source_shape = "box"
flow_rate = 50
litres_per_particle = 2
[pbf]
spacing = 0.4
kernel_radius = 1.2
iterations = 5
relaxation = 0.1
scorr_k = 0.02
scorr_n = 3
scorr_dq = 0.25
xsph = 0.1
vorticity = 1.5
sleep_threshold = 0.05
[sink]
kind = "box"
min = [1, 2, 3]
max = [4, 5, 6]
[collision]
query = "tree"
radius = 0.2
[field]
bounds = "terrain"
)");
    ASSERT_TRUE(pbf.ok()) << pbf.error().message;
    EXPECT_EQ(pbf->solver, SolverKind::Pbf);
    EXPECT_EQ(pbf->spawn.shape, SourceShape::Box);
    EXPECT_FLOAT_EQ(pbf->spawn.flow_rate, 50.0f);
    EXPECT_FLOAT_EQ(pbf->spawn.litres_per_particle, 2.0f);
    EXPECT_FLOAT_EQ(pbf->spawn.particles_per_second(), 25.0f);
    EXPECT_FLOAT_EQ(pbf->pbf.spacing, 0.4f);
    EXPECT_FLOAT_EQ(pbf->pbf.kernel_radius, 1.2f);
    EXPECT_EQ(pbf->pbf.iterations, 5);
    EXPECT_FLOAT_EQ(pbf->pbf.relaxation, 0.1f);
    EXPECT_FLOAT_EQ(pbf->pbf.scorr_k, 0.02f);
    EXPECT_EQ(pbf->pbf.scorr_n, 3);
    EXPECT_FLOAT_EQ(pbf->pbf.scorr_dq, 0.25f);
    EXPECT_FLOAT_EQ(pbf->pbf.xsph, 0.1f);
    EXPECT_FLOAT_EQ(pbf->pbf.vorticity, 1.5f);
    EXPECT_FLOAT_EQ(pbf->pbf.sleep_threshold, 0.05f);
    EXPECT_EQ(pbf->sink.kind, SinkKind::Box);
    EXPECT_EQ(pbf->sink.min, Vec3(1, 2, 3));
    EXPECT_EQ(pbf->sink.max, Vec3(4, 5, 6));
    EXPECT_EQ(pbf->collision.query, CollisionQuery::Tree);
    EXPECT_FLOAT_EQ(pbf->collision.radius, 0.2f);
    EXPECT_EQ(pbf->field.bounds, FieldBounds::Terrain);
    auto channel = parse("[particles]\nspawn_center = \"auto\"\ncount = \"auto\"\nflow_rate = \"auto\"\n");
    ASSERT_TRUE(channel.ok()) << channel.error().message;
    EXPECT_TRUE(channel->spawn.auto_center);
    EXPECT_FALSE(channel->spawn.auto_channel);
    EXPECT_EQ(channel->spawn.count, kAutoCount);
    EXPECT_TRUE(channel->spawn.auto_rate());

    auto file = parse("[terrain]\nheightmap = \"maps/h.png\"\n");
    ASSERT_TRUE(file.ok()) << file.error().message;
    EXPECT_EQ(file->source.kind, TerrainSource::File);
    EXPECT_EQ(file->source.heightmap, "dir/maps/h.png");  // relative to the scene file
    auto height = parse("[particles]\nspawn_center = \"auto\"\nauto_height = 3\n");
    ASSERT_TRUE(height.ok()) << height.error().message;
    EXPECT_FLOAT_EQ(height->spawn.auto_height, 3.0f);
    auto off = parse("surface = false\n[field]\nresolution = 2\n");  // the VDB export's voxel size
    ASSERT_TRUE(off.ok()) << off.error().message;
    EXPECT_FALSE(off->surface);
    EXPECT_FLOAT_EQ(off->field.resolution, 2.0f);
}

TEST(SceneToml, SpawnCenterAuto) {
    auto r = parse("[particles]\nspawn_center = \"auto\"\n");
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_TRUE(r->spawn.auto_center);
    expect_error("[particles]\nspawn_center = \"top\"\n", "particles.spawn_center");
}

TEST(SceneToml, SyntaxErrorNamesFileAndLine) { expect_error("[field]\nresolution = = 2\n", "dir/s.toml:2:"); }

TEST(SceneToml, RenderFlowDetailIsReadAndTyped) {
    // [render] is the renderer's: on by default, read as written, only known keys.
    EXPECT_TRUE(default_scene().render.flow_detail);
    auto r = parse("[render]\nflow_detail = false\n");
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_FALSE(r->render.flow_detail);
    expect_error("[render]\nflow_detail = 1\n", "render.flow_detail: must be true or false");
    expect_error("[render]\nflow = true\n", "render.flow: unknown key");
}

TEST(SceneToml, UnknownKeysAreErrors) {
    expect_error("particle_count = 3\n", "particle_count: unknown key");
    expect_error("[particles]\ncont = 3\n", "particles.cont: unknown key");
    expect_error("[fluid]\n", "fluid: unknown key");
}

TEST(SceneToml, WrongTypesAreErrors) {
    expect_error("[particles]\ncount = \"many\"\n", "particles.count: must be \"auto\" or a whole number");
    expect_error("[particles]\ncount = 2.5\n", "particles.count: must be an integer");
    expect_error("[field]\nresolution = \"high\"\n", "field.resolution: must be a number");
    expect_error("[particles]\nspawn_half_extent = [1, 2]\n", "particles.spawn_half_extent: must be an array of 3");
    expect_error("terrain = 3\n", "terrain: must be a table");
    expect_error("[terrain]\npaper_row_orientation = 1\n", "terrain.paper_row_orientation: must be true or false");
    expect_error("[terrain]\ncondition = \"flood\"\n", "terrain.condition");
}

TEST(SceneToml, SizesTheReferencePathsCannotFinishAreRefusedNamingTheAlternative) {
    // Issue 13: accepted input that effectively hung.
    expect_error("solver = \"springs\"\n[particles]\ncount = 1000000\n[springs]\nstiffness = 4.0\nmode = \"pairs\"\n",
                 "springs.mode = \"grid\"");
    expect_error("solver = \"springs\"\n[particles]\ncount = 100000\n[springs]\nmode = \"grid\"\n[field]\n"
                 "kernel = \"inverse_square\"\n",
                 "field.kernel = \"poly6\"");
    expect_error("solver = \"bullet\"\n[particles]\ncount = 3000000\n", "particles.count: solver = \"bullet\" is limited");
}

TEST(SceneToml, OutOfRangeValuesNameTheKeyAndTheRange) {
    // Issue 13: a micron spacing overflowed the kernel constants and respawned every
    // particle every step in silence.
    expect_error("solver = \"pbf\"\n[pbf]\nspacing = 1e-6\nkernel_radius = 2e-6\n", "pbf.spacing: must be in [0.001, 1000]");
    expect_error("[field]\nresolution = -2\n", "field.resolution: must be in (0, 64]");
    expect_error("[field]\nresolution = 0\n", "field.resolution: must be in (0, 64]");
    expect_error("[field]\nresolution = nan\n", "field.resolution");
    expect_error("[field]\nthreshold = inf\n", "field.threshold");
    expect_error("[integrator]\ndt = -0.01\n", "integrator.dt: must be 0 or in (0, 1]");
    expect_error("[integrator]\ndt = nan\n", "integrator.dt");
    expect_error("[particles]\ncount = 0\n", "particles.count: must be in [1, 10000000]");
    expect_error("[particles]\ncount = 1000000000000\n", "particles.count: must be in [1, 10000000]");
    expect_error("[particles]\nspawn_half_extent = [1, -1, 1]\n", "particles.spawn_half_extent");
    expect_error("[collision]\ndamping = 1.5\n", "collision.damping: must be in [0, 1]");
    expect_error("[collision]\nbvh_leaf_triangles = 1\n", "collision.bvh_leaf_triangles: must be in [2, 4096]");
    expect_error("[terrain]\nwidth = 1\n", "terrain.width: must be in [2, 4097]");
    expect_error("[terrain]\narea_scale = 0\n", "terrain.area_scale");
    expect_error("seed = -1\n", "seed: must be in [0, 4294967295]");
}

TEST(SceneToml, UnknownEnumValuesListTheChoices) {
    expect_error("[collision]\nmode = \"magic\"\n", "collision.mode: must be one of paper, robust, none");
    expect_error("[field]\nkernel = \"gauss\"\n", "field.kernel: must be one of inverse_square, radius_over_r");
    expect_error("[terrain]\nsource = \"moon\"\n", "terrain.source: must be one of");
}

TEST(SceneToml, FileSourceNeedsAHeightmap) { expect_error("[terrain]\nsource = \"file\"\n", "terrain.heightmap"); }

TEST(SceneFile, MissingFileIsAnError) {
    auto r = load_scene_file("/nonexistent/scene.toml");
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("/nonexistent/scene.toml"), std::string::npos);
}

TEST(Presets, PaperScenesCarryTheirExactParameters) {
    auto full = preset("paper-full");
    ASSERT_TRUE(full.ok());
    EXPECT_EQ(full->spawn.count, 20);
    EXPECT_EQ(full->spawn.center, Vec3(8, 7, 15));
    EXPECT_EQ(full->spawn.half_extent, Vec3(2, 1, 0.2f));
    EXPECT_EQ(full->spawn.interval, 80);
    EXPECT_FLOAT_EQ(full->integrator.gravity, 9.82f);
    EXPECT_FLOAT_EQ(full->springs.stiffness, 0.0f);
    EXPECT_FLOAT_EQ(full->springs.min_distance, 3.0f);
    EXPECT_FLOAT_EQ(full->springs.max_distance, 5.0f);
    EXPECT_FLOAT_EQ(full->collision.damping, 0.7f);
    EXPECT_FLOAT_EQ(full->collision.offset, 0.07f);
    EXPECT_EQ(full->collision.leaf_triangles, 8);
    EXPECT_EQ(full->collision.mode, CollisionMode::Paper);
    EXPECT_FLOAT_EQ(full->field.radius, 2.0f);
    EXPECT_FLOAT_EQ(full->field.resolution, 2.0f);
    EXPECT_FLOAT_EQ(full->field.threshold, 0.54f);
    EXPECT_FLOAT_EQ(full->field.bounds_offset, 4.0f);
    EXPECT_FLOAT_EQ(full->terrain.area_scale, 1.0f);
    EXPECT_FLOAT_EQ(full->terrain.height_scale, 7.0f);
    EXPECT_EQ(full->source.kind, TerrainSource::File);

    auto nile = preset("paper-nile");
    ASSERT_TRUE(nile.ok());
    EXPECT_EQ(nile->spawn.count, 50);
    EXPECT_EQ(nile->spawn.center, Vec3(27, 4.6f, 31));
    EXPECT_EQ(nile->spawn.half_extent, Vec3(2.5f, 1, 1));
    EXPECT_EQ(nile->spawn.interval, 15);
    EXPECT_FLOAT_EQ(nile->field.resolution, 1.0f);
    EXPECT_FLOAT_EQ(nile->field.threshold, 0.32f);
    EXPECT_FLOAT_EQ(nile->field.bounds_offset, 5.0f);

    auto bowl = preset("paper-bowl");
    ASSERT_TRUE(bowl.ok());
    EXPECT_GT(bowl->springs.stiffness, 0.0f);  // figure 6: springs on
    EXPECT_EQ(bowl->source.kind, TerrainSource::Bowl);

    for (const auto& n : preset_names()) {
        auto p = preset(n);
        ASSERT_TRUE(p.ok()) << n;
        SceneDef d = p.value();
        if (d.source.kind == TerrainSource::File) d.source.heightmap = "x.png";
        EXPECT_TRUE(validate(d).ok()) << n;
    }
    auto bad = preset("paper-moon");
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("paper-nile"), std::string::npos) << "lists the known presets";
}

TEST(SceneFile, TheScenesShippedInTheRepositoryStillLoad) {
    // docs/bullet/*.toml and the fuzz seed corpus: each scene loads, except the broken_*
    // seeds, which are refused.
    const std::filesystem::path src(METARIVER_SOURCE_DIR);
    int seen = 0;
    for (const char* dir : {"docs/bullet", "fuzz/corpus/scene_toml"})
        for (const auto& e : std::filesystem::directory_iterator(src / dir)) {
            if (e.path().extension() != ".toml") continue;
            ++seen;
            auto r = load_scene_file(e.path().string());
            if (e.path().filename().string().rfind("broken_", 0) == 0)
                EXPECT_FALSE(r.ok()) << e.path();
            else
                EXPECT_TRUE(r.ok()) << e.path() << ": " << r.error().message;
        }
    EXPECT_GE(seen, 20);
}

TEST(SceneToml, BulletTableIsRead) {
    auto r = parse(R"(
solver = "bullet"
[bullet]
terrain = "heightfield"
sphere_radius = 0.25
mass = 2
friction = 0.1
restitution = 0.3
particle_collisions = true
dt = 0.01
max_substeps = 4
solver_iterations = 20
ccd = true
sleep = false
springs = true
)");
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_EQ(r->solver, SolverKind::Bullet);
    EXPECT_EQ(r->bullet.terrain, BulletTerrainShape::Heightfield);
    EXPECT_FLOAT_EQ(r->bullet.sphere_radius, 0.25f);
    EXPECT_FLOAT_EQ(r->bullet.mass, 2.0f);
    EXPECT_FLOAT_EQ(r->bullet.friction, 0.1f);
    EXPECT_FLOAT_EQ(r->bullet.restitution, 0.3f);
    EXPECT_TRUE(r->bullet.particle_collisions);
    EXPECT_FLOAT_EQ(r->bullet.fixed_dt, 0.01f);
    EXPECT_EQ(r->bullet.max_substeps, 4);
    EXPECT_EQ(r->bullet.solver_iterations, 20);
    EXPECT_TRUE(r->bullet.ccd);
    EXPECT_FALSE(r->bullet.sleep);
    EXPECT_TRUE(r->bullet.springs);
    EXPECT_EQ(to_string(r->solver), "bullet");
}

TEST(SceneToml, BadBulletValuesNameTheKey) {
    expect_error("solver = \"havok\"\n", "solver: must be one of springs, bullet");
    expect_error("solver = \"bullet\"\n[bullet]\nterrain = \"voxels\"\n", "bullet.terrain: must be one of mesh, heightfield");
    expect_error("solver = \"bullet\"\n[bullet]\nsphere_radius = 0\n", "bullet.sphere_radius: must be in (0, 1000]");
    expect_error("solver = \"bullet\"\n[bullet]\nsphere_radius = nan\n", "bullet.sphere_radius");
    expect_error("solver = \"bullet\"\n[bullet]\nmass = -1\n", "bullet.mass: must be in (0, 1000000]");
    expect_error("solver = \"bullet\"\n[bullet]\nfriction = -0.1\n", "bullet.friction: must be in [0, 100]");
    expect_error("solver = \"bullet\"\n[bullet]\nrestitution = 2\n", "bullet.restitution: must be in [0, 1]");
    expect_error("solver = \"bullet\"\n[bullet]\ndt = 0\n", "bullet.dt: must be in (0, 1]");
    expect_error("solver = \"bullet\"\n[bullet]\nmax_substeps = -1\n", "bullet.max_substeps: must be in [0, 1000]");
    expect_error("solver = \"bullet\"\n[bullet]\nmax_substeps = 1.5\n", "bullet.max_substeps: must be an integer");
    expect_error("solver = \"bullet\"\n[bullet]\nsolver_iterations = 0\n", "bullet.solver_iterations: must be in [1, 1000]");
    expect_error("solver = \"bullet\"\n[bullet]\nccd = 1\n", "bullet.ccd: must be true or false");
    expect_error("solver = \"bullet\"\n[bullet]\nsprings = \"yes\"\n", "bullet.springs: must be true or false");
    expect_error("solver = \"bullet\"\n[bullet]\ngravity = 9.81\n", "bullet.gravity: unknown key");
    expect_error("bullet = 3\n", "bullet: must be a table");
}

TEST(Presets, PaperEngineScenesCarryTheirExactParameters) {
    auto engine = preset("paper-engine");
    ASSERT_TRUE(engine.ok());
    EXPECT_EQ(engine->solver, SolverKind::Bullet);
    EXPECT_EQ(engine->source.kind, TerrainSource::File);  // strict17.png from --heightmap
    EXPECT_EQ(engine->spawn.count, 40);
    EXPECT_EQ(engine->spawn.center, Vec3(8, 7, 15));
    EXPECT_EQ(engine->spawn.half_extent, Vec3(2, 1, 0.2f));
    EXPECT_EQ(engine->spawn.interval, 8);
    EXPECT_FLOAT_EQ(engine->field.radius, 2.0f);
    EXPECT_FLOAT_EQ(engine->field.resolution, 1.0f);
    EXPECT_FLOAT_EQ(engine->field.threshold, 0.48f);
    EXPECT_FLOAT_EQ(engine->field.bounds_offset, 4.0f);
    EXPECT_FLOAT_EQ(engine->terrain.area_scale, 1.0f);
    EXPECT_FLOAT_EQ(engine->terrain.height_scale, 7.0f);
    EXPECT_FLOAT_EQ(engine->integrator.gravity, 9.81f);  // the engine's (Unity's) default
    EXPECT_EQ(engine->bullet.terrain, BulletTerrainShape::Mesh);
    EXPECT_FALSE(engine->bullet.springs);
    EXPECT_FALSE(engine->bullet.particle_collisions);

    auto nile = preset("paper-nile-engine");
    ASSERT_TRUE(nile.ok());
    EXPECT_EQ(nile->solver, SolverKind::Bullet);
    EXPECT_EQ(nile->source.kind, TerrainSource::File);  // nile.png from --heightmap
    EXPECT_EQ(nile->spawn.count, 50);
    EXPECT_EQ(nile->spawn.center, Vec3(27, 4.6f, 31));
    EXPECT_EQ(nile->spawn.half_extent, Vec3(2.5f, 1, 1));
    EXPECT_EQ(nile->spawn.interval, 15);
    EXPECT_FLOAT_EQ(nile->field.resolution, 1.0f);
    EXPECT_FLOAT_EQ(nile->field.threshold, 0.32f);
    EXPECT_FLOAT_EQ(nile->field.bounds_offset, 5.0f);
    EXPECT_FLOAT_EQ(nile->integrator.gravity, 9.81f);
    EXPECT_FALSE(nile->bullet.springs);
}


TEST(SceneToml, ErrorsAreOneLineWhateverTheFileHolds) {
    // Found by fuzz/scene_toml_fuzz.cpp: toml++ quotes the text at a syntax error, so
    // "sleep = fals" followed by a newline gave a message with a line break in it; quoted
    // keys and string values can hold newlines, tabs and other control characters too.
    const char* const inputs[] = {
        "[bullet]\nsleep = fals\nccd = true\n",
        "solver = \"pbf\\nsprings\"\n",
        "\"na\\nme\" = 1\n",
        "[terrain]\nsource = \"val\\tley\\u0001\"\n",
        "[particles]\ncount = 1\r\ncount = 2\r\n",
        "x = \"\\u007f\"\n",
    };
    for (const char* text : inputs) {
        auto r = parse_scene_toml(text, "one_line.toml", default_scene());
        ASSERT_FALSE(r.ok()) << text;
        const std::string& m = r.error().message;
        EXPECT_EQ(m.rfind("one_line.toml", 0), 0u) << m;
        for (char c : m) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f) << "control character in: " << m;
    }
    auto r = parse_scene_toml("solver = \"pbf\\nsprings\"\n", "s.toml", default_scene());
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("(got 'pbf\\nsprings')"), std::string::npos) << r.error().message;
}

// Issue 11: [surface] chooses how the marching-cubes mesh is smoothed; `surface = false`
// (the switch) still works, and [surface] enabled is the same switch.
TEST(SceneToml, SurfaceTableChoosesTheSmoothing) {
    const SmoothingDef d = default_scene().smoothing;
    EXPECT_EQ(d.method, SmoothingMethod::Laplacian) << "the default river is smoothed";
    EXPECT_EQ(d.steps, SmoothingSteps::Chebyshev);
    for (const std::string& name : preset_names()) {
        if (name.rfind("paper-", 0) != 0 && name != "springs-valley") continue;
        auto p = preset(name);
        ASSERT_TRUE(p.ok()) << name;
        EXPECT_EQ(p->smoothing.method, SmoothingMethod::None) << name << " keeps the paper's surface";
    }
    // Taubin reads neither steps nor keep_volume (issue 13: a key the scene does not read
    // is an error): those two are read with Laplacian's uniform steps below.
    auto r = parse(R"(
[surface]
enabled = true
method = "taubin"
iterations = 30
lambda = 0.6
pass_band = 0.05
feature_count = 5
normal_iterations = 2
)");
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_TRUE(r->surface);
    EXPECT_EQ(r->smoothing.method, SmoothingMethod::Taubin);
    EXPECT_EQ(r->smoothing.iterations, 30);
    EXPECT_FLOAT_EQ(r->smoothing.lambda, 0.6f);
    EXPECT_FLOAT_EQ(r->smoothing.pass_band, 0.05f);
    EXPECT_FLOAT_EQ(r->smoothing.feature_count, 5.0f);
    EXPECT_EQ(r->smoothing.normal_iterations, 2);
    auto uniform = parse("[surface]\nmethod = \"laplacian\"\nsteps = \"uniform\"\nlambda = 0.5\nkeep_volume = false\n");
    ASSERT_TRUE(uniform.ok()) << uniform.error().message;
    EXPECT_EQ(uniform->smoothing.steps, SmoothingSteps::Uniform);
    EXPECT_FLOAT_EQ(uniform->smoothing.lambda, 0.5f);
    EXPECT_FALSE(uniform->smoothing.keep_volume);
    auto none = parse("[surface]\nmethod = \"none\"\n");
    ASSERT_TRUE(none.ok()) << none.error().message;
    EXPECT_EQ(none->smoothing.method, SmoothingMethod::None);
    EXPECT_TRUE(none->surface);
    auto off = parse("[surface]\nenabled = false\n");
    ASSERT_TRUE(off.ok());
    EXPECT_FALSE(off->surface);
    auto old = parse("surface = false\n");
    ASSERT_TRUE(old.ok());
    EXPECT_FALSE(old->surface);
    EXPECT_EQ(old->smoothing.method, SmoothingMethod::Laplacian);
    auto weights_off = parse("[surface]\nfeature_count = 0\n");
    ASSERT_TRUE(weights_off.ok()) << weights_off.error().message;

    expect_error("[surface]\nmethod = \"gauss\"\n", "surface.method: must be one of none, laplacian, taubin");
    expect_error("[surface]\nsteps = \"fast\"\n", "surface.steps: must be one of uniform, chebyshev");
    expect_error("[surface]\niterations = 101\n", "surface.iterations: must be in [0, 100]");
    expect_error("[surface]\niterations = 2.5\n", "surface.iterations: must be an integer");
    expect_error("[surface]\nsteps = \"uniform\"\nlambda = 0\n", "surface.lambda: must be in (0, 1]");
    expect_error("[surface]\nsteps = \"uniform\"\nlambda = 1.5\n", "surface.lambda: must be in (0, 1]");
    expect_error("[surface]\npass_band = 1\n", "surface.pass_band: must be in (0, 1)");
    expect_error("[surface]\npass_band = nan\n", "surface.pass_band");
    expect_error("[surface]\nfeature_count = 1\n", "surface.feature_count: must be 0 or in [2, 1000]");
    expect_error("[surface]\nnormal_iterations = -1\n", "surface.normal_iterations: must be in [0, 100]");
    expect_error("[surface]\nkeep_volume = 1\n", "surface.keep_volume: must be true or false");
    expect_error("[surface]\nradius = 1\n", "surface.radius: unknown key");
    expect_error("surface = 3\n", "surface: must be true or false, or a table");
}

}  // namespace
}  // namespace mr

namespace mr {
namespace {

TEST(SceneToml, FoamKeysAreReadAndRangeChecked) {
    // The default river makes foam; every [foam] key is read.
    EXPECT_TRUE(default_scene().foam.enabled);
    auto r = parse_scene_toml(R"(
[foam]
enabled = true
max_particles = 5000
trapped_air_min = 2.0
trapped_air_max = 9.0
wave_crest_min = 0.25
wave_crest_max = 4.0
energy_min = 1.0
energy_max = 12.0
trapped_air_rate = 30.0
wave_crest_rate = 10.0
lifetime_min = 1.0
lifetime_max = 2.5
spray_neighbours = 4
bubble_neighbours = 25
buoyancy = 1.5
drag = 0.25
)",
                              "dir/s.toml", default_scene());
    ASSERT_TRUE(r.ok()) << r.error().message;
    const FoamDef& f = r->foam;
    EXPECT_EQ(f.max_particles, 5000);
    EXPECT_FLOAT_EQ(f.trapped_air_min, 2.0f);
    EXPECT_FLOAT_EQ(f.trapped_air_max, 9.0f);
    EXPECT_FLOAT_EQ(f.wave_crest_min, 0.25f);
    EXPECT_FLOAT_EQ(f.wave_crest_max, 4.0f);
    EXPECT_FLOAT_EQ(f.energy_min, 1.0f);
    EXPECT_FLOAT_EQ(f.energy_max, 12.0f);
    EXPECT_FLOAT_EQ(f.trapped_air_rate, 30.0f);
    EXPECT_FLOAT_EQ(f.wave_crest_rate, 10.0f);
    EXPECT_FLOAT_EQ(f.lifetime_min, 1.0f);
    EXPECT_FLOAT_EQ(f.lifetime_max, 2.5f);
    EXPECT_EQ(f.spray_neighbours, 4);
    EXPECT_EQ(f.bubble_neighbours, 25);
    EXPECT_FLOAT_EQ(f.buoyancy, 1.5f);
    EXPECT_FLOAT_EQ(f.drag, 0.25f);

    auto bad = [](const std::string& text, const std::string& must_contain) {
        auto b = parse_scene_toml(text, "dir/s.toml", default_scene());
        ASSERT_FALSE(b.ok()) << "accepted: " << text;
        EXPECT_NE(b.error().message.find(must_contain), std::string::npos)
            << "message '" << b.error().message << "' lacks '" << must_contain << "'";
    };
    bad("[foam]\nmax_particles = -1\n", "foam.max_particles: must be in [0, 1000000] (got -1)");
    bad("[foam]\nmax_particles = 2000000\n", "foam.max_particles: must be in [0, 1000000]");
    bad("[foam]\ntrapped_air_min = -1\n", "foam.trapped_air_min: must be in [0, 1000]");
    bad("[foam]\ntrapped_air_min = 5\ntrapped_air_max = 4\n", "foam.trapped_air_max: must be in (foam.trapped_air_min = 5, 1000]");
    bad("[foam]\nwave_crest_max = 0.1\n", "foam.wave_crest_max: must be in (foam.wave_crest_min");
    bad("[foam]\nenergy_max = 2e6\n", "foam.energy_max: must be in (foam.energy_min");
    bad("[foam]\ntrapped_air_rate = -3\n", "foam.trapped_air_rate: must be in [0, 10000]");
    bad("[foam]\nwave_crest_rate = 1e5\n", "foam.wave_crest_rate: must be in [0, 10000]");
    bad("[foam]\nlifetime_min = 0\n", "foam.lifetime_min: must be in [0.01, 1000]");
    bad("[foam]\nlifetime_min = 3\nlifetime_max = 2\n", "foam.lifetime_max: must be in [foam.lifetime_min = 3, 1000]");
    bad("[foam]\nspray_neighbours = 30\n", "foam.bubble_neighbours: must be in [foam.spray_neighbours = 30, 1000]");
    bad("[foam]\nbubble_neighbours = 5000\n", "foam.bubble_neighbours: must be in [foam.spray_neighbours, 1000]");
    bad("[foam]\nbuoyancy = 101\n", "foam.buoyancy: must be in [0, 100]");
    bad("[foam]\ndrag = 1.5\n", "foam.drag: must be in [0, 1]");
    bad("[foam]\nenabled = 1\n", "foam.enabled: must be true or false");
    bad("[foam]\nspeed = 1\n", "foam.speed: unknown key");
    // Keys foam.enabled = false makes irrelevant name both.
    bad("[foam]\nenabled = false\nmax_particles = 10\n", "foam.max_particles: ignored when foam.enabled = false");
    // Only PBF and swe make foam.
    bad("solver = \"springs\"\n[foam]\nenabled = true\n", "foam.enabled: only solver = \"pbf\", \"swe\" or \"hybrid\" makes foam");
    bad("solver = \"springs\"\n[foam]\nlifetime_min = 1\n", "foam.lifetime_min: only solver = \"pbf\"");
    for (const char* ok : {"[foam]\nenabled = false\n", "solver = \"springs\"\n[foam]\nenabled = false\n",
                           "[foam]\nmax_particles = 0\n", "[foam]\nlifetime_min = 2\nlifetime_max = 2\n"}) {
        auto o = parse_scene_toml(ok, "dir/s.toml", default_scene());
        EXPECT_TRUE(o.ok()) << ok << (o.ok() ? "" : o.error().message);
    }
}

}  // namespace
}  // namespace mr
