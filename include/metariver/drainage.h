// metariver drainage: the terrain's drainage network, on its grid. ChannelMap fills the
// depressions (the priority flood that the drainage conditioning of terrain.h runs too),
// lets every cell drain to its steepest neighbour (D8) and accumulates the flow: the
// scene places an automatic source at the head of the main channel, carves the channel
// along its path, meters the outlets and measures how much of the water stays in the wet
// channel (wet_channel_fraction).
#pragma once

#include <metariver/core.h>
#include <metariver/terrain.h>

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace mr {

/// The terrain's drainage network, on its grid. Depressions are filled (priority flood,
/// Barnes et al. 2014, with a tiny epsilon gradient), every cell drains to its steepest
/// of 8 neighbours (D8), and accumulation counts the cells upstream of each (itself
/// included). Channel cells have accumulation >= channel_threshold().
class ChannelMap {
public:
    static ChannelMap build(const Terrain& t);

    /// The map of `t` after its samples in rows [i0, i1] x columns [j0, j1] changed (a
    /// sculpt stroke or its undo; this map was built or updated for `t` before them), the
    /// same cell for cell as build(t) (tested). Only what the change reaches is redone:
    /// the filled heights of the changed cells and of those whose fill came through them,
    /// the receivers around cells whose fill changed, the accumulation along the old and
    /// new flow paths below changed receivers, the distances around cells that joined or
    /// left the channel (the head and the outlets are found again: a scan of the cells).
    /// A change of the terrain's lowest or highest sample (the fill's epsilon follows
    /// them) builds the map again. Returns the number of cells it wrote (stats, bench).
    size_t update(const Terrain& t, int i0, int i1, int j0, int j1);

    int rows() const { return rows_; }
    int columns() const { return columns_; }
    uint32_t accumulation(int i, int j) const { return acc_[size_t(i) * columns_ + j]; }
    uint32_t channel_threshold() const { return threshold_; }
    bool is_channel(int i, int j) const { return accumulation(i, j) >= threshold_; }
    /// Horizontal distance (metres) from cell (i, j) to the nearest channel cell.
    float distance_to_channel(int i, int j) const { return dist_[size_t(i) * columns_ + j]; }
    /// Head of the main channel: from the cell with the largest accumulation, walk
    /// upstream along the largest contributing neighbour while it is a channel cell.
    /// Returns (row, column).
    std::pair<int, int> main_head() const { return head_; }
    /// Downhill direction (x, z unit vector) of the flow at cell (i, j).
    Vec3 flow_direction(int i, int j) const;
    /// The flow path from cell (i, j): (i, j), its D8 receiver, that one's receiver, ...
    /// up to the border cell where the flow leaves the terrain (receiver -1), included.
    /// Every cell drains to a border cell (the depressions are filled), so it ends there.
    std::vector<std::pair<int, int>> path_from(int i, int j) const;
    /// The last cell of path_from(i, j): where the flow from (i, j) leaves the terrain.
    std::pair<int, int> outlet_of(int i, int j) const;
    /// The channel cell (accumulation >= threshold) nearest to cell (i, j) (Euclidean, in
    /// cells; ties: the lowest row-major index); (i, j) itself when there is no channel cell.
    std::pair<int, int> nearest_channel_cell(int i, int j) const;
    /// A border cell that is a channel cell and drains out of the terrain (receiver -1).
    struct Outlet {
        int row = 0, column = 0;
        uint32_t accumulation = 0;  ///< cells that drain out through it (itself included)
    };
    /// Every outlet, largest accumulation first (ties: row-major order).
    std::span<const Outlet> outlets() const { return outlets_; }

private:
    int rows_ = 0, columns_ = 0;
    float area_scale_ = 1.0f;
    uint32_t threshold_ = 1;
    std::vector<uint32_t> acc_;
    std::vector<int32_t> receiver_;  ///< D8 receiver cell index, -1 at outlets
    std::vector<float> dist_;
    // What update() needs from the build: the filled heights, the fill's epsilon and the
    // terrain's height range it came from, and for the fill and the distances the
    // neighbour each cell's value came through (-1: its own).
    std::vector<double> filled_;
    double eps_ = 0.0, lo_ = 0.0, hi_ = 0.0;
    std::vector<int32_t> fill_from_, dist_from_;

    void find_head_and_outlets();
    std::pair<int, int> head_{0, 0};
    std::vector<Outlet> outlets_;
};

/// Wet channel: a particle is in it when it lies within `width` metres (horizontally)
/// of a channel cell and at most `depth` metres above the terrain there.
struct WetChannelDef {
    float width = 3.0f;  ///< metres
    float depth = 3.0f;  ///< metres
};
/// Fraction of the active particles inside the wet channel (0 when none is active).
float wet_channel_fraction(const Terrain& t, const ChannelMap& m, std::span<const Vec3> positions,
                           std::span<const uint8_t> active, const WetChannelDef& def = {});

}  // namespace mr
