// End-to-end tests of `metariver run` with the shallow-water solver (solver = "swe") and
// the hybrid's grid: its --stats block (wet cells, volumes, mass balance, substeps, cell
// updates) and the hybrid's outflow by volume.
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

// The hybrid's run (the weir preset, 10 s): the grid's swe block is there, with the volume
// exchanged with the particles in its balance, and the plausibility's outflow is the water
// that left through the grid's edges (the particles leave none at sinks): about half the
// 3 m^3/s over the second half, as the swe block's own ratio says.
TEST_F(SweCli, StatsOfAHybridRunHaveItsGridsBlockAndItsOutflowByVolume) {
    const fs::path stats = dir_ / "h.json";
    CliResult r = run("run --preset weir --frames 600 --no-progress --stats " + stats.string());
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* word : {"swe: ", " exchanged with the particles", "hybrid: ", " of inflow over the second half"})
        EXPECT_NE(r.out.find(word), std::string::npos) << word << " in " << r.out;
    const auto j = nlohmann::json::parse(slurp(stats));
    ASSERT_EQ(j["solver"], "hybrid");
    ASSERT_TRUE(j["swe"].is_object()) << j.dump();
    const auto& s = j["swe"];
    const auto& v = s["volume_m3"];
    const auto& h = j["hybrid"];
    // What the grid gave and took back is the hybrid's hand-over, and the balance closes with it.
    EXPECT_LT(v["exchanged"].get<double>(), 0.0) << s.dump();
    EXPECT_NEAR(v["exchanged"].get<double>(), h["to_grid_m3"].get<double>() - h["to_particles_m3"].get<double>(), 1e-9);
    const double in = v["initial"].get<double>() + v["inflow"].get<double>() + v["rain"].get<double>();
    EXPECT_NEAR(in + v["exchanged"].get<double>() - v["outflow"].get<double>() - v["sunk"].get<double>(),
                v["stored"].get<double>(), 1e-9 * in);
    EXPECT_LE(s["balance_error_relative"].get<double>(), 1e-9) << s.dump();
    EXPECT_GT(s["wet_cells"].get<long long>(), 0);
    EXPECT_GE(s["substeps"].get<long long>(), 600);
    EXPECT_GE(s["substeps_per_frame"]["max"].get<double>(), 1.0);
    // The outflow: the grid's edges and sinks plus the particles lost since the start; the
    // rate and the ratio over the second half (5 s, 3 m^3/s in), the ratio as the swe block's.
    const auto& p = j["plausibility"];
    const double out = v["outflow"].get<double>() + v["sunk"].get<double>() + h["lost_m3"].get<double>();
    EXPECT_GT(out, 0.0) << s.dump();
    EXPECT_NEAR(p["outflow_m3"].get<double>(), out, 1e-12);
    EXPECT_GT(p["outflow_m3_per_s"].get<double>(), 0.5) << p.dump();
    EXPECT_LE(p["outflow_m3_per_s"].get<double>() * 5.0, out + 1e-9);
    EXPECT_GT(p["outflow_over_inflow"].get<double>(), 0.2) << p.dump();
    // Over the same half: the rate over the ratio is the inflow's rate, the source's 3 m^3/s
    // (the pour measured 30.7 m^3 in 10 s).
    EXPECT_NEAR(p["outflow_m3_per_s"].get<double>() / p["outflow_over_inflow"].get<double>(), 3.0, 0.15);
    EXPECT_NEAR(p["outflow_over_inflow"].get<double>(), s["outflow_over_inflow"].get<double>(), 1e-6);  // none lost
    EXPECT_GT(p["first_outflow_s"].get<double>(), 0.0);
    EXPECT_LE(p["first_outflow_s"].get<double>(), 10.0);
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
