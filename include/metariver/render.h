// metariver render: the OpenGL 4.5 renderer (terrain, water surface, sky, debug views)
// and the orbit camera and its picking ray. A context to render in: a window's, or the
// headless one of gl_context.h.
//
// This header carries no OpenGL type: the renderer keeps its GL objects behind a
// pointer, so apps and tests include it without the GL headers. The renderer reads
// a SceneView (scene_view.h: terrain, tree, particles, surface, foam, bodies); it never changes them.
//
// Water shading: Schlick's Fresnel term (F0 = 0.02, water) mixes a reflection of the
// analytic sky with the refracted terrain colour behind the water, absorbed with
// Beer-Lambert over the water depth read from the terrain's depth buffer; Blinn-Phong
// specular for the sun. The paper's look (per-vertex "Gouraud" lighting, translucent
// blue) is kept as WaterShading::Gouraud. Flow detail (RenderSettings::flow_detail):
// the particles' velocity interpolated onto the surface's vertices advects a tiling,
// flow-aligned normal and foam-streak texture, two phases cross-faded (Vlachos, "Water
// Flow in Portal 2", SIGGRAPH 2010); still water (speed 0) is left untouched.
#pragma once

#include <metariver/core.h>
#include <metariver/scene_view.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>

namespace mr::render {

/// An orbit camera: the eye sits `distance` metres from `target`, at `yaw` degrees
/// around +y (0: on the +z side, looking towards -z) and `pitch` degrees above the
/// horizontal plane.
struct Camera {
    Vec3 target{0.0f};
    float yaw_deg = 30.0f;
    float pitch_deg = 35.0f;
    float distance = 80.0f;    ///< metres, > 0
    float fov_y_deg = 45.0f;   ///< vertical field of view, degrees, (1, 170)
    float near_m = 0.1f;       ///< near plane, metres
    float far_m = 1000.0f;     ///< far plane, metres

