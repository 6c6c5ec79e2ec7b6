// End-to-end tests of `metariver render` and `metariver view`: the PNG sequence has the
// requested count and size and its frames differ as the water moves; bad --size,
// unwritable --out, a missing ffmpeg fail with one line and exit code 2, writing nothing;
// `view` without a display says so and points to `render`. Rendering tests skip when no
// headless OpenGL can be created (a machine without Mesa).
#include <metariver/gl_context.h>
#include <metariver/io.h>

#include <gtest/gtest.h>
#include "cli_fixture.h"
#include <nlohmann/json.hpp>
#include "small_disk.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include "require.h"

namespace fs = std::filesystem;

namespace {

using mr::test::CliResult;
using mr::test::slurp;

bool headless_gl_available(std::string& why) {
    static int state = -1;
    static std::string reason;
    if (state < 0) {
        auto ctx = mr::gl::HeadlessContext::create();
        state = ctx.ok() ? 1 : 0;
        if (!ctx.ok()) reason = ctx.error().message;
    }
    why = reason;
    return state == 1;
}

#define REQUIRE_GL()                                                                  \
    do {                                                                              \
        std::string why;                                                              \
        if (!headless_gl_available(why)) {                                            \
            MR_SKIP_OR_FAIL("no headless OpenGL: " << why);                            \
        }                                                                             \
    } while (0)

class RenderCli : public mr::test::CliFixture {
protected:
    /// `ENV metariver ARGS` (env: variable assignments, may be empty).
    CliResult run(const std::string& args, const std::string& env = "") { return CliFixture::run(args, env); }
    size_t entries(const fs::path& p) {
        size_t n = 0;
        for (auto it = fs::directory_iterator(p); it != fs::directory_iterator(); ++it) ++n;
        return n;
    }
};

int count_lines(const std::string& s) {
    int n = 0;
    for (char c : s) n += c == '\n';
    return n;
}

TEST_F(RenderCli, AFullDiskPartWayLeavesNoFrameAndNamesThePath) {
    // Issue 13: PNG frames onto a small tmpfs (root only) that fills after about half of them.
    REQUIRE_GL();
    const std::string args = "render --preset paper-bowl --frames 8 --size 64x48 --warmup 40 --out ";
    const fs::path probe = dir_ / "probe";
    CliResult p = run(args + probe.string());
    ASSERT_EQ(p.code, 0) << p.err;
    size_t room = 0;
    for (int f = 0; f < 4; ++f)
        room += mr::test::SmallDisk::charged(fs::file_size(probe / ("frame_0000" + std::to_string(f) + ".png")));
    mr::test::SmallDisk disk(dir_ / "disk", room);
    if (!disk.mounted()) MR_SKIP_OR_FAIL(disk.why());
    const fs::path out = disk.dir() / "frames";
    const CliResult r = run(args + out.string());
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(out.string() + "/frame_0000"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("No space left on device"), std::string::npos) << r.err;
    EXPECT_EQ(entries(disk.dir()), 0u) << "no frame, temporary or folder of the run left";
}

}  // namespace

