// Helpers simulation.cpp and simulation_edit.cpp share (not part of the library's API).
#pragma once

#include <metariver/scene.h>

#include <utility>
#include <vector>

namespace mr::detail {

/// The main channel from the source: from the main head for the automatic channel
/// source, else from the channel cell nearest the source's centre, to where it leaves.
std::vector<std::pair<int, int>> main_channel_path(const Terrain& t, const ChannelMap& m, const SpawnDef& asked,
                                                   const Vec3& center);
/// Particles per second that fill kRiverFill (three quarters) of the carved section at
/// `speed`: a river a couple of layers deep on the channel's floor, inside its walls.
float section_rate(const SceneDef& def, float area_scale, float speed);
/// The spacing the carve and the source's basin are sized for (SceneDef::carve_spacing).
float carve_spacing_of(const SceneDef& def);
/// field.bounds = "terrain": an error when the fixed field box's samples per axis would
/// not fit (kMaxFieldAxisSamples).
Status field_box_fits(const FieldDef& f, const Terrain& t);
/// swe.rain_mask of a swe or hybrid scene: an error naming the key and the file when the
/// image cannot be read (the solver itself only warns).
Status rain_mask_readable(const SceneDef& d);

}  // namespace mr::detail
