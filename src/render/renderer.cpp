// The OpenGL 4.5 renderer: sky, terrain, bodies, water surface, debug particles and tree boxes.
//
// A frame, in passes:
//   1. scene framebuffer (colour + depth textures): sky, terrain with skirts, bodies, debug
//      particles and boxes;
//   2. final framebuffer: the scene's colour and depth are blitted in, then the water
//      is drawn depth-tested against the terrain, sampling the scene's colour (what
//      lies behind, refracted) and depth (how much water the view ray crosses);
//   3. the final colour goes to a window (blit) or to memory (glReadPixels).
// The water's vertices carry the fluid's velocity (surface_velocities, each update)
// for the flow detail; its texture is made once (flow_texture.h).
// GL objects are made once (create, set_scene, first use of a size); frames only refill
// buffers (orphaned with glBufferData, grown by 1.5x) and re-specify textures on resize.
#include <metariver/render.h>

#include "body_geometry.h"
#include "flow_texture.h"
#include "gl_objects.h"
#include "gl_shader.h"
#include "terrain_geometry.h"
#include "shaders.h"

#include <epoxy/gl.h>
#include <fmt/format.h>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>

namespace mr::render {

namespace {

/// The std140 block `Frame` of shaders.h, field for field.
struct FrameUniforms {
    glm::mat4 viewproj;
    glm::mat4 inv_viewproj;
    glm::vec4 eye;
    glm::vec4 sun;
    glm::vec4 viewport;
    glm::vec4 water;
    glm::vec4 params;
    glm::vec4 terrain;
    glm::vec4 rect;
    glm::vec4 mode;
};
static_assert(sizeof(FrameUniforms) == 2 * 64 + 8 * 16, "std140 layout of Frame");
static_assert(kFlowDetailMinSpeed == static_cast<float>(MR_FLOW_MIN_SPEED) &&
                  kFlowDetailFullSpeed == static_cast<float>(MR_FLOW_FULL_SPEED),
              "the water shader's flow speeds (shaders.h) are render.h's");

}  // namespace

struct Renderer::Impl {
    RenderStats stats;
    GLuint prog_sky = 0, prog_terrain = 0, prog_water = 0, prog_particles = 0, prog_boxes = 0, prog_foam = 0, prog_bodies = 0;
    GLuint ubo = 0;
    GLuint vao_empty = 0, vao_terrain = 0, vao_water = 0, vao_particles = 0, vao_boxes = 0, vao_foam = 0, vao_bodies = 0;
    GLuint terrain_vbo = 0, terrain_ibo = 0, cube_vbo = 0, box_vbo = 0;
    GLuint terrain_tex = 0, flow_tex = 0;
    DynamicBuffer water_pos, water_normal, water_vel, water_idx, particle_pos, foam_buf, body_vbo, body_ibo;
    Target scene, final;

    size_t terrain_index_count = 0;
    TerrainGeometry geo;      // what terrain_vbo / terrain_ibo hold (bounds, texture rect)
    TreeBoxes tree;             // what box_vbo holds
    std::vector<std::pair<uint32_t, uint32_t>> box_spans;  // update_terrain: the boxes the refit moved
    bool has_texture = false;

    const void* last_owner = nullptr;
    uint64_t last_frame = ~uint64_t{0};
    std::vector<Vec3> scratch_positions;  // reused for the active particles
    std::vector<glm::vec4> scratch_foam;  // reused: diffuse position, kind
    std::vector<Vec3> scratch_velocity;   // reused: the fluid's velocity per water vertex
    std::vector<BodyVertex> scratch_body;       // reused: the bodies' world-space vertices
    std::vector<uint32_t> scratch_body_index;   // and their triangles
    SurfaceVelocityWorkspace flow_ws;

