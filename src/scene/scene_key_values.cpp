// Scene key values as text: a key's value as TOML, a range and its words, the range
// checks of keys and list entries, and a list's entries as TOML (scene_keys.h). The
// table of keys itself is scene_keys.cpp.
#include <metariver/scene_keys.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <type_traits>
#include <variant>

namespace mr {

namespace {
std::string number(double v) { return fmt::format("{}", v); }
}  // namespace

std::string_view to_string(KeyType t) {
    switch (t) {
        case KeyType::Bool: return "bool";
        case KeyType::Int: return "integer";
        case KeyType::Seed: return "integer";
        case KeyType::Float: return "number";
        case KeyType::Vec3: return "[x, y, z]";
        case KeyType::String: return "string";
        case KeyType::Choice: return "choice";
    }
    return "?";
}

bool KeyRange::contains(double v) const {
    if (!std::isfinite(v)) return false;
    if (zero_too && v == 0.0) return true;
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
}

std::string KeyRange::describe() const {
    if (!text.empty()) return std::string(text);
    return fmt::format("{}{}{}, {}{}", zero_too ? "0 or " : "", lo_open ? "(" : "[", number(lo), number(hi), hi_open ? ")" : "]");
}

std::string KeyRange::phrase() const {
    if (!text.empty() || !zero_too) return "in " + describe();
    return "0 or in " + KeyRange{lo, hi, lo_open, hi_open}.describe();
}

namespace {

/// A float as TOML writes it: the shortest text that reads back to the same float,
/// always with a fraction or an exponent (TOML's 1 is an integer).
std::string toml_float(float v) {
    std::string s = fmt::format("{}", v);
    if (s.find_first_of(".en") == std::string::npos) s += ".0";
    return s;
}

std::string toml_string(std::string_view s) {
    std::string out = "\"";
    for (const char ch : s) {
        const auto c = static_cast<unsigned char>(ch);
        if (ch == '"' || ch == '\\') out += {'\\', ch};
        else if (c < 0x20 || c == 0x7f) out += fmt::format("\\u{:04x}", c);
        else out += ch;
    }
    return out + "\"";
}

/// Reading a key's field from a const scene: the accessor takes a mutable one but only
/// its address is used here.
FieldRef read_field(const SceneKey& k, const SceneDef& d) { return k.field(const_cast<SceneDef&>(d)); }

}  // namespace

std::string key_value_toml(const SceneKey& k, const SceneDef& d) {
    if (k.words.current) {
        if (const int w = k.words.current(d); w >= 0) return toml_string(k.words.words[static_cast<size_t>(w)]);
    }
    return field_value_toml(k, read_field(k, d));
}

std::string field_value_toml(const SceneKey& k, const FieldRef& f) {
    if (auto* p = std::get_if<bool*>(&f)) return **p ? "true" : "false";
    if (auto* p = std::get_if<int*>(&f)) return fmt::format("{}", **p);
    if (auto* p = std::get_if<uint32_t*>(&f)) return fmt::format("{}", **p);
    if (auto* p = std::get_if<float*>(&f)) return toml_float(**p);
    if (auto* p = std::get_if<Vec3*>(&f)) return fmt::format("[{}, {}, {}]", toml_float((*p)->x), toml_float((*p)->y), toml_float((*p)->z));
    if (auto* p = std::get_if<std::string*>(&f)) return toml_string(**p);
    const EnumRef& e = std::get<EnumRef>(f);
    const int i = e.get(e.field);
    return i >= 0 && static_cast<size_t>(i) < k.choices.size() ? toml_string(k.choices[static_cast<size_t>(i)]) : "\"?\"";
}

std::string key_range_error(const SceneKey& k, const SceneDef& d) {
    if (k.words.current && k.words.current(d) >= 0) return {};
    return field_range_error(k, read_field(k, d));
}

std::string field_range_error(const SceneKey& k, const FieldRef& f) {
    if (!k.numeric()) return {};
    if (auto* p = std::get_if<Vec3*>(&f)) {
        const Vec3& v = **p;
        if (k.range.contains(v.x) && k.range.contains(v.y) && k.range.contains(v.z)) return {};
        return fmt::format("every component must be {} (got [{}, {}, {}])", k.range.phrase(), v.x, v.y, v.z);
    }
    double v = 0.0;
    std::string got;
    if (auto* p = std::get_if<int*>(&f)) v = **p, got = fmt::format("{}", **p);
    else if (auto* p = std::get_if<uint32_t*>(&f)) v = **p, got = fmt::format("{}", **p);
    else if (auto* p = std::get_if<float*>(&f)) v = **p, got = fmt::format("{}", **p);
    if (k.range.contains(v)) return {};
    return fmt::format("must be {} (got {})", k.range.phrase(), got);
}

std::string set_choice(const SceneKey& k, const FieldRef& f, std::string_view value) {
    const auto it = std::find(k.choices.begin(), k.choices.end(), value);
    if (it == k.choices.end()) {
        std::string all;
        for (auto c : k.choices) all += fmt::format("{}{}", all.empty() ? "" : ", ", c);
        return fmt::format("must be one of {} (got '{}')", all, value);
    }
    const EnumRef& e = std::get<EnumRef>(f);
    e.set(e.field, static_cast<int>(it - k.choices.begin()));
    return {};
}

void copy_field(const FieldRef& from, const FieldRef& to) {
    std::visit(
        [&](const auto& a) {
            using P = std::decay_t<decltype(a)>;
            const P& b = std::get<P>(to);
            if constexpr (std::is_same_v<P, EnumRef>) b.set(b.field, a.get(a.field));
            else *b = *a;
        },
        from);
}

std::string list_range_error(const SceneDef& d) {
    for (const SceneList& l : scene_lists()) {
        if (!l.readers(d)) continue;
        const size_t n = l.size(d);
        if (n > l.max) return fmt::format("{}: at most {} entries (got {})", l.name, l.max, n);
        SceneDef& m = const_cast<SceneDef&>(d);  // FieldRef is mutable; only read here
        for (size_t i = 0; i < n; ++i)
            for (const SceneListKey& k : l.keys)
                if (std::string e = field_range_error(k.key, k.item(m, i)); !e.empty())
                    return fmt::format("{}: {}", l.entry_key(i, k), e);
    }
    return {};
}

namespace {

/// A body's shape against its other values: the size components it reads, its OBJ;
/// the message names the key after `key` ("bodies[2]" in a scene, "bodies" for one body).
std::string body_shape_error(const BodyDef& b, std::string_view key) {
    const bool mesh_shape = b.shape == BodyShape::ConvexMesh || b.shape == BodyShape::TriangleMesh;
    const int used = b.shape == BodyShape::Box ? 3 : 1;  // a capsule's length .y may be 0 (a sphere)
    const std::string_view shape = to_string(b.shape);
    for (int c = 0; c < used; ++c)
        if (!(b.size[c] > 0.0f))
            return fmt::format("{}.size: component {} must be in (0, 1000] for shape = \"{}\" (got {})", key, "xyz"[c], shape,
                               b.size[c]);
    if (mesh_shape && b.mesh.empty()) return fmt::format("{}.mesh: required for shape = \"{}\" (the OBJ file)", key, shape);
    if (!mesh_shape && !b.mesh.empty())
        return fmt::format("{}.mesh: ignored for shape = \"{}\" (only convex_mesh and triangle_mesh read an OBJ): remove it", key,
                           shape);
    return {};
}

const SceneList& bodies_list() {
    for (const SceneList& l : scene_lists())
        if (l.name == "bodies") return l;
    std::abort();  // the table has [[bodies]] (scene_keys.cpp)
}

}  // namespace

std::string bodies_error(const SceneDef& d) {
    if (d.bodies.empty()) return {};
    if (!bodies_list().readers(d))
        return fmt::format("bodies: only solver = \"pbf\", \"swe\" or \"hybrid\" moves bodies (the water's coupling with "
                           "them; solver = \"{}\" has none): remove [[bodies]]",
                           to_string(d.solver));
    for (size_t i = 0; i < d.bodies.size(); ++i)
        if (std::string e = body_shape_error(d.bodies[i], fmt::format("bodies[{}]", i + 1)); !e.empty()) return e;
    return {};
}

// One body through the [[bodies]] key table's ranges (the scene file's, one definition)
// and its shape's needs; the messages name bodies.<key>.
Status validate_body(const BodyDef& def) {
    SceneDef one;
    one.bodies = {def};
    for (const SceneListKey& k : bodies_list().keys)
        if (std::string e = field_range_error(k.key, k.item(one, 0)); !e.empty())
            return Error{fmt::format("bodies.{}: {}", k.key.name, e)};
    if (std::string e = body_shape_error(def, "bodies"); !e.empty()) return Error{e};
    return Ok{};
}

std::string list_toml(const SceneList& l, const SceneDef& d) {
    std::string out;
    SceneDef& m = const_cast<SceneDef&>(d);  // only read
    for (size_t i = 0; i < l.size(d); ++i) {
        out += fmt::format("[[{}]]\n", l.name);
        for (const SceneListKey& k : l.keys) out += fmt::format("{} = {}\n", k.key.name, field_value_toml(k.key, k.item(m, i)));
    }
    return out;
}

}  // namespace mr
