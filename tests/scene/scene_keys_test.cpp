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
    // Scenes in which the keys are read: the default river (PBF), the springs, Bullet and
    // shallow-water solvers, a box sink, a file terrain, Taubin and uniform smoothing, no flow rate.
    const std::vector<FileLines> contexts = {
        {},
        {{"", {{"solver", "\"springs\""}}}},
        {{"", {{"solver", "\"bullet\""}}}},
        {{"", {{"solver", "\"swe\""}}}},
        {{"", {{"solver", "\"hybrid\""}}}},
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

/// The first condition of `k`'s readers that scene `d` fails where the reader accepts the
/// key anyway (its value agrees with what the scene does without it), or null.
bool agrees(const SceneKey& k, const SceneDef& d) {
    const ReadIf* c = k.readers.failing(d);
    return c && c->scope != ReadScope::Section && c->agrees && c->agrees(d);
}

/// The TOML value `v` of key `k` and the scene `base` with it set (as the reader sets it;
/// `source_written`: the file sets terrain.source, else a heightmap implies "file").
std::vector<std::pair<std::string, SceneDef>> values_in(const SceneKey& k, const SceneDef& base, bool source_written) {
    std::vector<std::pair<std::string, SceneDef>> out;
    auto add = [&](SceneDef d) {
        if (k.words.apply) k.words.apply(d, -1);
        if (k.name == "terrain.heightmap" && !source_written) d.source.kind = TerrainSource::File;
        const std::string v = key_value_toml(k, d);
        for (const auto& [w, e] : out)
            if (w == v) return;
        out.emplace_back(v, d);
    };
    add(base);
    SceneDef d = base;
    const FieldRef f = k.field(d);
    if (auto* p = std::get_if<bool*>(&f)) {
        for (bool b : {true, false}) **p = b, add(d);
    } else if (auto* p = std::get_if<int*>(&f)) {
        for (int v : {**p + 1, 0, static_cast<int>(k.range.lo) + 1})
            if (k.range.contains(v)) **p = v, add(d);
    } else if (auto* p = std::get_if<uint32_t*>(&f)) {
        **p += 1, add(d);
    } else if (auto* p = std::get_if<float*>(&f)) {
        for (double x : {**p * 1.25, 0.0, (k.range.lo + std::min(k.range.hi, 1e3)) / 2.0})
            if (k.range.contains(x)) **p = static_cast<float>(x), add(d);
    } else if (auto* p = std::get_if<Vec3*>(&f)) {
        **p += Vec3(0.5f, 0.25f, 0.75f), add(d);
    } else if (auto* p = std::get_if<std::string*>(&f)) {
        **p = "/maps/h.png", add(d);
    } else {
        const EnumRef e = std::get<EnumRef>(f);
        for (size_t i = 0; i < k.choices.size(); ++i) e.set(e.field, static_cast<int>(i)), add(d);
    }
    for (size_t i = 0; i < k.words.words.size(); ++i) {
        SceneDef w = base;
        k.words.apply(w, static_cast<int>(i));
        if (key_value_toml(k, w) == fmt::format("\"{}\"", k.words.words[i])) out.emplace_back(key_value_toml(k, w), w);
    }
    return out;
}

/// Scene files over a preset whose keys' readers differ: another solver, the surface or
/// a contact off, no rate, a box sink, a procedural terrain, ...
std::vector<FileLines> contexts_to_read() {
    return {
        {},
        {{"", {{"solver", "\"springs\""}}}},
        {{"", {{"solver", "\"bullet\""}}}},
        {{"", {{"solver", "\"bullet\""}}}, {"bullet", {{"springs", "true"}}}},
        {{"", {{"solver", "\"springs\""}}}, {"terrain", {{"condition", "\"carve\""}}}},
        {{"", {{"surface", "false"}}}},
        {{"surface", {{"method", "\"none\""}}}},
        {{"surface", {{"method", "\"taubin\""}}}},
        {{"surface", {{"iterations", "0"}}}},
        {{"field", {{"kernel", "\"radius_over_r\""}}}},
        {{"sink", {{"kind", "\"box\""}, {"min", "[-10, -10, -10]"}, {"max", "[10, 10, 10]"}}}},
        {{"collision", {{"mode", "\"none\""}}}},
        {{"particles", {{"flow_rate", "0"}}}},
        {{"particles", {{"spawn_center", "[1, 2, 3]"}, {"source_shape", "\"point\""}}}},
        {{"terrain", {{"source", "\"bowl\""}}}},
        {{"foam", {{"enabled", "false"}}}, {"pbf", {{"scorr_k", "0.0"}}}},
    };
}

/// What the file `f` that sets key `k` to `v` in the scene `d` (as written) must get from
/// the reader (`r`): accepted where the key's readers say `d` reads it (or the value
/// agrees), else refused with the first failing condition's message, naming the key or
/// its section. Returns whether it was refused for not being read.
bool expect_read_as_the_table_says(const SceneKey& k, const std::string& v, const SceneDef& d, const FileLines& f,
                                   const Result<SceneDef>& r) {
    const bool read = k.readers(d) || agrees(k, d);
    if (r) {
        EXPECT_TRUE(read) << "accepted, but its readers (" << k.readers.text << ") say it is not read";
        EXPECT_EQ(key_value_toml(k, *r), v);
        EXPECT_EQ(k.readers(*r), k.readers(d)) << "the scene as written";
        return false;
    }
    const std::string& m = r.error().message;
    const ReadIf* c = read ? nullptr : k.readers.failing(d);
    const std::string named(c && c->scope == ReadScope::Section ? k.section() : k.name);
    if (m.rfind("s.toml: " + named + ": ", 0) != 0) {  // another key's error may come first
        size_t keys = 0;
        for (const auto& [section, lines] : f) keys += lines.size();
        EXPECT_TRUE(keys > 1 || !validate(d).ok())
            << "refused, not for " << k.name << ", though it is the only key: " << m;
        return false;
    }
    if (read) {  // only for its value: a range another key bounds (validate()), or one the solver cannot take
        const bool value_rule = m.find("\"auto\" sizes a PBF river") != std::string::npos ||
                                m.find("\"paper\" (reflection) is solver = \"springs\"'s response") != std::string::npos;
        EXPECT_TRUE(!validate(d).ok() || value_rule) << "refused though read: " << m;
        return false;
    }
    const SceneFileView file{d, [&](std::string_view name) {
                                 const size_t dot = name.find('.');
                                 if (dot == std::string_view::npos) return f.count(std::string(name)) > 0;
                                 auto t = f.find(std::string(name.substr(0, dot)));
                                 return t != f.end() && t->second.count(std::string(name.substr(dot + 1))) > 0;
                             }};
    EXPECT_EQ(m, "s.toml: " + named + ": " + c->refusal(file));
    return true;
}

// The table is the only source of which keys a scene reads (issue 42): for every preset,
// in a few scenes written over it (another solver, the surface or a contact off, ...),
// every key set to a few of its values is accepted exactly where the key's readers say the
// scene as written reads it (or the value agrees with what the scene does without it),
// and otherwise refused with an error naming the key, or its section where the scene
// reads none of that section.
TEST(SceneKeys, AFileMaySetAKeyExactlyWhereItsReadersSayTheSceneReadsIt) {
    const std::vector<FileLines> contexts = contexts_to_read();
    int accepted = 0, refused = 0;
    for (const std::string& name : preset_names()) {
        SceneDef base = preset(name).value();
        base.source.heightmap = "/maps/" + name + ".png";  // a PNG preset's, the others' not read
        for (const FileLines& c : contexts) {
            auto scene = parse_scene_toml(render(c), "s.toml", base);  // the scene the context writes
            if (!scene) continue;  // one this preset does not read
            for (const SceneKey& k : scene_keys()) {
                if (auto t = c.find(std::string(k.section())); t != c.end() && t->second.count(std::string(k.leaf()))) continue;
                const bool source_written = c.count("terrain") && c.at("terrain").count("source");
                for (const auto& [v, d] : values_in(k, *scene, source_written)) {
                    FileLines f = c;
                    f[std::string(k.section())][std::string(k.leaf())] = v;
                    SCOPED_TRACE(name + ":\n" + render(f));
                    const bool no = expect_read_as_the_table_says(k, v, d, f, parse_scene_toml(render(f), "s.toml", base));
                    refused += no;
                    accepted += !no;
                }
            }
        }
        // The lists: [[particles.source]], [[sink.box]] (an entry without a rate of its own),
        // [[bodies]] (a box: its first shape, no mesh, the highest density).
        for (const SceneList& l : scene_lists()) {
            std::string entry;
            for (const SceneListKey& k : l.keys) {
                const KeyType t = k.key.type;
                const std::string v = t == KeyType::Vec3     ? "[1, 2, 3]"
                                      : t == KeyType::Choice ? fmt::format("\"{}\"", k.key.choices[0])
                                      : t == KeyType::String ? "\"\""
                                      : k.key.range.contains(0.0) ? "0.0"
                                                                  : fmt::format("{:.1f}", k.key.range.hi);
                entry += fmt::format("{} = {}\n", k.key.name, v);
            }
            const std::string text = fmt::format("[[{}]]\n{}", l.name, entry);
            auto r = parse_scene_toml(text, "s.toml", base);
            EXPECT_EQ(r.ok(), l.readers(base)) << name << ": " << text << (r ? "" : r.error().message);
        }
    }
    EXPECT_GT(accepted, 5000);
    EXPECT_GT(refused, 3000);
}

/// What a scene made of its first frames: particles, terrain, surface and foam (FNV-1a).
uint64_t run_fingerprint(const SceneDef& d, int frames) {
    auto sim = Simulation::create(d);
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    if (!sim.ok()) return 0;
    Simulation& s = *sim.value();
    for (int f = 0; f < frames; ++f) s.step(1.0f / 60.0f);
    uint64_t h = 1469598103934665603ull;
    auto mix = [&](const void* p, size_t n) {
        for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<const uint8_t*>(p)[i]) * 1099511628211ull;
    };
    const uint64_t state = s.state_hash();
    mix(&state, sizeof state);
    mix(s.terrain().vertices().data(), s.terrain().vertices().size_bytes());
    mix(s.surface().positions.data(), s.surface().positions.size() * sizeof(Vec3));
    const size_t foam = s.foam() ? s.foam()->particles().size() : 0;
    mix(&foam, sizeof foam);
    return h;
}

