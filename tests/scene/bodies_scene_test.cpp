// [[bodies]] in scene files (issue 44): every BodyDef field is a key of the table, read,
// checked (the key and its range in the message) and written back by `metariver scene`.
// The physics of the bodies is tested elsewhere; this is the file format only.
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <gtest/gtest.h>

#include <string>

namespace mr {
namespace {

constexpr const char* kTwoBodies = R"(
[[bodies]]
shape = "box"
size = [2.0, 0.5, 0.4]
density = 250.0
position = [20.0, 12.0, 30.0]
rotation = [0.0, 90.0, 0.0]
velocity = [1.0, 0.0, -0.5]
angular_velocity = [0.0, 0.25, 0.0]
friction = 0.8
[[bodies]]
shape = "convex_mesh"
mesh = "meshes/rock.obj"
size = [1.5, 0.0, 0.0]
density = 2000.0
)";

std::string error(const std::string& text) {
    auto r = parse_scene_toml(text, "bad.toml", default_scene());
    return r.ok() ? std::string("(loaded)") : r.error().message;
}

TEST(SceneBodies, EveryFieldIsReadFromTheFile) {
    auto r = parse_scene_toml(kTwoBodies, "dir/two.toml", default_scene());
    ASSERT_TRUE(r.ok()) << r.error().message;
    const SceneDef& d = r.value();
    ASSERT_EQ(d.bodies.size(), 2u);
    const BodyDef& a = d.bodies[0];
    EXPECT_EQ(a.shape, BodyShape::Box);
    EXPECT_EQ(a.size, Vec3(2.0f, 0.5f, 0.4f));
    EXPECT_FLOAT_EQ(a.density, 250.0f);
    EXPECT_EQ(a.position, Vec3(20, 12, 30));
    EXPECT_EQ(a.rotation, Vec3(0, 90, 0));
    EXPECT_EQ(a.velocity, Vec3(1, 0, -0.5f));
    EXPECT_EQ(a.angular_velocity, Vec3(0, 0.25f, 0));
    EXPECT_FLOAT_EQ(a.friction, 0.8f);
    const BodyDef& b = d.bodies[1];
    EXPECT_EQ(b.shape, BodyShape::ConvexMesh);
    EXPECT_EQ(b.mesh, "dir/meshes/rock.obj") << "an OBJ path is relative to the scene file, as the heightmap";
    EXPECT_FLOAT_EQ(b.friction, BodyDef{}.friction) << "a key left out keeps its default";
    EXPECT_TRUE(default_scene().bodies.empty()) << "the default river has no bodies";
}

TEST(SceneBodies, AWrittenSceneLoadsBackWithItsBodies) {
    auto r = parse_scene_toml(kTwoBodies, "two.toml", default_scene());
    ASSERT_TRUE(r.ok()) << r.error().message;
    const std::string text = scene_to_toml(r.value());
    EXPECT_NE(text.find("[[bodies]]\nshape = \"box\"\nsize = [2.0, 0.5, 0.4]"), std::string::npos) << text;
    EXPECT_EQ(text.find("does not load"), std::string::npos) << text;
    auto back = parse_scene_toml(text, "back.toml", default_scene());
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back.value().bodies, r.value().bodies);
    // No bodies: the file explains the list and holds none.
    const std::string plain = scene_to_toml(default_scene());
    EXPECT_EQ(plain.find("\n[[bodies]]"), std::string::npos);
    EXPECT_NE(plain.find("# [[bodies]]: Rigid bodies"), std::string::npos) << plain;
    EXPECT_NE(plain.find("#   density: "), std::string::npos);
}

TEST(SceneBodies, TheShapesNamesAreToStringsInBodyShapesOrder) {
    const SceneList* bodies = nullptr;
    for (const SceneList& l : scene_lists())
        if (l.name == "bodies") bodies = &l;
    ASSERT_NE(bodies, nullptr);
    const SceneKey& shape = bodies->keys[0].key;
    ASSERT_EQ(shape.name, "shape");
    ASSERT_EQ(shape.choices.size(), 5u);
    for (size_t i = 0; i < shape.choices.size(); ++i) EXPECT_EQ(shape.choices[i], to_string(static_cast<BodyShape>(i)));
}

