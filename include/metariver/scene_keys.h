// metariver scene keys: the one table of every key a scene file can hold (name, type,
// unit, range, default, help, which scenes read it, what a live edit of it needs). It
// drives the TOML reader (key lookup, types, ranges, which keys a file may set where),
// validate()'s ranges, Simulation::apply's rebuilds, the viewer's parameter panel, the
// CLI's choices (--collision), the reference in docs/scene-format.md
// (scene_reference_markdown(), checked equal by a test) and the commented scene files
// `metariver scene --preset NAME` prints (scene_to_toml()).
#pragma once

#include <metariver/scene.h>

#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <variant>

namespace mr {

enum class KeyType {
    Bool,
    Int,     ///< int
    Seed,    ///< uint32_t, [0, 4294967295]
    Float,   ///< float
    Vec3,    ///< [x, y, z]: three floats, each in the range
    String,
    Choice,  ///< a string from SceneKey::choices
};
std::string_view to_string(KeyType t);

/// The allowed values of a number (every component of a Vec3). `zero_too`: 0 is also
/// allowed (off / the default behaviour) outside [lo, hi]. `text`, when set, is what the
/// reference and the messages say instead (a range that depends on another key, checked
/// by validate() beyond these static bounds).
struct KeyRange {
    double lo = 0.0, hi = 0.0;
    bool lo_open = false, hi_open = false;
    bool zero_too = false;
    std::string_view text;

    bool contains(double v) const;
    /// "[0, 1]", "(0, 64]", "0 or [2, 1000]", or `text`.
    std::string describe() const;
    /// What a message says: "in [0, 1]", "0 or in [2, 1000]".
    std::string phrase() const;
};

/// An enum field seen as the index of its value in SceneKey::choices (the enum's
/// declaration order, checked by a test against the enum's to_string).
struct EnumRef {
    void* field = nullptr;
    int (*get)(const void* field) = nullptr;
    void (*set)(void* field, int index) = nullptr;
    std::string_view (*name)(const void* field) = nullptr;  ///< the enum's to_string
};
/// Where a key's value lives in a SceneDef.
using FieldRef = std::variant<bool*, int*, uint32_t*, float*, Vec3*, std::string*, EnumRef>;

/// A scene file as the reader's refusals see it: the scene as written (the file's values,
/// the base scene's where the file is silent) and what the file holds.
struct SceneFileView {
    const SceneDef& def;
    /// Whether the file holds `name`: a key ("particles.flow_rate") or, for a section's
    /// name, that section as a table ("surface": [surface] rather than surface = false).
    std::function<bool(std::string_view name)> wrote;
};

/// What a condition of a key's readers is about; the TOML reader reports a file's
/// refusals in this order (the largest mistake first).
enum class ReadScope {
    Section,  ///< the scene reads nothing of the key's section ([bullet] outside Bullet)
    Solver,   ///< the scene's solver does not read the key (seed in PBF)
    Value,    ///< another key's value makes it irrelevant (sink.min without a box sink)
};

/// One condition for a scene to read a key, and what the reader says to a file that sets
/// the key in a scene where it fails ("ignored when surface.method = \"none\" (...): remove
/// it or choose a method"), after the key's name, or after its section's for a Section
/// condition (whatever the value; a table of the section that holds no key the scene
/// reads is refused too, an empty [bullet]).
struct ReadIf {
    bool (*holds)(const SceneDef& d) = nullptr;
    std::string (*refusal)(const SceneFileView& f) = nullptr;
    ReadScope scope = ReadScope::Value;
    /// The values that do what the scene does without the key (foam.enabled = false
    /// outside PBF, litres_per_particle = 0 without a rate): accepted though not read;
    /// null: none. Not for a Section condition.
    bool (*agrees)(const SceneDef& d) = nullptr;
};

/// Which scenes read a key: the words for the reference and the viewer, and the conditions
/// (all hold: the scene reads it; none: every scene). validate() checks a key's range only
/// where it is read; the viewer's panel shows only the keys the edited scene reads; the
/// TOML reader refuses a key a file sets where it is not read, with the message of the
/// first condition that fails (scene_toml.cpp). The one place that says who reads a key.
struct KeyReaders {
    std::string_view text;
    std::span<const ReadIf> conditions;

    bool operator()(const SceneDef& d) const { return failing(d) == nullptr; }
    /// The first condition `d` fails, or null when `d` reads the key.
    const ReadIf* failing(const SceneDef& d) const {
        for (const ReadIf& c : conditions)
            if (!c.holds(d)) return &c;
        return nullptr;
    }
};

/// What a live edit of a key (Simulation::apply, the viewer's panel) needs.
enum class KeyEdit {
    /// The solver reads it: applied in place, except by a solver that builds its world
    /// once from its defs (Bullet), where it needs a new Simulation.
    Solver,
    /// Read after the solver (the field, the surface, the renderer, reports): applied in place.
    Live,
    /// What the terrain, the tree, the particle arrays, the random stream or the carve were
    /// built from: a new Simulation.
    Rebuild,
};

/// Words a number-typed key also takes (`count = "auto"`, `spawn_center = "channel"`).
struct KeyWords {
    std::span<const std::string_view> words;
    /// The word the scene's value stands for, -1 when it is a number.
    int (*current)(const SceneDef& d) = nullptr;
    /// Sets word `index`, or -1: a number was just written (clears what a word set).
    void (*apply)(SceneDef& d, int index) = nullptr;
};

struct SceneKey {
    std::string_view name;  ///< "section.key" ("seed" for a root key)
    KeyType type = KeyType::Float;
    std::string_view unit;  ///< "m", "m/s", "1/s^2", ...; empty: none
    KeyRange range;         ///< numbers only
    std::span<const std::string_view> choices;  ///< Choice only, in the enum's order
    KeyWords words;         ///< optional
    KeyReaders readers;
    KeyEdit edit = KeyEdit::Solver;
    std::string_view help;
    FieldRef (*field)(SceneDef& d) = nullptr;

