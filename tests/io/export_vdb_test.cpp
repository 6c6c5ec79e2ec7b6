// The VDB export read back by OpenVDB's own reader (openvdb::io::File) and by its
// vdb_print program (libopenvdb-tools; the test skips without it): grid names, class,
// voxel size, active voxel and point counts, the level set's zero crossing on the mesh,
// and the point attributes by id. The one test file that includes OpenVDB.
#include "export_fixture.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/points/PointAttribute.h>
#include <openvdb/points/PointCount.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/tools/Interpolation.h>

#include <array>
#include <cmath>
#include <map>
#include <regex>
#include <set>
#include "require.h"

namespace mr {
namespace {

class ExportVdb : public test::ExportFixture {
protected:
    static void SetUpTestSuite() { openvdb::initialize(); }

    /// Every grid of the file, read with openvdb::io::File.
    static openvdb::GridPtrVecPtr read_grids(const std::filesystem::path& path) {
        openvdb::io::File file(path.string());
        file.open();
        auto grids = file.getGrids();
        file.close();
        return grids;
    }
};

TEST_F(ExportVdb, OpenVdbReadsALevelSetWhoseZeroCrossingIsTheMesh) {
    const float voxel = 0.1f;
    const test::Sphere s = test::sphere_mesh(1.5f, 0.1f);
    VdbStats stats;
    auto bytes = encode_vdb_level_set(mesh_view(s.mesh), voxel, &stats);
    ASSERT_TRUE(bytes.ok()) << bytes.error().message;
    const auto path = put("water_00000.vdb", bytes.value());

    auto grids = read_grids(path);
    ASSERT_EQ(grids->size(), 1u);
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>((*grids)[0]);
    ASSERT_TRUE(grid);
    EXPECT_EQ(grid->getName(), "surface");
    EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
    EXPECT_NEAR(grid->voxelSize()[0], voxel, 1e-6);
    EXPECT_EQ(grid->activeVoxelCount(), stats.active_voxels);
    // A band of 2 x 3 voxels around a sphere of area 4 pi r^2: about 6 r^2 4 pi / voxel^2
    // voxels (28 000); the band's shell is not exact on a lattice, so within a third.
    const double band = 6.0 * 4.0 * 3.14159265 * 1.5 * 1.5 / (voxel * voxel);
    EXPECT_GT(double(stats.active_voxels), band * 0.67);
    EXPECT_LT(double(stats.active_voxels), band * 1.33);

    // The distance is 0 on the mesh: trilinear samples at the vertices are within half a
    // voxel of it (the marching-cubes facets cut the sphere's chords, the field is exact
    // to the mesh, and trilinear interpolation of a distance errs by less than a voxel /
    // 2 across a voxel).
    openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(*grid);
    float worst = 0.0f;
    for (const Vec3& v : s.mesh.positions) worst = std::max(worst, std::abs(float(sampler.wsSample({v.x, v.y, v.z}))));
    EXPECT_LT(worst, 0.5f * voxel);
    // Negative inside, positive outside (the band's background beyond it).
    EXPECT_LT(sampler.wsSample({s.center.x, s.center.y, s.center.z}), 0.0);
    const Vec3 outside = s.center + Vec3(s.radius + 2.0f, 0.0f, 0.0f);
    EXPECT_GT(sampler.wsSample({outside.x, outside.y, outside.z}), 0.0);
    // 0.5 voxel outside the surface along a normal: +0.05 m within the facet error.
    const Vec3 near = s.center + Vec3(0.0f, s.radius + 0.5f * voxel, 0.0f);
    EXPECT_NEAR(sampler.wsSample({near.x, near.y, near.z}), 0.5 * voxel, 0.3 * voxel);
}

TEST_F(ExportVdb, OpenVdbReadsThePointsWithVelocityIdAndAge) {
    const Particles p = test::sample_particles(300, 257, 40);
    ParticleFrame f;
    gather_particle_frame(p, 40, 0.25, f);
    VdbStats stats;
    auto bytes = encode_vdb_points(f, 0.5f, &stats);
    ASSERT_TRUE(bytes.ok()) << bytes.error().message;
    EXPECT_EQ(stats.points, 257u);
    const auto path = put("particles_00000.vdb", bytes.value());

    auto grids = read_grids(path);
    ASSERT_EQ(grids->size(), 1u);
    auto grid = openvdb::gridPtrCast<openvdb::points::PointDataGrid>((*grids)[0]);
    ASSERT_TRUE(grid);
    EXPECT_EQ(grid->getName(), "points");
    EXPECT_NEAR(grid->voxelSize()[0], 0.5, 1e-9);
    EXPECT_EQ(openvdb::points::pointCount(grid->tree()), 257u);

    std::map<int32_t, size_t> by_id;  // id -> index in the frame
    for (size_t k = 0; k < f.size(); ++k) by_id[static_cast<int32_t>(f.id[k])] = k;
    size_t seen = 0;
    for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf) {
        const auto& set = leaf->attributeSet();
        ASSERT_NE(set.find("v"), openvdb::points::AttributeSet::INVALID_POS);
        openvdb::points::AttributeHandle<openvdb::Vec3f> pos(leaf->constAttributeArray("P"));
        openvdb::points::AttributeHandle<openvdb::Vec3f> vel(leaf->constAttributeArray("v"));
        openvdb::points::AttributeHandle<int32_t> id(leaf->constAttributeArray("id"));
        openvdb::points::AttributeHandle<float> age(leaf->constAttributeArray("age"));
        for (auto idx = leaf->beginIndexOn(); idx; ++idx) {
            const auto it = by_id.find(id.get(*idx));
            ASSERT_NE(it, by_id.end()) << "unknown id " << id.get(*idx);
            const size_t k = it->second;
            // P is voxel-local (index space relative to the voxel centre).
            const openvdb::Vec3d world = grid->transform().indexToWorld(pos.get(*idx) + idx.getCoord().asVec3d());
            // Float positions stored relative to the voxel: a rounding of 1e-6 m.
            EXPECT_NEAR(world.x(), f.position[k].x, 1e-5);
            EXPECT_NEAR(world.y(), f.position[k].y, 1e-5);
            EXPECT_NEAR(world.z(), f.position[k].z, 1e-5);
            EXPECT_EQ(vel.get(*idx), openvdb::Vec3f(f.velocity[k].x, f.velocity[k].y, f.velocity[k].z));
            EXPECT_EQ(age.get(*idx), f.age[k]);
            ++seen;
        }
    }
    EXPECT_EQ(seen, 257u);
}

TEST_F(ExportVdb, EmptyFramesAreValidFilesWithNoVoxelsOrPoints) {
    VdbStats stats{.active_voxels = 99, .points = 99};
    auto ls = encode_vdb_level_set(MeshView{}, 0.25f, &stats);
    ASSERT_TRUE(ls.ok());
    auto pts = encode_vdb_points(ParticleFrame{}, 0.25f, &stats);
    ASSERT_TRUE(pts.ok());
    EXPECT_EQ(stats.active_voxels, 0u);
    EXPECT_EQ(stats.points, 0u);
    auto a = read_grids(put("water.vdb", ls.value()));
    auto b = read_grids(put("points.vdb", pts.value()));
    ASSERT_EQ(a->size(), 1u);
    ASSERT_EQ(b->size(), 1u);
    EXPECT_EQ((*a)[0]->activeVoxelCount(), 0u);
    EXPECT_FALSE(encode_vdb_level_set(MeshView{}, 0.0f).ok()) << "a zero voxel is refused";
}

TEST_F(ExportVdb, VdbPrintReportsTheVoxelSizeAndCountsWritten) {
    const std::string vdb_print = test::find_program("vdb_print");
    if (vdb_print.empty())
        MR_SKIP_OR_FAIL("vdb_print is not installed (apt-get install libopenvdb-tools): VDB files not read by it");
    const test::Sphere s = test::sphere_mesh(1.0f, 0.1f);
    VdbStats ls, pts;
    const auto water = put("water_00000.vdb", encode_vdb_level_set(mesh_view(s.mesh), 0.125f, &ls).value());
    const Particles p = test::sample_particles(100, 64, 10);
    ParticleFrame f;
    gather_particle_frame(p, 10, 0.1, f);
    const auto points = put("particles_00000.vdb", encode_vdb_points(f, 0.5f, &pts).value());

    const test::CliResult r = test::run_shell(vdb_print + " -l " + water.string() + " " + points.string(), dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    const test::CliResult v = test::run_shell(vdb_print + " -version", dir_);
    std::printf("%s", v.out.c_str());
    // vdb_print -l prints one block per file: "Name: ...", the tree type, "Number of active
    // voxels: 5,040", "class: level set" (metadata), "voxel size: 0.125".
    const size_t split = r.out.find(points.string());
    ASSERT_NE(split, std::string::npos) << r.out;
    const std::string wb = r.out.substr(0, split), pb = r.out.substr(split);
    const auto number = [](const std::string& block, const char* pattern) -> double {
        std::smatch m;
        if (!std::regex_search(block, m, std::regex(pattern))) return -1.0;
        std::string d = m[1].str();
        d.erase(std::remove(d.begin(), d.end(), ','), d.end());
        return std::stod(d);
    };
    EXPECT_NE(wb.find("Name: surface"), std::string::npos) << wb;
    EXPECT_NE(wb.find("class: level set"), std::string::npos) << wb;
    EXPECT_EQ(number(wb, R"(voxel size:\s*([0-9.eE+-]+))"), 0.125) << wb;
    EXPECT_EQ(number(wb, R"(Number of active voxels:\s*([0-9,]+))"), double(ls.active_voxels)) << wb;
    EXPECT_NE(pb.find("Name: points"), std::string::npos) << pb;
    EXPECT_NE(pb.find("Type: Tree_ptdataidx32"), std::string::npos) << "a VDB points tree: " << pb;
    EXPECT_EQ(number(pb, R"(voxel size:\s*([0-9.eE+-]+))"), 0.5) << pb;
    // A points grid's active voxels are the voxels holding points: count them here from
    // the positions (voxel centres at integer multiples of the voxel size).
    std::set<std::array<long, 3>> voxels;
    for (const Vec3& q : f.position)
        voxels.insert({std::lround(q.x / 0.5f), std::lround(q.y / 0.5f), std::lround(q.z / 0.5f)});
    EXPECT_EQ(number(pb, R"(Number of active voxels:\s*([0-9,]+))"), double(voxels.size())) << pb;
}

}  // namespace
}  // namespace mr
