// The table of scene keys (include/metariver/scene_keys.h): every key in it is read from a
// file into the field it names, its choices follow its enum, the reference in
// docs/scene-format.md is the one generated from it, and every preset written out as a
// commented TOML file loads back to the same scene.
#include <metariver/scene_keys.h>

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace mr {
namespace {

TEST(SceneKeys, NamesAreUniqueAndEverySectionIsListed) {
    std::map<std::string_view, int> seen;
    for (const SceneKey& k : scene_keys()) {
        EXPECT_EQ(++seen[k.name], 1) << k.name;
        EXPECT_NE(k.field, nullptr) << k.name;
        EXPECT_FALSE(k.help.empty()) << k.name;
        EXPECT_FALSE(k.readers.text.empty()) << k.name;
        bool listed = false;
        for (const SceneSection& s : scene_sections()) listed |= s.name == k.section();
        EXPECT_TRUE(listed) << k.name;
        EXPECT_EQ(find_scene_key(k.name), &k);
        if (k.numeric()) {
            EXPECT_LE(k.range.lo, k.range.hi) << k.name;
        }
    }
    EXPECT_EQ(find_scene_key("pbf.nonsense"), nullptr);
    // Every key has a field of its own (two keys on one field would leave one unread
    // and the round trips below comparing through the table blind to it).
    SceneDef d;
    std::map<const void*, std::string_view> owner;
    for (const SceneKey& k : scene_keys()) {
        const FieldRef f = k.field(d);
        const void* at = std::visit(
            [](auto p) -> const void* {
                if constexpr (std::is_same_v<decltype(p), EnumRef>) return p.field;
                else return p;
            },
            f);
        const auto [it, fresh] = owner.emplace(at, k.name);
        EXPECT_TRUE(fresh) << k.name << " and " << it->second << " share a field";
    }
    // The keys the docs used to miss (issue 14) are in the table.
    EXPECT_NE(find_scene_key("field.bounds"), nullptr);
    EXPECT_NE(find_scene_key("pbf.sleep_threshold"), nullptr);
}

TEST(SceneKeys, ChoicesFollowTheirEnumsToString) {
    for (const SceneKey& k : scene_keys()) {
        if (k.type != KeyType::Choice) continue;
        SceneDef d = default_scene();
        const EnumRef e = std::get<EnumRef>(k.field(d));
        for (size_t i = 0; i < k.choices.size(); ++i) {
            e.set(e.field, static_cast<int>(i));
            EXPECT_EQ(e.name(e.field), k.choices[i]) << k.name;
            EXPECT_EQ(e.get(e.field), static_cast<int>(i)) << k.name;
        }
    }
}

TEST(SceneKeys, RangesSayWhatTheyAccept) {
    const KeyRange r{.lo = 0, .hi = 1, .lo_open = true};
    EXPECT_EQ(r.describe(), "(0, 1]");
    EXPECT_FALSE(r.contains(0.0));
    EXPECT_TRUE(r.contains(1.0));
    EXPECT_FALSE(r.contains(NAN));
    const KeyRange z{.lo = 2, .hi = 1000, .zero_too = true};
    EXPECT_EQ(z.phrase(), "0 or in [2, 1000]");
    EXPECT_TRUE(z.contains(0.0));
    EXPECT_FALSE(z.contains(1.0));
    SceneDef d = default_scene();
    d.field.resolution = -2.0f;
    EXPECT_EQ(key_range_error(*find_scene_key("field.resolution"), d), "must be in (0, 64] (got -2)");
    EXPECT_EQ(key_range_error(*find_scene_key("field.threshold"), d), "");
}

/// A scene file as sections of lines; the key under test replaces a context's line of the same name.
using FileLines = std::map<std::string, std::map<std::string, std::string>>;

std::string render(const FileLines& f) {
    std::string s;
    if (auto root = f.find(""); root != f.end())
        for (const auto& [k, v] : root->second) s += fmt::format("{} = {}\n", k, v);
    for (const auto& [section, lines] : f) {
        if (section.empty()) continue;
        s += fmt::format("[{}]\n", section);
        for (const auto& [k, v] : lines) s += fmt::format("{} = {}\n", k, v);
    }
    return s;
}

/// Values other than the default scene's that a key may take, as TOML.
std::vector<std::string> other_values(const SceneKey& k) {
    const SceneDef base = default_scene();
    const std::string now = key_value_toml(k, base);
    std::vector<std::string> out;
    auto add = [&](SceneDef d) {
        if (k.words.apply) k.words.apply(d, -1);
        if (const std::string v = key_value_toml(k, d); v != now) out.push_back(v);
    };
    SceneDef d = base;
    const FieldRef f = k.field(d);
    if (auto* p = std::get_if<bool*>(&f)) {
        **p = !**p;
        add(d);
    } else if (auto* p = std::get_if<int*>(&f)) {
        for (int v : {**p + 1, **p - 1, static_cast<int>(k.range.lo) + 1, 7})
            if (k.range.contains(v)) **p = v, add(d);
    } else if (auto* p = std::get_if<uint32_t*>(&f)) {
        **p += 1;
        add(d);
    } else if (auto* p = std::get_if<float*>(&f)) {
        const float v = **p;
        for (double x : {v * 1.25, v * 0.75, (k.range.lo + std::min(k.range.hi, 1e3)) / 2.0, 0.5})
            if (k.range.contains(x)) **p = static_cast<float>(x), add(d);
    } else if (auto* p = std::get_if<Vec3*>(&f)) {
        const Vec3 v = **p;
        for (Vec3 x : {v - Vec3(0.5f, 0.25f, 0.75f), v + Vec3(0.5f, 0.25f, 0.75f)})
            if (k.range.contains(x.x) && k.range.contains(x.y) && k.range.contains(x.z)) **p = x, add(d);
    } else if (auto* p = std::get_if<std::string*>(&f)) {
        **p = "h.png";
        add(d);
    } else {
        const EnumRef e = std::get<EnumRef>(f);
        for (size_t i = 0; i < k.choices.size(); ++i) e.set(e.field, static_cast<int>(i)), add(d);
    }
    for (auto w : k.words.words)
        if (fmt::format("\"{}\"", w) != now) out.push_back(fmt::format("\"{}\"", w));
    return out;
}

TEST(SceneKeys, EveryKeyInTheTableIsReadIntoItsField) {
    // Scenes in which the keys are read: the default river (PBF), the springs and Bullet
    // solvers, a box sink, a file terrain, Taubin and uniform smoothing, no flow rate.
    const std::vector<FileLines> contexts = {
        {},
        {{"", {{"solver", "\"springs\""}}}},
        {{"", {{"solver", "\"bullet\""}}}},
        {{"sink", {{"kind", "\"box\""}, {"min", "[-10, -10, -10]"}, {"max", "[10, 10, 10]"}}}},
        {{"terrain", {{"source", "\"file\""}, {"heightmap", "\"map.png\""}}}},
        {{"surface", {{"method", "\"taubin\""}}}},
        {{"surface", {{"steps", "\"uniform\""}}}},
        {{"particles", {{"flow_rate", "0"}}}},
        {{"particles", {{"spawn_center", "\"auto\""}}}},
    };
    for (const SceneKey& k : scene_keys()) {
        const auto values = other_values(k);
        ASSERT_FALSE(values.empty()) << k.name;
        int read = 0;
        std::string last_error;
        for (const std::string& v : values) {
            for (const FileLines& c : contexts) {
                FileLines f = c;
                f[std::string(k.section())][std::string(k.leaf())] = v;
                auto r = parse_scene_toml(render(f), "s.toml", default_scene());
                if (!r) {
                    last_error = r.error().message;
                    continue;
                }
                EXPECT_EQ(key_value_toml(k, *r), v) << k.name << " in\n" << render(f);
                EXPECT_TRUE(k.readers(*r)) << k.name << " accepted but its readers (" << k.readers.text
                                           << ") say this scene does not read it:\n" << render(f);
                ++read;
                break;
            }
        }
        EXPECT_GT(read, 0) << k.name << ": no scene read any of its values; last error: " << last_error;
    }
}

std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

TEST(SceneKeys, TheDocsHoldTheGeneratedReference) {
    // Regenerate with: metariver scene --update-doc docs/scene-format.md
    const std::string doc = read_text(std::string(METARIVER_SOURCE_DIR) + "/docs/scene-format.md");
    const size_t begin = doc.find(kReferenceBegin);
    ASSERT_NE(begin, std::string::npos) << "docs/scene-format.md lacks " << kReferenceBegin;
    const size_t end = doc.find(kReferenceEnd, begin);
    ASSERT_NE(end, std::string::npos);
    const std::string generated = scene_reference_markdown();
    EXPECT_EQ(doc.substr(begin, end + kReferenceEnd.size() + 1 - begin), generated)
        << "docs/scene-format.md is stale: run metariver scene --update-doc docs/scene-format.md";
    for (const SceneKey& k : scene_keys()) EXPECT_NE(generated.find(fmt::format("| `{}` |", k.name)), std::string::npos) << k.name;
}

TEST(SceneKeys, EveryPresetWrittenOutLoadsBackToTheSameScene) {
    for (const std::string& name : preset_names()) {
        SceneDef d = preset(name).value();
        if (d.source.kind == TerrainSource::File) d.source.heightmap = "/maps/" + name + ".png";
        const std::string text = scene_to_toml(d, name);
        EXPECT_EQ(text.find("does not load"), std::string::npos) << name << ":\n" << text;
        auto back = parse_scene_toml(text, "/scenes/" + name + ".toml", default_scene());
        ASSERT_TRUE(back.ok()) << name << ": " << back.error().message << "\n" << text;
        for (const SceneKey& k : scene_keys())
            EXPECT_EQ(key_value_toml(k, *back), key_value_toml(k, d)) << name << ": " << k.name;
        // The fields that are not keys of their own.
        EXPECT_EQ(back->spawn.auto_center, d.spawn.auto_center) << name;
        EXPECT_EQ(back->spawn.auto_channel, d.spawn.auto_channel) << name;
        EXPECT_EQ(back->carve_spacing, d.carve_spacing) << name;
        // Every key is in the file, written or commented out.
        for (const SceneKey& k : scene_keys()) {
            const bool written = text.find(fmt::format("\n{} = ", k.leaf())) != std::string::npos ||
                                 text.find(fmt::format("\n# {} = ", k.leaf())) != std::string::npos;
            EXPECT_TRUE(written) << name << ": " << k.name;
        }
    }
}

TEST(SceneKeys, AKeyTheSceneDoesNotReadIsWrittenCommentedOutWithTheReason) {
    const std::string text = scene_to_toml(default_scene());
    // PBF draws no random number: the root seed is refused, so it is a comment.
    EXPECT_NE(text.find("\n# seed = 1"), std::string::npos) << text;
    EXPECT_NE(text.find("# [bullet]"), std::string::npos) << text;
    EXPECT_NE(text.find("(not read here: only solver = \"bullet\" reads [bullet]"), std::string::npos) << text;
    EXPECT_NE(text.find("\nkernel_radius = 1.0"), std::string::npos) << text;
    SceneDef full = preset("paper-full").value();
    const std::string paper = scene_to_toml(full);
    EXPECT_NE(paper.find("(required: this preset's terrain is a PNG"), std::string::npos) << paper;
}

}  // namespace
}  // namespace mr
