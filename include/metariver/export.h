// metariver export: the water surface, the particles and the terrain as files other
// tools read (Blender, Houdini, game engines), one file per frame and format, and a
// JSON manifest per export (docs/export.md).
//
// Formats: Wavefront OBJ (text), PLY (binary little-endian), glTF 2.0 binary (glb,
// written with tinygltf) and OpenVDB (the water as a narrow-band level set, the
// particles as a points grid). Files: terrain.EXT once (mesh formats), then for every
// exported frame water_NNNNN.EXT and particles_NNNNN.EXT. Particles carry position,
// velocity, id and age wherever the format can hold them (PLY properties, glTF
// attributes, VDB point attributes; OBJ holds positions only). With [foam], the diffuse
// particles go to foam_NNNNN.ply beside them, whatever the formats (PLY carries their
// kind and remaining life with the positions). Units: metres, seconds,
// y up, right-handed (the simulation's own frame; glTF's too).
//
// Every file is written completely or not at all (write_file_atomic); an Exporter that
// fails part-way, or is destroyed before finish(), removes what it wrote.
#pragma once

#include <metariver/bodies.h>
#include <metariver/core.h>
#include <metariver/foam.h>
#include <metariver/particles.h>
#include <metariver/solver.h>
#include <metariver/surface.h>
#include <metariver/terrain.h>

#include <glm/vec2.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace mr {

/// Npy: the heightfield water's grid (depth, velocity x and z, bed) as NumPy arrays, for a
/// solver with heightfield water only (solver = "swe"); the others: the water mesh and particles.
enum class ExportFormat : uint8_t { Obj, Ply, Glb, Vdb, Npy };
inline constexpr std::array<ExportFormat, 5> kExportFormats{ExportFormat::Obj, ExportFormat::Ply, ExportFormat::Glb,
                                                            ExportFormat::Vdb, ExportFormat::Npy};
/// "obj", "ply", "glb", "vdb", "npy": the name on the command line and the file extension.
std::string_view to_string(ExportFormat f);
/// A comma-separated list ("ply" or "obj,vdb"), each format at most once, in the
/// order given. The error names `option` and the allowed values.
Result<std::vector<ExportFormat>> parse_export_formats(std::string_view list, std::string_view option = "--format");

/// The active particles of one frame, in the solver's order: what a particle file holds.
struct ParticleFrame {
    std::vector<Vec3> position;  ///< metres
    std::vector<Vec3> velocity;  ///< metres per second
    std::vector<uint32_t> id;    ///< stable particle id (Particles::id)
    std::vector<float> age;      ///< seconds since the particle's latest emission
    size_t size() const { return position.size(); }
};
/// Gathers the active particles of `p` into `out` (cleared first). Age = (solver_frame -
/// birth_frame) * frame_dt: `solver_frame` is the solver's frame counter after the
/// frame (Solver::frame()), `frame_dt` the seconds one solver frame simulates.
void gather_particle_frame(const Particles& p, uint64_t solver_frame, double frame_dt, ParticleFrame& out);

/// A triangle mesh to encode. `normals` and `uvs` are empty or hold one entry per
/// position; uvs are (u, v) with v running down the image (glTF's convention).
struct MeshView {
    std::span<const Vec3> positions;
    std::span<const Vec3> normals;
    std::span<const glm::vec2> uvs;
    std::span<const uint32_t> indices;  ///< three per triangle, counter-clockwise seen from outside
    size_t vertex_count() const { return positions.size(); }
    size_t triangle_count() const { return indices.size() / 3; }
};
MeshView mesh_view(const SurfaceMesh& m);

/// The terrain's per-vertex attributes for export: bilinear normals, and texture
/// coordinates that drape the heightmap image (u = column / (W - 1), v = image row /
/// (H - 1), so a texture of the map itself lines up; render --texture uses the same).
struct TerrainAttributes {
    std::vector<Vec3> normals;
    std::vector<glm::vec2> uvs;
};
TerrainAttributes terrain_attributes(const Terrain& terrain);
MeshView terrain_view(const Terrain& terrain, const TerrainAttributes& a);

// ---- Encoders: the bytes of one file (the readers in tests/io decode them) ----

