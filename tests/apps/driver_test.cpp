// The lifecycle the commands share (apps/metariver/driver.h): it steps exactly what it
// says (the same particles as a Simulation stepped by hand), a failure takes back what
// the command wrote and leaves what was there, finish() keeps the outputs and writes the
// stats, and errors carry the exit code and the option's name.
#include "driver.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace mr::app {
namespace {

class AppDriver : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               fmt::format("metariver-driver-{}-{}", ::getpid(),
                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    /// paper-bowl (springs, 20 particles one every 20 frames): small and quick.
    static SceneOptions bowl() {
        SceneOptions o;
        o.preset = "paper-bowl";
        o.seed = 3;
        return o;
    }
    static void touch(const fs::path& p) { std::ofstream(p) << "x"; }

    fs::path dir_;
};

TEST_F(AppDriver, StepsWarmupPlusFramesTimesStepsLikeASimulationSteppedByHand) {
    Driver d({.command = "test", .frames = 7, .steps = 3, .warmup = 5, .dt = 1.0 / 50.0, .quiet = true});
    ASSERT_TRUE(d.resolve(bowl()) && d.create()) << d.error();
    d.warm_up();
    std::vector<long long> seen;
    ASSERT_TRUE(d.loop([&](long long f) {
        seen.push_back(f);
        EXPECT_EQ(d.sim().frame(), static_cast<uint64_t>(d.steps_done(f))) << "the frame's steps come before its work";
        return true;
    }));
    EXPECT_EQ(seen, (std::vector<long long>{0, 1, 2, 3, 4, 5, 6}));
    EXPECT_EQ(d.steps_done(6), 5 + 7 * 3);
    EXPECT_DOUBLE_EQ(d.time_s(6), 26.0 / 50.0);
    EXPECT_EQ(d.stage_ms().fed(), 7u);
    for (double ms : d.stage_ms().column(kStageStepWall)) EXPECT_GE(ms, 0.0);
    for (double ms : d.stage_ms().column(kStageExport)) EXPECT_EQ(ms, 0.0) << "no export";

    auto by_hand = Simulation::create(bowl().resolve().value());
    ASSERT_TRUE(by_hand) << by_hand.error().message;
    for (int i = 0; i < 26; ++i) by_hand.value()->step(static_cast<float>(1.0 / 50.0));
    EXPECT_EQ(d.sim().state_hash(), by_hand.value()->state_hash());
}

TEST_F(AppDriver, AFailureInTheLoopStopsItAndTakesBackWhatTheCommandWrote) {
    const fs::path existing = dir_ / "existing", created = dir_ / "created";
    fs::create_directories(existing);
    touch(existing / "users.txt");
    {
        Driver d({.command = "test", .frames = 10, .quiet = true});
        ASSERT_TRUE(d.resolve(bowl()) && d.create());
        ASSERT_TRUE(d.outputs().make_folder("--out", existing.string())) << "an existing folder is fine";
        ASSERT_TRUE(d.outputs().make_folder("--out", (created / "sub").string()));
        long long last = -1;
        const bool ok = d.loop([&](long long f) {
            last = f;
            const fs::path a = existing / fmt::format("a{}", f), b = created / "sub" / fmt::format("b{}", f);
            touch(a);
            touch(b);
            d.outputs().add_file(a.string());
            d.outputs().add_file(b.string());
            return f < 3 ? true : d.stop(kExitFailure, fmt::format("frame {} failed", f));
        });
        EXPECT_FALSE(ok);
        EXPECT_EQ(last, 3) << "no frame after the failure";
        EXPECT_EQ(d.exit_code(), kExitFailure);
        EXPECT_EQ(d.error(), "frame 3 failed");
        EXPECT_EQ(d.stage_ms().fed(), 3u) << "the failed frame is not timed";
    }
    EXPECT_FALSE(fs::exists(created / "sub")) << "the folders it made go with what is in them";
    std::vector<std::string> left;
    for (const auto& e : fs::directory_iterator(existing)) left.push_back(e.path().filename().string());
    EXPECT_EQ(left, std::vector<std::string>{"users.txt"}) << "the folder that was there stays, with the user's file";
}

TEST_F(AppDriver, FinishWritesTheStatsAndKeepsTheOutputs) {
    const fs::path stats = dir_ / "s.json", kept = dir_ / "frame.txt";
    {
        Driver d({.command = "test", .frames = 4, .stats = stats.string(), .quiet = true});
        ASSERT_TRUE(d.resolve(bowl()) && d.create() && d.check_stats());
        ASSERT_TRUE(d.loop([&](long long) { return true; }));
        touch(kept);
        d.outputs().add_file(kept.string());
        ASSERT_TRUE(d.finish([&] { return nlohmann::json{{"frames", d.stage_ms().fed()}}; }));
    }
    ASSERT_TRUE(fs::exists(stats));
    std::ifstream in(stats);
    EXPECT_EQ(nlohmann::json::parse(in)["frames"], 4);
    EXPECT_TRUE(fs::exists(kept)) << "finished: the outputs stay";
}

TEST_F(AppDriver, WithoutFinishTheOutputsGoWhenTheDriverDoes) {
    const fs::path made = dir_ / "made";
    {
        Driver d({.command = "test", .quiet = true});
        ASSERT_TRUE(d.outputs().make_folder("--obj-dir", made.string()));
        touch(made / "f.obj");
        d.outputs().add_file((made / "f.obj").string());
    }  // e.g. an exception out of the command
    EXPECT_FALSE(fs::exists(made));
}

TEST_F(AppDriver, ErrorsCarryTheExitCodeAndNameTheOption) {
    {
        SceneOptions bad;
        bad.preset = "no-such-preset";
        Driver d({.command = "test", .quiet = true});
        EXPECT_FALSE(d.resolve(bad));
        EXPECT_EQ(d.exit_code(), kExitBadInput);
        EXPECT_NE(d.error().find("no-such-preset"), std::string::npos) << d.error();
    }
    {
        Driver d({.command = "test", .stats = dir_.string(), .quiet = true});
        EXPECT_FALSE(d.check_stats());
        EXPECT_EQ(d.exit_code(), kExitBadInput);
        EXPECT_NE(d.error().find("--stats " + dir_.string() + ": is a folder"), std::string::npos) << d.error();
    }
    {
        touch(dir_ / "file");
        Outputs out;
        const Status s = out.make_folder("--out", (dir_ / "file").string());
        ASSERT_FALSE(s);
        EXPECT_EQ(s.error().message, "--out " + (dir_ / "file").string() + ": exists and is not a folder");
    }
    EXPECT_EQ(range_error("--frames", 0, 1, 10), "--frames: must be in [1, 10] (got 0)");
    EXPECT_EQ(range_error("--frames", 10, 1, 10), "");
    EXPECT_EQ(dt_error(0.0), "--dt: must be in (0, 1] seconds (got 0)");
    EXPECT_EQ(dt_error(1.0), "");
}

TEST_F(AppDriver, AFailurePrintsOneLineNamingTheCommandUnlessQuiet) {
    Driver d({.command = "render"});
    ::testing::internal::CaptureStderr();
    EXPECT_EQ(d.fail(kExitBadInput, "--size: bad"), kExitBadInput);
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "metariver render: --size: bad\n");
    Driver q({.command = "bench", .quiet = true});
    ::testing::internal::CaptureStderr();
    q.fail(kExitFailure, "skipped");
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

TEST_F(AppDriver, TheExportRunsAtOneFramePerStepsTimesDt) {
    Driver d({.command = "test", .frames = 12, .steps = 4, .dt = 1.0 / 80.0, .quiet = true});
    ASSERT_TRUE(d.resolve(bowl()));
    ExportOptions exp;
    exp.dir = (dir_ / "exp").string();
    exp.every = 5;
    auto e = d.export_def(exp, 12);
    ASSERT_TRUE(e) << e.error().message;
    EXPECT_DOUBLE_EQ(e->frame_rate, 20.0);
    EXPECT_DOUBLE_EQ(e->solver_dt, 1.0 / 80.0);
    ASSERT_TRUE(d.resolve_export(exp) && d.create() && d.begin_export()) << d.error();
    ASSERT_TRUE(d.loop([](long long) { return true; }));
    ASSERT_NE(d.exporter(), nullptr);
    std::vector<long long> frames;
    for (const ExportedFrame& f : d.exporter()->frames()) frames.push_back(f.frame);
    EXPECT_EQ(frames, (std::vector<long long>{0, 5, 10})) << "the frames --every 5 asks for";
    const std::vector<double> export_ms = d.stage_ms().column(kStageExport);
    EXPECT_GT(export_ms[0], 0.0);
    EXPECT_EQ(export_ms[1], 0.0) << "frame 1 is not due";
    ASSERT_TRUE(d.finish([] { return nlohmann::json(); }));
    EXPECT_TRUE(fs::exists(dir_ / "exp" / "export.json"));
}

}  // namespace
}  // namespace mr::app
