// An export session: the folder, the terrain once, every due frame in every format,
// the manifest last; what it wrote is recorded so a failure (or an exit before
// finish()) takes all of it back. docs/export.md describes the files and the manifest.
#include <metariver/export.h>
#include <metariver/io.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <unistd.h>

namespace mr {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

bool is_mesh_format(ExportFormat f) { return f != ExportFormat::Vdb && f != ExportFormat::Npy; }

/// One file's bytes for the water or the particles in format `f`.
Result<std::string> encode_water(ExportFormat f, const MeshView& m, const ExportDef& def, long long frame,
                                 VdbStats& vdb) {
    const std::string comment = fmt::format("metariver water surface, scene {}, frame {}", def.scene, frame);
    switch (f) {
        case ExportFormat::Obj: return encode_obj_mesh(m, comment);
        case ExportFormat::Ply: return encode_ply_mesh(m, comment);
        case ExportFormat::Glb: return encode_glb_mesh(m, "water", true);
        case ExportFormat::Vdb: return encode_vdb_level_set(m, def.voxel_size, &vdb);
        case ExportFormat::Npy: break;  // the grid: Exporter::write_grid
    }
    return Error{"unknown export format"};
}

Result<std::string> encode_particles(ExportFormat f, const ParticleFrame& p, const ExportDef& def, long long frame,
                                     VdbStats& vdb) {
    const std::string comment = fmt::format("metariver particles, scene {}, frame {}", def.scene, frame);
    switch (f) {
        case ExportFormat::Obj: return encode_obj_points(p, comment);
        case ExportFormat::Ply: return encode_ply_points(p, comment);
        case ExportFormat::Glb: return encode_glb_points(p, "particles");
        case ExportFormat::Vdb: return encode_vdb_points(p, def.voxel_size, &vdb);
        case ExportFormat::Npy: break;
    }
    return Error{"unknown export format"};
}

std::string frame_file(std::string_view stem, long long frame, int digits, ExportFormat f) {
    return fmt::format("{}_{:0{}}.{}", stem, frame, digits, to_string(f));
}

/// The npy grid's shape and place: sample (r, c) lies at x = origin[0] + c * spacing,
/// z = origin[1] + r * spacing (metres).
json grid_json(const HeightfieldWater& g, int digits) {
    const std::string hash(static_cast<size_t>(digits), '#');
    return {{"rows", g.rows},
            {"columns", g.columns},
            {"origin", {g.origin.x, g.origin.z}},
            {"spacing", g.spacing},
            {"dtype", "<f4"},
            {"order", "C"},
            {"shape", "(rows, columns): row r along +z, column c along +x"},
            {"arrays", {{"depth", "depth_" + hash + ".npy: metres of water above the bed, 0 where dry"},
                        {"velocity_x", "velocity_x_" + hash + ".npy: depth-averaged velocity along +x, m/s"},
                        {"velocity_z", "velocity_z_" + hash + ".npy: depth-averaged velocity along +z, m/s"},
                        {"bed", "bed_" + hash + ".npy: the bed's height (y), metres; the surface is bed + depth"}}}};
}

/// How to bring the files into other tools (the manifest's "import").
json import_notes(const ExportDef& d) {
    const auto has = [&](ExportFormat f) { return std::find(d.formats.begin(), d.formats.end(), f) != d.formats.end(); };
    const std::string hash(static_cast<size_t>(d.digits), '#');
    json j;
    j["blender"] = {
        {"script", "blender -b -P scripts/blender_import.py -- DIR [--frame N] [--render OUT.png]: the terrain, the "
                   "water as a mesh sequence (one object per frame, shown on its frame) and the VDB level set as a "
                   "volume sequence"},
        {"by_hand", "meshes: File > Import > Wavefront (.obj) / Stanford (.ply) / glTF 2.0 (.glb), one frame per "
                    "file; volume: Add > Volume > Import OpenVDB, pick water_" + std::string(static_cast<size_t>(d.digits), '0') +
                    ".vdb and tick Sequence (grid 'surface', a level set: add a Volume to Mesh modifier for a surface)"}};
    json houdini;
    for (ExportFormat f : d.formats) {
        if (f == ExportFormat::Npy) continue;  // arrays, not geometry
        const std::string ext(to_string(f));
        houdini["water_" + ext] = fmt::format("File SOP, File: DIR/water_$F{}.{}", d.digits, ext);
        if (d.particles) houdini["particles_" + ext] = fmt::format("File SOP, File: DIR/particles_$F{}.{}", d.digits, ext);
    }
    if (d.particles) houdini["foam_ply"] = fmt::format("File SOP, File: DIR/foam_$F{}.ply (with [foam])", d.digits);
    houdini["note"] = fmt::format("DIR is this folder; file numbers are frame numbers ({} per second); with --every N "
                                  "use `padzero({}, $F*N)` for $F{}. PLY particle properties vx vy vz id age and VDB "
                                  "point attributes v id age come in as point attributes",
                                  d.frame_rate, d.digits, d.digits);
    j["houdini"] = houdini;
    j["unity_unreal"] = has(ExportFormat::Glb)
                            ? "glTF 2.0 binary: terrain.glb once, water_" + hash +
                                  ".glb per frame (Unity: glTFast or UnityGLTF package; Unreal: the glTF Importer "
                                  "plugin, or Interchange in 5.x). Particles: POINTS with _VELOCITY, _ID, _AGE"
                            : "export with --format glb for engines";
    return j;
}

}  // namespace

