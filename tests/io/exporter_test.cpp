// An export session on a real simulation: the frames due, the files and the manifest,
// and nothing left behind when a write fails (a file size limit: write() fails as on a
// full disk) or the session is dropped before finish().
#include "export_fixture.h"

#include <metariver/scene.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <csignal>
#include <map>
#include <set>
#include <sys/resource.h>

namespace mr {
namespace {

namespace fs = std::filesystem;

class Exporting : public test::ExportFixture {
protected:
    /// The default river, small: 600 particles at 420 per second (water from frame 0,
    /// the source still emitting at frame 12).
    static std::unique_ptr<Simulation> small_river() {
        SceneDef d = default_scene();
        d.spawn.count = 600;
        d.spawn.flow_rate = 420.0f;
        auto sim = Simulation::create(d);
        EXPECT_TRUE(sim.ok()) << (sim.ok() ? "" : sim.error().message);
        return std::move(sim.value());
    }

    static std::set<std::string> names(const fs::path& dir) {
        std::set<std::string> n;
        for (const auto& e : fs::directory_iterator(dir)) n.insert(e.path().filename().string());
        return n;
    }
};

TEST(ExportDue, FramesOnTheStrideInsideTheRange) {
    auto e = Exporter::begin(ExportDef{.dir = (fs::temp_directory_path() / fmt::format("metariver_due_{}", ::getpid())).string(),
                                       .every = 5, .first = 2, .last = 13});
    ASSERT_TRUE(e.ok()) << e.error().message;
    std::vector<long long> due;
    for (long long f = 0; f < 20; ++f)
        if (e.value()->due(f)) due.push_back(f);
    EXPECT_EQ(due, (std::vector<long long>{2, 7, 12}));
}

TEST_F(Exporting, WritesTheDueFramesInEveryFormatAndAManifestListingThem) {
    auto sim = small_river();
    ASSERT_TRUE(sim);
    const fs::path out = dir_ / "export";
    ExportDef def{.dir = out.string(),
                  .formats = {ExportFormat::Obj, ExportFormat::Ply, ExportFormat::Glb, ExportFormat::Vdb},
                  .every = 5,
                  .first = 1,
                  .last = 11,
                  .voxel_size = 1.0f / 3.0f,
                  .scene = "default"};
    auto started = Exporter::begin(def);
    ASSERT_TRUE(started.ok()) << started.error().message;
    Exporter& e = *started.value();
    ASSERT_TRUE(e.write_terrain(sim->terrain()).ok());
    std::map<long long, std::pair<size_t, size_t>> counts;  // frame -> (particles, triangles)
    for (long long f = 0; f < 12; ++f) {
        sim->step(1.0f / 60.0f);
        if (!e.due(f)) continue;
        ASSERT_TRUE(e.write_frame(f, double(f + 1) / 60.0, sim->surface(), sim->particles(), sim->frame()).ok());
        counts[f] = {sim->particles().active_count(), sim->surface().triangle_count()};
    }
    ASSERT_TRUE(e.finish().ok());

    std::set<std::string> want{"terrain.obj", "terrain.ply", "terrain.glb", "export.json"};
    for (const char* frame : {"00001", "00006", "00011"})
        for (const char* ext : {"obj", "ply", "glb", "vdb"}) {
            want.insert(fmt::format("water_{}.{}", frame, ext));
            want.insert(fmt::format("particles_{}.{}", frame, ext));
        }
    EXPECT_EQ(names(out), want) << "exactly these files, no temporaries";

    const auto j = nlohmann::json::parse(test::slurp(out / "export.json"));
    EXPECT_EQ(j["units"]["length"], "metre");
    EXPECT_EQ(j["units"]["up"], "+y");
    EXPECT_EQ(j["frames"]["written"], 3);
    EXPECT_EQ(j["frames"]["every"], 5);
    EXPECT_EQ(j["formats"], (nlohmann::json{"obj", "ply", "glb", "vdb"}));
    ASSERT_EQ(j["frame_files"].size(), 3u);
    std::map<std::string, uint64_t> bytes;  // per format, from the files on disk
    for (const auto& f : j["frame_files"]) {
        const long long frame = f["frame"];
        ASSERT_TRUE(counts.count(frame)) << frame;
        EXPECT_EQ(f["particles"].get<size_t>(), counts[frame].first);
        EXPECT_EQ(f["triangles"].get<size_t>(), counts[frame].second);
        EXPECT_GT(counts[frame].first, 0u);
        EXPECT_GT(f["active_voxels"].get<uint64_t>(), 0u);
        EXPECT_NEAR(f["time_s"].get<double>(), double(frame + 1) / 60.0, 1e-12);
        ASSERT_EQ(f["files"].size(), 8u);
        for (const auto& name : f["files"]) {
            const fs::path p = out / name.get<std::string>();
            ASSERT_TRUE(fs::exists(p)) << p;
            bytes[p.extension().string().substr(1)] += fs::file_size(p);
        }
    }
    for (const char* ext : {"obj", "ply", "glb", "vdb"}) {
        EXPECT_EQ(j["stats"][ext]["bytes"].get<uint64_t>(), bytes[ext]) << ext;
        EXPECT_EQ(j["stats"][ext]["files"].get<uint64_t>(), 6u) << ext;
        EXPECT_GT(j["stats"][ext]["ms_per_frame"]["median"].get<double>(), 0.0) << ext;
    }
    // The binary PLY particle file holds 32 bytes per particle after its header.
    const std::string ply = test::slurp(out / "particles_00011.ply");
    const size_t header = ply.find("end_header\n") + 11;
    EXPECT_EQ(ply.size() - header, 32 * counts[11].first);
}

TEST_F(Exporting, FoamGoesToOnePlyPerFrameBesideTheParticlesAndIntoTheManifest) {
    auto sim = small_river();
    ASSERT_TRUE(sim);
    ASSERT_NE(sim->foam(), nullptr) << "the default river makes foam";
    for (int f = 0; f < 3; ++f) sim->step(1.0f / 60.0f);
    DiffuseParticles made;  // a known set, so the count is not 0 by chance
    for (int i = 0; i < 5; ++i) {
        made.position.push_back(Vec3(float(i), 1.0f, 2.0f));
        made.velocity.push_back(Vec3(0.0f, 0.0f, float(i)));
        made.kind.push_back(uint8_t(i % 3));
        made.life.push_back(0.5f * float(i + 1));
        made.neighbours.push_back(0);
        made.fluid_velocity.push_back(Vec3(0.0f));
    }
    const fs::path out = dir_ / "export";
    auto e = Exporter::begin(ExportDef{.dir = out.string(), .formats = {ExportFormat::Obj, ExportFormat::Ply}});
    ASSERT_TRUE(e.ok());
    const DiffuseParticles& live = sim->foam()->particles();
    ASSERT_TRUE(e.value()->write_frame(0, 0.0, sim->surface(), sim->particles(), sim->frame(), &live).ok());
    ASSERT_TRUE(e.value()->write_frame(1, 0.0, sim->surface(), sim->particles(), sim->frame(), &made).ok());
    ASSERT_TRUE(e.value()->write_frame(2, 0.0, sim->surface(), sim->particles(), sim->frame()).ok());  // no foam
    ASSERT_TRUE(e.value()->finish().ok());
    const auto files = names(out);
    EXPECT_TRUE(files.count("foam_00000.ply") && files.count("foam_00001.ply")) << "one per frame, once for two formats";
    EXPECT_FALSE(files.count("foam_00002.ply")) << "nothing without foam";
    EXPECT_FALSE(files.count("foam_00000.obj")) << "PLY only";
    for (auto [name, n] : {std::pair{"foam_00000.ply", live.size()}, std::pair{"foam_00001.ply", made.size()}}) {
        const std::string ply = test::slurp(out / name);
        const size_t header = ply.find("end_header\n") + 11;
        EXPECT_EQ(ply.size() - header, 29 * n) << name;
    }
    const auto j = nlohmann::json::parse(test::slurp(out / "export.json"));
    EXPECT_EQ(j["frame_files"][0]["foam"], live.size());
    EXPECT_EQ(j["frame_files"][1]["foam"], 5u);
    EXPECT_EQ(j["frame_files"][2]["foam"], 0u);
    EXPECT_EQ(j["patterns"]["foam"], "foam_#####.ply");

    // --no-particles: no foam either.
    const fs::path bare = dir_ / "bare";
    auto b = Exporter::begin(ExportDef{.dir = bare.string(), .formats = {ExportFormat::Ply}, .particles = false});
    ASSERT_TRUE(b.ok());
    ASSERT_TRUE(b.value()->write_frame(0, 0.0, sim->surface(), sim->particles(), sim->frame(), &made).ok());
    EXPECT_FALSE(names(bare).count("foam_00000.ply"));
}

TEST_F(Exporting, BodiesGoToTheManifestEveryFrameAndToAGlbWithGlb) {
    auto sim = small_river();
    ASSERT_TRUE(sim);
    sim->step(1.0f / 60.0f);
    auto mesh = std::make_shared<BodyMesh>(BodyMesh{.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, -1)},
                                                     .normals = {Vec3(0, 1, 0), Vec3(0, 1, 0), Vec3(0, 1, 0)},
                                                     .indices = {0, 1, 2}});
    std::vector<BodyState> bodies(1);
    bodies[0] = {.id = 5, .position = Vec3(12.0f, 3.0f, 40.0f), .orientation = glm::quat(0.0f, 0.0f, 1.0f, 0.0f),
                 .velocity = Vec3(0.5f, 0.0f, -1.5f), .submerged_fraction = 0.4f, .mesh = mesh};
    for (const bool glb : {false, true}) {
        const fs::path out = dir_ / (glb ? "with_glb" : "obj_only");
        auto e = Exporter::begin(ExportDef{.dir = out.string(),
                                           .formats = glb ? std::vector{ExportFormat::Obj, ExportFormat::Glb}
                                                          : std::vector{ExportFormat::Obj}});
        ASSERT_TRUE(e.ok()) << e.error().message;
        ASSERT_TRUE(e.value()->write_frame(0, 0.0, sim->surface(), sim->particles(), sim->frame(), nullptr, bodies).ok());
        ASSERT_TRUE(e.value()->write_frame(1, 0.1, sim->surface(), sim->particles(), sim->frame()).ok());  // none
        ASSERT_TRUE(e.value()->finish().ok());
        EXPECT_EQ(fs::exists(out / "bodies_00000.glb"), glb);
        EXPECT_FALSE(fs::exists(out / "bodies_00001.glb")) << "a frame without bodies has no bodies file";
        const auto j = nlohmann::json::parse(test::slurp(out / "export.json"));
        EXPECT_EQ(j["patterns"]["bodies"].is_null(), !glb);
        const auto& f0 = j["frame_files"][0];
        ASSERT_EQ(f0["bodies"].size(), 1u);
        EXPECT_EQ(f0["bodies"][0]["id"], 5);
        EXPECT_EQ(f0["bodies"][0]["position"], (nlohmann::json{12.0f, 3.0f, 40.0f}));
        EXPECT_EQ(f0["bodies"][0]["orientation"], (nlohmann::json{0.0f, 1.0f, 0.0f, 0.0f})) << "x y z w";
        EXPECT_EQ(f0["bodies"][0]["velocity"], (nlohmann::json{0.5f, 0.0f, -1.5f}));
        EXPECT_FLOAT_EQ(f0["bodies"][0]["submerged_fraction"].get<float>(), 0.4f);
        EXPECT_TRUE(j["frame_files"][1]["bodies"].empty());
        const auto& files = f0["files"];
        EXPECT_EQ(std::count(files.begin(), files.end(), "bodies_00000.glb"), glb ? 1 : 0);
    }
}

