// metariver workloads: the scenes and inputs that tests, `metariver bench` and the
// peer drivers share, defined once (box2d's shared/benchmarks.h idea).
//
// W1 and W2 are defined in shared/peers/README.md; the formulas here reproduce them
// exactly (same LCG, same order of draws), so our numbers sit beside the peers'.
#pragma once

#include <metariver/core.h>
#include <metariver/scene.h>
#include <metariver/terrain.h>

#include <vector>

namespace mr {

// W1 balls: w1_balls() in sparse_field.h (the field layer's tests use them too).

// W1 kernel and grid: w1_kernel_for() and w1_grid() in sparse_field.h.

/// W2 'spheres on terrain': the 257 x 257 valley heightfield (heights in metres,
/// sample (i, j) at world (x, z) = (i, j)), as a Heightmap for TerrainDef
/// {area_scale 1, height_scale 1, paper_row_orientation false}.
Heightmap w2_heightmap();
TerrainDef w2_terrain_def();
/// The analytic W2 height h(x, z).
float w2_height(float x, float z);
/// The first n spheres of the W2 spawn lattice with the seeded jitter.
std::vector<Vec3> w2_spheres(int n, uint32_t seed = 12345u);
inline constexpr float kW2Radius = 0.5f;

/// The default river scene scaled to n particles for the fast pipeline: neighbour-grid
/// springs, robust heightfield collision, all particles spawned at once along the
/// upper channel, spacing shrinking as n grows so the river keeps its size.
SceneDef river_scene(int n);

/// Particles the default PBF river (default_scene(), spacing 0.5 m) holds on the valley
/// once its flow is steady (measured: 786-805 active at 35-120 s, docs/benchmarks.md).
inline constexpr float kPbfRiverSteadyParticles = 800.0f;
/// Field samples per metre pbf_river_scene() stays under (the dense count of the
/// river's bounding box must stay under kMaxFieldSamples).
inline constexpr float kPbfRiverMaxFieldResolution = 9.0f;
/// The default PBF river resolved with about n particles in steady flow (`bench
/// --scenario pbf`): the same terrain, carved channel and volume of water per second,
/// at the spacing s = 0.5 m x cbrt(kPbfRiverSteadyParticles / n) (clamped to [0.05,
/// 1] m). Everything sized in spacings scales with it (kernel radius 2 s, collision
/// radius 0.2 s and offset 0.01 s, field radius 2 s and 1.5 / s samples per metre, at
/// most kPbfRiverMaxFieldResolution); the
/// flow rate is the self-sized default's (size_river) times (0.5 m / s)^3; the budget
/// is 1.5 n, so the source never waits for recycled water.
SceneDef pbf_river_scene(int n);

/// W3 (../shared/peers/pbf_anchor/README.md): an nx * nx * nx/2 block of particles at
/// kW3Spacing with 1 % jitter (std::mt19937 seed 1, the anchor's draws in its order),
/// its lowest corner near `origin` (x along nx, y along nx/2, z along nx).
std::vector<Vec3> w3_block(int nx, Vec3 origin);
inline constexpr float kW3Spacing = 0.1f;

}  // namespace mr