std::string encode_obj_mesh(const MeshView& m, std::string_view comment);
/// Positions as OBJ points ("v" lines and "p" elements); OBJ has no place for the rest.
std::string encode_obj_points(const ParticleFrame& p, std::string_view comment);
/// Binary little-endian PLY: float x y z [nx ny nz] [s t], faces as "list uchar uint
/// vertex_indices".
std::string encode_ply_mesh(const MeshView& m, std::string_view comment);
/// Binary little-endian PLY vertices: float x y z, float vx vy vz, uint id, float age.
std::string encode_ply_points(const ParticleFrame& p, std::string_view comment);
/// The diffuse particles ([foam]) as binary little-endian PLY vertices: float x y z,
/// float vx vy vz, uchar kind (DiffuseKind: 0 spray, 1 foam, 2 bubble), float life
/// (seconds left).
std::string encode_ply_foam(const DiffuseParticles& d, std::string_view comment);
/// NumPy .npy v1.0: a rows x columns array of little-endian float32 ('<f4'), C order (row
/// r's columns one after another); values past the end of `values` are 0.
std::string encode_npy_f32(std::span<const float> values, int rows, int columns);
/// glTF 2.0 binary: one node and mesh named `name`, POSITION (with min/max), NORMAL
/// (unit length), TEXCOORD_0, UNSIGNED_INT indices, a material (`water` = true: blue,
/// alpha-blended; else the terrain's matte green-grey). An empty mesh gives a file with
/// one empty node.
Result<std::string> encode_glb_mesh(const MeshView& m, std::string_view name, bool water);
/// glTF 2.0 binary POINTS primitive: POSITION, and the application-specific attributes
/// _VELOCITY (VEC3 float, m/s), _ID (float: exact below 2^24 > kMaxParticles; glTF
/// allows UNSIGNED_INT only for indices) and _AGE (float, seconds).
Result<std::string> encode_glb_points(const ParticleFrame& p, std::string_view name);
/// glTF 2.0 binary of the bodies (bodies.h): one scene, one node per body named
/// "body_<id>" with its transform (translation: the centre of mass; rotation: the
/// orientation as x, y, z, w) and its mesh in the body's own frame (POSITION, NORMAL,
/// UNSIGNED_INT indices, material "wood"); a body without a mesh is a node without one.
Result<std::string> encode_glb_bodies(std::span<const BodyState> bodies);

/// What a VDB file holds (for the manifest and the tests).
struct VdbStats {
    uint64_t active_voxels = 0;  ///< level set: voxels in the narrow band
    uint64_t points = 0;         ///< points grid: points
};
/// Grid names: the level set is "surface" (Houdini's name for an SDF), class level
/// set, narrow band kVdbHalfWidth voxels each side; the points grid is "points" with
/// attributes P, v (vec3f), id (int32), age (float).
inline constexpr float kVdbHalfWidth = 3.0f;
/// The water as a narrow-band level set of the (closed) mesh, voxel edge `voxel_size` metres.
Result<std::string> encode_vdb_level_set(const MeshView& m, float voxel_size, VdbStats* stats = nullptr);
/// The particles as an OpenVDB points grid, voxel edge `voxel_size` metres.
Result<std::string> encode_vdb_points(const ParticleFrame& p, float voxel_size, VdbStats* stats = nullptr);

// ---- An export: the files of one run, its manifest, cleanup on failure ----

inline constexpr long long kExportToEnd = -1;
inline constexpr long long kMaxExportEvery = 1'000'000'000;

struct ExportDef {
    std::string dir;                                  ///< output folder; created when missing
    std::vector<ExportFormat> formats{ExportFormat::Obj};
    long long every = 1;                              ///< frame stride, [1, kMaxExportEvery]
    long long first = 0;                              ///< first frame written (file numbers are frame numbers)
    long long last = kExportToEnd;                    ///< last frame written, inclusive; kExportToEnd: the run's last
    bool particles = true;                            ///< write particles_NNNNN files beside the water
    float voxel_size = 0.25f;                         ///< VDB voxel edge, metres, (0, 100]
    double frame_rate = 60.0;                         ///< exported frame numbers per simulated second (manifest)
    double solver_dt = 1.0 / 60.0;                    ///< seconds one solver frame simulates (particle ages)
    int digits = 5;                                   ///< width of the zero-padded frame number, [5, 12]
    std::string scene;                                ///< scene name (manifest)
};