TEST_F(RenderCli, PngSequenceHasCountAndSizeAndFramesDiffer) {
    REQUIRE_GL();
    const fs::path out = dir_ / "frames";
    const CliResult r = run("render --frames 4 --size 80x48 --steps 6 --warmup 240 --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("wrote 4 PNG frames"), std::string::npos) << r.out;
    std::vector<mr::Image> frames;
    for (int i = 0; i < 4; ++i) {
        const fs::path p = out / ("frame_0000" + std::to_string(i) + ".png");
        auto img = mr::load_image(p.string(), 3);
        ASSERT_TRUE(img.ok()) << img.error().message;
        EXPECT_EQ(img->width, 80);
        EXPECT_EQ(img->height, 48);
        frames.push_back(std::move(img.value()));
    }
    EXPECT_EQ(entries(out), 4u) << "exactly the requested frames, no temporaries left";
    for (int i = 1; i < 4; ++i) {
        size_t changed = 0;
        for (size_t k = 0; k < frames[0].pixels.size(); ++k) changed += frames[i].pixels[k] != frames[i - 1].pixels[k];
        EXPECT_GT(changed, 10u) << "frame " << i << " equals frame " << i - 1 << ": the water did not move";
    }
}

// render --stats of a shallow-water scene writes run --stats' swe block: the same volumes,
// substeps and balance as run on the same scene and frames (the same simulation), and a
// particle scene's is null as in run.
TEST_F(RenderCli, StatsOfASweRenderHaveRunsSweBlock) {
    REQUIRE_GL();
    const fs::path scene = dir_ / "swe.toml", rs = dir_ / "render.json", us = dir_ / "run.json";
    std::ofstream(scene) << "solver = \"swe\"\n\n[swe]\ndischarge = 5.0\nrain = 50.0\ninitial_level = 3.0\n";
    const std::string frames = " --frames 30 --no-progress --scene " + scene.string();
    CliResult r = run("render --size 64x40 --out " + (dir_ / "frames").string() + frames + " --stats " + rs.string());
    ASSERT_EQ(r.code, 0) << r.err;
    r = run("run" + frames + " --stats " + us.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto rendered = nlohmann::json::parse(slurp(rs))["swe"], ran = nlohmann::json::parse(slurp(us))["swe"];
    ASSERT_TRUE(rendered.is_object()) << rendered.dump();
    EXPECT_EQ(rendered["volume_m3"], ran["volume_m3"]);
    EXPECT_EQ(rendered["substeps"], ran["substeps"]);
    EXPECT_EQ(rendered["wet_cells"], ran["wet_cells"]);
    EXPECT_EQ(rendered["balance_error_m3"], ran["balance_error_m3"]);
    EXPECT_GT(rendered["volume_m3"]["inflow"].get<double>(), 0.0);
    EXPECT_LE(rendered["balance_error_relative"].get<double>(), 1e-5);
    EXPECT_GE(rendered["substeps_per_frame"]["mean"].get<double>(), 1.0);
    r = run("render --preset paper-bowl --frames 2 --size 32x32 --no-progress --out " + (dir_ / "p").string() +
            " --stats " + rs.string());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(nlohmann::json::parse(slurp(rs))["swe"].is_null());
}

TEST_F(RenderCli, Mp4WhenFfmpegIsThere) {
    REQUIRE_GL();
    if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0) MR_SKIP_OR_FAIL("ffmpeg is not installed");
    const fs::path out = dir_ / "river.mp4";
    const CliResult r = run("render --frames 6 --size 64x40 --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    ASSERT_TRUE(fs::exists(out));
    const std::string bytes = slurp(out);
    EXPECT_GT(bytes.size(), 100u);
    EXPECT_EQ(bytes.substr(4, 4), "ftyp") << "an MP4 file starts with an ftyp box";
    EXPECT_EQ(entries(dir_), 1u) << "no partial file left beside the video";
}

TEST_F(RenderCli, BadSizeFailsWithExitCode2AndWritesNothing) {
    const fs::path out = dir_ / "frames";
    for (const std::string size : {"0x10", "100", "abcxdef", "100x-5", "20000x100", "100x8"}) {
        const CliResult r = run("render --frames 2 --size " + size + " --out " + out.string());
        EXPECT_EQ(r.code, 2) << size << ": " << r.err;
        EXPECT_EQ(count_lines(r.err), 1) << r.err;
        EXPECT_NE(r.err.find("--size"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(out)) << size;
    }
}

TEST_F(RenderCli, UnwritableOutFailsWithExitCode2AndWritesNothing) {
    // A path under a regular file cannot be created, whoever runs the test (root too).
    const fs::path file = dir_ / "a_file";
    std::ofstream(file) << "x";
    const fs::path out = file / "frames";
    CliResult r = run("render --frames 2 --size 32x32 --out " + out.string());
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
    // --out naming an existing file.
    r = run("render --frames 2 --size 32x32 --out " + file.string());
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("not a folder"), std::string::npos) << r.err;
    // An MP4 in a folder that does not exist.
    r = run("render --frames 2 --size 32x32 --out " + (dir_ / "missing" / "v.mp4").string());
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    EXPECT_EQ(entries(dir_), 1u) << "only the test's own file";
}

TEST_F(RenderCli, Mp4WithoutFfmpegIsAClearError) {
    const fs::path out = dir_ / "v.mp4";
    const CliResult r = run("render --frames 2 --size 32x32 --out " + out.string(), "PATH=/nonexistent");
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("ffmpeg"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(RenderCli, OtherBadOptionsFailWithExitCode2) {
    for (const std::string args : {"--frames 0", "--camera 1,2", "--water glossy", "--preset nope", "--texture /nonexistent.png"}) {
        const CliResult r = run("render --size 32x32 --out " + (dir_ / "o").string() + " " + args);
        EXPECT_EQ(r.code, 2) << args << ": " << r.err;
        EXPECT_EQ(count_lines(r.err), 1) << r.err;
        EXPECT_FALSE(fs::exists(dir_ / "o")) << args;
    }
}

TEST_F(RenderCli, ViewWithoutDisplaySaysSoAndSuggestsRender) {
    const CliResult r = run("view", "env -u DISPLAY -u WAYLAND_DISPLAY");
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("no display"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("metariver render"), std::string::npos) << r.err;
}
