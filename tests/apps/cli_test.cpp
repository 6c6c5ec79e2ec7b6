// End-to-end tests of the metariver binary: good runs and every kind of bad input
// (exit code 2, one line naming the file/option/key, nothing written).
#include <metariver/io.h>
#include <metariver/terrain.h>

#include <gtest/gtest.h>
#include "cli_fixture.h"
#include "png_test_util.h"
#include <nlohmann/json.hpp>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <vector>
#include "require.h"

namespace fs = std::filesystem;

namespace {

using mr::test::CliResult;
using mr::test::slurp;

class Cli : public mr::test::CliFixture {
protected:
    fs::path write(const std::string& name, const std::string& bytes) {
        const fs::path p = dir_ / name;
        std::ofstream(p, std::ios::binary) << bytes;
        return p;
    }

    /// Files left in the test folder (the command must not leave partial output).
    size_t files_left() const {
        size_t n = 0;
        for (const auto& e : fs::recursive_directory_iterator(dir_)) n += e.is_regular_file() || e.is_directory();
        return n;
    }

    /// Runs a bad command: exit 2, one line on stderr naming `must_contain`, and
    /// neither the stats file nor the OBJ folder appear.
    void expect_bad(const std::string& args, const std::string& must_contain) {
        const size_t before = files_left();
        const std::string outputs = " --stats " + (dir_ / "s.json").string() + " --obj-dir " + (dir_ / "objs").string();
        CliResult r = run(args + outputs);
        EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
        EXPECT_NE(r.err.find(must_contain), std::string::npos) << args << ": '" << r.err << "'";
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
        EXPECT_FALSE(fs::exists(dir_ / "s.json")) << args;
        EXPECT_FALSE(fs::exists(dir_ / "objs")) << args;
        EXPECT_EQ(files_left(), before) << args;
    }

};

std::string shared_map(const char* name) {
    return std::string(METARIVER_SHARED_DIR) + "/heightmaps/metawater/" + name;
}

TEST_F(Cli, RunWritesStatsAndObjs) {
    const fs::path stats = dir_ / "s.json", objs = dir_ / "objs";
    CliResult r = run("run --preset paper-bowl --frames 40 --seed 3 --stats " + stats.string() + " --obj-dir " +
                      objs.string());
    ASSERT_EQ(r.code, 0) << r.err;
    auto j = nlohmann::json::parse(slurp(stats));
    EXPECT_EQ(j["frames"], 40);
    EXPECT_EQ(j["particles_active"], 2);  // interval 20: frames 0 and 20
    for (const char* key : {"triangles", "vertices", "tunneled", "respawned", "particles_active"})
        EXPECT_TRUE(j.contains(key)) << key;
    for (const char* stage : {"simulate", "field", "surface"}) {
        EXPECT_TRUE(j["stage_ms"][stage].contains("median")) << stage;
        EXPECT_TRUE(j["stage_ms"][stage].contains("p95")) << stage;
        EXPECT_GE(j["stage_ms"][stage]["p95"].get<double>(), j["stage_ms"][stage]["median"].get<double>());
    }
    EXPECT_GT(j["triangles"].get<int>(), 0);
    size_t obj_files = 0;
    for (const auto& e : fs::directory_iterator(objs)) obj_files += e.path().extension() == ".obj";
    EXPECT_EQ(obj_files, 41u);  // terrain + 40 frames
    EXPECT_NE(slurp(objs / "terrain.obj").find("f 1//1"), std::string::npos);
    // Last frame's OBJ has the triangle count the stats report.
    const std::string last = slurp(objs / "surface_00039.obj");
    size_t faces = 0;
    std::istringstream lines(last);
    for (std::string line; std::getline(lines, line);) faces += line.rfind("f ", 0) == 0;
    EXPECT_EQ(faces, j["triangles"].get<size_t>());
}

TEST_F(Cli, RunStatsCountFoamWhereTheSceneMakesIt) {
    // The default river makes foam ([foam], issue 11): counts, the potentials and a stage.
    const fs::path stats = dir_ / "f.json";
    CliResult r = run("run --frames 90 --no-progress --stats " + stats.string());
    ASSERT_EQ(r.code, 0) << r.err;
    auto j = nlohmann::json::parse(slurp(stats));
    ASSERT_TRUE(j["foam"].is_object()) << j["foam"].dump();
    const auto& f = j["foam"];
    for (const char* key : {"spray", "foam", "bubbles", "total", "max_particles", "generated_total", "capped_total"})
        EXPECT_TRUE(f.contains(key)) << key;
    EXPECT_EQ(f["total"].get<size_t>(), f["spray"].get<size_t>() + f["foam"].get<size_t>() + f["bubbles"].get<size_t>());
    EXPECT_LE(f["total"].get<int>(), f["max_particles"].get<int>());
    for (const char* p : {"trapped_air", "wave_crest", "kinetic_energy"}) EXPECT_TRUE(f["potentials"][p].contains("p95")) << p;
    EXPECT_TRUE(j["stage_ms"]["foam"].contains("median"));
    // Its surface is smoothed: the smoothing's share of the surface stage (issue 11).
    ASSERT_TRUE(j["stage_ms"].contains("smoothing"));
    EXPECT_GT(j["stage_ms"]["smoothing"]["median"].get<double>(), 0.0);
    EXPECT_LE(j["stage_ms"]["smoothing"]["median"].get<double>(), j["stage_ms"]["surface"]["median"].get<double>());
    // The paper's scenes (springs) make none: null, and no foam stage; their surface is
    // not smoothed (method none): no smoothing stage.
    CliResult p = run("run --preset paper-bowl --frames 5 --no-progress --stats " + stats.string());
    ASSERT_EQ(p.code, 0) << p.err;
    j = nlohmann::json::parse(slurp(stats));
    EXPECT_TRUE(j["foam"].is_null());
    EXPECT_FALSE(j["stage_ms"].contains("foam"));
    EXPECT_FALSE(j["stage_ms"].contains("smoothing"));
}

TEST_F(Cli, RunObjEveryWritesEveryNthAndTheLastFrame) {
    const fs::path objs = dir_ / "objs";
    CliResult r = run("run --preset paper-bowl --frames 12 --obj-every 5 --obj-dir " + objs.string());
    ASSERT_EQ(r.code, 0) << r.err;
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(objs)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    const std::vector<std::string> want{"surface_00000.obj", "surface_00005.obj", "surface_00010.obj",
                                        "surface_00011.obj", "terrain.obj"};
    EXPECT_EQ(names, want);
    EXPECT_NE(r.out.find("wrote 5 OBJ files"), std::string::npos) << r.out;
}

TEST_F(Cli, AHeightmapThatIsNotARegularFileIsRefusedAtOnce) {
    // Issue 13: a FIFO hung `run` forever (it was read before anything checked it).
    const fs::path fifo = dir_ / "map.png";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    expect_bad("run --frames 1 --heightmap " + fifo.string(), "not a regular file");
    fs::remove(fifo);
}

TEST_F(Cli, BadObjEvery) {
    for (const char* bad : {"0", "-5", "1000000001"})
        expect_bad(std::string("run --frames 3 --obj-every ") + bad, "--obj-every: must be in [1, 1000000000]");
    expect_bad("run --frames 3 --obj-every often", "--obj-every");
    expect_bad("run --frames 3 --obj-every 99999999999999999999", "--obj-every");
    // Without a folder to write to.
    const fs::path stats = dir_ / "s.json";
    CliResult r = run("run --frames 3 --obj-every 2 --stats " + stats.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("--obj-every"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("--obj-dir"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(stats));
}

TEST_F(Cli, StatsHaveFinalSpeedSprayAndGuarded) {
    const fs::path stats = dir_ / "s.json";
    CliResult r = run("run --preset paper-bowl --frames 60 --seed 3 --stats " + stats.string());
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* word : {"guarded ", "spray ", "final speed p95 "})
        EXPECT_NE(r.out.find(word), std::string::npos) << word << " in " << r.out;
    const auto j = nlohmann::json::parse(slurp(stats));
    const auto& pl = j["plausibility"];
    ASSERT_TRUE(pl.contains("final_speed") && pl.contains("spray_fraction") && pl.contains("guarded")) << pl.dump();
    EXPECT_EQ(pl["guarded"], j["guarded"]);
    const double median = pl["final_speed"]["median"], p95 = pl["final_speed"]["p95"], max = pl["final_speed"]["max"];
    EXPECT_GT(median, 0.0);  // three particles falling or sliding in the bowl
    EXPECT_LE(median, p95);
    EXPECT_LE(p95, max);
    EXPECT_LE(max, pl["max_speed"].get<double>() * (1.0 + 1e-6));  // the last frame is one of the frames
    const double spray = pl["spray_fraction"];
    EXPECT_GE(spray, 0.0);
    EXPECT_LE(spray, 1.0);
}

// The default river on the valley for 360 frames (6 s): the outlet keys, consistent with
// each other and with the sink counter.
TEST_F(Cli, StatsHaveOutletsCoverageAndOutflowOverInflow) {
    const fs::path stats = dir_ / "s.json";
    CliResult r = run("run --frames 360 --stats " + stats.string());
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* word : {"main outlet ", " of inflow", "channel coverage "})
        EXPECT_NE(r.out.find(word), std::string::npos) << word << " in " << r.out;
    const auto all = nlohmann::json::parse(slurp(stats));
    const auto pl = all["plausibility"];
    for (const char* key : {"outlets", "outlet_other", "outflow_over_inflow", "time_to_outlet_s", "channel_coverage",
                            "main_channel_cells", "wet_channel_fraction"})
        ASSERT_TRUE(pl.contains(key)) << key << " in " << pl.dump();
    ASSERT_TRUE(pl["outlets"].is_array() && !pl["outlets"].empty()) << pl.dump();
    int mains = 0;
    uint64_t particles = pl["outlet_other"]["particles"].get<uint64_t>();
    double main_rate = 0.0;
    uint64_t main_particles = 0;
    for (const auto& o : pl["outlets"]) {
        ASSERT_TRUE(o.contains("cell") && o.contains("position") && o.contains("particles") && o.contains("rate_per_s"))
            << o.dump();
        EXPECT_EQ(o["cell"].size(), 2u);
        EXPECT_EQ(o["position"].size(), 2u);
        EXPECT_GE(o["rate_per_s"].get<double>(), 0.0);
        particles += o["particles"].get<uint64_t>();
        if (o["main"].get<bool>()) {
            ++mains;
            main_rate = o["rate_per_s"];
            main_particles = o["particles"];
        }
    }
    EXPECT_EQ(mains, 1);
    EXPECT_EQ(particles, pl["sunk"].get<uint64_t>()) << "every particle the edges took is at an outlet or other";
    EXPECT_GT(pl["main_channel_cells"].get<int>(), 20);
    const double coverage = pl["channel_coverage"];
    EXPECT_GT(coverage, 0.0) << "the source sits on the main channel";
    EXPECT_LE(coverage, 1.0);
    // Over the source's nominal rate (the default river sizes it: sizing.flow_rate). The
    // carved channel starts full (particles.prefill), so its water leaves within 6 s.
    const double nominal = all["sizing"]["flow_rate"];
    ASSERT_GT(nominal, 0.0);
    EXPECT_GT(main_rate, 0.0) << "nothing left through the main outlet in 6 s";
    EXPECT_NEAR(pl["outflow_over_inflow"].get<double>(), main_rate / nominal, 1e-9);
    const double first = pl["time_to_outlet_s"];
    EXPECT_TRUE(first == -1.0 || (first > 0.0 && first <= 6.0 + 1e-9)) << first;
    EXPECT_EQ(first > 0.0, main_particles > 0);
}

// Two particles falling far above flat ground: both isolated and airborne at every
// sampled frame (spray 1), and after 30 frames of free fall both move at g t.
TEST_F(Cli, StatsOfAFreeFall) {
    const fs::path scene = write("fall.toml", R"(solver = "springs"
surface = false
[terrain]
source = "flat"
width = 9
height = 9
[particles]
count = 2
spawn_center = [4.0, 200.0, 4.0]
spawn_half_extent = [3.0, 0.0, 3.0]
spawn_interval = 0
initial_velocity = [0.0, 0.0, 0.0]
flow_rate = 0.0
[sink]
kind = "none"
[springs]
stiffness = 0.0
[forces]
gravity = 9.82
)");
    const fs::path stats = dir_ / "s.json";
    CliResult r = run("run --scene " + scene.string() + " --frames 30 --stats " + stats.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto pl = nlohmann::json::parse(slurp(stats))["plausibility"];
    EXPECT_EQ(pl["spray_fraction"].get<double>(), 1.0);
    EXPECT_NEAR(pl["final_speed"]["median"].get<double>(), 9.82 * 30.0 / 60.0, 0.05) << pl.dump();
    EXPECT_NEAR(pl["final_speed"]["max"].get<double>(), 9.82 * 30.0 / 60.0, 0.05) << pl.dump();
}

TEST_F(Cli, RunIsDeterministicForASeed) {
    auto hash = [&](const std::string& seed) {
        const fs::path stats = dir_ / ("h" + seed + ".json");
        CliResult r = run("run --preset paper-bowl --frames 60 --seed " + seed + " --stats " + stats.string());
        EXPECT_EQ(r.code, 0) << r.err;
        return nlohmann::json::parse(slurp(stats))["state_hash"].get<std::string>();
    };
    EXPECT_EQ(hash("5"), hash("5"));
    EXPECT_NE(hash("5"), hash("6"));
}

TEST_F(Cli, PaperNileWithTheRealHeightmap) {
    if (!fs::exists(shared_map("nile.png"))) MR_SKIP_OR_FAIL("no " << shared_map("nile.png"));
    const fs::path stats = dir_ / "s.json";
    CliResult r = run("run --preset paper-nile --heightmap " + shared_map("nile.png") + " --frames 800 --stats " +
                      stats.string());
    ASSERT_EQ(r.code, 0) << r.err;
    auto j = nlohmann::json::parse(slurp(stats));
    EXPECT_EQ(j["particles_active"], 50);  // 15-frame interval: all 50 by frame 735
    EXPECT_GT(j["triangles"].get<int>(), 0);
    EXPECT_GT(j["vertices"].get<int>(), 0);
}

TEST_F(Cli, BadHeightmaps) {
    expect_bad("run --heightmap " + (dir_ / "missing.png").string(), "missing.png");
    expect_bad("run --heightmap " + write("empty.png", "").string(), "empty.png");
    expect_bad("run --heightmap " + write("text.png", "this is not an image\n").string(), "text.png");
    // A truncated PNG: the signature and a cut-off header chunk.
    expect_bad("run --heightmap " + write("trunc.png", std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0", 18)).string(),
               "trunc.png");
    if (mr::test::have_file(shared_map("nile.png"))) {
        const std::string full = slurp(shared_map("nile.png"));
        expect_bad("run --heightmap " + write("half.png", full.substr(0, full.size() / 2)).string(), "half.png");
    }
    // A valid 1x1 gray PNG (generated with Python zlib/struct).
    const std::string one_by_one(
        "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52"
        "\x00\x00\x00\x01\x00\x00\x00\x01\x08\x00\x00\x00\x00\x3a\x7e\x9b"
        "\x55\x00\x00\x00\x0a\x49\x44\x41\x54\x78\x9c\x63\x68\x00\x00\x00"
        "\x82\x00\x81\x77\xcd\x72\xb6\x00\x00\x00\x00\x49\x45\x4e\x44\xae"
        "\x42\x60\x82",
        67);
    expect_bad("run --heightmap " + write("one.png", one_by_one).string(), "one.png");
}

TEST_F(Cli, BadPresetsScenesAndOptions) {
    expect_bad("run --preset paper-moon", "unknown preset 'paper-moon'");
    expect_bad("run --preset paper-nile", "--heightmap");
    expect_bad("run --scene " + (dir_ / "nope.toml").string(), "nope.toml");
    expect_bad("run --scene " + write("syntax.toml", "[field\nresolution = 2\n").string(), "syntax.toml:1");
    expect_bad("run --scene " + write("unknown.toml", "[field]\nresolutoin = 2\n").string(), "field.resolutoin: unknown key");
    expect_bad("run --scene " + write("neg.toml", "[field]\nresolution = -2\n").string(), "field.resolution: must be in (0, 64]");
    expect_bad("run --scene " + write("nan.toml", "[forces]\ngravity = nan\n").string(), "forces.gravity");
    expect_bad("run --scene " + write("dt.toml", "[integrator]\ndt = 0.0\nsubsteps = 0\n").string(), "integrator.substeps");
    expect_bad("run --scene " + write("count.toml", "[particles]\ncount = 99999999999\n").string(), "particles.count: must be in [1, 10000000]");
    expect_bad("run --dt 0", "--dt: must be in (0, 1]");
    expect_bad("run --dt -0.5", "--dt: must be in (0, 1]");
    expect_bad("run --dt nan", "--dt");
    expect_bad("run --frames 0", "--frames: must be in [1,");
    expect_bad("run --frames -3", "--frames");
    expect_bad("run --collision magic", "--collision: must be one of paper, robust, none");
    // Issue 13: --collision the solver does not use (PBF never reflects; Bullet has its own contacts).
    expect_bad("run --collision paper", "--collision: solver = \"pbf\" slides along the terrain");
    expect_bad("run --scene " + write("b.toml", "solver = \"bullet\"\n").string() + " --collision robust",
               "--collision: solver = \"bullet\" does not use it");
    // Issue 13: --seed with PBF, which draws no random number (its lattice source places every particle).
    expect_bad("run --seed 3", "--seed: solver = \"pbf\" does not use it");
    expect_bad("run --frames many", "--frames");
    expect_bad("run --preset default --scene x.toml", "--preset");
    expect_bad("fly", "fly");
}

/// The box of the vertices of an OBJ file.
struct ObjBox {
    double min[3] = {1e30, 1e30, 1e30}, max[3] = {-1e30, -1e30, -1e30};
};
ObjBox obj_box(const fs::path& obj) {
    ObjBox b;
    std::istringstream lines(slurp(obj));
    for (std::string line; std::getline(lines, line);) {
        if (line.rfind("v ", 0) != 0) continue;
        std::istringstream v(line.substr(2));
        for (int k = 0; k < 3; ++k) {
            double x = 0.0;
            v >> x;
            b.min[k] = std::min(b.min[k], x);
            b.max[k] = std::max(b.max[k], x);
        }
    }
    return b;
}

/// Heightmap scale options (issue 10): a 9 x 7 map from 0 to 255 (a ramp down its rows)
/// and the terrain's extent in terrain.obj: (W-1) area_scale, height_scale, (H-1) area_scale.
class CliScale : public Cli {
protected:
    fs::path map_;

    void SetUp() override {
        Cli::SetUp();
        std::vector<uint16_t> px;
        for (int r = 0; r < 7; ++r)
            for (int c = 0; c < 9; ++c) px.push_back(static_cast<uint16_t>(255 - r * 40 - (c == 4 ? 15 : 0)));
        px.back() = 0;
        const auto png = mr::test::encode_png_raw(9, 7, 1, 8, px);
        map_ = write("map.png", std::string(png.begin(), png.end()));
    }

    /// x, y and z extents of the terrain of `run --heightmap map.png OPTIONS` (one frame).
    std::array<double, 3> extent(const std::string& options) {
        const fs::path objs = dir_ / "objs";
        fs::remove_all(objs);
        // The heights as given: the default river would carve its channel (below y = 0 at the outlet).
        const bool own_scene = options.find("--scene") != std::string::npos;
        const fs::path scene = write("as_given.toml", "[terrain]\ncondition = \"none\"\n");
        CliResult r = run("run --frames 1 " + (own_scene ? std::string() : "--scene " + scene.string() + " ") +
                          "--heightmap " + map_.string() + " " + options + " --obj-dir " + objs.string());
        EXPECT_EQ(r.code, 0) << options << "\n" << r.err;
        const ObjBox b = obj_box(objs / "terrain.obj");
        fs::remove_all(objs);
        EXPECT_NEAR(b.min[0], 0.0, 1e-6);
        EXPECT_NEAR(b.min[1], 0.0, 1e-6);
        EXPECT_NEAR(b.min[2], 0.0, 1e-6);
        return {b.max[0], b.max[1], b.max[2]};
    }
};

/// x, y, z extents expected for area scale `a` and height scale `h` on the 9 x 7 map.
std::array<double, 3> box_of(double a, double h) { return {8.0 * a, h, 6.0 * a}; }

void expect_extent(const std::array<double, 3>& got, const std::array<double, 3>& want) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], want[k], 1e-4 * want[k]) << "axis " << k;
}

