// Export, the light formats: format names, the particle and terrain views every
// encoder reads, and the OBJ (text) and PLY (binary little-endian) encoders.
// PLY: Greg Turk's format as http://paulbourke.net/dataformats/ply/ describes it.
#include <metariver/export.h>
#include <metariver/io.h>

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cstring>

namespace mr {

static_assert(std::endian::native == std::endian::little, "the PLY and glb encoders copy little-endian memory as is");
static_assert(sizeof(Vec3) == 3 * sizeof(float), "Vec3 is three packed floats");

std::string_view to_string(ExportFormat f) {
    switch (f) {
        case ExportFormat::Obj: return "obj";
        case ExportFormat::Ply: return "ply";
        case ExportFormat::Glb: return "glb";
        case ExportFormat::Vdb: return "vdb";
        case ExportFormat::Npy: return "npy";
    }
    return "?";
}

Result<std::vector<ExportFormat>> parse_export_formats(std::string_view list, std::string_view option) {
    const auto allowed = [&] {
        std::string a;
        for (ExportFormat f : kExportFormats) a += (a.empty() ? "" : ", ") + std::string(to_string(f));
        return a;
    };
    std::vector<ExportFormat> out;
    size_t start = 0;
    while (true) {
        const size_t end = std::min(list.find(',', start), list.size());
        const std::string_view name = list.substr(start, end - start);
        bool found = false;
        for (ExportFormat f : kExportFormats) {
            if (name != to_string(f)) continue;
            if (std::find(out.begin(), out.end(), f) != out.end())
                return Error{fmt::format("{}: '{}' is listed twice (allowed: {}; several separated by commas)", option,
                                         name, allowed())};
            out.push_back(f);
            found = true;
        }
        if (!found)
            return Error{fmt::format("{}: unknown format '{}' (allowed: {}; several separated by commas, e.g. ply,vdb)",
                                     option, name, allowed())};
        if (end == list.size()) break;
        start = end + 1;
    }
    return out;
}

void gather_particle_frame(const Particles& p, uint64_t solver_frame, double frame_dt, ParticleFrame& out) {
    out.position.clear();
    out.velocity.clear();
    out.id.clear();
    out.age.clear();
    for (size_t i = 0; i < p.size(); ++i) {
        if (!p.active[i]) continue;
        out.position.push_back(p.position[i]);
        out.velocity.push_back(p.velocity[i]);
        out.id.push_back(p.id[i]);
        const double frames = static_cast<double>(solver_frame) - static_cast<double>(p.birth_frame[i]);
        out.age.push_back(static_cast<float>(std::max(frames, 0.0) * frame_dt));
    }
}

MeshView mesh_view(const SurfaceMesh& m) {
    return MeshView{.positions = m.positions, .normals = m.normals, .uvs = {}, .indices = m.indices};
}

TerrainAttributes terrain_attributes(const Terrain& terrain) {
    TerrainAttributes a;
    const std::span<const Vec3> v = terrain.vertices();
    a.normals.reserve(v.size());
    a.uvs.reserve(v.size());
    const int w = terrain.columns(), h = terrain.rows();
    for (size_t c = 0; c < v.size(); ++c) {
        a.normals.push_back(terrain.normal_bilinear(v[c].x, v[c].z));
        // Vertex c = i*W + j sits on image row H-1-i (docs/architecture.md).
        const int i = static_cast<int>(c / static_cast<size_t>(w)), j = static_cast<int>(c % static_cast<size_t>(w));
        a.uvs.emplace_back(w > 1 ? float(j) / float(w - 1) : 0.0f, h > 1 ? float(h - 1 - i) / float(h - 1) : 0.0f);
    }
    return a;
}

MeshView terrain_view(const Terrain& terrain, const TerrainAttributes& a) {
    return MeshView{.positions = terrain.vertices(), .normals = a.normals, .uvs = a.uvs, .indices = terrain.indices()};
}

std::string encode_obj_mesh(const MeshView& m, std::string_view comment) {
    return obj_text(m.positions, m.normals, m.indices, comment, m.uvs);
}

std::string encode_obj_points(const ParticleFrame& p, std::string_view comment) {
    fmt::memory_buffer b;
    b.reserve(p.size() * 48 + 128);
    fmt::format_to(std::back_inserter(b),
                   "# {}\n# {} points (positions only: velocity, id and age are in the ply, glb and vdb exports)\n",
                   comment, p.size());
    for (const Vec3& q : p.position) fmt::format_to(std::back_inserter(b), "v {:.6g} {:.6g} {:.6g}\n", q.x, q.y, q.z);
    for (size_t k = 0; k < p.size(); ++k) fmt::format_to(std::back_inserter(b), "p {}\n", k + 1);
    return fmt::to_string(b);
}

namespace {

template <class T>
void put(std::string& out, const T& value) {
    const size_t at = out.size();
    out.resize(at + sizeof(T));
    std::memcpy(out.data() + at, &value, sizeof(T));
}

/// One comment line: PLY comments end at the newline.
std::string ply_comment(std::string_view comment) {
    std::string c(comment);
    for (char& ch : c)
        if (ch == '\n' || ch == '\r') ch = ' ';
    return c;
}

}  // namespace

std::string encode_ply_mesh(const MeshView& m, std::string_view comment) {
    const bool normals = m.normals.size() == m.positions.size() && !m.positions.empty();
    const bool uvs = m.uvs.size() == m.positions.size() && !m.positions.empty();
    std::string out = fmt::format("ply\nformat binary_little_endian 1.0\ncomment {}\nelement vertex {}\n"
                                  "property float x\nproperty float y\nproperty float z\n",
                                  ply_comment(comment), m.vertex_count());
    if (normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
    if (uvs) out += "property float s\nproperty float t\n";
    out += fmt::format("element face {}\nproperty list uchar uint vertex_indices\nend_header\n", m.triangle_count());
    const size_t vertex_bytes = sizeof(float) * (3 + (normals ? 3 : 0) + (uvs ? 2 : 0));
    out.reserve(out.size() + m.vertex_count() * vertex_bytes + m.triangle_count() * 13);
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        put(out, m.positions[v]);
        if (normals) put(out, m.normals[v]);
        // PLY's t runs up the image (Blender and Houdini read it so), the view's v down.
        if (uvs) put(out, glm::vec2(m.uvs[v].x, 1.0f - m.uvs[v].y));
    }
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        put(out, uint8_t{3});
        for (int k = 0; k < 3; ++k) put(out, m.indices[3 * t + static_cast<size_t>(k)]);
    }
    return out;
}