TEST_F(Exporting, DroppedBeforeFinishItRemovesWhatItWroteAndTheFolderItMade) {
    auto sim = small_river();
    ASSERT_TRUE(sim);
    sim->step(1.0f / 60.0f);
    const fs::path made = dir_ / "new" ;
    {
        auto e = Exporter::begin(ExportDef{.dir = made.string(), .formats = {ExportFormat::Ply, ExportFormat::Vdb}});
        ASSERT_TRUE(e.ok());
        ASSERT_TRUE(e.value()->write_terrain(sim->terrain()).ok());
        ASSERT_TRUE(e.value()->write_frame(0, 1.0 / 60.0, sim->surface(), sim->particles(), sim->frame()).ok());
        EXPECT_EQ(names(made).size(), 5u);  // terrain.ply, water and particles in ply and vdb
    }
    EXPECT_FALSE(fs::exists(made));

    // A folder that was there stays, with what else it held.
    const fs::path existing = dir_ / "existing";
    fs::create_directories(existing);
    put("existing/notes.txt", "mine");
    {
        auto e = Exporter::begin(ExportDef{.dir = existing.string(), .formats = {ExportFormat::Obj}});
        ASSERT_TRUE(e.ok());
        ASSERT_TRUE(e.value()->write_frame(0, 1.0 / 60.0, sim->surface(), sim->particles(), sim->frame()).ok());
    }
    EXPECT_EQ(names(existing), std::set<std::string>{"notes.txt"});
}

