// Scene rules that resolve a PBF river from its terrain: what counts as a river, the
// automatic values ("auto") a river and still water resolve to, the carved channel's
// section, and the river's self-sizing (docs/river.md, "Sizing" and "Spacing").
#include <metariver/scene.h>

#include "simulation_internal.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace mr {

namespace detail {
float section_rate(const SceneDef& def, float area_scale, float speed) {
    const CarveDef c = carve_def(def, area_scale);
    const float s = def.pbf.spacing;
    return kRiverFill * c.floor_m * c.depth_m * speed / (s * s * s);
}

float carve_spacing_of(const SceneDef& def) { return def.carve_spacing > 0.0f ? def.carve_spacing : def.pbf.spacing; }
}  // namespace detail

bool is_river(const SceneDef& def) {
    return def.solver == SolverKind::Pbf && def.sink.kind == SinkKind::Edges &&
           (def.spawn.has_rate() || def.spawn.auto_rate());
}

TerrainCondition resolved_condition(const SceneDef& def) {
    if (def.terrain.condition != TerrainCondition::Auto) return def.terrain.condition;
    return is_river(def) ? TerrainCondition::Carve : TerrainCondition::None;
}

namespace {
/// A PBF value with "auto" (`automatic`) resolved: 0 for a river, `still` for still water.
float river_or_still(const SceneDef& def, float value, float automatic, float still) {
    if (value != automatic) return value;
    return is_river(def) ? 0.0f : still;
}
}  // namespace

float resolved_sleep_threshold(const SceneDef& def) {
    return river_or_still(def, def.pbf.sleep_threshold, kAutoSleep, kSleepThreshold);
}

float resolved_damping(const SceneDef& def) { return river_or_still(def, def.pbf.damping, kAutoDamping, kStillDamping); }

float resolved_wall_density(const SceneDef& def) {
    return river_or_still(def, def.pbf.wall_density, kAutoWallDensity, kStillWallDensity);
}

float resolved_contact_band(const SceneDef& def) {
    return river_or_still(def, def.pbf.contact_band, kAutoContactBand, kStillContactBand);
}

CarveDef carve_def(const SceneDef& def, float area_scale) {
    // A flat bed three samples (or four spacings) wide, walls 1.5 samples (or two
    // spacings) wide on each side, two spacings deep.
    const float d = detail::carve_spacing_of(def);
    const float floor = std::max(3.0f * area_scale, 4.0f * d);
    return CarveDef{.width_m = floor + 2.0f * std::max(1.5f * area_scale, 2.0f * d), .floor_m = floor, .depth_m = 2.0f * d};
}

std::vector<std::pair<int, int>> keep_off_edges(std::span<const std::pair<int, int>> path, int rows, int columns,
                                                int margin) {
    std::vector<std::pair<int, int>> out;
    if (path.empty()) return out;
    const int mi = std::clamp(margin, 0, rows / 4), mj = std::clamp(margin, 0, columns / 4);
    auto step_to = [&](std::pair<int, int> c) {  // straight 8-connected steps from out.back()
        if (out.empty()) {
            out.push_back(c);
            return;
        }
        auto [i, j] = out.back();
        while (i != c.first || j != c.second) {
            i += (c.first > i) - (c.first < i);
            j += (c.second > j) - (c.second < j);
            out.emplace_back(i, j);
        }
    };
    for (size_t k = 0; k < path.size(); ++k) {
        auto [i, j] = path[k];
        if (k > 0 && k + 1 < path.size()) {
            i = std::clamp(i, mi, std::max(mi, rows - 1 - mi));
            j = std::clamp(j, mj, std::max(mj, columns - 1 - mj));
        }
        step_to({i, j});
    }
    return out;
}

float river_speed(float slope) {
    const float s = std::isfinite(slope) ? std::max(slope, kCarveLeastSlope) : 1.0f;
    return std::clamp(kRiverSpeedPerRootSlope * std::sqrt(s), kRiverTransitSpeed, kRiverSpeed);
}

RiverSize size_river(const SceneDef& def, float area_scale, float channel_length_m, float channel_slope) {
    RiverSize r;
    r.channel_length_m = channel_length_m;
    r.channel_slope = channel_slope;
    r.speed = river_speed(channel_slope);
    r.rate = std::clamp(detail::section_rate(def, area_scale, r.speed), kRiverMinRate, kRiverMaxRate);
    // The budget: the particles on their way (the rate times the time they spend on the
    // channel at kRiverTransitSpeed, twice over: slower reaches, the source's basin,
    // eddies) plus the particles the source's pile holds.
    const float transit_s = channel_length_m / kRiverTransitSpeed;
    const double want = double(r.rate) * double(transit_s) * kRiverBudgetMargin + kRiverSourcePile;
    r.count = int(std::clamp(std::ceil(want), double(kRiverMinCount), double(kRiverMaxCount)));
    if (want > double(kRiverMaxCount)) {  // the budget's ceiling: a thinner river, not gaps
        r.rate = std::max(kRiverMinRate, float((kRiverMaxCount - kRiverSourcePile) / (transit_s * kRiverBudgetMargin)));
        r.capped = true;
    }
    return r;
}

void scale_river_lengths(SceneDef& d, float spacing, float max_field_resolution) {
    const float k = spacing / d.pbf.spacing;
    if (!(k > 0.0f) || !std::isfinite(k) || k == 1.0f) return;
    d.pbf.spacing = spacing;
    d.pbf.kernel_radius *= k;
    d.collision.radius *= k;
    d.collision.offset *= k;
    d.field.radius *= k;
    d.field.bounds_offset *= k;
    d.field.resolution = std::min(max_field_resolution, d.field.resolution / k);
    if (d.carve_spacing == 0.0f) {  // the source with the channel it was sized for
        d.spawn.half_extent *= k;
        d.spawn.auto_height *= k;
    }
}

float auto_spacing(const SceneDef& def, const Terrain& t) {
    // Two particles per sample at the scene's spacing per metre of area_scale (the bed,
    // three samples wide, holds six across at any scale), at most kAutoSpacingAcross
    // across the terrain's shorter side.
    float d = def.pbf.spacing * t.area_scale();
    const Vec3 e = t.bounds().extent();
    const float shorter = std::min(e.x, e.z);
    if (shorter > 0.0f) d = std::min(d, shorter / kAutoSpacingAcross);
    return std::clamp(d, kAutoSpacingMin, kAutoSpacingMax);
}

}  // namespace mr
