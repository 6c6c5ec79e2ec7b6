// Export as OpenVDB (Debian's libopenvdb-dev). The only translation unit that includes
// OpenVDB: its headers are heavy, so every VDB call of the project lives here.
//
// The water: a narrow-band signed distance field of the closed marching-cubes mesh
// (openvdb::tools::meshToLevelSet; Museth, "VDB: High-resolution sparse volumes with
// dynamic topology", ACM TOG 2013), grid "surface", class level set. The particles: a
// VDB points grid "points" with P (world-space positions, full precision), v, id, age.
// Files are serialised to memory through a seekable archive (the same bytes
// openvdb::io::File writes), then written atomically by write_file_atomic.
#include <metariver/export.h>

#include <fmt/format.h>
#include <openvdb/io/Archive.h>
#include <openvdb/openvdb.h>
#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointCount.h>
#include <openvdb/tools/MeshToVolume.h>

#include <mutex>
#include <sstream>

namespace mr {

namespace {

void init_openvdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

/// Archive::write(std::ostream&, ..., seekable) is protected; io::File only writes to a
/// path. This gives the seekable form (grid offsets, so readers can load one grid
/// without the others) to any stream.
class MemoryArchive : public openvdb::io::Archive {
public:
    std::string bytes(const openvdb::GridCPtrVec& grids) const {
        std::ostringstream out(std::ios::out | std::ios::binary);
        write(out, grids, /*seekable=*/true);
        return std::move(out).str();
    }
};

openvdb::math::Transform::Ptr transform(float voxel_size) {
    return openvdb::math::Transform::createLinearTransform(static_cast<double>(voxel_size));
}

Result<std::string> serialise(const openvdb::GridBase::Ptr& grid, std::string_view what) {
    try {
        grid->insertMeta("creator", openvdb::StringMetadata("metariver"));
        MemoryArchive archive;
        return archive.bytes(openvdb::GridCPtrVec{grid});
    } catch (const std::exception& e) {
        return Error{fmt::format("vdb {}: {}", what, e.what())};
    }
}

}  // namespace

Result<std::string> encode_vdb_level_set(const MeshView& m, float voxel_size, VdbStats* stats) {
    if (!(voxel_size > 0.0f) || voxel_size > 100.0f)
        return Error{fmt::format("vdb: voxel size must be in (0, 100] metres (got {})", voxel_size)};
    init_openvdb();
    try {
        std::vector<openvdb::Vec3s> points(m.vertex_count());
        for (size_t v = 0; v < points.size(); ++v)
            points[v] = openvdb::Vec3s(m.positions[v].x, m.positions[v].y, m.positions[v].z);
        std::vector<openvdb::Vec3I> triangles(m.triangle_count());
        for (size_t t = 0; t < triangles.size(); ++t)
            // OpenVDB's winding is clockwise seen from outside; the sign comes from a flood
            // fill, not the winding, so either order gives the same field.
            triangles[t] = openvdb::Vec3I(m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]);
        openvdb::FloatGrid::Ptr grid;
        if (triangles.empty()) {
            grid = openvdb::createLevelSet<openvdb::FloatGrid>(static_cast<double>(voxel_size), kVdbHalfWidth);
        } else {
            grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform(voxel_size), points, triangles,
                                                                      kVdbHalfWidth);
        }
        grid->setName("surface");
        grid->setGridClass(openvdb::GRID_LEVEL_SET);
        if (stats) stats->active_voxels = grid->activeVoxelCount();
        return serialise(grid, "level set");
    } catch (const std::exception& e) {
        return Error{fmt::format("vdb level set: {}", e.what())};
    }
}

Result<std::string> encode_vdb_points(const ParticleFrame& p, float voxel_size, VdbStats* stats) {
    if (!(voxel_size > 0.0f) || voxel_size > 100.0f)
        return Error{fmt::format("vdb: voxel size must be in (0, 100] metres (got {})", voxel_size)};
    init_openvdb();
    namespace pts = openvdb::points;
    try {
        const size_t n = p.size();
        std::vector<openvdb::Vec3f> position(n), velocity(n);
        std::vector<int32_t> id(n);
        for (size_t k = 0; k < n; ++k) {
            position[k] = openvdb::Vec3f(p.position[k].x, p.position[k].y, p.position[k].z);
            velocity[k] = openvdb::Vec3f(p.velocity[k].x, p.velocity[k].y, p.velocity[k].z);
            id[k] = static_cast<int32_t>(p.id[k]);  // ids < kMaxParticles fit
        }
        const auto xform = transform(voxel_size);
        const pts::PointAttributeVector<openvdb::Vec3f> position_wrapper(position);
        auto index = openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(position_wrapper, *xform);
        pts::PointDataGrid::Ptr grid =
            pts::createPointDataGrid<pts::NullCodec, pts::PointDataGrid>(*index, position_wrapper, *xform);
        pts::PointDataTree& tree = grid->tree();
        if (tree.leafCount() > 0) {  // attributes live in the leaves: none without points
            pts::appendAttribute<openvdb::Vec3f>(tree, "v");
            pts::populateAttribute(tree, index->tree(), "v", pts::PointAttributeVector<openvdb::Vec3f>(velocity));
            pts::appendAttribute<int32_t>(tree, "id");
            pts::populateAttribute(tree, index->tree(), "id", pts::PointAttributeVector<int32_t>(id));
            pts::appendAttribute<float>(tree, "age");
            pts::populateAttribute(tree, index->tree(), "age", pts::PointAttributeVector<float>(p.age));
        }
        grid->setName("points");
        if (stats) stats->points = pts::pointCount(tree);
        return serialise(grid, "points");
    } catch (const std::exception& e) {
        return Error{fmt::format("vdb points: {}", e.what())};
    }
}

}  // namespace mr