TEST_F(Exporting, AFolderThatCannotBeMadeIsOneLineNamingIt) {
    put("file", "a file where the folder should go");
    auto e = Exporter::begin(ExportDef{.dir = (dir_ / "file" / "sub").string()});
    ASSERT_FALSE(e.ok());
    EXPECT_NE(e.error().message.find("--export " + (dir_ / "file" / "sub").string()), std::string::npos)
        << e.error().message;
    EXPECT_EQ(e.error().message.find('\n'), std::string::npos);
    auto f = Exporter::begin(ExportDef{.dir = (dir_ / "file").string()});
    ASSERT_FALSE(f.ok());
    EXPECT_NE(f.error().message.find("not a folder"), std::string::npos) << f.error().message;
}

/// Sets the process's file size limit for its lifetime (write() then fails with EFBIG
/// past it, as it fails with ENOSPC on a full disk); SIGXFSZ ignored so it is an error,
/// not a kill.
class FileSizeLimit {
public:
    explicit FileSizeLimit(rlim_t bytes) {
        getrlimit(RLIMIT_FSIZE, &old_);
        old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
        rlimit r = old_;
        r.rlim_cur = bytes;
        setrlimit(RLIMIT_FSIZE, &r);
    }
    ~FileSizeLimit() {
        setrlimit(RLIMIT_FSIZE, &old_);
        std::signal(SIGXFSZ, old_handler_);
    }

private:
    rlimit old_{};
    void (*old_handler_)(int) = nullptr;
};