/// Scenes whose keys' readers differ: each preset alone, and the springs valley and the
/// default river with another solver, the surface or a contact off, ... (written as a
/// file over them; the river only where it stays a PBF river with the compact kernel:
/// 4000 springs or metaballs of the paper's kernels take seconds a frame).
std::vector<SceneDef> scenes_to_read() {
    std::vector<SceneDef> out;
    for (const std::string& name : preset_names()) out.push_back(preset(name).value());
    for (const std::string name : {"default", "springs-valley"})
        for (const FileLines& c : contexts_to_read())
            if (auto d = parse_scene_toml(render(c), "s.toml", preset(name).value()))
                if (name != "default" || (d->solver == SolverKind::Pbf && d->field.kernel == FieldKernel::Poly6)) out.push_back(*d);
    return out;
}

// The table's readers against the code that reads the keys: in each of those scenes (a
// PNG's terrain replaced by its procedural equivalent), a key the table says the scene does
// not read, set to another value, changes nothing the scene makes in its first frames. (Not
// a key the reader accepts only at the value that agrees with the scene, ReadIf::agrees:
// its other values never run; source_shape = "disc" in Bullet would move an automatic
// source's centre.)
TEST(SceneKeys, AKeyTheTableSaysASceneDoesNotReadChangesNothingInIt) {
    int checked = 0;
    for (SceneDef d : scenes_to_read()) {
        if (!SolverRegistry::builtin().find(d.solver)) continue;  // a build without Bullet: no "bullet" scene runs
        if (d.source.kind == TerrainSource::File) d.source = {.kind = TerrainSource::Strict, .width = d.source.width, .height = d.source.height};
        const int frames = d.spawn.count > 1000 ? 2 : 12;  // the river emits (and prefills) from its first frame
        const uint64_t reference = run_fingerprint(d, frames);
        for (const SceneKey& k : scene_keys()) {
            if (k.readers(d) || k.readers.failing(d)->agrees) continue;
            for (const auto& [v, e] : values_in(k, d, true)) {
                if (v == key_value_toml(k, d) || !validate(e).ok()) continue;
                SCOPED_TRACE(d.name + " (" + std::string(to_string(d.solver)) + "): " + std::string(k.name) + " = " + v);
                EXPECT_EQ(run_fingerprint(e, frames), reference) << "read, though its readers (" << k.readers.text << ") say not";
                ++checked;
                break;
            }
        }
    }
    EXPECT_GT(checked, 1000);
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