TEST_F(CliScale, OptionsSetTheScales) {
    // The default scene's scales: area_scale "auto", 1 m per sample raised so that the
    // shorter side (6 samples) is kAutoMinSide = 16 m.
    expect_extent(extent(""), box_of(16.0 / 6.0, 24.0));
    expect_extent(extent("--area-scale 2.5 --height-scale 60"), box_of(2.5, 60.0));
    expect_extent(extent("--height-scale 5"), box_of(16.0 / 6.0, 5.0));
    // A scene's "auto" is the same rule; a number is used as given.
    const fs::path autos = write("auto.toml", "[terrain]\narea_scale = \"auto\"\ncondition = \"none\"\n");
    expect_extent(extent("--scene " + autos.string()), box_of(16.0 / 6.0, 24.0));
    expect_extent(extent("--area-scale 1"), box_of(1.0, 24.0));
    // Over a scene's keys.
    const fs::path scene =
        write("s.toml", "[terrain]\nheightmap = \"map.png\"\narea_scale = 3.0\nheight_scale = 9.0\ncondition = \"none\"\n");
    expect_extent(extent("--scene " + scene.string()), box_of(3.0, 9.0));
    expect_extent(extent("--scene " + scene.string() + " --area-scale 1.5"), box_of(1.5, 9.0));
}

