// The C API on a shallow-water world (solver = "swe"): the grid read back as flat arrays
// (mr_world_heightfield, mr_world_copy_heightfield), equal to the C++ Simulation's, its
// errors, the water queries answering from the heightfield's surface, and rain per cell
// (mr_world_set_rain) measured by the grid's volumes (mr_world_water_balance).
#include "capi_support.h"

#include <metariver/swe_solver.h>

#include <fmt/format.h>

#include <cmath>
#include <vector>

namespace capi_test {
namespace {

/// A still lake up to 13 m on the default valley.
mr_world_desc lake_desc() {
    mr_world_desc d = mr_world_desc_default();
    d.scene_toml = "solver = \"swe\"\n[swe]\ninitial_level = 13.0\nedges = \"open\"\n";  // at rest: the lake reaches the valley's edge
    return d;
}

TEST(CApiSwe, TheGridIsReadAsFlatArraysEqualToTheSimulations) {
    World world(lake_desc());
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(10);
    mr_heightfield_info info{};
    ASSERT_EQ(mr_world_heightfield(world.w, &info), MR_OK) << world.last_error();
    const mr_terrain_info t = terrain_info(world);
    EXPECT_EQ(info.columns, t.columns);
    EXPECT_EQ(info.rows, t.rows);
    EXPECT_EQ(info.spacing, t.area_scale);
    const size_t n = size_t(info.rows) * size_t(info.columns);
    std::vector<float> depth(n), velocity(2 * n), bed(n);
    ASSERT_EQ(mr_world_copy_heightfield(world.w, depth.data(), velocity.data(), bed.data(), n), MR_OK);
    EXPECT_EQ(bed, terrain_heights(world));
    // A lake at rest: wet where the bed is under 13 m, its surface there at 13 m.
    size_t wet = 0;
    for (size_t k = 0; k < n; ++k) {
        EXPECT_NEAR(depth[k], std::max(13.0f - bed[k], 0.0f), 1e-4f) << k;
        EXPECT_NEAR(velocity[2 * k], 0.0f, 1e-3f);
        wet += depth[k] > 0.0f;
    }
    EXPECT_GT(wet, 100u);
    // NULL buffers are skipped; a short capacity writes nothing.
    EXPECT_EQ(mr_world_copy_heightfield(world.w, nullptr, nullptr, nullptr, 0), MR_OK);
    std::vector<float> small(3, -1.0f);
    EXPECT_EQ(mr_world_copy_heightfield(world.w, small.data(), nullptr, nullptr, 3), MR_ERROR_BUFFER_TOO_SMALL);
    EXPECT_TRUE(contains(world.last_error(), "capacity: 3")) << world.last_error();
    EXPECT_EQ(small[0], -1.0f);
    EXPECT_EQ(mr_world_heightfield(world.w, nullptr), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_heightfield(nullptr, &info), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_copy_heightfield(nullptr, nullptr, nullptr, nullptr, 0), MR_ERROR_NULL_ARGUMENT);
}

TEST(CApiSwe, AParticleWorldHasNoGridAndSaysSo) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    mr_heightfield_info info{};
    EXPECT_EQ(mr_world_heightfield(world.w, &info), MR_ERROR_UNSUPPORTED);
    EXPECT_TRUE(contains(world.last_error(), "mr_world_heightfield: solver = \"pbf\" has no water grid"))
        << world.last_error();
    float d[1];
    EXPECT_EQ(mr_world_copy_heightfield(world.w, d, nullptr, nullptr, 1), MR_ERROR_UNSUPPORTED);
}

TEST(CApiSwe, WaterQueriesReadTheLakesSurface) {
    World world(lake_desc());
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    world.step(2);
    mr_heightfield_info info{};
    ASSERT_EQ(mr_world_heightfield(world.w, &info), MR_OK);
    const size_t n = size_t(info.rows) * size_t(info.columns);
    std::vector<float> depth(n);
    ASSERT_EQ(mr_world_copy_heightfield(world.w, depth.data(), nullptr, nullptr, n), MR_OK);
    size_t deepest = 0;
    for (size_t k = 0; k < n; ++k)
        if (depth[k] > depth[deepest]) deepest = k;
    const float xz[2] = {info.origin[0] + info.spacing * float(deepest % size_t(info.columns)),
                         info.origin[1] + info.spacing * float(deepest / size_t(info.columns))};
    mr_water_sample s{};
    ASSERT_EQ(mr_world_sample_water(world.w, xz, 1, &s), MR_OK) << world.last_error();
    EXPECT_EQ(s.wet, 1);
    EXPECT_NEAR(s.surface_y, 13.0f, 0.01f);
    EXPECT_NEAR(s.depth, depth[deepest], 0.01f);
}

/// A dry valley with the scene's rain over the whole map (36 mm/h) and no source.
mr_world_desc rain_desc() {
    mr_world_desc d = mr_world_desc_default();
    d.scene_toml = "solver = \"swe\"\n[swe]\ndischarge = 0\nrain = 36\n";
    return d;
}

mr_water_balance balance_of(const World& world) {
    mr_water_balance b{};
    EXPECT_EQ(mr_world_water_balance(world.w, &b), MR_OK) << world.last_error();
    return b;
}

mr_heightfield_info grid_of(const World& world) {
    mr_heightfield_info info{};
    EXPECT_EQ(mr_world_heightfield(world.w, &info), MR_OK) << world.last_error();
    return info;
}

/// Rain volume of `mm_per_h` over `seconds`: its integral (cells x spacing^2) x the time.
double rain_volume(const std::vector<float>& mm_per_h, double spacing, double seconds) {
    double sum = 0.0;
    for (const float r : mm_per_h) sum += double(r);
    return sum * 1e-3 / 3600.0 * spacing * spacing * seconds;
}

TEST(CApiSwe, RainPerCellRainsItsIntegralTimesTheTime) {
    World world(rain_desc());
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const mr_heightfield_info g = grid_of(world);
    const size_t n = size_t(g.rows) * size_t(g.columns);
    // A ramp across the valley: 0 in column 0 .. 3600 mm/h (1 mm/s) in the last column.
    std::vector<float> rate(n);
    for (size_t k = 0; k < n; ++k) rate[k] = 3600.0f * float(k % size_t(g.columns)) / float(g.columns - 1);
    ASSERT_EQ(mr_world_set_rain(world.w, rate.data(), n), MR_OK) << world.last_error();
    EXPECT_EQ(balance_of(world).rain_set, 1);
    world.step(1);
    // After a frame the rain is where the rates put it: column 0 (rate 0) dry, the last wet
    // (later the water runs downhill into column 0's low rows).
    std::vector<float> depth(n);
    ASSERT_EQ(mr_world_copy_heightfield(world.w, depth.data(), nullptr, nullptr, n), MR_OK);
    int wet_first = 0, wet_last = 0;
    for (int j = 0; j < g.rows; ++j) {
        wet_first += depth[size_t(j) * size_t(g.columns)] > 0.0f;
        wet_last += depth[size_t(j) * size_t(g.columns) + size_t(g.columns - 1)] > 0.0f;
    }
    EXPECT_EQ(wet_first, 0);
    EXPECT_EQ(wet_last, g.rows);
    world.step(29);
    mr_water_balance b = balance_of(world);
    EXPECT_NEAR(b.simulated_s, 30.0 * double(kDt), 1e-9);
    // 1e-9 relative: the grid sums each substep's rain in doubles (round-off only).
    const double expected = rain_volume(rate, g.spacing, b.simulated_s);
    EXPECT_GT(expected, 1.0);
    EXPECT_NEAR(b.rain, expected, 1e-9 * expected);
    EXPECT_NEAR(b.error, 0.0, 1e-9 * expected);
    EXPECT_GT(b.substeps, 0u);
    // A live edit of another key keeps the rates (the scene's 36 mm/h does not come back).
    int32_t applied = 0;
    ASSERT_EQ(mr_world_apply_toml(world.w, "[swe]\nmanning = 0.04\n", &applied), MR_OK) << world.last_error();
    EXPECT_EQ(applied, 1);
    world.step(30);
    const mr_water_balance after = balance_of(world);
    const double more = rain_volume(rate, g.spacing, after.simulated_s - b.simulated_s);
    EXPECT_NEAR(after.rain - b.rain, more, 1e-9 * more);
}

TEST(CApiSwe, ZeroRainRainsNothingAndClearingBringsTheScenesRainBack) {
    World world(rain_desc());
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const mr_heightfield_info g = grid_of(world);
    const size_t n = size_t(g.rows) * size_t(g.columns);
    const std::vector<float> zero(n, 0.0f);
    ASSERT_EQ(mr_world_set_rain(world.w, zero.data(), n), MR_OK) << world.last_error();
    world.step(20);
    mr_water_balance b = balance_of(world);
    EXPECT_EQ(b.rain, 0.0);
    EXPECT_EQ(b.stored, 0.0);
    // NULL, 0: the scene's swe.rain = 36 mm/h over every cell again.
    ASSERT_EQ(mr_world_set_rain(world.w, nullptr, 0), MR_OK) << world.last_error();
    EXPECT_EQ(balance_of(world).rain_set, 0);
    world.step(20);
    const mr_water_balance after = balance_of(world);
    const double expected = rain_volume(std::vector<float>(n, 36.0f), g.spacing, after.simulated_s - b.simulated_s);
    EXPECT_NEAR(after.rain, expected, 1e-9 * expected);
}

TEST(CApiSwe, BadRainIsRefusedNamingTheArgumentAndChangesNothing) {
    World world(rain_desc());
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const mr_heightfield_info g = grid_of(world);
    const size_t n = size_t(g.rows) * size_t(g.columns);
    std::vector<float> rate(n, 100.0f);
    ASSERT_EQ(mr_world_set_rain(world.w, rate.data(), n), MR_OK);
    std::vector<float> bad = rate;
    EXPECT_EQ(mr_world_set_rain(world.w, bad.data(), n - 1), MR_ERROR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(world.last_error(), fmt::format("mr_world_set_rain: count: must be the grid's {} cells", n)))
        << world.last_error();
    const size_t k = size_t(g.columns) + 2;  // row 1, column 2
    for (const float v : {std::nanf(""), -1.0f, 1e4f * 1.01f, INFINITY}) {
        bad[k] = v;
        EXPECT_EQ(mr_world_set_rain(world.w, bad.data(), n), MR_ERROR_INVALID_ARGUMENT) << v;
        EXPECT_TRUE(contains(world.last_error(), fmt::format("mr_world_set_rain: mm_per_h[{}] (row 1, column 2): must be "
                                                             "in [0, 10000] mm/h", k)))
            << world.last_error();
    }
    EXPECT_EQ(mr_world_set_rain(world.w, nullptr, n), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_set_rain(nullptr, rate.data(), n), MR_ERROR_NULL_ARGUMENT);
    // The refusals changed nothing: the 100 mm/h everywhere still falls.
    world.step(10);
    const mr_water_balance b = balance_of(world);
    const double expected = rain_volume(rate, g.spacing, b.simulated_s);
    EXPECT_NEAR(b.rain, expected, 1e-9 * expected);
    EXPECT_EQ(b.rain_set, 1);
    EXPECT_EQ(mr_world_water_balance(world.w, nullptr), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_water_balance(nullptr, nullptr), MR_ERROR_NULL_ARGUMENT);
}

TEST(CApiSwe, AParticleWorldHasNoRainGridAndSaysSo) {
    World world;
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const float r[1] = {1.0f};
    EXPECT_EQ(mr_world_set_rain(world.w, r, 1), MR_ERROR_UNSUPPORTED);
    EXPECT_TRUE(contains(world.last_error(), "mr_world_set_rain: solver = \"pbf\" has no water grid"))
        << world.last_error();
    mr_water_balance b{};
    EXPECT_EQ(mr_world_water_balance(world.w, &b), MR_ERROR_UNSUPPORTED);
    EXPECT_TRUE(contains(world.last_error(), "mr_world_water_balance: solver = \"pbf\" has no water grid"))
        << world.last_error();
}

TEST(CApiSwe, MovingTheSourceMovesTheGridsSource) {
    mr_world_desc d = mr_world_desc_default();
    d.scene_toml = "solver = \"swe\"\n";  // the river rule's source at the channel's head
    World world(d);
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const mr_heightfield_info g = grid_of(world);
    const size_t n = size_t(g.rows) * size_t(g.columns), k = size_t(g.rows / 2) * size_t(g.columns) + 4;
    std::vector<float> depth(n);
    world.step(30);
    ASSERT_EQ(mr_world_copy_heightfield(world.w, depth.data(), nullptr, nullptr, n), MR_OK);
    ASSERT_EQ(depth[k], 0.0f) << "the valley's side is dry";
    const float to[3] = {g.origin[0] + 4.0f * g.spacing, 20.0f, g.origin[1] + float(g.rows / 2) * g.spacing};
    ASSERT_EQ(mr_world_move_source(world.w, to), MR_OK) << world.last_error();
    const double before = balance_of(world).inflow;
    world.step(1);
    ASSERT_EQ(mr_world_copy_heightfield(world.w, depth.data(), nullptr, nullptr, n), MR_OK);
    EXPECT_GT(depth[k], 0.0f) << "the source pours where it was moved";
    EXPECT_GT(balance_of(world).inflow, before);
}

TEST(CApiSwe, SinkBoxesAreRefusedOnTheGrid) {
    World world(rain_desc());
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const float box[6] = {20.0f, -5.0f, 20.0f, 40.0f, 30.0f, 40.0f};
    EXPECT_EQ(mr_world_set_sink_boxes(world.w, box, 1), MR_ERROR_UNSUPPORTED);  // it was taken and did nothing
    EXPECT_TRUE(contains(world.last_error(), "mr_world_set_sink_boxes: solver = \"swe\" has no sink boxes: its sinks "
                                             "are [[swe.sinks]]"))
        << world.last_error();
}

TEST(CApiSwe, WarningsNameASourceOffTheMap) {
    mr_world_desc d = mr_world_desc_default();
    d.scene_toml = "solver = \"swe\"\n[[swe.sources]]\nstart = [-500.0, 0.0, 10.0]\ndischarge = 1.0\n";
    World world(d);
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    size_t length = 0;
    ASSERT_EQ(mr_world_warnings(world.w, nullptr, 0, &length), MR_ERROR_BUFFER_TOO_SMALL);
    ASSERT_GT(length, 0u);
    std::string text(length + 1, '\0');
    ASSERT_EQ(mr_world_warnings(world.w, text.data(), text.size(), &length), MR_OK) << world.last_error();
    text.resize(length);
    EXPECT_TRUE(contains(text, "swe.sources[1]: lies outside the terrain; it pours nothing")) << text;
    // Moved onto the map (a live edit): no warning left about it.
    ASSERT_EQ(mr_world_apply_toml(world.w, "[[swe.sources]]\nstart = [30.0, 0.0, 50.0]\n", nullptr), MR_OK)
        << world.last_error();
    char buffer[4096];
    ASSERT_EQ(mr_world_warnings(world.w, buffer, sizeof buffer, &length), MR_OK) << world.last_error();
    EXPECT_FALSE(contains(buffer, "swe.sources")) << buffer;
    EXPECT_EQ(mr_world_warnings(world.w, buffer, sizeof buffer, nullptr), MR_ERROR_NULL_ARGUMENT);
    EXPECT_EQ(mr_world_warnings(world.w, nullptr, 8, &length), MR_ERROR_NULL_ARGUMENT);
}

TEST(CApiSwe, TheHybridsGridTakesRainToo) {
    mr_world_desc d = mr_world_desc_default();
    d.scene_toml = "solver = \"hybrid\"\n[swe]\ndischarge = 0\n";
    World world(d);
    ASSERT_EQ(world.status, MR_OK) << world.error.message;
    const mr_heightfield_info g = grid_of(world);
    const std::vector<float> rate(size_t(g.rows) * size_t(g.columns), 360.0f);
    ASSERT_EQ(mr_world_set_rain(world.w, rate.data(), rate.size()), MR_OK) << world.last_error();
    world.step(5);
    const mr_water_balance b = balance_of(world);
    const double expected = rain_volume(rate, g.spacing, b.simulated_s);
    EXPECT_NEAR(b.rain, expected, 1e-9 * expected);
}

}  // namespace
}  // namespace capi_test
