// `run --export` and `render --export` end to end: the files of the frames asked for,
// bad options (exit 2, one line naming the option and what is allowed, nothing
// written), and a write that fails part-way (exit 1, one line naming the file, nothing
// left behind).
#include "export_fixture.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <set>
#include "require.h"

namespace mr {
namespace {

namespace fs = std::filesystem;
using test::CliResult;

class ExportCli : public test::ExportFixture {
protected:
    std::set<std::string> names(const fs::path& dir) const {
        std::set<std::string> n;
        if (!fs::exists(dir)) return n;
        for (const auto& e : fs::recursive_directory_iterator(dir)) n.insert(fs::relative(e.path(), dir).string());
        return n;
    }

    /// Exit 2, one line on stderr holding `must_contain`, and the test folder unchanged.
    void expect_bad(const std::string& args, const std::string& must_contain) {
        const std::set<std::string> before = names(dir_);
        const CliResult r = run(args);
        EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
        EXPECT_NE(r.err.find(must_contain), std::string::npos) << args << ": '" << r.err << "'";
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
        EXPECT_EQ(names(dir_), before) << args;
    }
};

TEST_F(ExportCli, RunWritesTheFramesOfTheRangeOnTheStrideWithAManifest) {
    const fs::path out = dir_ / "exp";
    const CliResult r = run("run --preset paper-bowl --frames 12 --seed 3 --export " + out.string() +
                            " --format ply,vdb --every 5 --range 1:");
    ASSERT_EQ(r.code, 0) << r.err;
    std::set<std::string> want{"export.json", "terrain.ply"};
    for (const char* f : {"00001", "00006", "00011"})
        for (const char* ext : {"ply", "vdb"}) {
            want.insert(fmt::format("water_{}.{}", f, ext));
            want.insert(fmt::format("particles_{}.{}", f, ext));
        }
    EXPECT_EQ(names(out), want);
    EXPECT_NE(r.out.find("exported 3 frames"), std::string::npos) << r.out;
    const auto j = nlohmann::json::parse(test::slurp(out / "export.json"));
    EXPECT_EQ(j["scene"], "paper-bowl");
    EXPECT_DOUBLE_EQ(j["frame_rate"].get<double>(), 60.0);
    EXPECT_EQ(j["frames"]["first"], 1);
    EXPECT_EQ(j["frames"]["last"], 11);
    // The paper's bowl activates one ball every 20 frames from frame 0: 1 ball at frame 1.
    EXPECT_EQ(j["frame_files"][0]["particles"], 1);
    EXPECT_NEAR(j["contents"]["vdb"]["voxel_size"].get<double>(), 0.5, 1e-6) << "1 / field.resolution (2)";
}

TEST_F(ExportCli, NoParticlesWritesTheWaterOnlyAndObjDirStillWorksBesideIt) {
    const fs::path out = dir_ / "exp", objs = dir_ / "objs";
    const CliResult r = run("run --preset paper-bowl --frames 3 --export " + out.string() + " --no-particles --obj-dir " +
                            objs.string());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(names(out), (std::set<std::string>{"export.json", "terrain.obj", "water_00000.obj", "water_00001.obj",
                                                 "water_00002.obj"}));
    EXPECT_EQ(names(objs), (std::set<std::string>{"terrain.obj", "surface_00000.obj", "surface_00001.obj",
                                                  "surface_00002.obj"}));
    // The same surface, two writers: the earlier --obj-dir one and the export's.
    const std::string a = test::slurp(out / "water_00002.obj"), b = test::slurp(objs / "surface_00002.obj");
    EXPECT_EQ(a.substr(a.find("\nv ")), b.substr(b.find("\nv ")));
}

TEST_F(ExportCli, BadExportOptionsAreOneLineNamingTheOptionAndWriteNothing) {
    const std::string out = (dir_ / "exp").string();
    const std::string base = "run --preset paper-bowl --frames 12 --export " + out;
    expect_bad(base + " --format stl", "--format: unknown format 'stl' (allowed: obj, ply, glb, vdb");
    expect_bad(base + " --format ply,ply", "--format: 'ply' is listed twice");
    expect_bad(base + " --every 0", "--every: must be in [1, 1000000000] (got 0)");
    expect_bad(base + " --every often", "--every");
    expect_bad(base + " --range 5:2", "--range: expected FIRST:LAST frame numbers with 0 <= FIRST <= LAST <= 11");
    expect_bad(base + " --range 0:12", "--range: expected FIRST:LAST");
    expect_bad(base + " --range 3", "--range: expected FIRST:LAST");
    expect_bad(base + " --range -1:4", "--range");
    expect_bad(base + " --voxel-size 0", "--voxel-size: must be in (0, 100] metres");
    expect_bad("run --preset paper-bowl --frames 3 --format ply", "--format: needs --export");
    expect_bad("run --preset paper-bowl --frames 3 --every 2", "--every: needs --export");
    expect_bad("run --preset paper-bowl --frames 3 --range 0:1", "--range: needs --export");
    put("file", "in the way");
    expect_bad("run --preset paper-bowl --frames 3 --export " + (dir_ / "file").string(), "exists and is not a folder");
    expect_bad("run --preset paper-bowl --frames 3 --export " + (dir_ / "file" / "sub").string(), "cannot create folder");
    if (::geteuid() != 0) {  // root writes anywhere
        fs::create_directories(dir_ / "ro");
        fs::permissions(dir_ / "ro", fs::perms::owner_read | fs::perms::owner_exec);
        expect_bad("run --preset paper-bowl --frames 3 --export " + (dir_ / "ro").string(), "folder is not writable");
        fs::permissions(dir_ / "ro", fs::perms::owner_all);
    }
}

TEST_F(ExportCli, AWriteThatFailsPartWayExitsOneNamingTheFileAndLeavesNothing) {
    // A file size limit (ulimit -f, in 512-byte blocks for sh) makes write() fail the way
    // a full disk does. The river's VDB files grow with the water: a limit between the
    // first frame's files and the largest lets the run start and stops it part-way.
    const std::string run_args = "run --frames 40 --export ";
    const fs::path probe = dir_ / "probe";
    CliResult p = run(run_args + probe.string() + " --format vdb");
    ASSERT_EQ(p.code, 0) << p.err;
    const uintmax_t first = std::max(fs::file_size(probe / "water_00000.vdb"), fs::file_size(probe / "particles_00000.vdb"));
    uintmax_t largest = 0;
    for (const auto& e : fs::directory_iterator(probe)) largest = std::max(largest, e.file_size());
    ASSERT_GT(largest, first + 2048) << "the water outgrows the first frame's files";
    const uintmax_t limit_blocks = (first + largest) / 2 / 512;
    fs::remove_all(probe);

    const fs::path out = dir_ / "exp", stats = dir_ / "s.json";
    const CliResult r = run(run_args + out.string() + " --format vdb --stats " + stats.string(),
                            "ulimit -f " + std::to_string(limit_blocks) + ";");
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.err.find(out.string() + "/water_000"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find(out.string() + "/water_00000.vdb"), std::string::npos) << "part-way, not at the start: " << r.err;
    EXPECT_NE(r.err.find("write failed"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out)) << "left behind: " << ::testing::PrintToString(names(out));
    EXPECT_FALSE(fs::exists(stats));
}

TEST_F(ExportCli, RenderExportsTheWaterOfEveryImage) {
    const fs::path out = dir_ / "exp", frames = dir_ / "png";
    const CliResult r = run("render --preset paper-bowl --frames 3 --size 64x48 --out " + frames.string() +
                                " --export " + out.string() + " --format glb --range 1:2",
                            "XDG_RUNTIME_DIR=/tmp");
    if (r.code == 1 && r.err.find("EGL") != std::string::npos) MR_SKIP_OR_FAIL("no headless OpenGL here: " << r.err);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(names(out), (std::set<std::string>{"export.json", "terrain.glb", "water_00001.glb", "water_00002.glb",
                                                 "particles_00001.glb", "particles_00002.glb"}));
    const auto j = nlohmann::json::parse(test::slurp(out / "export.json"));
    EXPECT_NEAR(j["frame_files"][1]["time_s"].get<double>(), 3.0 / 60.0, 1e-12) << "image 2 shows frame 3's state";
    expect_bad("render --preset paper-bowl --frames 3 --size 64x48 --out " + frames.string() + " --export " +
                   out.string() + "2 --range 2:3",
               "--range: expected FIRST:LAST frame numbers with 0 <= FIRST <= LAST <= 2");
}

TEST_F(ExportCli, TheViewersRecordExportsEveryStepWhileItRuns) {
    const std::string xvfb = test::find_program("xvfb-run");
    if (xvfb.empty()) MR_SKIP_OR_FAIL("xvfb-run is not installed (apt-get install xvfb): the viewer's Record not run");
    const fs::path out = dir_ / "rec";
    const CliResult r = run("view --preset paper-bowl --frames 8 --record --export " + out.string() + " --format ply",
                            "XDG_RUNTIME_DIR=/tmp " + xvfb + " -a -s '-screen 0 1024x768x24'");
    if (r.code != 0 && r.err.find("cannot") != std::string::npos) MR_SKIP_OR_FAIL("no OpenGL 4.5 window here: " << r.err);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("recording to " + out.string()), std::string::npos) << r.out;
    const auto j = nlohmann::json::parse(test::slurp(out / "export.json"));
    const size_t frames = j["frame_files"].size();
    EXPECT_GE(frames, 1u) << "the simulation steps at least once in 8 display frames";
    EXPECT_NE(r.out.find(fmt::format("exported {} frames to {}", frames, out.string())), std::string::npos) << r.out;
    // Frames count from the start of the recording, one per simulation step.
    for (size_t k = 0; k < frames; ++k) {
        EXPECT_EQ(j["frame_files"][k]["frame"].get<size_t>(), k);
        EXPECT_TRUE(fs::exists(out / fmt::format("water_{:05}.ply", k)));
    }
    const CliResult bad = run("view --preset paper-bowl --frames 2 --format stl",
                              "XDG_RUNTIME_DIR=/tmp " + xvfb + " -a -s '-screen 0 1024x768x24'");
    EXPECT_EQ(bad.code, 2) << bad.err;
    EXPECT_NE(bad.err.find("--format: unknown format 'stl'"), std::string::npos) << bad.err;
    EXPECT_FALSE(fs::exists("metariver_export")) << "nothing recorded";
}

}  // namespace
}  // namespace mr