Exporter::Exporter(ExportDef def) : def_(std::move(def)) {
    for (ExportFormat f : def_.formats) stats_.push_back(ExportFormatStats{.format = f});
}

Exporter::~Exporter() {
    if (!kept_) abort();
}

std::string Exporter::manifest_path() const { return (fs::path(def_.dir) / "export.json").string(); }

Result<std::unique_ptr<Exporter>> Exporter::begin(const ExportDef& def) {
    if (def.formats.empty()) return Error{"--format: no format given (allowed: obj, ply, glb, vdb, npy)"};
    if (def.every < 1 || def.every > kMaxExportEvery)
        return Error{fmt::format("--every: must be in [1, {}] (got {})", kMaxExportEvery, def.every)};
    if (!(def.voxel_size > 0.0f) || def.voxel_size > 100.0f)
        return Error{fmt::format("--export: VDB voxel size must be in (0, 100] metres (got {})", def.voxel_size)};
    std::unique_ptr<Exporter> e(new Exporter(def));
    std::error_code ec;
    const fs::path dir(def.dir);
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
        return Error{fmt::format("--export {}: exists and is not a folder", def.dir)};
    if (!fs::exists(dir, ec)) {
        if (!fs::create_directories(dir, ec) || ec)
            return Error{fmt::format("--export {}: cannot create folder: {}", def.dir,
                                     ec ? ec.message() : std::string("unknown error"))};
        e->created_dir_ = true;
    }
    // Permission bits say nothing for root or on a read-only mount: create a file.
    const std::string probe = (dir / fmt::format(".metariver-probe-{}", ::getpid())).string();
    if (auto s = write_file_atomic(probe, ""); !s)
        return Error{fmt::format("--export {}: folder is not writable", def.dir)};
    std::remove(probe.c_str());
    return e;
}

Status Exporter::write_terrain(const Terrain& terrain) {
    const TerrainAttributes attributes = terrain_attributes(terrain);
    const MeshView view = terrain_view(terrain, attributes);
    for (ExportFormat f : def_.formats) {
        if (!is_mesh_format(f)) continue;
        Result<std::string> bytes = Error{""};
        if (f == ExportFormat::Obj) bytes = encode_obj_mesh(view, "metariver terrain");
        else if (f == ExportFormat::Ply) bytes = encode_ply_mesh(view, "metariver terrain");
        else bytes = encode_glb_mesh(view, "terrain", false);
        const std::string name = fmt::format("terrain.{}", to_string(f));
        Status s = bytes ? write(name, bytes.value())
                         : Status(Error{fmt::format("{}: {}", (fs::path(def_.dir) / name).string(), bytes.error().message)});
        if (!s) {
            abort();
            return s;
        }
        terrain_files_.push_back(name);
    }
    return Ok{};
}

bool Exporter::due(long long frame) const {
    if (frame < def_.first || (def_.last != kExportToEnd && frame > def_.last)) return false;
    return (frame - def_.first) % def_.every == 0;
}

Status Exporter::write(const std::string& name, const std::string& bytes) {
    if (aborted_ || kept_) return Error{fmt::format("--export {}: the export is already {}", def_.dir, kept_ ? "finished" : "aborted")};
    const std::string path = (fs::path(def_.dir) / name).string();
    if (auto s = write_file_atomic(path, bytes); !s) return s;
    written_.push_back(path);
    return Ok{};
}