TEST(SceneBodies, TheReferenceListsEveryKey) {
    const std::string ref = scene_reference_markdown();
    EXPECT_NE(ref.find("#### [[bodies]]"), std::string::npos);
    for (const char* key : {"shape", "size", "mesh", "density", "position", "rotation", "velocity", "angular_velocity",
                            "friction"})
        EXPECT_NE(ref.find(std::string("| `bodies.") + key + "` |"), std::string::npos) << key;
    EXPECT_NE(ref.find("| `bodies.density` | number | kg/m^3 | (0, 100000] |"), std::string::npos) << ref;
}

TEST(SceneBodies, BadValuesNameTheKeyAndTheRange) {
    EXPECT_EQ(error("[[bodies]]\nshape = \"cone\"\n"),
              "bad.toml: bodies[1].shape: must be one of box, sphere, capsule, convex_mesh, triangle_mesh (got 'cone')");
    EXPECT_EQ(error("[[bodies]]\ndensity = 0.0\n"), "bad.toml: bodies[1].density: must be in (0, 100000] (got 0)");
    EXPECT_EQ(error("[[bodies]]\n[[bodies]]\nfriction = 3.0\n"), "bad.toml: bodies[2].friction: must be in [0, 2] (got 3)");
    EXPECT_EQ(error("[[bodies]]\nsize = [1.0, -1.0, 1.0]\n"),
              "bad.toml: bodies[1].size: every component must be in (0, 1000] (the components the shape reads) (got [1, -1, 1])");
    EXPECT_EQ(error("[[bodies]]\nsize = [1.0, 0.0, 1.0]\n"),
              "bad.toml: bodies[1].size: component y must be in (0, 1000] for shape = \"box\" (got 0)");
    EXPECT_EQ(error("[[bodies]]\nshape = \"sphere\"\nsize = [0.5, 0.0, 0.0]\n"), "(loaded)")
        << "a sphere reads the radius only";
    EXPECT_EQ(error("[[bodies]]\nrotation = [0.0, 400.0, 0.0]\n"),
              "bad.toml: bodies[1].rotation: every component must be in [-360, 360] (got [0, 400, 0])");
    EXPECT_EQ(error("[[bodies]]\nvelocity = \"fast\"\n"), "bad.toml: bodies[1].velocity: must be an array of 3 numbers [x, y, z]");
    EXPECT_EQ(error("[[bodies]]\ncolour = 1\n"),
              "bad.toml: bodies[1].colour: unknown key (allowed here: shape, size, mesh, density, position, rotation, "
              "velocity, angular_velocity, friction)");
    EXPECT_EQ(error("[[bodies]]\nshape = \"triangle_mesh\"\n"),
              "bad.toml: bodies[1].mesh: required for shape = \"triangle_mesh\" (the OBJ file)");
    EXPECT_EQ(error("[[bodies]]\nmesh = \"log.obj\"\n"),
              "bad.toml: bodies[1].mesh: ignored for shape = \"box\" (only convex_mesh and triangle_mesh read an OBJ): "
              "remove it");
    EXPECT_EQ(error("bodies = 3\n"), "bad.toml: bodies: must be a list of tables, each written [[bodies]]");
    std::string many;
    for (size_t i = 0; i <= kMaxBodies; ++i) many += "[[bodies]]\n";
    EXPECT_EQ(error(many), "bad.toml: bodies: at most 1024 entries (got 1025)");
    // Bodies are PBF's, swe's and hybrid's: another solver names the list.
    EXPECT_EQ(error("solver = \"springs\"\n[particles]\nflow_rate = 0.0\n[[bodies]]\n"),
              "bad.toml: bodies: ignored: only solver = pbf, swe, hybrid reads it; remove it");
    SceneDef springs = default_scene();
    springs.solver = SolverKind::Springs;
    springs.bodies.resize(1);
    auto v = validate(springs);
    ASSERT_FALSE(v.ok());
    EXPECT_EQ(v.error().message.rfind("bodies: only solver = \"pbf\", \"swe\" or \"hybrid\" moves bodies", 0), 0u) << v.error().message;
}

}  // namespace
}  // namespace mr
