// The viewer's scene editor: every key of the table (include/metariver/scene_keys.h) the
// edited scene reads, so the panel, the TOML reader and docs/scene-format.md list the
// same keys with the same ranges.
#include "scene_panel.h"

#include <metariver/scene_keys.h>

#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <string>

namespace mr::app {

namespace {

float lower(const KeyRange& r) {
    const auto lo = static_cast<float>(r.zero_too ? std::min(0.0, r.lo) : r.lo);
    return r.lo_open && !r.zero_too ? std::nextafter(lo, INFINITY) : lo;
}
float upper(const KeyRange& r) { return static_cast<float>(r.hi); }
int lower_int(const KeyRange& r) { return static_cast<int>(std::max<double>(r.lo, INT_MIN)); }
int upper_int(const KeyRange& r) { return static_cast<int>(std::min<double>(r.hi, INT_MAX)); }
float speed(float v) { return std::max(std::abs(v) * 0.01f, 1e-4f); }

void tooltip(const SceneKey& k) {
    if (!ImGui::IsItemHovered()) return;
    std::string what = k.numeric() ? k.range.describe() : std::string(to_string(k.type));
    if (!k.unit.empty()) what += " " + std::string(k.unit);
    ImGui::SetTooltip("%s\n%s; read by %s\n%s", std::string(k.name).c_str(), what.c_str(),
                      std::string(k.readers.text).c_str(), std::string(k.help).c_str());
}

/// The words a number-typed key takes ("auto", "channel") and "value": true when an edit
/// was committed; `number` says whether the key now holds a number to edit.
bool word_combo(const SceneKey& k, SceneDef& d, bool& number) {
    const int w = k.words.current(d);
    number = w < 0;
    bool commit = false;
    const std::string label = fmt::format("{}##words {}", k.leaf(), k.name);
    if (ImGui::BeginCombo(label.c_str(), w >= 0 ? std::string(k.words.words[size_t(w)]).c_str() : "value")) {
        for (size_t i = 0; i < k.words.words.size(); ++i)
            if (ImGui::Selectable(std::string(k.words.words[i]).c_str(), int(i) == w) && int(i) != w) {
                k.words.apply(d, int(i));
                commit = true;
            }
        if (ImGui::Selectable("value", w < 0) && w >= 0) {
            k.words.apply(d, -1);
            // A word's stand-in value (count 0, flow_rate -1) becomes a number in range.
            const FieldRef f = k.field(d);
            if (auto* p = std::get_if<int*>(&f); p && !k.range.contains(**p))
                **p = std::clamp(kFixedDefaultCount, lower_int(k.range), upper_int(k.range));
            if (auto* p = std::get_if<float*>(&f); p && !k.range.contains(**p)) **p = std::clamp(0.0f, lower(k.range), upper(k.range));
            commit = true;
        }
        ImGui::EndCombo();
    }
    tooltip(k);
    number = k.words.current(d) < 0;
    return commit;
}

/// The widget of field `f` as key `k`, labelled `leaf` (and the unit), `id` unique.
bool field_widget(const SceneKey& k, const FieldRef& f, std::string_view leaf, std::string_view id) {
    bool commit = false;
    const std::string label = k.unit.empty() ? fmt::format("{}##{}", leaf, id) : fmt::format("{} ({})##{}", leaf, k.unit, id);
    const ImGuiSliderFlags clamp = ImGuiSliderFlags_AlwaysClamp;
    if (auto* p = std::get_if<bool*>(&f)) {
        commit |= ImGui::Checkbox(label.c_str(), *p);
    } else if (auto* p = std::get_if<int*>(&f)) {
        ImGui::DragInt(label.c_str(), *p, std::max(0.2f, speed(float(**p))), lower_int(k.range), upper_int(k.range), "%d", clamp);
        commit |= ImGui::IsItemDeactivatedAfterEdit();
    } else if (auto* p = std::get_if<uint32_t*>(&f)) {
        int i = static_cast<int>(std::min<uint32_t>(**p, 1'000'000'000u));
        ImGui::DragInt(label.c_str(), &i, 1.0f, 0, 1'000'000'000, "%d", clamp);
        **p = static_cast<uint32_t>(i);
        commit |= ImGui::IsItemDeactivatedAfterEdit();
    } else if (auto* p = std::get_if<float*>(&f)) {
        ImGui::DragFloat(label.c_str(), *p, speed(**p), lower(k.range), upper(k.range), "%.4g", clamp);
        commit |= ImGui::IsItemDeactivatedAfterEdit();
    } else if (auto* p = std::get_if<Vec3*>(&f)) {
        ImGui::DragFloat3(label.c_str(), &(*p)->x, speed(std::max({std::abs((*p)->x), std::abs((*p)->y), std::abs((*p)->z), 1.0f})),
                          lower(k.range), upper(k.range), "%.3g", clamp);
        commit |= ImGui::IsItemDeactivatedAfterEdit();
    } else if (auto* p = std::get_if<std::string*>(&f)) {
        const bool heightmap = k.name == "terrain.heightmap";
        ImGui::TextWrapped("%s: %s", std::string(leaf).c_str(),
                           (*p)->empty() && heightmap ? "(drop a PNG on the window)" : (*p)->c_str());
    } else {
        const EnumRef e = std::get<EnumRef>(f);
        const int now = e.get(e.field);
        if (ImGui::BeginCombo(label.c_str(), std::string(k.choices[size_t(now)]).c_str())) {
            for (size_t i = 0; i < k.choices.size(); ++i)
                if (ImGui::Selectable(std::string(k.choices[i]).c_str(), int(i) == now) && int(i) != now) {
                    e.set(e.field, int(i));
                    commit = true;
                }
            ImGui::EndCombo();
        }
    }
    return commit;
}

bool key_widget(const SceneKey& k, SceneDef& d) {
    bool commit = false;
    if (k.words.current) {
        bool number = false;
        commit = word_combo(k, d, number);
        if (!number) return commit;
    }
    commit |= field_widget(k, k.field(d), k.leaf(), k.name);
    tooltip(k);
    return commit;
}

/// A list's entries ([[particles.source]]): each entry's keys and a button that removes
/// it; a button that adds one (a copy of the last, or the list's defaults).
bool list_widget(const SceneList& l, SceneDef& d) {
    bool commit = false;
    const size_t n = l.size(d);
    const std::string title = fmt::format("[[{}]]: {} of at most {}###{}", l.name, n, l.max, l.name);
    if (!ImGui::TreeNode(title.c_str())) return false;
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", std::string(l.help).c_str());
    for (size_t i = 0; i < l.size(d); ++i) {
        ImGui::PushID(static_cast<int>(i));
        ImGui::TextDisabled("%s[%zu]", std::string(l.name).c_str(), i + 1);
        ImGui::SameLine();
        if (ImGui::SmallButton("remove")) {
            for (size_t j = i + 1; j < l.size(d); ++j)  // entries after i move up one place
                for (const SceneListKey& k : l.keys) copy_field(k.item(d, j), k.item(d, j - 1));
            l.resize(d, l.size(d) - 1);
            ImGui::PopID();
            commit = true;
            break;
        }
        for (const SceneListKey& k : l.keys) {
            commit |= field_widget(k.key, k.item(d, i), k.key.name, l.entry_key(i, k));
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s: %s", l.entry_key(i, k).c_str(), std::string(k.key.help).c_str());
        }
        ImGui::PopID();
    }
    if (n < l.max && ImGui::SmallButton("add")) {
        l.resize(d, n + 1);
        if (n > 0)
            for (const SceneListKey& k : l.keys) copy_field(k.item(d, n - 1), k.item(d, n));
        commit = true;
    }
    ImGui::TreePop();
    return commit;
}

}  // namespace

bool scene_editor(SceneDef& d) {
    bool commit = false;
    for (const SceneSection& s : scene_sections()) {
        // A section none of whose keys this scene reads ([bullet] in a river) is left out.
        const SceneDef before = d;
        const bool any = std::any_of(scene_keys().begin(), scene_keys().end(),
                                     [&](const SceneKey& k) { return k.section() == s.name && k.readers(before); });
        if (!any) continue;
        const bool open = s.name.empty() || s.name == "particles" || s.name == "field";
        const std::string header = s.name.empty() ? "Scene" : fmt::format("[{}]", s.name);
        if (!ImGui::CollapsingHeader(header.c_str(), open ? ImGuiTreeNodeFlags_DefaultOpen : 0)) continue;
        for (const SceneKey& k : scene_keys())
            if (k.section() == s.name && k.readers(before)) commit |= key_widget(k, d);
        for (const SceneList& l : scene_lists())
            if (l.section() == s.name && l.readers(before)) commit |= list_widget(l, d);
    }
    return commit;
}

}  // namespace mr::app
