// Export formats read back by readers the project did not write: Debian's assimp for
// OBJ, PLY and glb (counts and positions as written), the Khronos glTF validator (npm
// gltf-validator, through node) for glb. A test whose reader is missing says so and
// skips; scripts/install-deps.sh installs them all. The VDB files: export_vdb_test.cpp.
#include "export_fixture.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#ifdef METARIVER_HAVE_ASSIMP
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/version.h>
#include "require.h"
#endif

namespace mr {
namespace {

using test::ExportFixture;

TEST(ExportFormats, ListsParseInOrderAndBadNamesAreOneLineNamingTheOption) {
    auto one = parse_export_formats("ply");
    ASSERT_TRUE(one.ok());
    EXPECT_EQ(one.value(), std::vector<ExportFormat>{ExportFormat::Ply});
    auto all = parse_export_formats("vdb,obj,glb,ply");
    ASSERT_TRUE(all.ok());
    EXPECT_EQ(all.value(), (std::vector<ExportFormat>{ExportFormat::Vdb, ExportFormat::Obj, ExportFormat::Glb,
                                                      ExportFormat::Ply}));
    for (const char* bad : {"", "stl", "obj,", "obj,,ply", "OBJ", "obj ply", "obj,obj"}) {
        auto r = parse_export_formats(bad, "--format");
        ASSERT_FALSE(r.ok()) << bad;
        EXPECT_EQ(r.error().message.rfind("--format: ", 0), 0u) << r.error().message;
        EXPECT_NE(r.error().message.find("obj, ply, glb, vdb"), std::string::npos) << r.error().message;
        EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
    }
}

TEST(ExportParticles, GatherTakesTheActiveOnesWithTheirIdsAndAges) {
    const Particles p = test::sample_particles(50, 40, /*solver_frame=*/100);
    ParticleFrame f;
    gather_particle_frame(p, 100, 0.5, f);
    ASSERT_EQ(f.size(), 40u);
    for (size_t k = 0; k < f.size(); ++k) {
        EXPECT_EQ(f.id[k], p.id[k]);
        EXPECT_EQ(f.position[k], p.position[k]);
        EXPECT_EQ(f.velocity[k], p.velocity[k]);
        EXPECT_FLOAT_EQ(f.age[k], 0.5f * float(100 - p.birth_frame[k]));
    }
}

TEST(ExportPly, HeaderAndBinaryLayoutAreWhatTheHeaderSays) {
    const test::Sphere s = test::sphere_mesh(2.0f, 0.25f);
    const std::string ply = encode_ply_mesh(mesh_view(s.mesh), "sphere");
    const size_t end = ply.find("end_header\n");
    ASSERT_NE(end, std::string::npos);
    const std::string header = ply.substr(0, end);
    EXPECT_EQ(header.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
    EXPECT_NE(header.find(fmt::format("element vertex {}\n", s.mesh.vertex_count())), std::string::npos);
    EXPECT_NE(header.find(fmt::format("element face {}\n", s.mesh.triangle_count())), std::string::npos);
    // 6 floats per vertex, then 1 + 3 * 4 bytes per face: nothing more, nothing less.
    EXPECT_EQ(ply.size() - end - 11, s.mesh.vertex_count() * 24 + s.mesh.triangle_count() * 13);
}

TEST(ExportPly, FoamRecordsAreWhatTheHeaderSaysAndReadBackExactly) {
    DiffuseParticles d;
    const Vec3 pos[3] = {Vec3(1.5f, 2.25f, -3.0f), Vec3(0.0f, 7.0f, 9.5f), Vec3(-4.0f, 0.125f, 2.0f)};
    const Vec3 vel[3] = {Vec3(2.0f, -1.0f, 0.5f), Vec3(0.25f, 0.0f, -0.75f), Vec3(0.0f, 3.0f, 0.0f)};
    const DiffuseKind kind[3] = {DiffuseKind::Spray, DiffuseKind::Foam, DiffuseKind::Bubble};
    const float life[3] = {0.5f, 1.75f, 2.25f};
    for (int i = 0; i < 3; ++i) {
        d.position.push_back(pos[i]);
        d.velocity.push_back(vel[i]);
        d.kind.push_back(static_cast<uint8_t>(kind[i]));
        d.life.push_back(life[i]);
        d.neighbours.push_back(0);
        d.fluid_velocity.push_back(Vec3(0.0f));
    }
    const std::string ply = encode_ply_foam(d, "foam test");
    const size_t end = ply.find("end_header\n");
    ASSERT_NE(end, std::string::npos);
    const std::string header = ply.substr(0, end);
    EXPECT_EQ(header.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
    EXPECT_NE(header.find("element vertex 3\n"), std::string::npos);
    EXPECT_NE(header.find("property float vz\nproperty uchar kind\nproperty float life\n"), std::string::npos);
    // 6 floats, 1 byte, 1 float per particle: 29 bytes, nothing more.
    ASSERT_EQ(ply.size() - end - 11, 3u * 29u);
    const char* rec = ply.data() + end + 11;
    for (int i = 0; i < 3; ++i, rec += 29) {
        float f[6];
        std::memcpy(f, rec, sizeof f);
        EXPECT_EQ(Vec3(f[0], f[1], f[2]), pos[i]);
        EXPECT_EQ(Vec3(f[3], f[4], f[5]), vel[i]);
        EXPECT_EQ(static_cast<uint8_t>(rec[24]), static_cast<uint8_t>(kind[i]));
        float l = 0.0f;
        std::memcpy(&l, rec + 25, sizeof l);
        EXPECT_EQ(l, life[i]);
    }
    EXPECT_EQ(encode_ply_foam(DiffuseParticles{}, "none").find("element vertex 0\n") != std::string::npos, true);
}

/// The three things every export writes: a closed water surface, the terrain, particles.
struct Samples {
    test::Sphere water = test::sphere_mesh(2.0f, 0.25f);
    Terrain terrain = test::small_terrain();
    TerrainAttributes attributes = terrain_attributes(terrain);
    ParticleFrame particles;
    std::vector<BodyState> bodies;  ///< a turned body with the sphere as its mesh, one without a mesh
    Samples() {
        gather_particle_frame(test::sample_particles(50, 40, 10), 10, 1.0 / 60.0, particles);
        auto m = std::make_shared<BodyMesh>();
        for (const Vec3& p : water.mesh.positions) m->positions.push_back(p - water.center);  // its own frame
        m->normals = water.mesh.normals;
        m->indices = water.mesh.indices;
        bodies.resize(2);
        bodies[0] = {.id = 4, .shape = BodyShape::ConvexMesh, .position = Vec3(10.0f, 2.0f, -3.0f),
                     .orientation = glm::angleAxis(0.5f, glm::normalize(Vec3(1.0f, 2.0f, 0.5f))), .mesh = m};
        bodies[1] = {.id = 9, .shape = BodyShape::Box, .position = Vec3(1.0f, 0.5f, 2.0f)};
    }
    MeshView water_view() const { return mesh_view(water.mesh); }
    MeshView terrain_mesh() const { return terrain_view(terrain, attributes); }
};

#ifdef METARIVER_HAVE_ASSIMP

std::string assimp_version() {
    return fmt::format("{}.{}.{}", aiGetVersionMajor(), aiGetVersionMinor(), aiGetVersionPatch());
}

/// The mesh's triangles as position triples, as assimp gives them (it may duplicate
/// vertices per corner; the positions are what must match).
std::vector<std::array<Vec3, 3>> corners(const aiMesh& m) {
    std::vector<std::array<Vec3, 3>> t;
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
        const aiFace& face = m.mFaces[f];
        if (face.mNumIndices != 3) continue;
        std::array<Vec3, 3> c;
        for (int k = 0; k < 3; ++k) {
            const aiVector3D& v = m.mVertices[face.mIndices[k]];
            c[size_t(k)] = Vec3(v.x, v.y, v.z);
        }
        t.push_back(c);
    }
    return t;
}

/// Every triangle read equals the one written, in order, within `tol` metres.
void expect_same_triangles(const aiMesh& read, const SurfaceMesh& written, float tol) {
    const auto got = corners(read);
    ASSERT_EQ(got.size(), written.triangle_count());
    for (size_t t = 0; t < got.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            const Vec3 want = written.positions[written.indices[3 * t + size_t(k)]];
            ASSERT_LE(glm::length(got[t][size_t(k)] - want), tol) << "triangle " << t << " corner " << k;
        }
}

/// What a file read by assimp must hold: one mesh with these counts (vertices 0: any,
/// OBJ corners are not shared), normals / texture coordinates when asked, and, given
/// `triangles`, the same triangles in the same order within `tol` metres.
struct Expected {
    size_t vertices = 0;
    size_t faces = 0;
    bool normals = false;
    bool uvs = false;
    bool points = false;
    const SurfaceMesh* triangles = nullptr;
    float tol = 0.0f;
};

void expect_read(const std::filesystem::path& file, const Expected& want) {
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(file.string(), 0);
    ASSERT_NE(scene, nullptr) << file << ": " << importer.GetErrorString() << " (assimp " << assimp_version() << ")";
    ASSERT_EQ(scene->mNumMeshes, 1u) << file;
    const aiMesh& m = *scene->mMeshes[0];
    if (want.vertices) {
        EXPECT_EQ(m.mNumVertices, want.vertices) << file;
    }
    EXPECT_EQ(m.mNumFaces, want.faces) << file;
    EXPECT_TRUE(!want.normals || m.HasNormals()) << file << ": normals";
    EXPECT_TRUE(!want.uvs || m.HasTextureCoords(0)) << file << ": texture coordinates";
    EXPECT_TRUE(!want.points || m.mPrimitiveTypes == unsigned(aiPrimitiveType_POINT)) << file << ": points";
    if (want.triangles) expect_same_triangles(m, *want.triangles, want.tol);
}

/// The particle file's positions as assimp reads them, in order.
std::vector<Vec3> read_points(const std::filesystem::path& file) {
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(file.string(), 0);
    std::vector<Vec3> out;
    if (!scene || scene->mNumMeshes != 1) return out;
    for (unsigned v = 0; v < scene->mMeshes[0]->mNumVertices; ++v) {
        const aiVector3D& q = scene->mMeshes[0]->mVertices[v];
        out.emplace_back(q.x, q.y, q.z);
    }
    return out;
}

class ExportAssimp : public ExportFixture {};

TEST_F(ExportAssimp, ReadsTheObjWaterTerrainAndParticlesWithTheCountsWritten) {
    const Samples s;
    const size_t triangles = s.water.mesh.triangle_count(), points = s.particles.size();
    // "%.6g" text: 6 significant digits of coordinates below 10 m.
    expect_read(put("water_00000.obj", encode_obj_mesh(s.water_view(), "sphere")),
                {.faces = triangles, .normals = true, .triangles = &s.water.mesh, .tol = 1e-4f});
    expect_read(put("terrain.obj", encode_obj_mesh(s.terrain_mesh(), "terrain")),
                {.faces = s.terrain.triangle_count(), .normals = true, .uvs = true});
    expect_read(put("particles_00000.obj", encode_obj_points(s.particles, "points")),
                {.vertices = points, .faces = points, .points = true});
}

TEST_F(ExportAssimp, ReadsThePlyWaterTerrainAndParticlesWithTheCountsWritten) {
    const Samples s;
    // Binary floats: exact.
    expect_read(put("water_00000.ply", encode_ply_mesh(s.water_view(), "sphere")),
                {.vertices = s.water.mesh.vertex_count(), .faces = s.water.mesh.triangle_count(), .normals = true,
                 .triangles = &s.water.mesh});
    expect_read(put("terrain.ply", encode_ply_mesh(s.terrain_mesh(), "terrain")),
                {.vertices = s.terrain.vertices().size(), .faces = s.terrain.triangle_count(), .normals = true,
                 .uvs = true});
    // The velocity, id and age columns are skipped right when the positions come out equal.
    EXPECT_EQ(read_points(put("particles_00000.ply", encode_ply_points(s.particles, "points"))), s.particles.position);
}

TEST_F(ExportAssimp, ReadsTheGlbWaterTerrainAndParticlesWithTheCountsWritten) {
    const Samples s;
    expect_read(put("water_00000.glb", encode_glb_mesh(s.water_view(), "water", true).value()),
                {.vertices = s.water.mesh.vertex_count(), .faces = s.water.mesh.triangle_count(), .normals = true,
                 .triangles = &s.water.mesh});
    expect_read(put("terrain.glb", encode_glb_mesh(s.terrain_mesh(), "terrain", false).value()),
                {.vertices = s.terrain.vertices().size(), .faces = s.terrain.triangle_count(), .normals = true,
                 .uvs = true});
    const auto points = put("particles_00000.glb", encode_glb_points(s.particles, "particles").value());
    expect_read(points, {.vertices = s.particles.size(), .faces = s.particles.size(), .points = true});
    EXPECT_EQ(read_points(points), s.particles.position);
}

TEST_F(ExportAssimp, ReadsTheGlbBodiesAsNodesWithTheirTransformsAndMeshes) {
    const Samples s;
    const auto file = put("bodies_00000.glb", encode_glb_bodies(s.bodies).value());
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(file.string(), 0);
    ASSERT_NE(scene, nullptr) << importer.GetErrorString();
    ASSERT_EQ(scene->mNumMeshes, 1u) << "the body without a mesh is a node without one";
    EXPECT_EQ(scene->mMeshes[0]->mNumVertices, s.water.mesh.vertex_count());
    EXPECT_EQ(scene->mMeshes[0]->mNumFaces, s.water.mesh.triangle_count());
    for (const BodyState& b : s.bodies) {
        const aiNode* node = scene->mRootNode->FindNode(fmt::format("body_{}", b.id).c_str());
        ASSERT_NE(node, nullptr) << b.id;
        EXPECT_EQ(node->mNumMeshes, b.mesh ? 1u : 0u);
        aiVector3D scaling, position;
        aiQuaternion rotation;
        node->mTransformation.Decompose(scaling, rotation, position);
        EXPECT_NEAR(position.x, b.position.x, 1e-5f);
        EXPECT_NEAR(position.y, b.position.y, 1e-5f);
        EXPECT_NEAR(position.z, b.position.z, 1e-5f);
        EXPECT_NEAR(std::abs(rotation.w * b.orientation.w + rotation.x * b.orientation.x + rotation.y * b.orientation.y +
                             rotation.z * b.orientation.z),
                    1.0f, 1e-5f)
            << "the same rotation";
        EXPECT_NEAR(scaling.x, 1.0f, 1e-5f);
    }
}

#else

TEST(ExportAssimp, ReadsTheExportedFiles) {
    MR_SKIP_OR_FAIL("assimp is not installed (apt-get install libassimp-dev, then reconfigure): the OBJ, PLY and glb "
                    "files are not read back by assimp");
}

#endif

class ExportGltfValidator : public ExportFixture {};

TEST_F(ExportGltfValidator, KhronosValidatorFindsNoErrorsInWaterTerrainParticlesBodiesAndEmptyFrames) {
    const std::string node = test::find_program("node");
    const std::filesystem::path modules = std::filesystem::path(METARIVER_SOURCE_DIR) / "build/npm/node_modules";
    if (node.empty()) MR_SKIP_OR_FAIL("node is not installed (apt-get install nodejs npm): glb files not validated");
    if (!std::filesystem::exists(modules / "gltf-validator/package.json"))
        MR_SKIP_OR_FAIL("gltf-validator is not installed in " << modules
                        << " (scripts/install-deps.sh: npm install --prefix build/npm gltf-validator)");

    const Samples s;
    std::vector<std::filesystem::path> files{
        put("water_00000.glb", encode_glb_mesh(s.water_view(), "water", true).value()),
        put("terrain.glb", encode_glb_mesh(s.terrain_mesh(), "terrain", false).value()),
        put("particles_00000.glb", encode_glb_points(s.particles, "particles").value()),
        put("water_00001.glb", encode_glb_mesh(MeshView{}, "water", true).value()),
        put("particles_00001.glb", encode_glb_points(ParticleFrame{}, "particles").value()),
        put("bodies_00000.glb", encode_glb_bodies(s.bodies).value()),
        put("bodies_00001.glb", encode_glb_bodies({}).value())};
    std::string cmd = "NODE_PATH=" + modules.string() + " " + node + " " + METARIVER_SOURCE_DIR +
                      "/scripts/gltf_validate.cjs";
    for (const auto& file : files) cmd += " " + file.string();
    const test::CliResult r = test::run_shell(cmd, dir_);
    std::istringstream lines(r.out);
    std::string line;
    size_t reports = 0;
    while (std::getline(lines, line)) {
        const auto j = nlohmann::json::parse(line);
        ++reports;
        EXPECT_EQ(j["errors"].get<int>(), 0) << line;
        EXPECT_EQ(j["warnings"].get<int>(), 0) << line;
        if (reports == 1) std::printf("gltf-validator %s\n", j["validator"].get<std::string>().c_str());
    }
    EXPECT_EQ(reports, files.size()) << r.out << r.err;
    EXPECT_EQ(r.code, 0) << r.err;
}

}  // namespace
}  // namespace mr