// A sculpted terrain saved by the viewer's "Save terrain" (write_terrain_heightmap: a
// 16-bit PNG and its sidecar) loads back through --real-scale at its scale.
TEST_F(CliScale, ASavedTerrainLoadsBackAtItsScale) {
    mr::Heightmap m = mr::flat_heightmap(21, 13, 0.25f);
    auto t = mr::Terrain::build(m, mr::TerrainDef{.area_scale = 2.0f, .height_scale = 8.0f});
    ASSERT_TRUE(t.ok());
    ASSERT_TRUE(t->sculpt({.x = 20.0f, .z = 12.0f, .radius = 5.0f, .strength = 6.0f}).ok());
    auto saved = mr::write_terrain_heightmap((dir_ / "saved.png").string(), t.value(), true);
    ASSERT_TRUE(saved.ok()) << saved.error().message;
    EXPECT_FLOAT_EQ(saved->metres_min, 2.0f);
    EXPECT_FLOAT_EQ(saved->metres_max, 8.0f);
    map_ = dir_ / "saved.png";
    expect_extent(extent("--real-scale"), {20.0 * 2.0, 6.0, 12.0 * 2.0});
}

TEST_F(CliScale, RealScaleReadsTheSidecar) {
    // 2 m per sample and 120 m of relief; the explicit options win over the sidecar.
    write("map.json", R"({"metres_min": -20, "metres_max": 100, "sample_spacing_m": 2.0, "width": 9, "height": 7})");
    expect_extent(extent("--real-scale"), box_of(2.0, 120.0));
    expect_extent(extent("--real-scale --area-scale 4"), box_of(4.0, 120.0));
    expect_extent(extent("--real-scale --height-scale 30"), box_of(2.0, 30.0));
    // From a latitude/longitude box on the equator: 0.0009 degrees over 8 and 6 samples.
    write("map.json", R"({"metres_min": 0, "metres_max": 50, "lat": [0.0, 0.0009], "lon": [-0.0006, 0.0006],
                          "width": 9, "height": 7})");
    const double dz = 0.0009 * 111320.0 / 6.0, dx = 0.0012 * 111320.0 * std::cos(0.00045 * std::numbers::pi / 180.0) / 8.0;
    expect_extent(extent("--real-scale"), box_of(0.5 * (dx + dz), 50.0));
}

