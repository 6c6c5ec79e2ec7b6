// Peers for `metariver bench --peers`: the project's own drivers in bench/peers run
// three.js MarchingCubes (Node), VTK Flying Edges / Marching Cubes (Debian python3-vtk9)
// and Bullet (Debian libbullet-dev) on W1 and W2 exactly as ../shared/peers/README.md
// defines them; each driver prints one JSON line per configuration. W3's peer is the
// PBF anchor of ../shared/peers/pbf_anchor (CompactNSearch + a minimal PBF loop), built
// as bench_pbf_anchor; it prints one text line.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace mr::app {

struct PeerRequest {
    std::vector<std::pair<int, int>> w1_cases;  ///< (N, R) pairs to run
    std::vector<int> w2_sizes;                  ///< sphere counts to run
    std::vector<int> w3_nx;                     ///< W3 block sides to run (the PBF anchor)
    std::string peers_dir = "bench/peers";      ///< the drivers (source tree)
    std::string bullet_driver;                  ///< built w2 Bullet driver executable ("" = not built)
    std::string pbf_anchor;                     ///< built W3 anchor executable ("" = find it)
    int threads = 2;                            ///< threads for peers that can use them (VTK)
    int timeout_s = 600;                        ///< per driver process (`timeout` prefix); a hung peer is killed
    bool bullet_mesh = true;                    ///< W2: also Bullet's triangle-mesh shape (sizes <= 10000)
};

/// One peer measurement.
struct PeerRow {
    std::string workload;     ///< "w1", "w2" or "w3"
    std::string peer;         ///< e.g. "three.js MarchingCubes", "VTK FlyingEdges3D (2 thr)", "Bullet hf"
    int n = 0;                ///< balls, spheres or W3 particles
    int r = 0;                ///< W1 samples per axis, W3 nx (0 for W2)
    double median_ms = 0.0;   ///< what the peer's time covers is in `covers`
    std::string covers;       ///< "field+surface", "surface only", "step"
    size_t triangles = 0;
    nlohmann::json extra;     ///< anything else the driver printed (tunneled, ...)
};

/// Runs every installed peer on the requested workloads; a peer that is not installed
/// is reported in `missing` (one line each, with how to install it) and skipped.
std::vector<PeerRow> run_peers(const PeerRequest& request, std::vector<std::string>& missing);

/// The project's own figure for one workload size, to put beside the peers.
struct OursRow {
    std::string workload;        ///< "w1", "w2" or "w3"
    int n = 0;                   ///< balls, spheres or W3 particles
    int r = 0;                   ///< W1 samples per axis, W3 nx
    double field_surface_ms = 0.0;  ///< W1: field + surface median
    double surface_ms = 0.0;        ///< W1: surface-only median
    double step_ms = 0.0;           ///< W2, W3: step median
    size_t triangles = 0;
};

/// Prints the side-by-side table (like with like: three.js's frame against our field +
/// surface, VTK's extraction against our surface only, Bullet's and the PBF anchor's
/// step against our step)
/// and returns the JSON "peers" section: {"rows": [...with ours_ms and ratio...], "missing": [...]}.
nlohmann::json print_peers_side_by_side(const std::vector<OursRow>& ours, const std::vector<PeerRow>& peers,
                                        const std::vector<std::string>& missing, int threads);

}  // namespace mr::app
