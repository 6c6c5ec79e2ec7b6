// metariver emitters and sinks: where a river's water comes from and where it leaves.
//
// A source (box, disc or point) emits at a flow rate; sinks (a box, or the terrain's
// outlet edges) take particles out and hand them back to the source, so a river runs
// at a fixed particle budget. FlowMeter turns the sink counter into an outflow rate and
// a steady-state verdict. (The terrain's drainage network, which places an automatic
// source at the head of the main channel, is ChannelMap in drainage.h.)
#pragma once

#include <metariver/checkpoints.h>
#include <metariver/core.h>
#include <metariver/terrain.h>

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mr {

enum class SourceShape {
    Box,    ///< uniform in center +- half_extent
    Disc,   ///< uniform in the horizontal disc of radius half_extent.x, height +- half_extent.y
    Point,  ///< exactly at center
};
std::string_view to_string(SourceShape s);

enum class SinkKind {
    None,   ///< particles leaving the terrain are re-spawned (the paper)
    Box,    ///< particles entering [min, max] are recycled to the source
    Edges,  ///< particles leaving the terrain's rectangle over an edge (its outlets) are recycled
};
std::string_view to_string(SinkKind s);

/// A box that takes particles out (and back to the sources), [min, max] in metres.
struct SinkBox {
    Vec3 min{0.0f};
    Vec3 max{0.0f};
    bool contains(const Vec3& p) const {
        return p.x >= min.x && p.y >= min.y && p.z >= min.z && p.x <= max.x && p.y <= max.y && p.z <= max.z;
    }
    bool operator==(const SinkBox&) const = default;
};

/// Most entries of the scene's lists: more sources (`[[particles.source]]`) and more
/// sink boxes (`[[sink.box]]`).
inline constexpr size_t kMaxMoreSources = 16;
inline constexpr size_t kMaxMoreSinks = 16;

struct SinkDef {
    SinkKind kind = SinkKind::None;
    Vec3 min{0.0f};  ///< box sink corner, metres
    Vec3 max{0.0f};  ///< box sink corner, metres
    /// More box sinks (`[[sink.box]]`), taking particles whatever `kind` is; at most
    /// kMaxMoreSinks.
    std::vector<SinkBox> boxes;
    /// The particle at `p` is in the main box (kind = Box) or one of `boxes`.
    bool in_a_box(const Vec3& p) const {
        if (kind == SinkKind::Box && SinkBox{min, max}.contains(p)) return true;
        for (const SinkBox& b : boxes)
            if (b.contains(p)) return true;
        return false;
    }
};

/// One more source of a scene with a particle rate (`[[particles.source]]`): a volume of
/// the main source's shape (particles.source_shape), inflow velocity and ground
/// following, at its own centre, size and rate (in the main source's unit: particles
/// or, with particles.litres_per_particle, litres per second). All sources draw on the
/// one particle budget.
struct SourceDef {
    Vec3 center{0.0f};           ///< metres
    Vec3 half_extent{0.5f};      ///< metres (>= 0)
    float flow_rate = 0.0f;      ///< [0, 1e7]
    bool operator==(const SourceDef&) const = default;
};

/// The scene key of a field of source k, for messages: k = 0 the main source
/// ("particles.spawn_center", "particles.spawn_half_extent", "particles.flow_rate"), k >= 1
/// the list's entry k, 1-based as the reader counts ("particles.source[k].center", ...).
enum class SourceField { Center, HalfExtent, FlowRate };
std::string source_key(size_t k, SourceField f);

/// The half sizes of a source volume along x, y, z as the emitters fill it: a box its
/// half_extent, a disc half_extent.x across both horizontal axes, a point none. The one
/// rule the lattice, the terrain checks (validate_on_terrain) and the viewer's outlines read.
Vec3 source_half_size(SourceShape shape, const Vec3& half_extent);

/// A fluid source that never overlaps water: its volume (box, disc, or the single point
/// of a point source) is cut into a cubic lattice at the fluid's rest spacing, lattice
/// slots under the terrain are dropped, and a particle is emitted only into a slot with
/// no particle within `kFreeFraction` spacings. Slots are filled downstream first (along
/// the inflow velocity, or down when it is zero), so a steady stream leaves the source
/// as lattice layers at the inflow speed.
class LatticeSource {
public:
    struct Def {
        SourceShape shape = SourceShape::Box;
        Vec3 center{0.0f};
        Vec3 half_extent{0.0f};  ///< box half size; disc: radius x, half height y
        Vec3 inflow{0.0f};       ///< velocity given to emitted particles, m/s
        float spacing = 0.5f;    ///< lattice spacing = the fluid's rest spacing, metres
        float clearance = 0.0f;  ///< slots keep their centre this far above the terrain (radius + offset), metres
        float gravity = 9.82f;   ///< m/s^2: how fast a source with no inflow speed drains
        /// Each column of slots is lowered (never raised) until its lowest slot sits
        /// `clearance` + spacing / 4 above the highest ground of its cell footprint: a
        /// source on a slope is born on the ground instead of pouring from a flat disc
        /// metres above its downhill side. Order and max_rate() are as drawn.
        bool follow_ground = false;
    };
    /// A slot is free when no particle is closer than this many spacings.
    static constexpr float kFreeFraction = 0.9f;

    static LatticeSource build(const Def& def, const Terrain& terrain);

    const Def& def() const { return def_; }
    std::span<const Vec3> slots() const { return slots_; }
    /// Particles per second the source can deliver at its spacing and speed: every
    /// lattice layer across the inflow direction leaves once per spacing / speed
    /// seconds. Speed = |inflow| (or sqrt(g d / 2), the mean speed over the first
    /// spacing of a fall from rest, when the inflow speed is below it).
    float max_rate() const { return max_rate_; }
    /// Emits at most `want` particles: writes the chosen slots to `out` (cleared
    /// first), skipping slots within kFreeFraction spacings of any active position
    /// or of a slot chosen before: layer by layer across the inflow, downstream first,
    /// each layer scanned on from where its previous emission stopped (round robin).
    /// Deterministic; O(active + slots).
    void emit(std::span<const Vec3> positions, size_t active, size_t want, std::vector<Vec3>& out);

private:
    Def def_;
    std::vector<Vec3> slots_;
    /// Layers across the inflow direction: slots [layer_start_[l], layer_start_[l + 1]),
    /// downstream first; each layer is scanned from where its last emission stopped
    /// (next_[l]), so a layer fills evenly instead of always from the same side.
    std::vector<uint32_t> layer_start_, next_;
    float max_rate_ = 0.0f;
    Aabb box_;  ///< slots' box grown by one spacing
    // Scratch of emit(), reused: active particles in box_, binned by cell.
    std::vector<Vec3> near_, binned_;
    std::vector<uint32_t> start_, fill_;
};

/// Outflow measurement: feed the cumulative sink count after every frame. Constant memory
/// (kFlowRecords checkpoints): exact for runs of up to kFlowRecords frames; beyond, the
/// second half and its quarters start within a checkpoint stride of the exact frames.
class FlowMeter {
public:
    static constexpr size_t kFlowRecords = 4096;
    void record(double time_s, uint64_t sunk_total);
    struct Summary {
        double rate = 0.0;              ///< particles per second over the second half of the run
        double windows[4] = {0, 0, 0, 0};  ///< rates over the four quarters of the second half
        double first_outflow_s = -1.0;  ///< time of the first particle at a sink, seconds (-1: none)
        bool steady = false;            ///< rate > 0 and every window within +-25 % of the rate
    };
    Summary summary() const;

private:
    Checkpoints records_{kFlowRecords, 2};  ///< (time, sunk_total)
    double first_outflow_s_ = -1.0;
};

}  // namespace mr
