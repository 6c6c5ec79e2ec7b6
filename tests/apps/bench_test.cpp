// End-to-end tests of `metariver bench`: the JSON it writes (keys the docs and the
// peers' side-by-side rely on), bad options (exit 2, one line), and --peers never
// crashing whether or not the peers are installed.
#include <gtest/gtest.h>
#include "cli_fixture.h"
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include "require.h"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

using BenchRun = mr::test::CliResult;
using mr::test::slurp;

class Bench : public mr::test::CliFixture {
protected:
    /// `metariver bench ARGS` from the source tree, as documented (drivers in bench/peers).
    BenchRun run(const std::string& args) {
        return CliFixture::run("bench " + args, "cd " + std::string(METARIVER_SOURCE_DIR) + " &&");
    }

    void expect_bad(const std::string& args, const std::string& must_contain) {
        const BenchRun r = run(args);
        EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
        EXPECT_NE(r.err.find(must_contain), std::string::npos) << args << ": '" << r.err << "'";
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
    }

};

TEST_F(Bench, W2JsonHasTheDocumentedKeys) {
    const fs::path out = dir_ / "bench.json";
    const BenchRun r = run("--scenario w2 --spheres 200 --json " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    ASSERT_TRUE(fs::exists(out));
    const json j = json::parse(slurp(out));
    ASSERT_TRUE(j.contains("machine"));
    EXPECT_TRUE(j["machine"].contains("cpu"));
    ASSERT_TRUE(j.contains("results"));
    ASSERT_EQ(j["results"].size(), 1u);
    const json& res = j["results"][0];
    for (const char* key : {"particles", "triangles", "threads", "stages"}) EXPECT_TRUE(res.contains(key)) << key;
    EXPECT_EQ(res["particles"].get<int>(), 200);
    EXPECT_GE(res["threads"].get<int>(), 1);
    ASSERT_TRUE(res["stages"].is_object());
    ASSERT_FALSE(res["stages"].empty());
    for (const auto& [stage, s] : res["stages"].items()) {
        ASSERT_TRUE(s.contains("median_ms")) << stage;
        EXPECT_GE(s["median_ms"].get<double>(), 0.0) << stage;
    }
    EXPECT_FALSE(j.contains("peers")) << "peers only with --peers";
    for (const char* key : {"tunneled", "guarded"}) EXPECT_TRUE(res["quality"].contains(key)) << key;
}

// The river scenario's quality: the guard beside tunneled, spray and settled speed (issue 9).
TEST_F(Bench, RiverQualityHasGuardedSprayAndFinalSpeed) {
    const fs::path out = dir_ / "bench.json";
    const BenchRun r = run("--scenario river --particles 1000 --frames 3 --json " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const json q = json::parse(slurp(out))["results"][0]["quality"];
    for (const char* key : {"tunneled", "guarded", "spray_fraction", "final_speed_p95"})
        ASSERT_TRUE(q.contains(key)) << key << " in " << q.dump();
    EXPECT_GE(q["spray_fraction"].get<double>(), 0.0);
    EXPECT_LE(q["spray_fraction"].get<double>(), 1.0);
    EXPECT_GT(q["final_speed_p95"].get<double>(), 0.0);  // 30 frames after the first emission: moving
    EXPECT_LE(q["final_speed_p95"].get<double>(), q["max_speed"].get<double>() * (1.0 + 1e-6));
    EXPECT_NE(r.out.find("\"guarded\""), std::string::npos) << "the table shows it too";
}

// Export cost by format (issue 15): a stage per format, the bytes beside.
TEST_F(Bench, ExportTimesEveryFormatWithItsSize) {
    const fs::path out = dir_ / "bench.json";
    const BenchRun r = run("--scenario export --particles 300 --frames 2 --json " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const json res = json::parse(slurp(out))["results"][0];
    ASSERT_FALSE(res.contains("note")) << res.dump();
    EXPECT_GT(res["particles"].get<int>(), 0);
    for (const char* format : {"obj", "ply", "glb", "vdb"}) {
        ASSERT_TRUE(res["stages"].contains(format)) << format << " in " << res["stages"].dump();
        EXPECT_EQ(res["stages"][format]["samples"].get<int>(), 2) << format;
        EXPECT_GT(res["stages"][format]["median_ms"].get<double>(), 0.0) << format;
        EXPECT_GT(res["quality"]["mb_per_frame"][format].get<double>(), 0.0) << format;
    }
    // Text OBJ is larger than the binary PLY of the same mesh and points.
    EXPECT_GT(res["quality"]["mb_per_frame"]["obj"].get<double>(), res["quality"]["mb_per_frame"]["ply"].get<double>());
}

// The PBF river (issue 12) at a tiny size: the stages, the plausibility beside them, the
// sizing in params, and the plot beside the JSON.
TEST_F(Bench, PbfRiverHasStagesPlausibilityAndAPlot) {
    const fs::path out = dir_ / "bench.json";
    const BenchRun r = run("--scenario pbf --particles 300 --warmup 120 --frames 3 --json " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const json j = json::parse(slurp(out));
    ASSERT_EQ(j["results"].size(), 1u);
    const json& res = j["results"][0];
    ASSERT_FALSE(res.contains("note") && res["note"].get<std::string>().rfind("skipped", 0) == 0) << res.dump();
    EXPECT_EQ(res["scenario"], "pbf 300");
    EXPECT_GT(res["particles"].get<int>(), 0);  // 2 s of flow: on its way, not all of it yet
    // foam: the river is the default scene's, which makes foam ([foam], issue 11).
    // smoothing: part of surface (the default's [surface] method laplacian; issue 11).
    for (const char* stage : {"simulate", "foam", "field", "surface", "smoothing", "total"}) {
        ASSERT_TRUE(res["stages"].contains(stage)) << stage;
        EXPECT_EQ(res["stages"][stage]["samples"].get<int>(), 3) << stage;
        EXPECT_GE(res["stages"][stage]["p95_ms"].get<double>(), res["stages"][stage]["median_ms"].get<double>()) << stage;
    }
    EXPECT_LE(res["stages"]["smoothing"]["median_ms"].get<double>(), res["stages"]["surface"]["median_ms"].get<double>());
    // The summary table's header has the column (its title line names smoothing too).
    bool column = false;
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);)
        column |= line.rfind("scenario", 0) == 0 && line.find("coverage") != std::string::npos &&
                  line.find(" smoothing ") != std::string::npos;
    EXPECT_TRUE(column) << "the summary table's smoothing column: " << r.out;
    for (const char* key : {"channel_coverage", "outflow_over_inflow", "spray_fraction", "tunneled", "guarded", "foam"})
        ASSERT_TRUE(res["quality"].contains(key)) << key;
    for (const char* kind : {"spray", "foam", "bubbles"}) EXPECT_TRUE(res["quality"]["foam"].contains(kind)) << kind;
    EXPECT_EQ(res["quality"]["tunneled"].get<int>(), 0);
    for (const char* key : {"spacing", "flow_rate", "target_particles", "warmup"}) EXPECT_TRUE(res["params"].contains(key)) << key;
    // 300 particles in steady flow: a coarser spacing than the default's 0.5 m.
    EXPECT_GT(res["params"]["spacing"].get<double>(), 0.5);
    const fs::path svg = dir_ / "bench.svg";
    ASSERT_TRUE(fs::exists(svg));
    EXPECT_EQ(j["plot"].get<std::string>(), svg.string());
    const std::string text = slurp(svg);
    EXPECT_EQ(text.rfind("<svg", 0), 0u);
    EXPECT_NE(text.find("PBF river total"), std::string::npos);
    EXPECT_NE(text.find("<polyline"), std::string::npos);
    EXPECT_NE(r.out.find("coverage"), std::string::npos) << "the summary table: " << r.out;
}

// W3 (the anchor's block) run by our solver, and with --peers the anchor beside it or
// one missing line; the plot gets our step.
TEST_F(Bench, W3StepAndAnchorOrMissingLine) {
    const fs::path out = dir_ / "bench.json";
    const BenchRun r = run("--scenario w3 --nx 8 --frames 3 --peers --json " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const json j = json::parse(slurp(out));
    const json& res = j["results"][0];
    EXPECT_EQ(res["scenario"], "w3 nx=8");
    EXPECT_EQ(res["particles"].get<int>(), 8 * 8 * 4);
    EXPECT_EQ(res["stages"]["step"]["samples"].get<int>(), 3);
    EXPECT_GT(res["stages"]["step"]["median_ms"].get<double>(), 0.0);
    EXPECT_NEAR(res["params"]["kernel_radius"].get<double>(), 0.2, 1e-6);
    const json& p = j["peers"];
    EXPECT_FALSE(p["rows"].empty() && p["missing"].empty());
    for (const json& row : p["rows"]) {
        EXPECT_EQ(row["workload"], "w3");
        EXPECT_EQ(row["n"].get<int>(), 256);
        EXPECT_GT(row["ratio_peer_over_ours"].get<double>(), 0.0);
        EXPECT_EQ(row["driver"]["particles"].get<int>(), 256) << "the anchor's block is ours";
    }
    EXPECT_TRUE(fs::exists(dir_ / "bench.svg"));
}

// --gpu: the GPU step (gpu_pbf.h) on the same block beside our CPU step, or a skipped
// row naming why where no headless OpenGL is to be had; the plot gets a GPU series.
TEST_F(Bench, W3OnTheGpuBesideTheCpu) {
    const fs::path out = dir_ / "bench.json";
    const BenchRun r = run("--scenario w3 --gpu --nx 8 --frames 3 --json " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const json res = json::parse(slurp(out))["results"];
    ASSERT_EQ(res.size(), 2u);
    EXPECT_EQ(res[0]["scenario"], "w3 nx=8");
    EXPECT_EQ(res[1]["scenario"], "w3-gpu nx=8");
    if (res[1].contains("note") && res[1]["note"].get<std::string>().rfind("skipped", 0) == 0)
        MR_SKIP_OR_FAIL(res[1]["note"]);
    EXPECT_EQ(res[1]["particles"].get<int>(), 8 * 8 * 4);
    EXPECT_EQ(res[1]["stages"]["step"]["samples"].get<int>(), 3);
    EXPECT_GT(res[1]["stages"]["step"]["median_ms"].get<double>(), 0.0);
    EXPECT_FALSE(res[1]["params"]["device"].get<std::string>().empty());
    // The same block and step: the density error agrees with the CPU's to rounding.
    EXPECT_NEAR(res[1]["quality"]["density_error_max"].get<double>(),
                res[0]["quality"]["density_error_max"].get<double>(), 1e-5);
    EXPECT_NE(slurp(dir_ / "bench.svg").find("GPU"), std::string::npos);
    // EGL's device platform (the path NVIDIA's EGL takes) gives the same step.
    const fs::path out2 = dir_ / "device.json";
    const BenchRun d = CliFixture::run("bench --scenario w3 --gpu --nx 8 --frames 3 --json " + out2.string(),
                                       "cd " + std::string(METARIVER_SOURCE_DIR) + " && METARIVER_EGL_PLATFORM=device");
    ASSERT_EQ(d.code, 0) << d.err;
    const json res2 = json::parse(slurp(out2))["results"];
    ASSERT_EQ(res2.size(), 2u);
    EXPECT_FALSE(res2[1].contains("note")) << res2[1]["note"];
    EXPECT_EQ(res2[1]["quality"]["density_error_max"], res[1]["quality"]["density_error_max"]);
    // Beyond the CPU's sizes the GPU row runs alone.
    expect_bad("--scenario w3 --gpu --nx 251", "--nx: must be in [4, 250] with --gpu");
}

// --gpu on W1: the field by the GPU beside ours, its samples checked against ours.
TEST_F(Bench, W1FieldOnTheGpuBesideTheCpu) {
    const fs::path out = dir_ / "bench.json";
    const BenchRun r = run("--scenario w1 --gpu --balls 200 --res 32 --frames 2 --json " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const json res = json::parse(slurp(out))["results"];
    ASSERT_EQ(res.size(), 2u);
    EXPECT_EQ(res[0]["scenario"], "w1 N=200 R=32");
    EXPECT_EQ(res[1]["scenario"], "w1-gpu N=200 R=32");
    if (res[1].contains("note") && res[1]["note"].get<std::string>().rfind("skipped", 0) == 0)
        MR_SKIP_OR_FAIL(res[1]["note"]);
    EXPECT_EQ(res[1]["stages"]["field"]["samples"].get<int>(), 2);
    EXPECT_GT(res[1]["stages"]["field"]["median_ms"].get<double>(), 0.0);
    EXPECT_LT(res[1]["quality"]["max_relative_difference_vs_cpu"].get<double>(), 1e-5);
}

// Scenario maps (issue 10's frame budget): the default river on each --heightmap, one
// row each with its stages (surface on) and the river's plausibility.
TEST_F(Bench, MapsRunTheDefaultRiverOnEachHeightmap) {
    const fs::path out = dir_ / "bench.json";
    const std::string maps = "../shared/heightmaps/metawater";
    if (!fs::exists(fs::path(METARIVER_SOURCE_DIR) / maps / "nile.png")) MR_SKIP_OR_FAIL(maps << " not there");
    const BenchRun r = run("--heightmap " + maps + "/nile.png," + maps + "/strict17.png --warmup 30 --frames 3 --json " +
                           out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const json res = json::parse(slurp(out))["results"];
    ASSERT_EQ(res.size(), 2u) << "--heightmap alone runs only the maps";
    EXPECT_EQ(res[0]["scenario"].get<std::string>(), "default on nile.png");
    EXPECT_EQ(res[1]["scenario"].get<std::string>(), "default on strict17.png");
    for (const json& row : res) {
        ASSERT_FALSE(row.contains("note")) << row.dump();
        EXPECT_GT(row["particles"].get<int>(), 0);
        EXPECT_GT(row["triangles"].get<int>(), 0) << "surface on";
        for (const char* stage : {"simulate", "field", "surface", "total"})
            EXPECT_EQ(row["stages"][stage]["samples"].get<int>(), 3) << stage;
        for (const char* key : {"channel_coverage", "outflow_over_inflow", "spray_fraction", "tunneled"})
            EXPECT_TRUE(row["quality"].contains(key)) << key;
    }
}

TEST_F(Bench, MapsRefuseAMissingOrBrokenHeightmapBeforeRunning) {
    expect_bad("--heightmap " + (dir_ / "none.png").string(), "none.png: no such file");
    std::ofstream(dir_ / "broken.png", std::ios::binary) << "\x89PNG\r\n\x1a\nbroken";
    expect_bad("--heightmap " + (dir_ / "broken.png").string(), "broken.png");
    expect_bad("--scenario maps", "needs --heightmap");
    expect_bad("--scenario w1 --heightmap " + (dir_ / "none.png").string(), "only for scenario maps");
}

TEST_F(Bench, BadSizesNameTheOptionAndTheRange) {
    expect_bad("--scenario pbf --particles 0", "--particles");
    expect_bad("--scenario pbf --particles 0", "[100, 400000]");
    expect_bad("--scenario pbf --particles 99999999", "[100, 400000]");
    expect_bad("--scenario w3 --nx 0", "--nx: must be in [4, 100]");
    expect_bad("--scenario w3 --nx 1000", "--nx: must be in [4, 100]");
    expect_bad("--scenario river --particles 0", "--particles in [1,");
    expect_bad("--scenario w3 --warmup -5", "--warmup");
}

TEST_F(Bench, BadOptionsExitTwoWithOneLine) {
    expect_bad("--scenario nope", "--scenario");
    expect_bad("--balls -1", "--balls");
    const fs::path missing = dir_ / "no-such-folder" / "bench.json";
    expect_bad("--scenario w2 --spheres 10 --json " + missing.string(), "no-such-folder");
    EXPECT_FALSE(fs::exists(dir_ / "no-such-folder"));
}

// --peers on a small W2: the Bullet driver (built with the bench when Bullet is there)
// runs, or its absence is one line under "missing"; either way no crash, exit 0.
TEST_F(Bench, PeersW2RowsOrMissingLines) {
    const fs::path out = dir_ / "bench.json";
    const BenchRun r = run("--scenario w2 --spheres 200 --peers --json " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const json j = json::parse(slurp(out));
    ASSERT_TRUE(j.contains("peers"));
    const json& p = j["peers"];
    ASSERT_TRUE(p.contains("rows") && p.contains("missing"));
    EXPECT_FALSE(p["rows"].empty() && p["missing"].empty());
    for (const json& row : p["rows"]) {
        EXPECT_EQ(row["workload"], "w2");
        EXPECT_EQ(row["n"].get<int>(), 200);
        EXPECT_GT(row["median_ms"].get<double>(), 0.0);
        EXPECT_GT(row["ours_ms"].get<double>(), 0.0);
        EXPECT_GT(row["ratio_peer_over_ours"].get<double>(), 0.0);
        EXPECT_EQ(row["driver"]["tunneled_below_surface"].get<int>(), 0);
    }
    EXPECT_NE(r.out.find("peers:"), std::string::npos) << r.out;
}

}  // namespace
