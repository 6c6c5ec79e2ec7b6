// Scene files in TOML (toml++). Every key is checked: unknown keys, wrong types and
// out-of-range values are one-line errors naming the file and the key. The keys, their
// types and ranges come from the table in scene_keys.cpp (docs/scene-format.md is
// generated from it), and so does which keys a scene reads: a key a file sets where its
// readers say the scene does not read it (a solver that does not, another key's value
// that makes it irrelevant) is an error with the message of the table's condition.
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <vector>

namespace mr {

namespace {

/// Reads keys of the table (scene_keys()) from a parsed file; the first error wins.
class Reader {
public:
    explicit Reader(std::string origin) : origin_(std::move(origin)) {}

    bool failed() const { return !error_.empty(); }
    const std::string& error() const { return error_; }

    void fail(const std::string& key, const std::string& what) {
        if (error_.empty()) error_ = fmt::format("{}: {}: {}", origin_, key, what);
    }

    /// Rejects keys of `t` not in `allowed`.
    void allow(const toml::table& t, const std::string& prefix, const std::vector<std::string_view>& allowed) {
        for (const auto& [k, v] : t) {
            if (std::find(allowed.begin(), allowed.end(), k.str()) != allowed.end()) continue;
            std::string list;
            for (auto a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
            fail(prefix + std::string(k.str()), fmt::format("unknown key (allowed here: {})", list));
            return;
        }
    }

    const toml::table* table(const toml::table& root, std::string_view key) {
        const toml::node* n = root.get(key);
        if (!n) return nullptr;
        if (!n->is_table()) {
            fail(std::string(key), "must be a table ([" + std::string(key) + "])");
            return nullptr;
        }
        return n->as_table();
    }

    /// Reads `k` from `t` (its section's table) into `d` when the file has it: the type
    /// is checked, an integer's range too (it must fit); the other numbers' ranges are
    /// checked by check_range once the scene is complete. Returns whether it was given.
    bool key(const toml::table& t, const SceneKey& k, SceneDef& d) {
        const toml::node* n = t.get(k.leaf());
        if (!n) return false;
        return value(*n, k, std::string(k.name), d, [&] { return k.field(d); });
    }

    /// Reads the list `l` from its section's table `t` when the file has it (an array
    /// of tables, at most l.max, each with only the list's keys); the entries replace
    /// the base scene's (validate() checks their ranges).
    void list(const toml::table& t, const SceneList& l, SceneDef& d) {
        const toml::node* n = t.get(l.leaf());
        if (!n) return;
        const std::string name(l.name);
        const toml::array* a = n->as_array();
        if (!a || !a->is_array_of_tables())
            return fail(name, fmt::format("must be a list of tables, each written [[{}]]", name));
        if (a->size() > l.max) return fail(name, fmt::format("at most {} entries (got {})", l.max, a->size()));
        l.resize(d, 0);
        l.resize(d, a->size());
        std::vector<std::string_view> allowed;
        for (const SceneListKey& k : l.keys) allowed.push_back(k.key.name);
        for (size_t i = 0; i < a->size() && !failed(); ++i) {
            const toml::table& e = *(*a)[i].as_table();
            allow(e, fmt::format("{}[{}].", name, i + 1), allowed);
            for (const SceneListKey& k : l.keys)
                if (const toml::node* v = e.get(k.key.name))
                    value(*v, k.key, l.entry_key(i, k), d, [&] { return k.item(d, i); });
        }
    }

    /// Reads `node` into the field `field()` finds, as key `k` (its type, words and an
    /// integer's range), naming it `key` in messages.
    template <class Field>
    bool value(const toml::node& node, const SceneKey& k, const std::string& key, SceneDef& d, Field&& field) {
        const toml::node* n = &node;
        if (k.words.apply && n->is_string()) {
            const std::string s = *n->value<std::string>();
            for (size_t i = 0; i < k.words.words.size(); ++i)
                if (s == k.words.words[i]) {
                    k.words.apply(d, static_cast<int>(i));
                    return true;
                }
            fail(key, fmt::format("must be {} or {}", quoted(k.words.words, " or "), what(k)));
            return true;
        }
        const FieldRef f = field();
        switch (k.type) {
            case KeyType::Bool:
                if (!n->is_boolean()) return fail(key, "must be true or false"), true;
                *std::get<bool*>(f) = n->as_boolean()->get();
                break;
            case KeyType::Int:
            case KeyType::Seed: {
                if (!n->is_integer()) return fail(key, fmt::format("must be an integer {}", k.range.phrase())), true;
                const long long v = n->as_integer()->get();
                if (!k.range.contains(static_cast<double>(v)))
                    return fail(key, fmt::format("must be {} (got {})", k.range.phrase(), v)), true;
                if (k.type == KeyType::Int) *std::get<int*>(f) = static_cast<int>(v);
                else *std::get<uint32_t*>(f) = static_cast<uint32_t>(v);
                break;
            }
            case KeyType::Float: {
                const auto v = n->value<double>();  // accepts integers too
                if (!v) return fail(key, "must be a number"), true;
                const auto x = static_cast<float>(*v);
                if (!std::isfinite(x) && std::isfinite(*v)) return fail(key, fmt::format("out of float range (got {})", *v)), true;
                *std::get<float*>(f) = x;
                break;
            }
            case KeyType::Vec3: {
                const toml::array* a = n->as_array();
                Vec3 out;
                for (int c = 0; a && a->size() == 3 && c < 3; ++c) {
                    auto v = (*a)[static_cast<size_t>(c)].value<double>();
                    if (!v) a = nullptr;
                    else out[c] = static_cast<float>(*v);
                }
                if (!a || a->size() != 3) return fail(key, "must be an array of 3 numbers [x, y, z]"), true;
                *std::get<Vec3*>(f) = out;
                break;
            }
            case KeyType::String: {
                auto s = n->value<std::string>();
                if (!s) return fail(key, "must be a string"), true;
                *std::get<std::string*>(f) = *s;
                break;
            }
            case KeyType::Choice: {
                auto s = n->value<std::string>();
                if (!s) return fail(key, "must be a string"), true;
                if (const std::string e = set_choice(k, f, *s); !e.empty()) return fail(key, e), true;
                break;
            }
        }
        if (k.words.apply) k.words.apply(d, -1);  // a number, not a word
        return true;
    }

    /// The range of a number the file gave (the table's static range).
    void check_range(const SceneKey& k, const SceneDef& d) {
        if (const std::string e = key_range_error(k, d); !e.empty()) fail(std::string(k.name), e);
    }

private:
    static std::string quoted(std::span<const std::string_view> words, const char* sep) {
        std::string s;
        for (auto w : words) s += fmt::format("{}\"{}\"", s.empty() ? "" : sep, w);
        return s;
    }
    /// What a number-typed key takes besides its words.
    static std::string what(const SceneKey& k) {
        if (k.type == KeyType::Vec3) return "an array of 3 numbers [x, y, z]";
        return fmt::format("a {} {}", k.type == KeyType::Float ? "number" : "whole number", k.range.phrase());
    }

    std::string origin_;
    std::string error_;
};

/// What a Bullet scene would otherwise inherit from the default river (its flow-rate
/// source, edge sinks and spawn-all-at-once) is replaced by the paper's engine scene's
/// spawning, where the file does not set it.
void bullet_spawning(const toml::table& root, SceneDef& d) {
    if (d.solver != SolverKind::Bullet) return;
    const toml::table* pt = root["particles"].as_table();
    auto given = [&](const char* key) { return pt && pt->get(key) != nullptr; };
    if (!given("flow_rate")) d.spawn.flow_rate = 0.0f;
    if (!given("litres_per_particle")) d.spawn.litres_per_particle = 0.0f;
    if (!given("source_shape")) d.spawn.shape = SourceShape::Box;
    if (!root.get("sink")) d.sink = SinkDef{};
    else if (const toml::table* st = root["sink"].as_table(); st && !st->get("kind")) d.sink.kind = SinkKind::None;
    if (!given("spawn_interval")) {
        auto engine = preset("paper-engine");
        if (engine) d.spawn.interval = engine->spawn.interval;
    }
}

/// The condition that makes the scene read no key of section `s` ([bullet] outside
/// Bullet), or null when it reads some or only another key's value stops it.
const ReadIf* section_unread(const SceneSection& s, const SceneDef& d) {
    const ReadIf* first = nullptr;
    for (const SceneKey& k : scene_keys()) {
        if (k.section() != s.name) continue;
        const ReadIf* c = k.readers.failing(d);
        if (!c || c->scope != ReadScope::Section || s.name.empty()) return nullptr;
        if (!first) first = c;
    }
    return first;
}

/// Keys the scene as written never reads (issue 13, "no silent option"): a key the file
/// sets where its readers (scene_keys(): a solver that does not read it, another key's
/// value that makes it irrelevant) say it is not read is an error naming the key, or its
/// section where none of that is read, with the message of the first failing condition:
/// what makes it irrelevant and the way out. Only what the file holds is checked (what it
/// inherits from the base scene is never an error); the deciding value may be inherited
/// (a spawn_interval under the default river's flow_rate = "auto"). A value that agrees
/// with what the scene does anyway (ReadIf::agrees) is accepted. The viewer's live editor
/// can change any value after loading; a key is judged by the scene as written.
void refuse_unread_keys(const toml::table& root, Reader& r, const SceneDef& d) {
    const SceneFileView file{d, [&](std::string_view name) {
                                 const size_t dot = name.find('.');
                                 if (dot == std::string_view::npos) {
                                     const toml::node* n = root.get(name);
                                     return n && (n->is_table() || find_scene_key(name));
                                 }
                                 const toml::table* t = root[name.substr(0, dot)].as_table();
                                 return t && t->get(name.substr(dot + 1));
                             }};
    // In the order of ReadScope: the sections the scene does not read at all ([bullet]
    // outside Bullet, even an empty table of one), the keys its solver does not read,
    // the keys another key's value makes irrelevant.
    for (const ReadScope scope : {ReadScope::Section, ReadScope::Solver, ReadScope::Value})
        for (const SceneSection& s : scene_sections()) {
            const toml::table* t = s.name.empty() ? &root : root[s.name].as_table();
            if (!t) continue;
            if (const ReadIf* c = section_unread(s, d)) {
                if (scope == ReadScope::Section) r.fail(std::string(s.name), c->refusal(file));
                continue;
            }
            for (const SceneKey& k : scene_keys()) {
                if (k.section() != s.name || !t->get(k.leaf())) continue;
                const ReadIf* c = k.readers.failing(d);
                if (!c || c->scope != scope || (c->agrees && c->agrees(d))) continue;
                r.fail(std::string(scope == ReadScope::Section ? s.name : k.name), c->refusal(file));
            }
        }
    for (const SceneList& l : scene_lists()) {  // a list the scene as written never reads
        const toml::table* t = l.section().empty() ? &root : root[l.section()].as_table();
        if (t && t->get(l.leaf()) && !l.readers(d))
            r.fail(std::string(l.name), fmt::format("ignored: only {} reads it; remove it", l.readers.text));
    }
}

/// Values a key the scene reads cannot take in this scene (what a scene reads at all is
/// refuse_unread_keys'): PBF slides or ignores the terrain, never reflects; "auto" sizes
/// only a PBF river's rate.
void refuse_values(const toml::table& root, Reader& r, const SceneDef& d) {
    const toml::table* ct = root["collision"].as_table();
    if (ct && ct->get("mode") && d.solver == SolverKind::Pbf)
        if (const std::string why = collision_mode_unused(d.solver, d.collision.mode); !why.empty()) r.fail("collision.mode", why);
    const toml::table* pt = root["particles"].as_table();
    if (pt && pt->get("flow_rate") && d.spawn.auto_rate() && d.solver != SolverKind::Pbf)
        r.fail("particles.flow_rate",
               fmt::format("\"auto\" sizes a PBF river (solver = \"pbf\"); solver = \"{}\" would run it as 0 (one "
                           "activation every spawn_interval frames): give a rate in particles per second, or 0",
                           to_string(d.solver)));
}

/// Messages stay one line whatever the file holds: control characters that reach a
/// message (a quoted key or a string value with a newline in it, toml++'s quote of the
/// text at a syntax error) are written as escapes. Found by fuzz/scene_toml_fuzz.cpp:
/// `sleep = fals` then a newline gave "expected 'false', saw 'fals" and a line break.
std::string one_line(std::string_view s) {
    std::string out;
    out.reserve(s.size());
    for (const char ch : s) {
        const auto c = static_cast<unsigned char>(ch);
        if (c == '\n') out += "\\n";
        else if (c == '\r') out += "\\r";
        else if (c == '\t') out += "\\t";
        else if (c < 0x20 || c == 0x7f) out += fmt::format("\\x{:02x}", c);
        else out += ch;
    }
    return out;
}

Result<SceneDef> parse_scene_toml_lines(std::string_view text, const std::string& origin, const SceneDef& base,
                                        const std::string& heightmap);

}  // namespace

Result<SceneDef> parse_scene_toml(std::string_view text, const std::string& origin, const SceneDef& base) {
    auto d = parse_scene_toml_lines(text, origin, base, {});
    if (!d) return Error{one_line(d.error().message)};
    return d;
}

namespace {

/// `heightmap`: when not empty, replaces the terrain of the scene as written (after its
/// keys were judged on it).
Result<SceneDef> parse_scene_toml_lines(std::string_view text, const std::string& origin, const SceneDef& base,
                                        const std::string& heightmap) {
    toml::table root;
    try {
        root = toml::parse(text, origin);
    } catch (const toml::parse_error& e) {
        return Error{fmt::format("{}:{}:{}: TOML syntax error: {}", origin, e.source().begin.line,
                                 e.source().begin.column, e.description())};
    }

    // `preset = "NAME"`: the file starts from that preset instead of `base` (what
    // `metariver scene --preset NAME` writes, so that the keys its scene does not read,
    // which the file cannot hold, keep the preset's values).
    SceneDef d = base;
    if (const toml::node* n = root.get("preset")) {
        const auto name = n->value<std::string>();
        auto p = name ? preset(*name) : Result<SceneDef>(Error{"must be a string, the name of a preset"});
        if (!p) return Error{fmt::format("{}: preset: {}", origin, p.error().message)};
        d = std::move(p.value());
    }
    Reader r(origin);
    std::vector<const SceneKey*> given;  // the numbers the file holds, range-checked at the end
    for (const SceneSection& s : scene_sections()) {
        std::vector<std::string_view> allowed;
        for (const SceneKey& k : scene_keys())
            if (k.section() == s.name) allowed.push_back(k.leaf());
        for (const SceneList& l : scene_lists())
            if (l.section() == s.name) allowed.push_back(l.leaf());
        const toml::table* t = &root;
        if (s.name.empty()) {
            allowed.push_back("preset");
            for (const SceneSection& sub : scene_sections())
                if (!sub.name.empty()) allowed.push_back(sub.name);
        } else if (const toml::node* n = root.get(s.name); s.name == "surface" && n && !n->is_table()) {
            // `surface` is either the switch (surface = false) or the table of the
            // smoothing ([surface], whose `enabled` is the same switch).
            if (!n->is_boolean()) r.fail("surface", "must be true or false, or a table ([surface])");
            else d.surface = n->as_boolean()->get();
            continue;
        } else {
            t = r.table(root, s.name);
        }
        if (!t) continue;
        r.allow(*t, s.name.empty() ? "" : std::string(s.name) + ".", allowed);
        for (const SceneKey& k : scene_keys())
            if (k.section() == s.name && r.key(*t, k, d) && k.numeric()) given.push_back(&k);
        for (const SceneList& l : scene_lists())
            if (l.section() == s.name) r.list(*t, l, d);
        if (s.name.empty() && root.get("bodies") && !r.failed())  // a body's OBJ, as the heightmap: relative to the scene file
            for (BodyDef& b : d.bodies) {
                const std::filesystem::path mp(b.mesh);
                if (mp.is_relative() && !mp.empty())
                    b.mesh = (std::filesystem::path(origin).parent_path() / mp).lexically_normal().string();
            }
        if (s.name == "swe" && t->get("rain_mask") && !r.failed()) {  // as the heightmap: relative to the scene file
            const std::filesystem::path rp(d.swe.rain_mask);
            if (rp.is_relative() && !rp.empty())
                d.swe.rain_mask = (std::filesystem::path(origin).parent_path() / rp).lexically_normal().string();
        }
        if (s.name == "terrain" && t->get("heightmap") && !r.failed()) {
            if (!t->get("source")) d.source.kind = TerrainSource::File;
            std::filesystem::path hp(d.source.heightmap);
            if (hp.is_relative() && !hp.empty())
                d.source.heightmap = (std::filesystem::path(origin).parent_path() / hp).lexically_normal().string();
        }
    }
    if (!r.failed()) {
        bullet_spawning(root, d);
        refuse_unread_keys(root, r, d);
        refuse_values(root, r, d);
    }
    for (const SceneKey* k : given) r.check_range(*k, d);
    if (r.failed()) return Error{r.error()};
    if (!heightmap.empty()) {
        d.source.kind = TerrainSource::File;
        d.source.heightmap = heightmap;
    }
    if (d.source.kind == TerrainSource::File && d.source.heightmap.empty())
        return Error{fmt::format("{}: terrain.heightmap: required when terrain.source = \"file\"", origin)};
    if (auto v = validate(d); !v) return Error{fmt::format("{}: {}", origin, v.error().message)};
    return d;
}
}  // namespace

Result<SceneDef> load_scene_file(const std::string& path, const std::string& heightmap) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        return Error{fmt::format("{}: scene file not found", path)};
    std::ifstream in(path, std::ios::binary);
    if (!in) return Error{fmt::format("{}: cannot open scene file", path)};
    std::ostringstream ss;
    ss << in.rdbuf();
    auto d = parse_scene_toml_lines(ss.str(), path, default_scene(), heightmap);
    if (!d) return Error{one_line(d.error().message)};
    return d;
}

}  // namespace mr