TEST_F(CliScale, BadScaleOptions) {
    const std::string run_map = "run --frames 1 --heightmap " + map_.string();
    for (const char* bad : {"0", "-1", "10000.5", "1e9", "nan", "inf", "1e-60"})
        expect_bad(run_map + " --area-scale " + bad, "--area-scale: must be in (0, 10000] metres");
    for (const char* bad : {"0", "-3", "100001", "nan"})
        expect_bad(run_map + " --height-scale " + bad, "--height-scale: must be in (0, 100000] metres");
    expect_bad(run_map + " --area-scale wide", "--area-scale");
    expect_bad("run --frames 1 --area-scale 0", "--area-scale");  // on the procedural valley too
    // --real-scale: a heightmap and a good sidecar beside it.
    expect_bad("run --frames 1 --real-scale", "--real-scale: needs a heightmap file");
    expect_bad(run_map + " --real-scale", "map.json: no such file");
    write("map.json", "{\"metres_min\": 0, \"metres_max\": }");
    expect_bad(run_map + " --real-scale", "map.json: not valid JSON (line 1, column");
    write("map.json", R"({"metres_min": 0, "sample_spacing_m": 1})");
    expect_bad(run_map + " --real-scale", "map.json: metres_max: missing");
    write("map.json", R"({"metres_min": 0, "metres_max": 10, "lat": [1, 2], "lon": [3, 4], "width": 9})");
    expect_bad(run_map + " --real-scale", "map.json: height: missing");
    write("map.json", R"({"metres_min": 5, "metres_max": 5, "sample_spacing_m": 1})");
    expect_bad(run_map + " --real-scale", "map.json: metres_max - metres_min: must be in (0, 100000]");
    write("map.json", R"({"metres_min": 0, "metres_max": 10, "sample_spacing_m": 1, "width": 10, "height": 7})");
    expect_bad(run_map + " --real-scale", "map.json: width, height: 10 x 7 does not match the heightmap's 9 x 7");
    // A bad explicit option is reported even where the sidecar would be fine.
    write("map.json", R"({"metres_min": 0, "metres_max": 10, "sample_spacing_m": 1})");
    expect_bad(run_map + " --real-scale --height-scale -1", "--height-scale: must be in (0, 100000]");
}

TEST_F(Cli, UnwritableStatsPathIsRefusedBeforeRunning) {
    CliResult r = run("run --frames 2 --stats " + (dir_ / "no/such/dir/s.json").string());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
}

}  // namespace
