// Scenes written out from the table of keys (scene_keys.cpp): a complete, commented TOML
// file (`metariver scene --preset NAME`) and the key reference of docs/scene-format.md
// (`metariver scene --doc`).
#include <metariver/scene_keys.h>

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

namespace mr {

namespace {

/// Appends `text` as comment lines starting at column `column` (the first after what
/// `out` already holds on its last line), wrapped at about 110 columns.
void comment(std::string& out, size_t column, std::string_view text) {
    constexpr size_t kWidth = 110;
    size_t line_start = out.rfind('\n') == std::string::npos ? 0 : out.rfind('\n') + 1;
    auto pad = [&] {
        const size_t at = out.size() - line_start;
        out.append(at < column ? column - at : (at == 0 ? 0 : 1), ' ');
        out += "#";
    };
    pad();
    size_t used = column + 1;
    size_t i = 0;
    while (i < text.size()) {
        size_t j = text.find(' ', i);
        if (j == std::string_view::npos) j = text.size();
        const std::string_view word = text.substr(i, j - i);
        if (used + 1 + word.size() > kWidth && used > column + 1) {
            out += '\n';
            line_start = out.size();
            pad();
            used = column + 1;
        }
        out += ' ';
        out += word;
        used += 1 + word.size();
        i = j + 1;
    }
    out += '\n';
}

/// What a key takes, for its comment and the reference: "number, m, (0, 64]".
std::string key_kind(const SceneKey& k, const char* bar) {
    std::string s;
    if (k.type == KeyType::Choice) {
        for (auto c : k.choices) s += fmt::format("{}{}", s.empty() ? "" : bar, c);
    } else {
        s = to_string(k.type);
    }
    for (auto w : k.words.words) s += fmt::format(" or \"{}\"", w);
    return s;
}

/// Type, unit and range: "number, m/s, [0, 10]".
std::string key_summary(const SceneKey& k) {
    std::string s = key_kind(k, " | ");
    if (!k.unit.empty()) s += ", " + std::string(k.unit);
    if (k.numeric()) s += ", " + k.range.describe();
    return s;
}

std::string key_comment(const SceneKey& k) { return fmt::format("{}; read by {}. {}", key_summary(k), k.readers.text, k.help); }

constexpr const char* kOrigin = "scene.toml";

/// The file with the keys (or whole sections) in `off` commented out with their reason.
std::string render(const SceneDef& d, std::string_view base, const std::map<std::string, std::string, std::less<>>& off) {
    std::string out;
    comment(out, 0,
            fmt::format("metariver scene \"{}\": every key with its value (docs/scene-format.md). A key this scene "
                        "does not read is commented out, with the reason.",
                        d.name));
    constexpr size_t kColumn = 34;
    out += fmt::format("preset = \"{}\"", base);
    comment(out, kColumn, "The scene this file starts from: a key left out (or commented out) keeps its value.");
    for (const SceneSection& s : scene_sections()) {
        const auto section_off = off.find(s.name);
        const bool all_off = !s.name.empty() && section_off != off.end();
        if (!s.name.empty()) {
            out += fmt::format("\n{}[{}]", all_off ? "# " : "", s.name);
            comment(out, kColumn, s.help);
            if (all_off) comment(out, 0, "(not read here: " + section_off->second + ")");
        }
        for (const SceneKey& k : scene_keys()) {
            if (k.section() != s.name) continue;
            const auto key_off = off.find(k.name);
            const bool commented = all_off || key_off != off.end();
            out += fmt::format("{}{} = {}", commented ? "# " : "", k.leaf(), key_value_toml(k, d));
            comment(out, kColumn, key_comment(k));
            if (!all_off && key_off != off.end()) comment(out, kColumn, "(not read here: " + key_off->second + ")");
            if (k.name == "terrain.heightmap" && d.source.kind == TerrainSource::File && d.source.heightmap.empty())
                comment(out, kColumn, "(required: this preset's terrain is a PNG; write its path here, or give --heightmap)");
        }
        // The section's lists after its keys (a [[list]] header ends the section's keys).
        for (const SceneList& l : scene_lists()) {
            if (l.section() != s.name || all_off) continue;
            const bool read = l.readers(d);
            out += "\n";
            comment(out, 0, fmt::format("[[{}]]: {} At most {}; read by {}.{}", l.name, l.help, l.max, l.readers.text,
                                        l.size(d) == 0 ? " None here." : ""));
            for (const SceneListKey& k : l.keys)
                comment(out, 0, fmt::format("  {}: {}. {}", k.key.name, key_summary(k.key), k.key.help));
            std::string entries = list_toml(l, d);
            if (!read) {  // kept as a comment: this scene would refuse it
                std::string c;
                for (size_t a = 0, b; a < entries.size(); a = b + 1) {
                    b = entries.find('\n', a);
                    c += "# " + entries.substr(a, b - a + 1);
                }
                entries = c;
            }
            out += entries;
        }
    }
    return out;
}

}  // namespace

std::string scene_to_toml(const SceneDef& d, std::string_view base) {
    // The reader decides what this scene reads: the file is parsed as it would be loaded,
    // and a key (or section) it refuses as unread is commented out with the reader's
    // reason, until it loads. An error that is not such a refusal (a value out of its
    // range) stops the search; the file then says it does not load.
    SceneDef probe = d;
    if (probe.source.kind == TerrainSource::File && probe.source.heightmap.empty()) probe.source.heightmap = "heightmap.png";
    std::map<std::string, std::string, std::less<>> off;
    std::string problem;
    for (size_t round = 0; round <= scene_keys().size(); ++round) {
        auto r = parse_scene_toml(render(probe, base, off), kOrigin, default_scene());
        if (r) break;
        const std::string& m = r.error().message;
        const size_t start = std::string_view(kOrigin).size() + 2;
        const size_t colon = m.find(": ", start);
        const std::string key = m.substr(start, colon == std::string::npos ? 0 : colon - start);
        const std::string why = colon == std::string::npos ? m : m.substr(colon + 2);
        const bool known = find_scene_key(key) != nullptr ||
                           std::any_of(scene_sections().begin(), scene_sections().end(), [&](auto& s) { return s.name == key; });
        const bool refusal = why.rfind("must be", 0) != 0 && why.rfind("every component", 0) != 0 &&
                             why.rfind("out of float range", 0) != 0 && why.rfind("unknown key", 0) != 0;
        if (!known || !refusal || off.count(key) || key.empty()) {
            problem = m;
            break;
        }
        off[key] = why;
    }
    std::string out = render(d, base, off);
    if (!problem.empty()) out = fmt::format("# This scene does not load as written: {}\n", problem) + out;
    return out;
}

std::string scene_reference_markdown() {
    const SceneDef def = default_scene();
    auto cell = [](std::string_view s) {
        std::string out;
        for (char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c);
        return out;
    };
    std::string out = std::string(kReferenceBegin) + "\n";
    for (const SceneSection& s : scene_sections()) {
        out += fmt::format("\n### {}\n\n{}\n\n", s.name.empty() ? "Top level" : fmt::format("[{}]", s.name), s.help);
        out += "| key | type | unit | range | default | read by | meaning |\n|---|---|---|---|---|---|---|\n";
        for (const SceneKey& k : scene_keys()) {
            if (k.section() != s.name) continue;
            out += fmt::format("| `{}` | {} | {} | {} | `{}` | {} | {} |\n", k.name, cell(key_kind(k, " | ")), k.unit,
                               k.numeric() ? k.range.describe() : "", cell(key_value_toml(k, def)), k.readers.text,
                               cell(k.help));
        }
        for (const SceneList& l : scene_lists()) {
            if (l.section() != s.name) continue;
            out += fmt::format("\n#### [[{}]]\n\n{} At most {} entries; read by {}; none in the default scene. "
                               "Messages name an entry by its place in the file: `{}[1]` is the first.\n\n",
                               l.name, l.help, l.max, l.readers.text, l.name);
            out += "| key | type | unit | range | meaning |\n|---|---|---|---|---|\n";
            for (const SceneListKey& k : l.keys)
                out += fmt::format("| `{}.{}` | {} | {} | {} | {} |\n", l.name, k.key.name, cell(key_kind(k.key, " | ")),
                                   k.key.unit, k.key.numeric() ? k.key.range.describe() : "", cell(k.key.help));
        }
    }
    return out + "\n" + std::string(kReferenceEnd) + "\n";
}

}  // namespace mr