    std::string_view section() const;  ///< "" for a root key
    std::string_view leaf() const;     ///< the name inside its section
    bool numeric() const { return type == KeyType::Int || type == KeyType::Seed || type == KeyType::Float || type == KeyType::Vec3; }
};

struct SceneSection {
    std::string_view name;  ///< "" for the root keys
    std::string_view help;
};

/// A list of tables in a scene file (`[[particles.source]]`, `[[sink.box]]`): every entry
/// holds the keys of `keys`, whose SceneKey rows carry the leaf name ("center"), type,
/// unit, range and help (no `field`, no words); `item` finds entry i's field. Messages
/// name an entry by its 1-based place in the file: "particles.source[2].center".
struct SceneListKey {
    SceneKey key;
    FieldRef (*item)(SceneDef& d, size_t i) = nullptr;
};

struct SceneList {
    std::string_view name;  ///< "section.leaf": the file's [[section.leaf]]
    std::string_view help;
    KeyReaders readers;
    size_t max = 0;  ///< most entries
    size_t (*size)(const SceneDef& d) = nullptr;
    void (*resize)(SceneDef& d, size_t n) = nullptr;
    std::span<const SceneListKey> keys;

    std::string_view section() const;  ///< "particles"
    std::string_view leaf() const;     ///< "source"
    /// "particles.source[2].center" (i is 0-based).
    std::string entry_key(size_t i, const SceneListKey& k) const;
};

/// Every key, section by section in the order of scene_sections().
std::span<const SceneKey> scene_keys();
/// The lists (each in its section).
std::span<const SceneList> scene_lists();
/// The sections, the root ("") first.
std::span<const SceneSection> scene_sections();
/// The key named `name` ("pbf.spacing"), or null.
const SceneKey* find_scene_key(std::string_view name);

/// The key's value in `d` as TOML ("0.5", "[1.0, 2.0, 3.0]", "\"auto\"", "\"poly6\"").
std::string key_value_toml(const SceneKey& key, const SceneDef& d);
/// "" when the key's value in `d` is inside its range (a word always is), else the
/// message without the key ("must be in (0, 64] (got -2)").
std::string key_range_error(const SceneKey& key, const SceneDef& d);
/// Sets the field `f` of Choice key `k` (k.field(d), or a list entry's) to `value`: "" or
/// the message without the key ("must be one of paper, robust, none (got 'x')").
std::string set_choice(const SceneKey& k, const FieldRef& f, std::string_view value);
/// Copies the value of field `from` into `to`, the same field of another SceneDef (or
/// list entry).
void copy_field(const FieldRef& from, const FieldRef& to);
/// The same two for a value found elsewhere (a list entry's field; no words).
std::string field_value_toml(const SceneKey& key, const FieldRef& f);
std::string field_range_error(const SceneKey& key, const FieldRef& f);
/// The lists' entries in `d` where the scene reads them: "" or the first message with
/// its key ("particles.source[2].flow_rate: must be in [0, 10000000] (got -1)", or too
/// many entries).
std::string list_range_error(const SceneDef& d);
/// What the table's ranges cannot say of [[bodies]]: "" or the first message naming the
/// key ("bodies: ..." outside solver = "pbf"; "bodies[2].size: ..." for a component the
/// shape reads that is 0; "bodies[1].mesh: ..." missing for a mesh shape or given to another).
std::string bodies_error(const SceneDef& d);
/// The list's entries in `d` as TOML ([[name]] blocks, one key per line); "" when empty.
std::string list_toml(const SceneList& list, const SceneDef& d);

/// The scene as a complete TOML file a user can start from: `preset = "<base>"` (the
/// scene keys left out keep the values of; a root key outside the table, read before all
/// others), then every key with its value and a comment (type, unit, range, help, who
/// reads it). A key the reader would refuse (one the solver or another key's value makes
/// irrelevant) is written commented out with the reader's reason: it keeps the base's
/// value. So for d = preset(base) (plus a heightmap), load_scene_file of the result gives
/// `d` back (tested for every preset).
std::string scene_to_toml(const SceneDef& d, std::string_view base = "default");

/// The reference section of docs/scene-format.md: one table per section, generated from
/// scene_keys() with the default scene's values (a test checks the file holds it).
std::string scene_reference_markdown();
/// Markers around that section in docs/scene-format.md.
inline constexpr std::string_view kReferenceBegin = "<!-- scene keys: generated by `metariver scene --doc`; do not edit -->";
inline constexpr std::string_view kReferenceEnd = "<!-- end of scene keys -->";

}  // namespace mr