Status Exporter::write_grid(long long frame, const HeightfieldWater* grid, const Terrain* terrain,
                            const std::function<Status(std::string_view, Result<std::string>)>& emit) {
    if (!grid || !terrain)
        return Error{fmt::format("--format npy: frame {}: the solver has no heightfield water (npy holds a "
                                 "heightfield solver's grid: solver = \"swe\")", frame)};
    const size_t cells = grid->size();
    const std::span<const Vec3> bed = terrain->vertices();
    if (grid->depth.size() != cells || bed.size() != cells)
        return Error{fmt::format("--format npy: frame {}: the water grid ({} x {}) is not the terrain's ({} x {})", frame,
                                 grid->rows, grid->columns, terrain->rows(), terrain->columns())};
    if (!grid_shape_) grid_shape_ = HeightfieldWater{.rows = grid->rows, .columns = grid->columns,
                                                     .origin = grid->origin, .spacing = grid->spacing};
    const auto array = [&](auto value) {
        grid_scratch_.resize(cells);
        for (size_t k = 0; k < cells; ++k) grid_scratch_[k] = value(k);
        return encode_npy_f32(grid_scratch_, grid->rows, grid->columns);
    };
    const bool moving = grid->velocity.size() == cells;
    Status s = emit("depth", array([&](size_t k) { return grid->depth[k]; }));
    if (s) s = emit("velocity_x", array([&](size_t k) { return moving ? grid->velocity[k].x : 0.0f; }));
    if (s) s = emit("velocity_z", array([&](size_t k) { return moving ? grid->velocity[k].z : 0.0f; }));
    if (s) s = emit("bed", array([&](size_t k) { return bed[k].y; }));
    return s;
}

Status Exporter::write_frame(long long frame, double time_s, const SurfaceMesh& water, const Particles& particles,
                             uint64_t solver_frame, const DiffuseParticles* foam, std::span<const BodyState> bodies,
                             const HeightfieldWater* grid, const Terrain* terrain) {
    ExportedFrame rec{.frame = frame,
                      .time_s = time_s,
                      .vertices = water.vertex_count(),
                      .triangles = water.triangle_count(),
                      .bodies = {bodies.begin(), bodies.end()}};
    if (def_.particles) {
        gather_particle_frame(particles, solver_frame, def_.solver_dt, scratch_);
        rec.particles = scratch_.size();
    }
    const MeshView view = mesh_view(water);
    for (ExportFormatStats& st : stats_) {
        const auto t0 = Clock::now();
        VdbStats vdb;
        uint64_t bytes_written = 0;
        auto emit = [&](std::string_view stem, Result<std::string> bytes) -> Status {
            const std::string name = frame_file(stem, frame, def_.digits, st.format);
            if (!bytes) return Error{fmt::format("{}: {}", (fs::path(def_.dir) / name).string(), bytes.error().message)};
            if (auto s = write(name, bytes.value()); !s) return s;
            rec.files.push_back(name);
            bytes_written += bytes.value().size();
            ++st.files;
            return Ok{};
        };
        const bool npy = st.format == ExportFormat::Npy;
        Status s = npy ? write_grid(frame, grid, terrain, emit) : emit("water", encode_water(st.format, view, def_, frame, vdb));
        if (s && !npy && def_.particles) s = emit("particles", encode_particles(st.format, scratch_, def_, frame, vdb));
        // The diffuse particles once per frame (PLY whatever the formats), with the first.
        if (s && def_.particles && foam && &st == &stats_.front()) {
            const std::string comment = fmt::format("metariver foam, spray and bubbles, scene {}, frame {}", def_.scene, frame);
            const std::string name = fmt::format("foam_{:0{}}.ply", frame, def_.digits);
            const std::string bytes = encode_ply_foam(*foam, comment);
            s = write(name, bytes);
            if (s) {
                rec.files.push_back(name);
                rec.foam = foam->size();
                bytes_written += bytes.size();
            }
        }
        // The bodies as nodes with their transforms, once per frame, with glb.
        if (s && !bodies.empty() && st.format == ExportFormat::Glb) s = emit("bodies", encode_glb_bodies(bodies));
        if (!s) {
            abort();
            return s;
        }
        st.bytes += bytes_written;
        st.ms.push_back(ms_since(t0));
        if (st.format == ExportFormat::Vdb) rec.active_voxels = vdb.active_voxels;
    }
    frames_.push_back(std::move(rec));
    return Ok{};
}

