// `--format npy`: the heightfield solver's grid (depth, velocity x and z, bed) per frame as
// NumPy .npy v1.0 files: the header a reader expects, the values the solver holds (read back
// here and, where it is installed, by NumPy itself), the grid's place in the manifest, and a
// clear refusal for a solver whose water is particles.
#include "export_fixture.h"

#include <metariver/scene.h>

#include <nlohmann/json.hpp>

#include <cstring>
#include <unistd.h>

namespace mr {
namespace {

namespace fs = std::filesystem;
using test::CliResult;

/// A parsed .npy v1.0 file of float32 ('<f4', C order), or rows = -1 when it is not one.
struct Npy {
    int rows = -1, columns = -1;
    std::string header;
    std::vector<float> values;
};

Npy read_npy(const std::string& bytes) {
    Npy n;
    if (bytes.size() < 10 || bytes.compare(0, 8, std::string("\x93NUMPY\x01\x00", 8)) != 0) return n;
    const size_t len = static_cast<unsigned char>(bytes[8]) | (static_cast<size_t>(static_cast<unsigned char>(bytes[9])) << 8);
    if (10 + len > bytes.size() || (10 + len) % 64 != 0) return n;
    n.header = bytes.substr(10, len);
    if (n.header.back() != '\n' || n.header.find("'descr': '<f4'") == std::string::npos ||
        n.header.find("'fortran_order': False") == std::string::npos)
        return n;
    if (std::sscanf(n.header.c_str() + n.header.find("'shape': ("), "'shape': (%d, %d)", &n.rows, &n.columns) != 2)
        return Npy{};
    const size_t count = static_cast<size_t>(n.rows) * static_cast<size_t>(n.columns);
    if (bytes.size() != 10 + len + 4 * count) return Npy{};
    n.values.resize(count);
    std::memcpy(n.values.data(), bytes.data() + 10 + len, 4 * count);
    return n;
}

TEST(ExportNpy, TheEncoderWritesAV1HeaderOnA64ByteBoundaryAndTheValuesInCOrder) {
    const std::vector<float> v{1.0f, -2.5f, 3.25f, 0.0f, 1e-7f, 7.0f};
    const Npy n = read_npy(encode_npy_f32(v, 2, 3));
    ASSERT_EQ(n.rows, 2) << n.header;
    EXPECT_EQ(n.columns, 3);
    EXPECT_EQ(n.values, v);
    // Fewer values than rows x columns: zeros after them, the file still what its header says.
    const Npy short_one = read_npy(encode_npy_f32(std::vector<float>{4.0f}, 1, 2));
    ASSERT_EQ(short_one.rows, 1);
    EXPECT_EQ(short_one.values, (std::vector<float>{4.0f, 0.0f}));
}

class ExportNpyCli : public test::ExportFixture {
protected:
    /// The swe scene of these tests: a lake to 3 m on the default valley, a source and rain.
    fs::path swe_scene() {
        return put("swe.toml", "solver = \"swe\"\n\n[swe]\ndischarge = 5.0\nrain = 50.0\ninitial_level = 3.0\n");
    }
};

// 21 frames exported every 10: frames 0, 10 and 20 hold the arrays of a Simulation of the same
// scene stepped as far, bit for bit, and the manifest places the grid where the terrain is.
TEST_F(ExportNpyCli, RunWritesTheSolversDepthVelocityAndBedPerFrame) {
    const fs::path out = dir_ / "exp", scene = swe_scene();
    const CliResult r = run("run --scene " + scene.string() + " --frames 21 --no-progress --export " + out.string() +
                            " --format npy --every 10");
    ASSERT_EQ(r.code, 0) << r.err;
    auto def = load_scene_file(scene.string());
    ASSERT_TRUE(def.ok()) << def.error().message;
    auto sim = Simulation::create(def.value());
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    for (int f = 0; f <= 20; ++f) s.step(1.0f / 60.0f);
    const HeightfieldWater& w = *s.heightfield();
    for (const char* stem : {"depth", "velocity_x", "velocity_z", "bed"})
        for (const char* frame : {"00000", "00010", "00020"})
            EXPECT_TRUE(fs::exists(out / fmt::format("{}_{}.npy", stem, frame))) << stem << frame;
    EXPECT_FALSE(fs::exists(out / "water_00000.npy"));
    EXPECT_FALSE(fs::exists(out / "terrain.npy"));
    const Npy depth = read_npy(test::slurp(out / "depth_00020.npy"));
    const Npy vx = read_npy(test::slurp(out / "velocity_x_00020.npy"));
    const Npy vz = read_npy(test::slurp(out / "velocity_z_00020.npy"));
    const Npy bed = read_npy(test::slurp(out / "bed_00020.npy"));
    ASSERT_EQ(depth.rows, w.rows) << depth.header;
    ASSERT_EQ(depth.columns, w.columns);
    ASSERT_EQ(vx.values.size(), w.size());
    ASSERT_EQ(vz.values.size(), w.size());
    ASSERT_EQ(bed.values.size(), w.size());
    EXPECT_EQ(depth.values, w.depth);
    size_t wet = 0, moving = 0;
    for (size_t k = 0; k < w.size(); ++k) {
        ASSERT_EQ(vx.values[k], w.velocity[k].x) << k;
        ASSERT_EQ(vz.values[k], w.velocity[k].z) << k;
        ASSERT_EQ(bed.values[k], s.terrain().vertices()[k].y) << k;
        wet += w.depth[k] > 0.0f;
        moving += w.velocity[k].x != 0.0f;
    }
    EXPECT_GT(wet, 0u);
    EXPECT_GT(moving, 0u);
    const auto j = nlohmann::json::parse(test::slurp(out / "export.json"));
    const auto& g = j["grid"];
    EXPECT_EQ(g["rows"], w.rows);
    EXPECT_EQ(g["columns"], w.columns);
    EXPECT_FLOAT_EQ(g["spacing"].get<float>(), s.terrain().area_scale());
    EXPECT_FLOAT_EQ(g["origin"][0].get<float>(), s.terrain().vertices()[0].x);
    EXPECT_FLOAT_EQ(g["origin"][1].get<float>(), s.terrain().vertices()[0].z);
    EXPECT_EQ(g["dtype"], "<f4");
    // Sample (r, c) at origin + (c, r) * spacing: the last sample is the terrain's last vertex.
    const Vec3 last = s.terrain().vertices()[w.size() - 1];
    EXPECT_NEAR(g["origin"][0].get<double>() + (w.columns - 1) * g["spacing"].get<double>(), last.x, 1e-3);
    EXPECT_NEAR(g["origin"][1].get<double>() + (w.rows - 1) * g["spacing"].get<double>(), last.z, 1e-3);
    EXPECT_EQ(j["frame_files"][2]["files"].size(), 4u);

    // NumPy reads the same arrays (skipped where Debian's python3-numpy is missing).
    if (::access("/usr/bin/python3", X_OK) != 0 || test::run_shell("/usr/bin/python3 -c 'import numpy'", dir_).code != 0)
        GTEST_SKIP() << "/usr/bin/python3 with numpy not found";
    const std::string script = fmt::format(
        "import numpy as np\n"
        "d = np.load('{0}/depth_00020.npy'); b = np.load('{0}/bed_00020.npy')\n"
        "assert d.dtype == np.float32 and d.shape == ({1}, {2}) and d.flags['C_CONTIGUOUS']\n"
        "print(repr(float(d.sum(dtype=np.float64))), int((d > 0).sum()), repr(float(b[{1} - 1, {2} - 1])))\n",
        out.string(), w.rows, w.columns);
    const fs::path py = put("check.py", script);
    const CliResult p = test::run_shell("/usr/bin/python3 " + py.string(), dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    double sum = 0.0;
    for (float h : w.depth) sum += h;
    double np_sum = 0.0, np_last = 0.0;
    size_t np_wet = 0;
    ASSERT_EQ(std::sscanf(p.out.c_str(), "%lf %zu %lf", &np_sum, &np_wet, &np_last), 3) << p.out;
    EXPECT_NEAR(np_sum, sum, 1e-6 * sum);
    EXPECT_EQ(np_wet, wet);
    EXPECT_EQ(static_cast<float>(np_last), last.y);
}

// A particle solver has no grid: exit 2, one line naming --format npy and the solver, nothing written.
TEST_F(ExportNpyCli, NpyForAParticleSolverIsRefusedAndWritesNothing) {
    const fs::path out = dir_ / "exp";
    const CliResult r = run("run --preset paper-bowl --frames 3 --no-progress --export " + out.string() + " --format npy");
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("--format npy: solver \"springs\" has no heightfield water"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace mr
