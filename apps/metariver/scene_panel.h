// The viewer's scene editor (Dear ImGui), listed from the table of scene keys.
#pragma once

#include <metariver/scene.h>

namespace mr::app {

/// One widget per key of scene_keys() that the edited scene reads (KeyReaders), grouped
/// by section; the label carries the unit, the tooltip the help, range and readers.
/// Numbers report an edit once it is finished (slider released, text entered), so
/// dragging a value does not rebuild the Simulation every frame. Returns true when an
/// edit was committed.
bool scene_editor(SceneDef& d);

}  // namespace mr::app