    Vec3 eye() const;
    glm::mat4 view() const;
    glm::mat4 projection(float aspect) const;
    /// Rotates by mouse motion (degrees); pitch is kept in [-89, 89].
    void orbit(float dyaw_deg, float dpitch_deg);
    /// Moves the target in the view plane by a fraction of the distance.
    void pan(float dx, float dy);
    /// Multiplies the distance by `factor` (> 0), clamped to [0.5, 1e5] metres.
    void zoom(float factor);
};

/// A camera that frames the terrain (and its near/far planes fitted to it).
Camera frame_terrain(const Terrain& terrain);
/// A camera straight above the terrain (pitch 89 degrees, x across the image) at the
/// distance that fits its whole rectangle into a view of this aspect (width / height).
Camera frame_terrain_from_above(const Terrain& terrain, float aspect);
/// Fits near/far to the terrain's bounds for the camera's current eye.
void fit_clip_planes(Camera& camera, const Terrain& terrain);

/// Parses "YAW,PITCH,DISTANCE" or "YAW,PITCH,DISTANCE,TX,TY,TZ" (degrees, metres) onto
/// `camera`. The message names the option and the expected form.
Status parse_camera(const std::string& text, Camera& camera);

/// The world-space ray under a pixel (x right, y down, in pixels of a w x h view).
struct Ray {
    Vec3 origin{0.0f};
    Vec3 direction{0.0f, 0.0f, -1.0f};  ///< unit length
};
Ray pixel_ray(const Camera& camera, float x, float y, int width, int height);
/// Where the pixel's ray first meets the terrain (Bvh::intersect_segment), if anywhere.
std::optional<Vec3> pick_terrain(const Camera& camera, float x, float y, int width, int height,
                                 const Terrain& terrain, const Bvh& bvh);

enum class WaterShading {
    Realistic,  ///< per pixel: Fresnel sky reflection, refraction, depth tint, specular
    Gouraud,    ///< the paper's look: lighting per vertex, interpolated, translucent blue
};

/// What to draw and how. Every field is read each frame; changing one costs no upload.
struct RenderSettings {
    bool terrain = true;
    bool water = true;
    bool sky = true;
    bool particles = false;           ///< debug: the active particles as shaded spheres
    float particle_radius = 0.3f;     ///< metres, drawn radius of a particle sphere
    bool foam = true;                 ///< diffuse particles ([foam]): foam on the water, spray, bubbles
    bool bodies = true;               ///< the rigid bodies (SceneView::bodies): their meshes, wood-coloured
    bool bvh = false;                 ///< debug: the AABB tree's boxes as lines
    int bvh_level = -1;               ///< tree depth to draw (0 = root); -1 = the leaves
    WaterShading shading = WaterShading::Realistic;
    Vec3 water_color{0.05f, 0.32f, 0.38f};  ///< colour deep water tends to (linear RGB)
    float water_absorption = 0.45f;   ///< Beer-Lambert extinction per metre of water
    float water_refraction = 0.03f;   ///< screen-space refraction offset (fraction of the view)
    Vec3 sun_direction{-0.55f, 0.65f, -0.25f};  ///< towards the sun (normalised when used)
    bool terrain_texture = true;      ///< use the texture given by set_terrain_texture, if any
    bool fog = true;                  ///< aerial perspective towards the horizon colour
    /// Realistic water only: streaks and ripples advected along the flow, stronger where
    /// it is faster; none below kFlowDetailMinSpeed (still water stays a mirror).
    bool flow_detail = true;
    /// Seconds on the flow detail's clock (the simulated time of the frame drawn): the
    /// texture moves with it, so two times give two images of the same particles.
    float time_s = 0.0f;
};

/// Surface speed (m/s) below which the flow detail adds nothing, and from which it
/// grows to full strength at kFlowDetailFullSpeed (the shader's smoothstep).
inline constexpr float kFlowDetailMinSpeed = 0.05f;
inline constexpr float kFlowDetailFullSpeed = 1.5f;

/// Counters tests and the viewer's overlay read.
struct RenderStats {
    uint64_t frames = 0;              ///< draw() calls
    uint64_t gl_objects_created = 0;  ///< buffers, textures, framebuffers, programs ever created
    uint64_t buffer_reallocations = 0;  ///< times a dynamic buffer had to grow
    uint64_t bytes_uploaded = 0;      ///< total bytes sent by update() and set_scene()
    uint64_t last_upload_bytes = 0;   ///< bytes sent by the latest update()
    uint64_t last_terrain_upload_bytes = 0;  ///< bytes sent by the latest terrain upload (set_scene or update_terrain)
    size_t water_triangles = 0;
    size_t terrain_triangles = 0;
    size_t particles = 0;
    size_t foam_particles = 0;        ///< diffuse particles uploaded (spray, foam and bubbles)
    size_t bodies = 0;                ///< bodies uploaded (those with a mesh)
    size_t body_triangles = 0;        ///< their triangles
    size_t bvh_boxes = 0;             ///< boxes drawn in the latest frame
    double flow_ms = 0.0;             ///< latest update(): surface_velocities, milliseconds
};

/// Scratch of surface_velocities, reused across frames (no allocation once warm).
struct SurfaceVelocityWorkspace {
    NeighborGrid grid;
};
/// The fluid's velocity at each vertex, m/s: the poly6-weighted (Shepard-normalised)
/// average of the velocities of the active particles within `radius` metres, zero where
/// there is none. `out` is resized to vertices.size(). Parallel over vertices, the same
/// result for any thread count.
void surface_velocities(std::span<const Vec3> vertices, const Particles& particles, float radius,
                        SurfaceVelocityWorkspace& ws, std::vector<Vec3>& out);
/// The obviously right twin: every particle for every vertex, serial (tests).
void surface_velocities_brute(std::span<const Vec3> vertices, const Particles& particles, float radius,
                              std::vector<Vec3>& out);

/// The OpenGL renderer. Needs a current OpenGL 4.5 core context (a window's, or
/// gl::HeadlessContext's) for its whole life; all GL objects are created by create() and
/// set_scene() and reused: draw() and update() create none (dynamic buffers grow by
/// 1.5x and are orphaned with glBufferData before each refill).
class Renderer {
public:
    /// Compiles the shaders and creates the fixed GL objects. Fails (one line) when the
    /// context is not OpenGL 4.5 core or a shader does not compile.
    static Result<std::unique_ptr<Renderer>> create();
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Uploads the terrain mesh (with skirts down to its box), its normals and the AABB
    /// tree's boxes, then the water and particles of `sim`. Pass terrain_changed = false
    /// for a rebuilt Simulation over the same terrain and tree (only the water and
    /// particles are sent then).
    /// `view` must be complete() (Simulation::view() is); an incomplete one draws nothing new.
    void set_scene(const SceneView& view, bool terrain_changed = true);
    /// After a sculpt stroke or its undo (Simulation::sculpt / restore) changed the heights
    /// of the samples in `changed` (its i0..i1, j0..j1): uploads only the terrain vertex
    /// rows around them, the skirts when they reach a border, and the tree boxes the refit
    /// moved; the same buffers as set_scene(view, true) would send, bit for bit. Falls
    /// back to the whole terrain when the view is of another terrain (another size) or its
    /// lowest point moved (the skirts' bottom).
    void update_terrain(const SceneView& view, const TerrainEdit& changed);
    /// Uploads what changed since the last call: the water surface and particles, only
    /// when the view's owner advanced a frame (or is a different owner).
    void update(const SceneView& view);
    /// An RGBA8 image draped over the terrain's x/z rectangle (image row 0 at the far
    /// end, as the heightmap); an empty span removes it.
    /// An error (nothing uploaded) when the buffer is not width x height x 4 bytes or a
    /// side exceeds GL_MAX_TEXTURE_SIZE; empty input turns the texture off.
    Status set_terrain_texture(std::span<const uint8_t> rgba, int width, int height);

    /// Draws a frame of width x height pixels into the renderer's own framebuffer.
    void draw(const Camera& camera, int width, int height, const RenderSettings& settings);
    /// Copies the latest frame into the bound draw framebuffer 0 (a window).
    void present_to_default_framebuffer();
    /// Reads the latest frame as tightly packed RGB8, top row first; `out` is resized
    /// to width * height * 3 (its capacity is reused).
    void read_rgb(std::vector<uint8_t>& out);

    const RenderStats& stats() const;
    /// "llvmpipe (LLVM 15.0.6, 256 bits) / 4.5 (Core Profile) Mesa 22.3.6".
    std::string gl_description() const;

private:
    struct Impl;
    explicit Renderer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace mr::render