/// Cost and size of one format over an export: encode + write time per frame.
struct ExportFormatStats {
    ExportFormat format = ExportFormat::Obj;
    uint64_t files = 0;        ///< per-frame files (water and particles)
    uint64_t bytes = 0;        ///< their total size
    std::vector<double> ms;    ///< per exported frame: water + particles, encode + write, milliseconds
};

/// One exported frame, as the manifest lists it.
struct ExportedFrame {
    long long frame = 0;              ///< the number in the file names
    double time_s = 0.0;              ///< simulated time, seconds
    size_t vertices = 0;              ///< water mesh
    size_t triangles = 0;             ///< water mesh
    size_t particles = 0;             ///< active particles written
    size_t foam = 0;                  ///< diffuse particles written (foam_NNNNN.ply; 0 without [foam])
    std::vector<BodyState> bodies;    ///< the bodies' states (their transforms go to the manifest)
    uint64_t active_voxels = 0;       ///< VDB level set (0 without vdb)
    std::vector<std::string> files;   ///< file names in the folder, water then particles per format
};

class Exporter {
public:
    /// Checks the definition, creates the folder when missing and checks a file can be
    /// created in it. Errors are one line naming the option or folder (bad input);
    /// nothing is left behind.
    static Result<std::unique_ptr<Exporter>> begin(const ExportDef& def);
    /// Writes the terrain once for every mesh format (terrain.obj / .ply / .glb). On an
    /// error this export's files are all removed, and the error names the file.
    Status write_terrain(const Terrain& terrain);
    ~Exporter();  ///< removes everything written unless finish() succeeded
    Exporter(const Exporter&) = delete;
    Exporter& operator=(const Exporter&) = delete;

    /// True when `frame` is in [first, last] on the stride.
    bool due(long long frame) const;
    /// Writes frame `frame`'s files for every format. `time_s`: simulated time of the
    /// frame; `solver_frame`: the solver's frame counter (for particle ages); `foam`:
    /// the diffuse particles (Simulation::foam()), written to foam_NNNNN.ply with the
    /// particles, or null; `bodies`: the rigid bodies (SceneView::bodies), their
    /// transforms in the manifest and, with glb, bodies_NNNNN.glb (encode_glb_bodies)
    /// when there are any. On an error this export's files are all removed, and the
    /// error names the file.
    /// `grid` and `terrain` (format npy only): the heightfield water (Simulation::heightfield())
    /// and its bed, written as depth_, velocity_x_, velocity_z_ and bed_NNNNN.npy; npy without
    /// a grid is an error.
    Status write_frame(long long frame, double time_s, const SurfaceMesh& water, const Particles& particles,
                       uint64_t solver_frame, const DiffuseParticles* foam = nullptr,
                       std::span<const BodyState> bodies = {}, const HeightfieldWater* grid = nullptr,
                       const Terrain* terrain = nullptr);
    /// Writes the manifest (export.json) last; after it the files stay.
    Status finish();
    /// Removes every file this export wrote (and the folder if it created it).
    void abort();

    const ExportDef& def() const { return def_; }
    std::span<const ExportFormatStats> stats() const { return stats_; }
    std::span<const ExportedFrame> frames() const { return frames_; }
    /// Every file written so far, in order (terrain first).
    std::span<const std::string> written() const { return written_; }
    std::string manifest_path() const;

private:
    explicit Exporter(ExportDef def);
    Status write(const std::string& name, const std::string& bytes);

    ExportDef def_;
    bool created_dir_ = false;
    bool kept_ = false;     ///< finish() succeeded: the files stay
    bool aborted_ = false;  ///< abort() ran: nothing more is written
    std::vector<std::string> written_;
    std::vector<std::string> terrain_files_;
    std::vector<ExportFormatStats> stats_;
    std::vector<ExportedFrame> frames_;
    ParticleFrame scratch_;
    std::optional<HeightfieldWater> grid_shape_;  ///< npy: the grid's rows, columns, origin, spacing (no values)
    std::vector<float> grid_scratch_;

    Status write_grid(long long frame, const HeightfieldWater* grid, const Terrain* terrain,
                      const std::function<Status(std::string_view, Result<std::string>)>& emit);
};

}  // namespace mr
