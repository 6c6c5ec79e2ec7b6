// Export as glTF 2.0 binary (glb) through tinygltf (Debian's libtinygltf-dev). One
// buffer, one tightly packed buffer view per attribute (4-byte aligned), accessors with
// the min/max glTF requires for POSITION, unit normals (the validator checks them).
// Spec: https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html
#include <metariver/export.h>

#include <fmt/format.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>

namespace mr {

namespace {

static_assert(kMaxParticles < (1 << 24), "particle ids go out as floats, exact below 2^24");

class GlbBuilder {
public:
    GlbBuilder() {
        model_.asset.version = "2.0";
        model_.asset.generator = "metariver";
        model_.buffers.emplace_back();
    }

    /// Appends `count` elements of `components` floats each; POSITION-style min/max when asked.
    int add_floats(const float* data, size_t count, int components, int type, bool min_max, int target) {
        const int view = add_view(data, count * size_t(components) * sizeof(float), target);
        tinygltf::Accessor a;
        a.bufferView = view;
        a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        a.count = count;
        a.type = type;
        if (min_max) {
            a.minValues.assign(size_t(components), std::numeric_limits<double>::max());
            a.maxValues.assign(size_t(components), std::numeric_limits<double>::lowest());
            for (size_t e = 0; e < count; ++e)
                for (int c = 0; c < components; ++c) {
                    const double v = data[e * size_t(components) + size_t(c)];
                    a.minValues[size_t(c)] = std::min(a.minValues[size_t(c)], v);
                    a.maxValues[size_t(c)] = std::max(a.maxValues[size_t(c)], v);
                }
        }
        model_.accessors.push_back(std::move(a));
        return int(model_.accessors.size()) - 1;
    }

