// A run that fails part-way (issue 13): the disk fills (a small tmpfs, root only), or a
// path the run is due to write turns out unwritable. Exit code 1, one line naming the
// path that failed, and nothing of the run left behind: no partial file, no temporary,
// no OBJ folder the run created.
#include <gtest/gtest.h>
#include "cli_fixture.h"
#include "small_disk.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>
#include "require.h"

namespace fs = std::filesystem;

namespace {

using mr::test::CliResult;
using mr::test::SmallDisk;

class FullDisk : public mr::test::CliFixture {
protected:
    static std::vector<std::string> names(const fs::path& dir) {
        std::vector<std::string> n;
        for (const auto& e : fs::recursive_directory_iterator(dir)) n.push_back(fs::relative(e.path(), dir).string());
        std::sort(n.begin(), n.end());
        return n;
    }
};

constexpr const char* kRun = "run --preset paper-bowl --frames 40 --seed 3";

TEST_F(FullDisk, ARunThatFillsTheDiskPartWayLeavesNothingAndNamesThePath) {
    // The sizes of what the run writes, on the real disk first.
    const fs::path probe = dir_ / "probe";
    CliResult p = run(std::string(kRun) + " --obj-dir " + probe.string());
    ASSERT_EQ(p.code, 0) << p.err;
    std::vector<std::string> files = names(probe);
    ASSERT_EQ(files.size(), 41u);  // terrain + 40 surfaces
    // Room for the terrain and the first 20 surfaces: the disk fills half-way.
    size_t room = SmallDisk::charged(fs::file_size(probe / "terrain.obj"));
    for (int f = 0; f < 20; ++f)
        room += SmallDisk::charged(fs::file_size(probe / ("surface_" + std::string(f < 10 ? "0000" : "000") + std::to_string(f) + ".obj")));
    SmallDisk disk(dir_ / "disk", room);
    if (!disk.mounted()) MR_SKIP_OR_FAIL(disk.why());

    const fs::path objs = disk.dir() / "objs", stats = disk.dir() / "s.json";
    CliResult r = run(std::string(kRun) + " --obj-dir " + objs.string() + " --stats " + stats.string());
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.err.find(objs.string() + "/surface_000"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("No space left on device"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(names(disk.dir()).empty()) << "left behind: " << ::testing::PrintToString(names(disk.dir()));
}

TEST_F(FullDisk, StatsThatDoNotFitLeaveNoFileAndTheRunTakesBackItsObjs) {
    // The OBJ folder on the real disk, the stats file on a full one: the run fails at its
    // very end and removes the OBJ files it wrote.
    SmallDisk disk(dir_ / "disk", 4096);
    if (!disk.mounted()) MR_SKIP_OR_FAIL(disk.why());
    // Fill the disk: the stats file (some kB) cannot be written.
    {
        std::ofstream fill(disk.dir() / "fill", std::ios::binary);
        fill << std::string(4096, 'x');
    }
    const fs::path objs = dir_ / "objs", stats = disk.dir() / "s.json";
    CliResult r = run(std::string(kRun) + " --obj-dir " + objs.string() + " --stats " + stats.string());
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.err.find(stats.string()), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(objs));
    EXPECT_EQ(names(disk.dir()), std::vector<std::string>{"fill"});
}

TEST_F(FullDisk, AnUnwritablePathMidRunLeavesNothingOfTheRunAndNamesThePath) {
    // No root needed: the OBJ folder exists and, where frame 3's surface goes, there is a
    // folder (with a file in it) that the run cannot replace.
    const fs::path objs = dir_ / "objs";
    fs::create_directories(objs / "surface_00003.obj");
    std::ofstream(objs / "surface_00003.obj" / "keep.txt") << "not the run's";
    CliResult r = run(std::string(kRun) + " --obj-dir " + objs.string());
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.err.find((objs / "surface_00003.obj").string()), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    // What was there before stays; frames 0-2 and the terrain are taken back.
    EXPECT_EQ(names(objs), (std::vector<std::string>{"surface_00003.obj", "surface_00003.obj/keep.txt"}));
}

}  // namespace
