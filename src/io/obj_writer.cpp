#include <metariver/export.h>
#include <metariver/io.h>

#include <fmt/format.h>

namespace mr {

std::string obj_text(std::span<const Vec3> positions, std::span<const Vec3> normals,
                     std::span<const uint32_t> indices, std::string_view comment, std::span<const glm::vec2> uvs) {
    const bool with_normals = normals.size() == positions.size();
    const bool with_uvs = !uvs.empty() && uvs.size() == positions.size();
    fmt::memory_buffer b;
    b.reserve(positions.size() * (with_uvs ? 88 : 64) + indices.size() * 12 + 64);
    fmt::format_to(std::back_inserter(b), "# {}\n# {} vertices, {} triangles\n", comment, positions.size(),
                   indices.size() / 3);
    for (const Vec3& p : positions) fmt::format_to(std::back_inserter(b), "v {:.6g} {:.6g} {:.6g}\n", p.x, p.y, p.z);
    if (with_normals)
        for (const Vec3& n : normals) fmt::format_to(std::back_inserter(b), "vn {:.5g} {:.5g} {:.5g}\n", n.x, n.y, n.z);
    if (with_uvs)  // OBJ's v runs up the image, the view's down
        for (const glm::vec2& t : uvs) fmt::format_to(std::back_inserter(b), "vt {:.6g} {:.6g}\n", t.x, 1.0f - t.y);
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        const uint32_t a = indices[t] + 1, c = indices[t + 1] + 1, d = indices[t + 2] + 1;
        if (with_uvs && with_normals)
            fmt::format_to(std::back_inserter(b), "f {0}/{0}/{0} {1}/{1}/{1} {2}/{2}/{2}\n", a, c, d);
        else if (with_uvs)
            fmt::format_to(std::back_inserter(b), "f {0}/{0} {1}/{1} {2}/{2}\n", a, c, d);
        else if (with_normals)
            fmt::format_to(std::back_inserter(b), "f {0}//{0} {1}//{1} {2}//{2}\n", a, c, d);
        else
            fmt::format_to(std::back_inserter(b), "f {} {} {}\n", a, c, d);
    }
    return fmt::to_string(b);
}

Status write_surface_obj(const std::string& path, const SurfaceMesh& mesh, std::string_view comment) {
    return write_file_atomic(path, obj_text(mesh.positions, mesh.normals, mesh.indices, comment));
}

Status write_terrain_obj(const std::string& path, const Terrain& terrain) {
    const TerrainAttributes a = terrain_attributes(terrain);
    return write_file_atomic(path, obj_text(terrain.vertices(), a.normals, terrain.indices(), "metariver terrain"));
}

}  // namespace mr