    int add_indices(std::span<const uint32_t> indices) {
        const int view = add_view(indices.data(), indices.size_bytes(), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
        tinygltf::Accessor a;
        a.bufferView = view;
        a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
        a.count = indices.size();
        a.type = TINYGLTF_TYPE_SCALAR;
        model_.accessors.push_back(std::move(a));
        return int(model_.accessors.size()) - 1;
    }

    int add_material(std::string_view name, std::array<double, 4> color, double roughness, bool blend) {
        tinygltf::Material m;
        m.name = std::string(name);
        m.pbrMetallicRoughness.baseColorFactor = {color[0], color[1], color[2], color[3]};
        m.pbrMetallicRoughness.metallicFactor = 0.0;
        m.pbrMetallicRoughness.roughnessFactor = roughness;
        m.alphaMode = blend ? "BLEND" : "OPAQUE";
        m.doubleSided = false;
        model_.materials.push_back(std::move(m));
        return int(model_.materials.size()) - 1;
    }

    /// A node named `name`, with the primitive when it has any attribute (else empty),
    /// in the file's one scene (made by the first node, named after it); `transform`:
    /// translation x y z then rotation x y z w, or none.
    tinygltf::Node& add_node(std::string_view name, std::optional<tinygltf::Primitive> primitive,
                             const std::optional<std::array<double, 7>>& transform = std::nullopt) {
        tinygltf::Node node;
        node.name = std::string(name);
        if (primitive) {
            tinygltf::Mesh mesh;
            mesh.name = std::string(name);
            mesh.primitives.push_back(std::move(*primitive));
            model_.meshes.push_back(std::move(mesh));
            node.mesh = int(model_.meshes.size()) - 1;
        }
        if (transform) {
            node.translation.assign(transform->begin(), transform->begin() + 3);
            node.rotation.assign(transform->begin() + 3, transform->end());
        }
        model_.nodes.push_back(std::move(node));
        if (model_.scenes.empty()) {
            model_.scenes.emplace_back();
            model_.scenes.back().name = std::string(name);
        }
        model_.scenes.front().nodes.push_back(int(model_.nodes.size()) - 1);
        model_.defaultScene = 0;
        return model_.nodes.back();
    }

    Result<std::string> bytes() {
        if (model_.buffers.front().data.empty()) model_.buffers.clear();  // glTF: a buffer holds >= 1 byte
        tinygltf::TinyGLTF writer;
        std::ostringstream out;
        if (!writer.WriteGltfSceneToStream(&model_, out, /*prettyPrint=*/false, /*writeBinary=*/true) || !out)
            return Error{"glb: tinygltf could not serialise the model"};
        return std::move(out).str();
    }

private:
    int add_view(const void* data, size_t bytes, int target) {
        std::vector<unsigned char>& buf = model_.buffers.front().data;
        const size_t offset = buf.size();  // every view's length is a multiple of 4: offsets stay aligned
        buf.resize(offset + bytes);
        if (bytes) std::memcpy(buf.data() + offset, data, bytes);
        tinygltf::BufferView v;
        v.buffer = 0;
        v.byteOffset = offset;
        v.byteLength = bytes;
        v.target = target;
        model_.bufferViews.push_back(std::move(v));
        return int(model_.bufferViews.size()) - 1;
    }

    tinygltf::Model model_;
};

}  // namespace

namespace {

/// The triangles of `m` with POSITION, unit NORMAL (when given), TEXCOORD_0 (when given)
/// and indices, into `b`.
tinygltf::Primitive mesh_primitive(GlbBuilder& b, const MeshView& m) {
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] = b.add_floats(&m.positions[0].x, m.vertex_count(), 3, TINYGLTF_TYPE_VEC3, true,
                                               TINYGLTF_TARGET_ARRAY_BUFFER);
    if (m.normals.size() == m.positions.size()) {
        // glTF requires unit normals; a zero gradient (flat field) gets straight up.
        std::vector<Vec3> unit(m.normals.begin(), m.normals.end());
        for (Vec3& n : unit) {
            const float len = glm::length(n);
            n = std::isfinite(len) && len > 1e-12f ? n / len : Vec3(0.0f, 1.0f, 0.0f);
        }
        prim.attributes["NORMAL"] =
            b.add_floats(&unit[0].x, unit.size(), 3, TINYGLTF_TYPE_VEC3, false, TINYGLTF_TARGET_ARRAY_BUFFER);
    }
    if (m.uvs.size() == m.positions.size())
        prim.attributes["TEXCOORD_0"] =
            b.add_floats(&m.uvs[0].x, m.uvs.size(), 2, TINYGLTF_TYPE_VEC2, false, TINYGLTF_TARGET_ARRAY_BUFFER);
    prim.indices = b.add_indices(m.indices);
    return prim;
}

}  // namespace

Result<std::string> encode_glb_mesh(const MeshView& m, std::string_view name, bool water) {
    GlbBuilder b;
    if (m.triangle_count() == 0 || m.positions.empty()) {
        b.add_node(name, std::nullopt);
        return b.bytes();
    }
    tinygltf::Primitive prim = mesh_primitive(b, m);
    prim.material = water ? b.add_material("water", {0.10, 0.35, 0.60, 0.70}, 0.05, true)
                          : b.add_material("terrain", {0.42, 0.45, 0.33, 1.0}, 0.9, false);
    b.add_node(name, std::move(prim));
    return b.bytes();
}

Result<std::string> encode_glb_points(const ParticleFrame& p, std::string_view name) {
    GlbBuilder b;
    if (p.size() == 0) {
        b.add_node(name, std::nullopt);
        return b.bytes();
    }
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_POINTS;
    prim.attributes["POSITION"] =
        b.add_floats(&p.position[0].x, p.size(), 3, TINYGLTF_TYPE_VEC3, true, TINYGLTF_TARGET_ARRAY_BUFFER);
    prim.attributes["_VELOCITY"] =
        b.add_floats(&p.velocity[0].x, p.size(), 3, TINYGLTF_TYPE_VEC3, false, TINYGLTF_TARGET_ARRAY_BUFFER);
    std::vector<float> ids(p.id.begin(), p.id.end());
    prim.attributes["_ID"] = b.add_floats(ids.data(), ids.size(), 1, TINYGLTF_TYPE_SCALAR, false, TINYGLTF_TARGET_ARRAY_BUFFER);
    prim.attributes["_AGE"] =
        b.add_floats(p.age.data(), p.age.size(), 1, TINYGLTF_TYPE_SCALAR, false, TINYGLTF_TARGET_ARRAY_BUFFER);
    b.add_node(name, std::move(prim));
    return b.bytes();
}

Result<std::string> encode_glb_bodies(std::span<const BodyState> bodies) {
    GlbBuilder b;
    if (bodies.empty()) {
        b.add_node("bodies", std::nullopt);
        return b.bytes();
    }
    int wood = -1;
    for (const BodyState& s : bodies) {
        const glm::quat q = glm::normalize(s.orientation);
        const std::array<double, 7> t{s.position.x, s.position.y, s.position.z, q.x, q.y, q.z, q.w};
        std::optional<tinygltf::Primitive> prim;
        const BodyMesh* m = s.mesh.get();
        const size_t n = m ? m->positions.size() : 0;
        if (m && n > 0 && !m->indices.empty() && m->indices.size() % 3 == 0 &&
            std::all_of(m->indices.begin(), m->indices.end(), [&](uint32_t i) { return i < n; })) {
            const MeshView view{.positions = m->positions, .normals = m->normals, .indices = m->indices};
            prim = mesh_primitive(b, view);
            if (wood < 0) wood = b.add_material("wood", {0.45, 0.30, 0.16, 1.0}, 0.8, false);
            prim->material = wood;
        }
        b.add_node(fmt::format("body_{}", s.id), std::move(prim), t);
    }
    return b.bytes();
}

}  // namespace mr
