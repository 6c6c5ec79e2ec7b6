// metariver field: the metaballs' scalar field on a regular 3D grid.
//
// Paper: "Real-time river simulation using metaballs", section 2.1, eq. 2: every grid
// value is the sum over the active balls of a falloff, divided by (active balls + 1).
#pragma once

#include <metariver/core.h>

#include <span>
#include <string_view>
#include <vector>

namespace mr {

/// The field layer's one grid: sample (i, j, k) at origin + spacing * (i, j, k), i < nx,
/// j < ny, k < nz; a sample's index is x fastest: i + nx*(j + ny*k). The sparse field
/// keeps only this geometry (its values live in blocks); ScalarGrid adds every value.
struct SampleGrid {
    Vec3 origin{0.0f};           ///< position of sample (0, 0, 0), metres
    float spacing = 1.0f;        ///< metres between neighbouring samples, > 0
    int nx = 0, ny = 0, nz = 0;  ///< samples per axis, >= 0

    size_t samples() const { return static_cast<size_t>(nx) * static_cast<size_t>(ny) * static_cast<size_t>(nz); }
    size_t index(int i, int j, int k) const {
        return static_cast<size_t>(i) + static_cast<size_t>(nx) * (static_cast<size_t>(j) + static_cast<size_t>(ny) * k);
    }
    Vec3 position(int i, int j, int k) const { return origin + spacing * Vec3(float(i), float(j), float(k)); }
};

/// A SampleGrid with a value at every sample (dense), in index order.
struct ScalarGrid : SampleGrid {
    std::vector<float> values;

    float at(int i, int j, int k) const { return values[index(i, j, k)]; }
    size_t size() const { return samples(); }
    /// Resizes (reusing capacity) and sets every value to `fill`.
    void reset(int nx_, int ny_, int nz_, Vec3 origin_, float spacing_, float fill = 0.0f);
};

/// The field layer's one kernel type: the paper's two dense kernels, which reach every
/// sample, and the two compact ones of the sparse field (KernelDef, sparse_field.h).
/// A scene's field.kernel is one of the first three; W1 is the peers' workload's.
enum class FieldKernel {
    InverseSquare,  ///< the paper's eq. 2: 1 / r^2 (r in metres); dense, every ball everywhere
    RadiusOverR,    ///< the paper's code: radius / r; dense
    Poly6,          ///< compact (1 - r^2/radius^2)^3, summed (not averaged): sparse blocks, parallel
    W1,             ///< compact max(0, strength / (r^2 + 1e-6 m^2) - subtract): three.js's addBall, W1
};

/// Where the field's grid lies.
enum class FieldBounds {
    Particles,  ///< the particles' bounding box grown by bounds_offset (the paper)
    Terrain,    ///< the terrain's box (fixed; compact kernels only)
};
std::string_view to_string(FieldBounds b);

std::string_view to_string(FieldKernel k);

struct FieldDef {
    FieldKernel kernel = FieldKernel::InverseSquare;
    FieldBounds bounds = FieldBounds::Particles;
    float radius = 2.0f;         ///< metaball radius, metres (RadiusOverR; Poly6: support radius)
    float resolution = 2.0f;     ///< grid cells per metre, in (0, 64]
    float bounds_offset = 4.0f;  ///< metres the particles' bounding box grows by on every side
    float threshold = 0.54f;     ///< iso value: a sample is inside when value > threshold
};

/// Largest grid the field accepts (samples): 2^27, 512 MiB of floats.
inline constexpr size_t kMaxFieldSamples = size_t{1} << 27;

/// The paper's field: a grid spanning the balls' bounding box grown by bounds_offset,
/// resolution cells per metre (samples per axis = ceil(extent * resolution) + 1), each
/// value the sum of the kernel over all balls divided by (balls + 1). Dense,
/// O(balls x samples). With no balls the grid is left empty (0 samples).
/// r^2 is clamped below at 1e-6 m^2 so a sample on a ball centre stays finite.
/// Returns false (grid left empty) when the grid would exceed kMaxFieldSamples, or for
/// FieldKernel::W1 (its strength and subtract are a KernelDef's: the sparse field's).
bool compute_field_paper(std::span<const Vec3> balls, const FieldDef& def, ScalarGrid& out);

}  // namespace mr
