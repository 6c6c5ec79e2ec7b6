// More sources and sinks in scenes (issue 14): [[particles.source]] and [[sink.box]] in
// scene files (read, checked, written back), on the terrain (checked against it), and
// placed or removed in a running simulation (Simulation::apply: the water keeps flowing).
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <gtest/gtest.h>

#include <string>

namespace mr {
namespace {

constexpr const char* kTwoSources = R"(
[particles]
flow_rate = 30.0
[[particles.source]]
center = [20.0, 12.0, 30.0]
half_extent = [1.0, 0.5, 1.0]
flow_rate = 12.5
[[particles.source]]
center = [40.0, 12.0, 20.0]
flow_rate = 0.0
[sink]
kind = "edges"
[[sink.box]]
min = [1.0, -5.0, 1.0]
max = [3.0, 20.0, 3.0]
)";

TEST(SceneLists, SourcesAndSinkBoxesAreReadFromTheFile) {
    auto r = parse_scene_toml(kTwoSources, "two.toml", default_scene());
    ASSERT_TRUE(r.ok()) << r.error().message;
    const SceneDef& d = r.value();
    ASSERT_EQ(d.spawn.sources.size(), 2u);
    EXPECT_EQ(d.spawn.sources[0].center, Vec3(20, 12, 30));
    EXPECT_EQ(d.spawn.sources[0].half_extent, Vec3(1, 0.5f, 1));
    EXPECT_FLOAT_EQ(d.spawn.sources[0].flow_rate, 12.5f);
    EXPECT_EQ(d.spawn.sources[1].half_extent, SourceDef{}.half_extent) << "a key left out keeps its default";
    ASSERT_EQ(d.sink.boxes.size(), 1u);
    EXPECT_EQ(d.sink.boxes[0], (SinkBox{Vec3(1, -5, 1), Vec3(3, 20, 3)}));
    EXPECT_FLOAT_EQ(d.spawn.total_particles_per_second(), 42.5f);
}

TEST(SceneLists, BadEntriesNameTheEntryAndTheKey) {
    auto error = [](const std::string& text) {
        auto r = parse_scene_toml(text, "bad.toml", default_scene());
        return r.ok() ? std::string("(loaded)") : r.error().message;
    };
    EXPECT_EQ(error("[[particles.source]]\ncenter = [1.0, 2.0, 3.0]\n[[particles.source]]\ncolour = 1\n"),
              "bad.toml: particles.source[2].colour: unknown key (allowed here: center, half_extent, flow_rate)");
    EXPECT_EQ(error("[[particles.source]]\nflow_rate = -1.0\n"),
              "bad.toml: particles.source[1].flow_rate: must be in [0, 10000000] (got -1)");
    EXPECT_EQ(error("[[particles.source]]\nhalf_extent = [1.0, -1.0, 1.0]\n"),
              "bad.toml: particles.source[1].half_extent: every component must be in [0, 10000] (got [1, -1, 1])");
    EXPECT_EQ(error("[[particles.source]]\ncenter = \"here\"\n"),
              "bad.toml: particles.source[1].center: must be an array of 3 numbers [x, y, z]");
    EXPECT_EQ(error("[particles]\nsource = 3\n"),
              "bad.toml: particles.source: must be a list of tables, each written [[particles.source]]");
    std::string many;
    for (int i = 0; i < 17; ++i) many += "[[sink.box]]\n";
    EXPECT_EQ(error(many), "bad.toml: sink.box: at most 16 entries (got 17)");
    EXPECT_EQ(error("[[sink.box]]\nmin = [1.0, 1.0, 1.0]\nmax = [2.0, 0.0, 2.0]\n"),
              "bad.toml: sink.box[1].max: every component must be >= sink.box[1].min's");
    // A list the scene as written never reads.
    EXPECT_NE(error("solver = \"bullet\"\n[sink]\nkind = \"none\"\n[[sink.box]]\nmax = [1.0, 1.0, 1.0]\n").find("sink.box: ignored: only solver = springs, pbf reads it"),
              std::string::npos);
    EXPECT_NE(error("solver = \"springs\"\n[particles]\nflow_rate = 0.0\n[[particles.source]]\n")
                  .find("particles.source: ignored: only a scene with a particle rate reads it"),
              std::string::npos);
}

TEST(SceneLists, AWrittenSceneLoadsBackWithItsLists) {
    auto r = parse_scene_toml(kTwoSources, "two.toml", default_scene());
    ASSERT_TRUE(r.ok()) << r.error().message;
    const std::string text = scene_to_toml(r.value());
    EXPECT_NE(text.find("[[particles.source]]\ncenter = [20.0, 12.0, 30.0]"), std::string::npos) << text;
    auto back = parse_scene_toml(text, "back.toml", default_scene());
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back.value().spawn.sources, r.value().spawn.sources);
    EXPECT_EQ(back.value().sink.boxes, r.value().sink.boxes);
    // No list: the file says so and holds none.
    const std::string plain = scene_to_toml(default_scene());
    EXPECT_EQ(plain.find("\n[[particles.source]]"), std::string::npos);
    EXPECT_NE(plain.find("# [[particles.source]]"), std::string::npos);
}

