// End-to-end tests of `metariver run` with the shallow-water solver (solver = "swe"):
// its --stats block (wet cells, volumes, mass balance, substeps, cell updates).
#include <gtest/gtest.h>
#include "cli_fixture.h"
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;

namespace {

using mr::test::CliResult;
using mr::test::slurp;

class SweCli : public mr::test::CliFixture {
protected:
    /// A swe scene on the default valley: a source at the head of the main channel, rain
    /// over the map and a lake up to `level` metres at the start.
    fs::path swe_scene(const std::string& level) {
        const fs::path p = dir_ / "swe.toml";
        std::ofstream(p) << "solver = \"swe\"\n\n[swe]\ndischarge = 5.0\nrain = 50.0\ninitial_level = " << level << "\n";
        return p;
    }
};

// 120 frames (2 s): every counter of the swe block is there and non-zero, and what came in
// (the lake, the source, the rain) equals what left plus what is stored to 1e-5 of it.
TEST_F(SweCli, StatsHaveTheMassBalanceAndCounters) {
    const fs::path stats = dir_ / "s.json";
    CliResult r = run("run --scene " + swe_scene("3.0").string() + " --frames 120 --no-progress --stats " +
                      stats.string());
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* word : {"swe: ", " wet cells", "balance error ", " substeps a frame", "cell updates/s"})
        EXPECT_NE(r.out.find(word), std::string::npos) << word << " in " << r.out;
    const auto j = nlohmann::json::parse(slurp(stats));
    ASSERT_EQ(j["solver"], "swe");
    ASSERT_TRUE(j["swe"].is_object()) << j.dump();
    const auto& s = j["swe"];
    const auto& v = s["volume_m3"];
    for (const char* key : {"initial", "inflow", "rain", "outflow", "stored"})
        EXPECT_GT(v[key].get<double>(), 0.0) << key << " in " << s.dump();
    EXPECT_NEAR(v["inflow"].get<double>(), 5.0 * 2.0, 1e-5);  // 5 m^3/s over 120 frames of 1/60 s
    const double in = v["initial"].get<double>() + v["inflow"].get<double>() + v["rain"].get<double>();
    const double error = in - v["outflow"].get<double>() - v["stored"].get<double>();
    EXPECT_NEAR(s["balance_error_m3"].get<double>(), error, 1e-9 * in);
    EXPECT_LE(s["balance_error_relative"].get<double>(), 1e-5) << s.dump();
    EXPECT_GT(s["wet_cells"].get<long long>(), 0);
    EXPECT_LT(s["wet_cells"].get<long long>(), s["grid"]["rows"].get<long long>() * s["grid"]["columns"].get<long long>());
    EXPECT_GE(s["substeps"].get<long long>(), 120);  // at least one a frame
    EXPECT_GE(s["substeps_per_frame"]["mean"].get<double>(), 1.0);
    EXPECT_GE(s["substeps_per_frame"]["max"].get<double>(), s["substeps_per_frame"]["mean"].get<double>());
    EXPECT_GT(s["cell_updates"].get<long long>(), 0);
    EXPECT_GT(s["cell_updates_per_s"].get<double>(), 0.0);
}

// A particle solver's stats have no swe block.
TEST_F(SweCli, StatsOfAParticleRunHaveNoSweBlock) {
    const fs::path stats = dir_ / "s.json";
    CliResult r = run("run --preset paper-bowl --frames 2 --no-progress --stats " + stats.string());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(nlohmann::json::parse(slurp(stats))["swe"].is_null());
    EXPECT_EQ(r.out.find("swe: "), std::string::npos) << r.out;
}

}  // namespace