    GLuint create_buffer() {
        GLuint b = 0;
        glCreateBuffers(1, &b);
        ++stats.gl_objects_created;
        return b;
    }
    GLuint create_texture() {
        GLuint t = 0;
        glCreateTextures(GL_TEXTURE_2D, 1, &t);
        glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        ++stats.gl_objects_created;
        return t;
    }
    GLuint create_vao() {
        GLuint v = 0;
        glCreateVertexArrays(1, &v);
        ++stats.gl_objects_created;
        return v;
    }
    void create_target(Target& t) {
        glCreateFramebuffers(1, &t.fbo);
        t.color = create_texture();
        t.depth = create_texture();
        glTextureParameteri(t.depth, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(t.depth, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        ++stats.gl_objects_created;
    }

    Status init() {
        struct P {
            GLuint* out;
            const char* vs;
            const char* fs;
            const char* name;
        };
        const P programs[] = {{&prog_sky, glsl::kSkyVert, glsl::kSkyFrag, "sky"},
                              {&prog_terrain, glsl::kTerrainVert, glsl::kTerrainFrag, "terrain"},
                              {&prog_water, glsl::kWaterVert, glsl::kWaterFrag, "water"},
                              {&prog_particles, glsl::kParticleVert, glsl::kParticleFrag, "particle"},
                              {&prog_boxes, glsl::kBoxVert, glsl::kBoxFrag, "box"},
                              {&prog_foam, glsl::kFoamVert, glsl::kFoamFrag, "foam"},
                              {&prog_bodies, glsl::kTerrainVert, glsl::kBodyFrag, "body"}};
        for (const P& p : programs) {
            auto r = link(p.vs, p.fs, p.name);
            if (!r) return r.error();
            *p.out = r.value();
            ++stats.gl_objects_created;
        }
        ubo = create_buffer();
        glNamedBufferData(ubo, sizeof(FrameUniforms), nullptr, GL_DYNAMIC_DRAW);

        vao_empty = create_vao();

        terrain_vbo = create_buffer();
        terrain_ibo = create_buffer();
        vao_terrain = create_vao();
        glVertexArrayVertexBuffer(vao_terrain, 0, terrain_vbo, 0, sizeof(TerrainVertex));
        glVertexArrayElementBuffer(vao_terrain, terrain_ibo);
        const GLuint offsets[] = {offsetof(TerrainVertex, pos), offsetof(TerrainVertex, normal),
                                  offsetof(TerrainVertex, skirt)};
        const GLint sizes[] = {3, 3, 1};
        for (GLuint a = 0; a < 3; ++a) {
            glEnableVertexArrayAttrib(vao_terrain, a);
            glVertexArrayAttribFormat(vao_terrain, a, sizes[a], GL_FLOAT, GL_FALSE, offsets[a]);
            glVertexArrayAttribBinding(vao_terrain, a, 0);
        }

        water_pos.id = create_buffer();
        water_normal.id = create_buffer();
        water_vel.id = create_buffer();
        water_idx.id = create_buffer();
        vao_water = create_vao();
        glVertexArrayVertexBuffer(vao_water, 0, water_pos.id, 0, sizeof(Vec3));
        glVertexArrayVertexBuffer(vao_water, 1, water_normal.id, 0, sizeof(Vec3));
        glVertexArrayVertexBuffer(vao_water, 2, water_vel.id, 0, sizeof(Vec3));
        glVertexArrayElementBuffer(vao_water, water_idx.id);
        for (GLuint a = 0; a < 3; ++a) {
            glEnableVertexArrayAttrib(vao_water, a);
            glVertexArrayAttribFormat(vao_water, a, 3, GL_FLOAT, GL_FALSE, 0);
            glVertexArrayAttribBinding(vao_water, a, a);
        }

        particle_pos.id = create_buffer();
        vao_particles = create_vao();
        glVertexArrayVertexBuffer(vao_particles, 0, particle_pos.id, 0, sizeof(Vec3));
        glEnableVertexArrayAttrib(vao_particles, 0);
        glVertexArrayAttribFormat(vao_particles, 0, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao_particles, 0, 0);

        foam_buf.id = create_buffer();
        vao_foam = create_vao();
        glVertexArrayVertexBuffer(vao_foam, 0, foam_buf.id, 0, sizeof(glm::vec4));
        glEnableVertexArrayAttrib(vao_foam, 0);
        glVertexArrayAttribFormat(vao_foam, 0, 4, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao_foam, 0, 0);

        body_vbo.id = create_buffer();
        body_ibo.id = create_buffer();
        vao_bodies = create_vao();
        glVertexArrayVertexBuffer(vao_bodies, 0, body_vbo.id, 0, sizeof(BodyVertex));
        glVertexArrayElementBuffer(vao_bodies, body_ibo.id);
        for (GLuint a = 0; a < 2; ++a) {
            glEnableVertexArrayAttrib(vao_bodies, a);
            glVertexArrayAttribFormat(vao_bodies, a, 3, GL_FLOAT, GL_FALSE, a == 0 ? offsetof(BodyVertex, pos)
                                                                                      : offsetof(BodyVertex, normal));
            glVertexArrayAttribBinding(vao_bodies, a, 0);
        }

        // The unit cube's 12 edges as 24 line endpoints.
        std::vector<Vec3> cube;
        for (int axis = 0; axis < 3; ++axis) {
            for (int a = 0; a < 2; ++a) {
                for (int b = 0; b < 2; ++b) {
                    Vec3 p0(0.0f), p1(0.0f);
                    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                    p0[u] = p1[u] = static_cast<float>(a);
                    p0[v] = p1[v] = static_cast<float>(b);
                    p1[axis] = 1.0f;
                    cube.push_back(p0);
                    cube.push_back(p1);
                }
            }
        }
        cube_vbo = create_buffer();
        glNamedBufferData(cube_vbo, static_cast<GLsizeiptr>(cube.size() * sizeof(Vec3)), cube.data(), GL_STATIC_DRAW);
        box_vbo = create_buffer();
        vao_boxes = create_vao();
        glVertexArrayVertexBuffer(vao_boxes, 0, cube_vbo, 0, sizeof(Vec3));
        glVertexArrayVertexBuffer(vao_boxes, 1, box_vbo, 0, sizeof(BoxInstance));
        glVertexArrayBindingDivisor(vao_boxes, 1, 1);
        glEnableVertexArrayAttrib(vao_boxes, 0);
        glVertexArrayAttribFormat(vao_boxes, 0, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao_boxes, 0, 0);
        const GLuint box_offsets[] = {offsetof(BoxInstance, min), offsetof(BoxInstance, max),
                                      offsetof(BoxInstance, depth)};
        for (GLuint a = 1; a < 4; ++a) {
            glEnableVertexArrayAttrib(vao_boxes, a);
            glVertexArrayAttribFormat(vao_boxes, a, a == 3 ? 1 : 3, GL_FLOAT, GL_FALSE, box_offsets[a - 1]);
            glVertexArrayAttribBinding(vao_boxes, a, 1);
        }

        terrain_tex = create_texture();
        glTextureParameteri(terrain_tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);

        // The flow detail's tiling texture (flow_texture.h), made once, mipmapped.
        flow_tex = create_texture();
        glTextureParameteri(flow_tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
        glTextureParameteri(flow_tex, GL_TEXTURE_WRAP_S, GL_REPEAT);
        glTextureParameteri(flow_tex, GL_TEXTURE_WRAP_T, GL_REPEAT);
        const std::vector<uint8_t> flow = make_flow_texture();
        glTextureStorage2D(flow_tex, 9, GL_RGBA8, kFlowTextureSide, kFlowTextureSide);
        glTextureSubImage2D(flow_tex, 0, 0, 0, kFlowTextureSide, kFlowTextureSide, GL_RGBA, GL_UNSIGNED_BYTE, flow.data());
        glGenerateTextureMipmap(flow_tex);
        stats.bytes_uploaded += flow.size();
        create_target(scene);
        create_target(final);
        if (glGetError() != GL_NO_ERROR) return Error{"renderer: OpenGL error while creating objects"};
        return Ok{};
    }

    void upload_terrain(const Terrain& t, const Bvh& bvh, bool paper_rows) {
        build_terrain_geometry(t, paper_rows, geo);
        glNamedBufferData(terrain_vbo, static_cast<GLsizeiptr>(geo.vertices.size() * sizeof(TerrainVertex)),
                          geo.vertices.data(), GL_STATIC_DRAW);
        glNamedBufferData(terrain_ibo, static_cast<GLsizeiptr>(geo.indices.size() * sizeof(uint32_t)), geo.indices.data(),
                          GL_STATIC_DRAW);
        stats.bytes_uploaded += geo.vertices.size() * sizeof(TerrainVertex) + geo.indices.size() * sizeof(uint32_t);
        terrain_index_count = geo.indices.size();
        stats.terrain_triangles = t.triangle_count();
        // Tree boxes grouped by depth, then the leaves, for drawing one level at a time.
        build_tree_boxes(bvh, tree);
        glNamedBufferData(box_vbo, static_cast<GLsizeiptr>(tree.boxes.size() * sizeof(BoxInstance)), tree.boxes.data(),
                          GL_STATIC_DRAW);
        stats.bytes_uploaded += tree.boxes.size() * sizeof(BoxInstance);
        stats.last_terrain_upload_bytes = geo.vertices.size() * sizeof(TerrainVertex) +
                                          geo.indices.size() * sizeof(uint32_t) + tree.boxes.size() * sizeof(BoxInstance);
    }

    /// After a sculpt stroke: the vertex rows around the changed samples, the skirts when
    /// they reach a border, and the spans of each tree level whose boxes the refit moved.
    void update_terrain(const Terrain& t, const Bvh& bvh, bool paper_rows, const TerrainEdit& changed) {
        TerrainEdit rows;
        if (terrain_index_count == 0 || !update_terrain_geometry(t, changed, geo, rows)) {
            upload_terrain(t, bvh, paper_rows);
            return;
        }
        uint64_t bytes = 0;
        const auto send = [&](GLuint buffer, size_t offset, const void* data, size_t size) {
            glNamedBufferSubData(buffer, static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(size), data);
            bytes += size;
        };
        if (!rows.empty()) {
            const size_t n = size_t(rows.j1 - rows.j0 + 1);
            for (int i = rows.i0; i <= rows.i1; ++i) {
                const size_t v = size_t(i) * size_t(geo.columns) + size_t(rows.j0);
                send(terrain_vbo, v * sizeof(TerrainVertex), &geo.vertices[v], n * sizeof(TerrainVertex));
            }
            if (touches_border(geo, rows)) {
                const size_t first = geo.grid_vertices();
                send(terrain_vbo, first * sizeof(TerrainVertex), &geo.vertices[first],
                     (geo.vertices.size() - first) * sizeof(TerrainVertex));
            }
        }
        if (!refit_tree_boxes(bvh, tree, box_spans)) {
            build_tree_boxes(bvh, tree);  // another tree: all of it
            glNamedBufferData(box_vbo, static_cast<GLsizeiptr>(tree.boxes.size() * sizeof(BoxInstance)),
                              tree.boxes.data(), GL_STATIC_DRAW);
            bytes += tree.boxes.size() * sizeof(BoxInstance);
        }
        for (const auto& [lo, hi] : box_spans)
            send(box_vbo, lo * sizeof(BoxInstance), &tree.boxes[lo], (hi - lo) * sizeof(BoxInstance));
        stats.bytes_uploaded += bytes;
        stats.last_terrain_upload_bytes = bytes;
    }

    void upload_dynamic(const SceneView& view) {
        stats.last_upload_bytes = 0;
        const SurfaceMesh& m = *view.surface;
        water_pos.upload(m.positions.data(), m.positions.size() * sizeof(Vec3), stats);
        water_normal.upload(m.normals.data(), m.normals.size() * sizeof(Vec3), stats);
        water_idx.upload(m.indices.data(), m.indices.size() * sizeof(uint32_t), stats);
        stats.water_triangles = m.triangle_count();
        const auto t0 = std::chrono::steady_clock::now();
        // The particles' velocities for the particle surface, the producer's own for the
        // vertices it knows them for (a heightfield's, at the end of the mesh).
        const size_t known = std::min(view.surface_velocity.size(), m.positions.size());
        const size_t from_particles = m.positions.size() - known;
        surface_velocities(std::span<const Vec3>(m.positions).first(from_particles), *view.particles, view.flow_radius,
                           flow_ws, scratch_velocity);
        if (view.surface_grid_velocity.size() == from_particles)  // the grid's share (a joined heightfield's)
            for (size_t i = 0; i < from_particles; ++i) {
                const glm::vec4 g = view.surface_grid_velocity[i];
                scratch_velocity[i] = g.w * Vec3(g) + (1.0f - g.w) * scratch_velocity[i];
            }
        scratch_velocity.insert(scratch_velocity.end(), view.surface_velocity.end() - std::ptrdiff_t(known),
                                view.surface_velocity.end());
        stats.flow_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        water_vel.upload(scratch_velocity.data(), scratch_velocity.size() * sizeof(Vec3), stats);
        view.particles->gather_active_positions(scratch_positions);
        particle_pos.upload(scratch_positions.data(), scratch_positions.size() * sizeof(Vec3), stats);
        stats.particles = scratch_positions.size();
        scratch_foam.clear();
        if (view.foam) {
            const DiffuseParticles& d = *view.foam;
            for (size_t i = 0; i < d.size(); ++i) scratch_foam.emplace_back(d.position[i], float(d.kind[i]));
        }
        foam_buf.upload(scratch_foam.data(), scratch_foam.size() * sizeof(glm::vec4), stats);
        stats.foam_particles = scratch_foam.size();
        build_body_geometry(view.bodies, scratch_body, scratch_body_index);
        body_vbo.upload(scratch_body.data(), scratch_body.size() * sizeof(BodyVertex), stats);
        body_ibo.upload(scratch_body_index.data(), scratch_body_index.size() * sizeof(uint32_t), stats);
        stats.bodies = size_t(std::count_if(view.bodies.begin(), view.bodies.end(), [](const BodyState& b) { return b.mesh != nullptr; }));
        stats.body_triangles = scratch_body_index.size() / 3;
        last_owner = view.owner;
        last_frame = view.frame;
    }
};

Renderer::Renderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Renderer::~Renderer() {
    Impl& r = *impl_;
    const GLuint programs[] = {r.prog_sky,       r.prog_terrain, r.prog_water, r.prog_particles,
                               r.prog_boxes,     r.prog_foam,    r.prog_bodies};
    for (GLuint p : programs) glDeleteProgram(p);
    const GLuint buffers[] = {r.ubo, r.terrain_vbo, r.terrain_ibo, r.cube_vbo, r.box_vbo, r.water_pos.id,
                              r.water_normal.id, r.water_vel.id, r.water_idx.id, r.particle_pos.id, r.foam_buf.id,
                              r.body_vbo.id, r.body_ibo.id};
    glDeleteBuffers(static_cast<GLsizei>(std::size(buffers)), buffers);
    const GLuint vaos[] = {r.vao_empty, r.vao_terrain, r.vao_water, r.vao_particles, r.vao_boxes, r.vao_foam, r.vao_bodies};
    glDeleteVertexArrays(static_cast<GLsizei>(std::size(vaos)), vaos);
    const GLuint textures[] = {r.terrain_tex, r.flow_tex, r.scene.color, r.scene.depth, r.final.color, r.final.depth};
    glDeleteTextures(static_cast<GLsizei>(std::size(textures)), textures);
    const GLuint fbos[] = {r.scene.fbo, r.final.fbo};
    glDeleteFramebuffers(2, fbos);
}

Result<std::unique_ptr<Renderer>> Renderer::create() {
    if (epoxy_gl_version() < 45 || epoxy_is_desktop_gl() == 0)
        return Error{fmt::format("renderer: needs OpenGL 4.5 core (the context has {}.{})", epoxy_gl_version() / 10,
                                 epoxy_gl_version() % 10)};
    auto impl = std::make_unique<Impl>();
    if (auto s = impl->init(); !s) return s.error();
    return std::unique_ptr<Renderer>(new Renderer(std::move(impl)));
}

void Renderer::set_scene(const SceneView& view, bool terrain_changed) {
    if (!view.complete()) return;
    if (terrain_changed || impl_->terrain_index_count == 0)
        impl_->upload_terrain(*view.terrain, *view.bvh, view.paper_rows);
    impl_->upload_dynamic(view);
}

void Renderer::update_terrain(const SceneView& view, const TerrainEdit& changed) {
    if (!view.complete()) return;
    impl_->update_terrain(*view.terrain, *view.bvh, view.paper_rows, changed);
}

void Renderer::update(const SceneView& view) {
    Impl& r = *impl_;
    if (!view.complete()) return;
    if (view.owner == r.last_owner && view.frame == r.last_frame) {
        r.stats.last_upload_bytes = 0;  // nothing moved: nothing to send
        return;
    }
    r.upload_dynamic(view);
}

Status Renderer::set_terrain_texture(std::span<const uint8_t> rgba, int width, int height) {
    Impl& r = *impl_;
    if (rgba.empty() || width <= 0 || height <= 0) {
        r.has_texture = false;
        return Ok{};
    }
    const uint64_t expected = uint64_t(width) * uint64_t(height) * 4u;
    if (rgba.size() != expected)
        return Error{fmt::format("texture: the pixel buffer has {} bytes; {} x {} RGBA needs {}", rgba.size(), width,
                                 height, expected)};
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (width > max_size || height > max_size)
        return Error{fmt::format("texture: {} x {} is larger than this OpenGL's GL_MAX_TEXTURE_SIZE ({})", width,
                                 height, max_size)};
    glBindTexture(GL_TEXTURE_2D, r.terrain_tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    glGenerateMipmap(GL_TEXTURE_2D);
    glBindTexture(GL_TEXTURE_2D, 0);
    r.stats.bytes_uploaded += rgba.size();
    r.has_texture = true;
    return Ok{};
}

void Renderer::draw(const Camera& camera, int width, int height, const RenderSettings& s) {
    Impl& r = *impl_;
    ++r.stats.frames;
    r.scene.resize(width, height);
    r.final.resize(width, height);

    const float aspect = static_cast<float>(width) / static_cast<float>(std::max(height, 1));
    const glm::mat4 proj = camera.projection(aspect);
    FrameUniforms u{};
    u.viewproj = proj * camera.view();
    u.inv_viewproj = glm::inverse(u.viewproj);
    u.eye = glm::vec4(camera.eye(), 1.0f);
    const Vec3 sun = glm::length(s.sun_direction) > 0.0f ? glm::normalize(s.sun_direction) : Vec3(0, 1, 0);
    u.sun = glm::vec4(sun, 0.0f);
    u.viewport = glm::vec4(static_cast<float>(width), static_cast<float>(height), camera.near_m, camera.far_m);
    u.water = glm::vec4(s.water_color, s.water_absorption);
    u.params = glm::vec4(s.water_refraction, s.fog ? 1.0f : 0.0f, s.particle_radius, proj[1][1]);
    const float fog_distance = 2.5f * glm::length(r.geo.bounds.empty() ? Vec3(100.0f) : r.geo.bounds.extent());
    u.terrain = glm::vec4(r.geo.bounds.empty() ? 0.0f : r.geo.bounds.min.y,
                          r.geo.bounds.empty() ? 1.0f : r.geo.bounds.max.y,
                          (s.terrain_texture && r.has_texture) ? 1.0f : 0.0f, fog_distance);
    u.rect = r.geo.rect;
    // The flow clock wraps every 1000 s (a multiple of the shader's phase period), so
    // float precision holds in long runs.
    u.mode = glm::vec4(s.shading == WaterShading::Gouraud ? 1.0f : 0.0f, static_cast<float>(r.tree.depth),
                       std::fmod(s.time_s, 1000.0f), s.flow_detail ? 1.0f : 0.0f);
    glNamedBufferSubData(r.ubo, 0, sizeof(u), &u);
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, r.ubo);

    // Pass 1: sky, terrain, debug views into the scene framebuffer.
    glBindFramebuffer(GL_FRAMEBUFFER, r.scene.fbo);
    glViewport(0, 0, width, height);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glDepthMask(GL_TRUE);
    const float clear_color[] = {0.74f, 0.83f, 0.92f, 1.0f};
    const float clear_depth = 1.0f;
    glClearNamedFramebufferfv(r.scene.fbo, GL_COLOR, 0, clear_color);
    glClearNamedFramebufferfv(r.scene.fbo, GL_DEPTH, 0, &clear_depth);
    if (s.sky) {
        glDisable(GL_DEPTH_TEST);
        glDepthMask(GL_FALSE);
        glUseProgram(r.prog_sky);
        glBindVertexArray(r.vao_empty);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glDepthMask(GL_TRUE);
    }
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    if (s.terrain && r.terrain_index_count > 0) {
        glUseProgram(r.prog_terrain);
        glBindTextureUnit(0, r.terrain_tex);
        glBindVertexArray(r.vao_terrain);
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(r.terrain_index_count), GL_UNSIGNED_INT, nullptr);
    }
    if (s.bodies && r.stats.body_triangles > 0) {  // under the water's pass: submerged parts are seen through it
        glUseProgram(r.prog_bodies);
        glBindVertexArray(r.vao_bodies);
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(r.stats.body_triangles * 3), GL_UNSIGNED_INT, nullptr);
    }
    if (s.particles && r.stats.particles > 0) {
        glEnable(GL_PROGRAM_POINT_SIZE);
        glUseProgram(r.prog_particles);
        glBindVertexArray(r.vao_particles);
        glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(r.stats.particles));
    }
    r.stats.bvh_boxes = 0;
    if (s.bvh && !r.tree.level_first.empty()) {
        uint32_t first = r.tree.leaves_first, count = r.tree.leaves_count;
        if (s.bvh_level >= 0) {
            const auto lvl = static_cast<size_t>(std::min(s.bvh_level, r.tree.depth));
            first = r.tree.level_first[lvl];
            count = r.tree.level_count[lvl];
        }
        glUseProgram(r.prog_boxes);
        glBindVertexArray(r.vao_boxes);
        glDrawArraysInstancedBaseInstance(GL_LINES, 0, 24, static_cast<GLsizei>(count), first);
        r.stats.bvh_boxes = count;
    }