Status Exporter::finish() {
    json j;
    j["generator"] = "metariver";
    j["manifest_version"] = 1;
    j["scene"] = def_.scene;
    j["units"] = {{"length", "metre"},
                  {"time", "second"},
                  {"velocity", "metre per second"},
                  {"up", "+y"},
                  {"handedness", "right"}};
    j["frame_rate"] = def_.frame_rate;
    j["frames"] = {{"first", frames_.empty() ? 0 : frames_.front().frame},
                   {"last", frames_.empty() ? 0 : frames_.back().frame},
                   {"every", def_.every},
                   {"written", frames_.size()}};
    json formats = json::array();
    for (ExportFormat f : def_.formats) formats.push_back(std::string(to_string(f)));
    j["formats"] = formats;
    const bool has_glb = std::find(def_.formats.begin(), def_.formats.end(), ExportFormat::Glb) != def_.formats.end();
    j["patterns"] = {{"water", fmt::format("water_{}.EXT", std::string(static_cast<size_t>(def_.digits), '#'))},
                     {"particles", def_.particles ? json(fmt::format("particles_{}.EXT",
                                                                     std::string(static_cast<size_t>(def_.digits), '#')))
                                                  : json(nullptr)},
                     {"foam", def_.particles ? json(fmt::format("foam_{}.ply", std::string(static_cast<size_t>(def_.digits), '#')))
                                             : json(nullptr)},
                     {"bodies", has_glb ? json(fmt::format("bodies_{}.glb", std::string(static_cast<size_t>(def_.digits), '#')))
                                        : json(nullptr)}};
    j["terrain"] = terrain_files_;
    if (grid_shape_) j["grid"] = grid_json(*grid_shape_, def_.digits);
    j["contents"] = {
        {"obj", "water: v, vn, f a//a; particles: v + p (positions only); terrain: v, vt, vn"},
        {"ply", "binary_little_endian 1.0; water: float x y z nx ny nz, faces list uchar uint; particles: float x y z "
                "vx vy vz, uint id, float age; terrain: + float s t"},
        {"glb", "glTF 2.0 binary; water: POSITION NORMAL, UNSIGNED_INT indices, material 'water'; particles: POINTS "
                "with POSITION, _VELOCITY (vec3), _ID (float), _AGE (float); terrain: + TEXCOORD_0"},
        {"vdb", {{"water", {{"grid", "surface"}, {"class", "level set"}, {"half_width_voxels", kVdbHalfWidth}}},
                 {"particles", {{"grid", "points"}, {"attributes", {"P", "v", "id", "age"}}}},
                 {"voxel_size", std::stod(fmt::format("{}", def_.voxel_size))}}},  // 0.33333334, not the double of the float
        {"npy", "NumPy .npy v1.0, '<f4', C order, shape (rows, columns): the heightfield solver's grid (\"grid\")"},
        {"age", "seconds since the particle's latest emission by the source"},
        {"bodies", "per frame: each body's id, position (centre of mass, m), orientation (quaternion x y z w, body to "
                   "world), velocity (m/s), angular_velocity (rad/s, world axes), submerged_fraction; with glb and "
                   "bodies: bodies_#.glb, one node per body 'body_<id>' with that transform and its mesh in its own "
                   "frame, material 'wood'"},
        {"foam", "with [foam]: foam_#.ply per frame whatever the formats, binary_little_endian 1.0: float x y z vx vy vz, "
                 "uchar kind (0 spray, 1 foam, 2 bubble), float life (seconds left)"}};
    json per_format = json::object();
    for (const ExportFormatStats& st : stats_) {
        const Percentiles p = percentiles(st.ms);
        per_format[std::string(to_string(st.format))] = {
            {"files", st.files},
            {"bytes", st.bytes},
            {"bytes_per_frame", frames_.empty() ? 0.0 : double(st.bytes) / double(frames_.size())},
            {"ms_per_frame", {{"median", p.median}, {"p95", p.p95}, {"mean", p.mean}, {"max", p.max}}}};
    }
    j["stats"] = per_format;
    const bool has_vdb = std::find(def_.formats.begin(), def_.formats.end(), ExportFormat::Vdb) != def_.formats.end();
    auto vec = [](const Vec3& v) { return json{v.x, v.y, v.z}; };
    json files = json::array();
    for (const ExportedFrame& f : frames_) {
        json e = {{"frame", f.frame},      {"time_s", f.time_s},       {"files", f.files},
                  {"vertices", f.vertices}, {"triangles", f.triangles}, {"particles", f.particles}, {"foam", f.foam}};
        if (has_vdb) e["active_voxels"] = f.active_voxels;
        json bodies = json::array();
        for (const BodyState& b : f.bodies)
            bodies.push_back({{"id", b.id},
                              {"position", vec(b.position)},
                              {"orientation", {b.orientation.x, b.orientation.y, b.orientation.z, b.orientation.w}},
                              {"velocity", vec(b.velocity)},
                              {"angular_velocity", vec(b.angular_velocity)},
                              {"submerged_fraction", b.submerged_fraction}});
        e["bodies"] = std::move(bodies);
        files.push_back(std::move(e));
    }
    j["frame_files"] = files;
    j["import"] = import_notes(def_);
    if (auto s = write("export.json", j.dump(2) + "\n"); !s) {
        abort();
        return s;
    }
    kept_ = true;
    return Ok{};
}

void Exporter::abort() {
    std::error_code ec;
    for (const std::string& f : written_) fs::remove(f, ec);
    written_.clear();
    if (created_dir_) fs::remove(def_.dir, ec);  // only when empty: nothing of anyone else's goes
    created_dir_ = false;
    aborted_ = true;
}

}  // namespace mr
