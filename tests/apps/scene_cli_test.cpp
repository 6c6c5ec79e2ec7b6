// `metariver scene` and `metariver --version` end to end: a preset printed as a scene
// file runs and prints back the same, the key reference is written between its markers,
// bad input is one line and exit code 2.
#include <gtest/gtest.h>
#include <build_options.h>
#include "cli_fixture.h"
#include "png_test_util.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

namespace fs = std::filesystem;

namespace {

using mr::test::CliResult;
using mr::test::slurp;

class SceneCli : public mr::test::CliFixture {};

TEST_F(SceneCli, VersionSaysTheVersionAndTheBuild) {
    CliResult r = run("--version");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(std::regex_search(r.out, std::regex(R"(^metariver \d+\.\d+\.\d+\nbuild: commit \S+ \(at configure time\), \S+, \S+ \S+\n$)")))
        << r.out;
}

// Found by CI's fuzz run: CLI11 took "--version=" for --version and exited 0 with no
// command run; a value on a flag that takes none is bad input, named in one line.
TEST_F(SceneCli, AValueOnVersionOrHelpIsBadInput) {
    for (const char* arg : {"--version=", "--version=1", "--help=", "--help=run"}) {
        CliResult r = run(arg);
        EXPECT_EQ(r.code, 2) << arg << ": " << r.out;
        EXPECT_NE(r.err.find("takes no value (got '" + std::string(arg) + "')"), std::string::npos) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    }
}

TEST_F(SceneCli, APresetPrintedAsASceneFileRunsAndPrintsBackTheSame) {
    CliResult first = run("scene --preset paper-bowl");
    ASSERT_EQ(first.code, 0) << first.err;
    EXPECT_NE(first.out.find("\npreset = \"paper-bowl\""), std::string::npos) << first.out;
    const fs::path file = dir_ / "bowl.toml";
    std::ofstream(file) << first.out;
    CliResult again = run("scene --scene " + file.string());
    ASSERT_EQ(again.code, 0) << again.err;
    // Written on the default scene this time: only the preset line differs.
    std::string expected = first.out;
    expected.replace(expected.find("preset = \"paper-bowl\""), 21, "preset = \"default\"   ");
    EXPECT_EQ(again.out, expected);
    CliResult ran = run("run --scene " + file.string() + " --frames 5 --no-progress");
    EXPECT_EQ(ran.code, 0) << ran.err;
    EXPECT_NE(ran.out.find("paper-bowl: 5 frames"), std::string::npos) << ran.out;
}

TEST_F(SceneCli, APresetWithoutItsHeightmapLeavesThePathToFillIn) {
    CliResult r = run("scene --preset paper-full");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("\nheightmap = \"\""), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("(required: this preset's terrain is a PNG"), std::string::npos) << r.out;
    CliResult with = run("scene --preset paper-full --heightmap maps/strict17.png --area-scale 2");
    ASSERT_EQ(with.code, 0) << with.err;
    EXPECT_NE(with.out.find("\nheightmap = \"" + (fs::current_path() / "maps/strict17.png").string() + "\""), std::string::npos)
        << "written absolute: " << with.out;
    EXPECT_NE(with.out.find("\narea_scale = 2.0"), std::string::npos) << with.out;
}

// The issue 42 reproduction: `scene --preset P > f.toml; run --scene f.toml --heightmap
// MAP` failed with "terrain.heightmap: required when terrain.source = file" for the
// presets whose terrain is a PNG, though --heightmap replaces a scene's terrain. The map
// is a 33 x 33 slope written here (every preset's source lies inside it).
TEST_F(SceneCli, HeightmapReplacesTheTerrainOfAPrintedSceneFile) {
    std::vector<uint8_t> px;
    for (int r = 0; r < 33; ++r)
        for (int c = 0; c < 33; ++c) px.push_back(static_cast<uint8_t>(20 + 3 * r + (c % 5)));
    const auto png = mr::test::encode_png8(33, 33, 1, px);
    const fs::path map = dir_ / "slope.png";
    std::ofstream(map, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
    for (const std::string preset : {"paper-full", "paper-nile", "paper-engine", "paper-nile-engine"}) {
        SCOPED_TRACE(preset);
        CliResult printed = run("scene --preset " + preset);
        ASSERT_EQ(printed.code, 0) << printed.err;
        ASSERT_NE(printed.out.find("\nheightmap = \"\""), std::string::npos) << "the path is left to fill in";
        const fs::path file = dir_ / (preset + ".toml");
        std::ofstream(file) << printed.out;
        const std::string stats = (dir_ / "s.json").string();
        CliResult ran = run("run --scene " + file.string() + " --heightmap " + map.string() +
                            " --frames 3 --no-progress --stats " + stats);
        if (!mr::test::kWithBullet && preset.ends_with("-engine")) {  // METARIVER_WITH_BULLET=OFF: refused, naming it
            EXPECT_NE(ran.code, 0);
            EXPECT_NE(ran.err.find("(got 'bullet'); this build leaves out the Bullet solver (METARIVER_WITH_BULLET=OFF)"),
                      std::string::npos) << ran.err;
            continue;
        }
        EXPECT_EQ(ran.code, 0) << ran.err;
        EXPECT_NE(ran.out.find(preset + ": 3 frames"), std::string::npos) << ran.out;
        // The file's own PNG, when it names one, is replaced too (this one does not exist).
        std::string named = printed.out;
        named.replace(named.find("\nheightmap = \"\""), 16, "\nheightmap = \"missing.png\"");
        std::ofstream(file) << named;
        CliResult over = run("run --scene " + file.string() + " --heightmap " + map.string() + " --frames 3 --no-progress");
        EXPECT_EQ(over.code, 0) << over.err;
        // Without --heightmap the file still needs its PNG.
        std::ofstream(file) << printed.out;
        CliResult without = run("run --scene " + file.string() + " --frames 3 --no-progress");
        EXPECT_EQ(without.code, 2);
        EXPECT_NE(without.err.find("terrain.heightmap: required when terrain.source = \"file\""), std::string::npos)
            << without.err;
    }
}

TEST_F(SceneCli, UpdateDocRewritesOnlyTheReference) {
    const fs::path doc = dir_ / "doc.md";
    std::ofstream(doc) << "# Title\n\nbefore\n<!-- scene keys: generated by `metariver scene --doc`; do not edit -->\nold "
                          "table\n<!-- end of scene keys -->\nafter\n";
    CliResult r = run("scene --update-doc " + doc.string());
    ASSERT_EQ(r.code, 0) << r.err;
    CliResult ref = run("scene --doc");
    ASSERT_EQ(ref.code, 0) << ref.err;
    EXPECT_EQ(slurp(doc), "# Title\n\nbefore\n" + ref.out + "after\n");
    EXPECT_NE(ref.out.find("| `field.bounds` |"), std::string::npos);
}

TEST_F(SceneCli, BadInputIsOneLineAndExitCode2) {
    for (const std::string args : {"scene --preset nope", "scene --scene missing.toml", "scene --update-doc missing.md",
                                   "scene --preset default --collision paper"}) {
        CliResult r = run(args);
        EXPECT_EQ(r.code, 2) << args;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
        EXPECT_TRUE(r.out.empty()) << args << ": " << r.out;
    }
    const fs::path doc = dir_ / "plain.md";
    std::ofstream(doc) << "no markers\n";
    CliResult r = run("scene --update-doc " + doc.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(slurp(doc), "no markers\n") << "left as it was";
}

}  // namespace