    // Pass 2: the water over a copy of the scene, reading the scene's colour and depth.
    glBlitNamedFramebuffer(r.scene.fbo, r.final.fbo, 0, 0, width, height, 0, 0, width, height,
                           GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, r.final.fbo);
    if (s.water && r.water_idx.size > 0) {
        glEnable(GL_CULL_FACE);
        glCullFace(GL_BACK);
        glFrontFace(GL_CCW);
        glUseProgram(r.prog_water);
        glBindTextureUnit(0, r.scene.color);
        glBindTextureUnit(1, r.scene.depth);
        glBindTextureUnit(2, r.flow_tex);
        glBindVertexArray(r.vao_water);
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(r.water_idx.size / sizeof(uint32_t)), GL_UNSIGNED_INT, nullptr);
        glDisable(GL_CULL_FACE);
    }
    if (s.foam && r.stats.foam_particles > 0) {
        // Over the water, depth-tested against it and the terrain, not writing depth.
        glEnable(GL_PROGRAM_POINT_SIZE);
        glEnable(GL_BLEND);
        glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        glDepthMask(GL_FALSE);
        glUseProgram(r.prog_foam);
        glBindVertexArray(r.vao_foam);
        glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(r.stats.foam_particles));
        glDepthMask(GL_TRUE);
        glDisable(GL_BLEND);
    }
    glBindVertexArray(0);
    glUseProgram(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void Renderer::present_to_default_framebuffer() {
    const Impl& r = *impl_;
    glBlitNamedFramebuffer(r.final.fbo, 0, 0, 0, r.final.width, r.final.height, 0, 0, r.final.width, r.final.height,
                           GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

void Renderer::read_rgb(std::vector<uint8_t>& out) {
    const Impl& r = *impl_;
    const size_t row = static_cast<size_t>(r.final.width) * 3;
    out.resize(row * static_cast<size_t>(r.final.height));
    glBindFramebuffer(GL_READ_FRAMEBUFFER, r.final.fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, r.final.width, r.final.height, GL_RGB, GL_UNSIGNED_BYTE, out.data());
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    // OpenGL's rows run bottom-up; images run top-down.
    for (int y = 0; y < r.final.height / 2; ++y) {
        uint8_t* a = out.data() + static_cast<size_t>(y) * row;
        uint8_t* b = out.data() + static_cast<size_t>(r.final.height - 1 - y) * row;
        std::swap_ranges(a, a + row, b);
    }
}

const RenderStats& Renderer::stats() const { return impl_->stats; }

std::string Renderer::gl_description() const {
    return gl::gl_string(GL_RENDERER) + " / " + gl::gl_string(GL_VERSION);
}

}  // namespace mr::render