TEST_F(Exporting, AWriteThatFailsPartWayNamesTheFileAndLeavesNothing) {
    auto sim = small_river();
    ASSERT_TRUE(sim);
    for (int f = 0; f < 10; ++f) sim->step(1.0f / 60.0f);
    const fs::path out = dir_ / "export";
    auto e = Exporter::begin(ExportDef{.dir = out.string(), .formats = {ExportFormat::Ply, ExportFormat::Obj}});
    ASSERT_TRUE(e.ok());
    ASSERT_TRUE(e.value()->write_terrain(sim->terrain()).ok());
    ASSERT_TRUE(e.value()->write_frame(0, 0.0, sim->surface(), sim->particles(), sim->frame()).ok());
    // The OBJ water is text, several times the binary PLY: a limit between the two lets
    // the PLY files of the next frame through and stops its OBJ water.
    const size_t ply = fs::file_size(out / "water_00000.ply"), obj = fs::file_size(out / "water_00000.obj");
    ASSERT_LT(2 * ply, obj);
    Status s = Ok{};
    {
        FileSizeLimit limit(static_cast<rlim_t>((ply + obj) / 2 + 4096));
        s = e.value()->write_frame(1, 0.0, sim->surface(), sim->particles(), sim->frame());
    }
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.error().message.find((out / "water_00001.obj").string()), std::string::npos) << s.error().message;
    EXPECT_NE(s.error().message.find("write failed"), std::string::npos) << s.error().message;
    EXPECT_EQ(s.error().message.find('\n'), std::string::npos);
    EXPECT_FALSE(fs::exists(out)) << "the export's files and the folder it made are gone";
    // And the session refuses to go on writing into a removed export.
    EXPECT_FALSE(e.value()->write_frame(2, 0.0, sim->surface(), sim->particles(), sim->frame()).ok());
    EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace mr