std::string encode_ply_points(const ParticleFrame& p, std::string_view comment) {
    std::string out = fmt::format("ply\nformat binary_little_endian 1.0\ncomment {}\n"
                                  "comment units: metres, metres per second, seconds; y up\nelement vertex {}\n"
                                  "property float x\nproperty float y\nproperty float z\n"
                                  "property float vx\nproperty float vy\nproperty float vz\n"
                                  "property uint id\nproperty float age\nend_header\n",
                                  ply_comment(comment), p.size());
    out.reserve(out.size() + p.size() * 32);
    for (size_t k = 0; k < p.size(); ++k) {
        put(out, p.position[k]);
        put(out, p.velocity[k]);
        put(out, p.id[k]);
        put(out, p.age[k]);
    }
    return out;
}

std::string encode_ply_foam(const DiffuseParticles& d, std::string_view comment) {
    std::string out = fmt::format("ply\nformat binary_little_endian 1.0\ncomment {}\n"
                                  "comment units: metres, metres per second, seconds; y up\n"
                                  "comment kind: 0 spray, 1 foam, 2 bubble; life: seconds left\nelement vertex {}\n"
                                  "property float x\nproperty float y\nproperty float z\n"
                                  "property float vx\nproperty float vy\nproperty float vz\n"
                                  "property uchar kind\nproperty float life\nend_header\n",
                                  ply_comment(comment), d.size());
    out.reserve(out.size() + d.size() * 29);
    for (size_t k = 0; k < d.size(); ++k) {
        put(out, d.position[k]);
        put(out, d.velocity[k]);
        put(out, d.kind[k]);
        put(out, d.life[k]);
    }
    return out;
}

}  // namespace mr