TEST(SceneLists, SourcesAndSinksAreCheckedAgainstTheTerrain) {
    auto sim = Simulation::create(default_scene());
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    const Aabb b = s.terrain().bounds();
    SceneDef d = s.requested();
    d.spawn.sources = {SourceDef{.center = Vec3(b.max.x + 5.0f, 10, 5), .flow_rate = 10.0f}};
    auto r = s.apply(d);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("particles.source[1].center: the source at"), std::string::npos) << r.error().message;
    d.spawn.sources = {SourceDef{.center = Vec3(0.5f, 10, 5), .half_extent = Vec3(1.0f), .flow_rate = 10.0f}};
    r = s.apply(d);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("particles.source[1].half_extent: the source volume around"), std::string::npos)
        << r.error().message;
    d.spawn.sources = {SourceDef{.center = Vec3(10, 10, 10), .flow_rate = 10.0f}};
    d.sink.boxes = {SinkBox{Vec3(9, 9, 9), Vec3(11, 11, 11)}};
    r = s.apply(d);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("sink.box[1]: the sink box overlaps the source volume"), std::string::npos)
        << r.error().message;
}

/// Particles emitted during `frames` frames.
uint64_t emitted_during(Simulation& s, int frames) {
    const uint64_t before = s.counters().emitted;
    for (int f = 0; f < frames; ++f) s.step(1.0f / 60.0f);
    return s.counters().emitted - before;
}

TEST(SceneLists, ASourcePlacedInARunningRiverEmitsAndRemovedStops) {
    // Two runs of the default river; at 2 s one of them gets a second source of 30
    // particles per second on the valley's side (apply: in place, no restart), at 4 s it
    // is removed again. The other run is the baseline.
    auto a = Simulation::create(default_scene()), b = Simulation::create(default_scene());
    ASSERT_TRUE(a.ok() && b.ok());
    Simulation& with = *a.value();
    Simulation& base = *b.value();
    for (int f = 0; f < 120; ++f) with.step(1.0f / 60.0f), base.step(1.0f / 60.0f);
    const size_t active = with.particles().active_count();
    const Aabb box = with.terrain().bounds();
    const float x = 0.5f * (box.min.x + box.max.x) + 6.0f, z = 0.5f * (box.min.z + box.max.z);
    SceneDef d = with.requested();
    d.spawn.sources = {SourceDef{.center = Vec3(x, with.terrain().height_mesh(x, z) + 1.5f, z),
                                 .half_extent = Vec3(1.0f, 0.5f, 1.0f), .flow_rate = 30.0f}};
    auto r = with.apply(d);
    ASSERT_TRUE(r.ok()) << r.error().message;
    ASSERT_TRUE(r.value().applied) << "rebuild asked for by " << r.value().rebuild_key;
    EXPECT_EQ(r.value().keys, std::vector<std::string>{"particles.source"});
    EXPECT_EQ(with.particles().active_count(), active) << "the water keeps flowing";
    const uint64_t more = emitted_during(with, 120), usual = emitted_during(base, 120);
    std::printf("2 s with a second source of 30/s: %llu emitted, %llu without it\n", (unsigned long long)more,
                (unsigned long long)usual);
    EXPECT_NEAR(double(more) - double(usual), 60.0, 6.0);
    d.spawn.sources.clear();
    r = with.apply(d);
    ASSERT_TRUE(r.ok() && r.value().applied);
    const uint64_t after = emitted_during(with, 120), usual_after = emitted_during(base, 120);
    std::printf("2 s after removing it: %llu emitted, %llu without it\n", (unsigned long long)after,
                (unsigned long long)usual_after);
    EXPECT_NEAR(double(after), double(usual_after), 6.0);
    EXPECT_EQ(with.counters().tunneled, 0u);
}

}  // namespace
}  // namespace mr
