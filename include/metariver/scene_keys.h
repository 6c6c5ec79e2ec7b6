// metariver scene keys: the one table of every key a scene file can hold (name, type,
// unit, range, default, help, which solver or mode reads it). It drives the TOML reader
// (key lookup, types, ranges), validate()'s ranges, the viewer's parameter panel, the
// reference in docs/scene-format.md (scene_reference_markdown(), checked equal by a test)
// and the commented scene files `metariver scene --preset NAME` prints (scene_to_toml()).
#pragma once

#include <metariver/scene.h>

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

/// Which solver or mode reads a key: the words for the reference and the viewer, and the
/// test on a scene (null: every scene). validate() checks a key's range only where it
/// is read; the viewer's panel shows only the keys the edited scene reads.
struct KeyReaders {
    std::string_view text;
    bool (*reads)(const SceneDef& d) = nullptr;
    bool operator()(const SceneDef& d) const { return !reads || reads(d); }
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
