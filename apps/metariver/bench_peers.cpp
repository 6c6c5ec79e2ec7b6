// `metariver bench --peers`: runs the project's peer drivers (bench/peers) as child
// processes, one per workload size, each under `timeout` so that a hung peer cannot hang
// the bench, and reads the one JSON line per configuration each prints.
//   three.js  node bench/peers/w1_three.mjs --cases N:R --frames 10 --warmup 3
//   VTK       /usr/bin/python3 bench/peers/w1_vtk.py --cases N:R --reps 7 --configs fe:T,fe:1,mc
//   Bullet    bench_w2_bullet --n N --shape hf|mesh --steps 600 --settle 120
//   W3 anchor env OMP_NUM_THREADS=T bench_pbf_anchor NX 3   (one text line, not JSON)
// A peer that is not installed, or whose driver fails, becomes one line in `missing`.
#include "bench_peers.h"

#include <fmt/format.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace mr::app {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

constexpr const char* kSetupHint = "run bash bench/peers/setup.sh";

struct ProcResult {
    int code = -1;                 ///< exit status; 124/137 when `timeout` stopped it, 127 not found
    std::vector<json> lines;       ///< stdout lines that parsed as JSON objects
    std::vector<std::string> text; ///< every non-empty stdout line
    std::string last_err;          ///< last non-empty stderr line
};

std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// Runs argv with `timeout -k 10 T`, stdout through a pipe, stderr into a temporary file.
ProcResult run_process(const std::vector<std::string>& argv, int timeout_s) {
    ProcResult r;
    std::string err_path = (fs::temp_directory_path() / "metariver-peer-XXXXXX").string();
    const int fd = mkstemp(err_path.data());
    if (fd < 0) {
        r.last_err = "cannot create a temporary file";
        return r;
    }
    close(fd);
    std::string cmd = fmt::format("timeout -k 10 {} ", timeout_s);
    for (const auto& a : argv) cmd += shell_quote(a) + " ";
    cmd += "2>" + shell_quote(err_path) + " </dev/null";
    std::fflush(stdout);
    if (FILE* p = popen(cmd.c_str(), "r")) {
        std::string out;
        std::array<char, 4096> buf{};
        size_t got = 0;
        while ((got = std::fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), got);
        const int status = pclose(p);
        r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
        std::istringstream lines(out);
        std::string line;
        while (std::getline(lines, line)) {
            if (!line.empty()) r.text.push_back(line);
            if (line.empty() || line.front() != '{') continue;
            json j = json::parse(line, nullptr, false);
            if (!j.is_discarded() && j.is_object()) r.lines.push_back(std::move(j));
        }
    } else {
        r.last_err = "cannot start: " + cmd;
    }
    std::ifstream err(err_path);
    std::string line;
    while (std::getline(err, line))
        if (line.find_first_not_of(" \t\r") != std::string::npos) r.last_err = line;
    std::error_code ec;
    fs::remove(err_path, ec);
    return r;
}

/// Why a run gave nothing usable, in one line.
std::string failure_line(const std::string& peer, const std::string& what, const ProcResult& r, int timeout_s) {
    if (r.code == 124 || r.code == 137) return fmt::format("{}: {}: timed out after {} s", peer, what, timeout_s);
    if (r.code == 127) return fmt::format("{}: {}: not installed ({}): {}", peer, what, r.last_err, kSetupHint);
    if (r.code == 3) return fmt::format("{}: {}", peer, r.last_err.empty() ? std::string("not installed") : r.last_err);
    return fmt::format("{}: {}: failed (exit {}): {}", peer, what, r.code,
                       r.last_err.empty() ? std::string("no output") : r.last_err);
}

fs::path self_dir() {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return ec ? fs::path() : exe.parent_path();
}

/// The drivers' folder: the requested one if it holds the drivers, else the source tree's.
fs::path find_peers_dir(const std::string& requested) {
    std::vector<fs::path> candidates = {requested};
#ifdef METARIVER_PEERS_DIR
    candidates.emplace_back(METARIVER_PEERS_DIR);
#endif
    for (const auto& c : candidates)
        if (fs::exists(c / "w1_three.mjs")) return fs::absolute(c);
    return {};
}

/// A built driver: the requested path, the build's (a compile definition, "" when not
/// built), or next to the metariver binary (<build>/apps/metariver ->
/// <build>/bench/peers/<target>).
fs::path find_built_driver(const std::string& requested, const char* compiled, const char* target) {
    std::vector<fs::path> candidates;
    if (!requested.empty()) candidates.emplace_back(requested);
    if (compiled && *compiled) candidates.emplace_back(compiled);
    if (const fs::path d = self_dir(); !d.empty()) candidates.push_back(d.parent_path() / "bench/peers" / target);
    for (const auto& c : candidates)
        if (access(c.c_str(), X_OK) == 0) return c;
    return {};
}

#ifdef METARIVER_BULLET_DRIVER
constexpr const char* kBulletDriver = METARIVER_BULLET_DRIVER;
#else
constexpr const char* kBulletDriver = "";
#endif
#ifdef METARIVER_PBF_ANCHOR
constexpr const char* kPbfAnchor = METARIVER_PBF_ANCHOR;
#else
constexpr const char* kPbfAnchor = "";
#endif

double median_of(const json& j, const char* key) {
    const json& v = j.at(key);
    return v.is_object() ? v.at("median").get<double>() : v.get<double>();
}

void run_three(const fs::path& dir, const PeerRequest& q, int n, int r, std::vector<PeerRow>& rows,
               std::vector<std::string>& missing) {
    const std::string what = fmt::format("W1 N={} R={}", n, r);
    fmt::print(stderr, "peers: three.js MarchingCubes, {} ...\n", what);
    const ProcResult p = run_process({"node", (dir / "w1_three.mjs").string(), "--cases", fmt::format("{}:{}", n, r),
                                      "--frames", "10", "--warmup", "3"},
                                     q.timeout_s);
    bool got = false;
    for (const json& j : p.lines) {
        if (j.value("bench", "") != "W1" || j.value("N", 0) != n || j.value("R", 0) != r) continue;
        PeerRow row{.workload = "w1", .peer = "three.js MarchingCubes (1 thr)", .n = n, .r = r,
                    .median_ms = median_of(j, "ms_frame"), .covers = "field+surface",
                    .triangles = j.value("triangles", size_t(0)), .extra = j};
        rows.push_back(std::move(row));
        got = true;
    }
    if (!got) missing.push_back(failure_line("three.js", what, p, q.timeout_s));
}

void run_vtk(const fs::path& dir, const PeerRequest& q, int n, int r, std::vector<PeerRow>& rows,
             std::vector<std::string>& missing) {
    const std::string what = fmt::format("W1 N={} R={}", n, r);
    if (access("/usr/bin/python3", X_OK) != 0) {
        missing.push_back(fmt::format("VTK: /usr/bin/python3 not found: {}", kSetupHint));
        return;
    }
    fmt::print(stderr, "peers: VTK FlyingEdges3D / MarchingCubes, {} ...\n", what);
    const int t = std::max(1, q.threads);
    const std::string configs = t > 1 ? fmt::format("fe:{},fe:1,mc", t) : std::string("fe:1,mc");
    const ProcResult p = run_process({"/usr/bin/python3", (dir / "w1_vtk.py").string(), "--cases",
                                      fmt::format("{}:{}", n, r), "--reps", "7", "--configs", configs},
                                     q.timeout_s);
    bool got = false;
    for (const json& j : p.lines) {
        if (j.value("bench", "") != "W1" || j.value("N", 0) != n || j.value("R", 0) != r) continue;
        const std::string cls = j.value("peer", "VTK ?");  // "VTK vtkFlyingEdges3D"
        const int threads = j.value("smp_threads", 1);
        const std::string name = cls.find("FlyingEdges") != std::string::npos
                                     ? fmt::format("VTK FlyingEdges3D ({} thr)", threads)
                                     : std::string("VTK MarchingCubes (1 thr)");
        rows.push_back(PeerRow{.workload = "w1", .peer = name, .n = n, .r = r, .median_ms = median_of(j, "ms_extract"),
                               .covers = "surface only", .triangles = j.value("triangles", size_t(0)), .extra = j});
        got = true;
    }
    if (!got) missing.push_back(failure_line("VTK", what, p, q.timeout_s));
}

void run_bullet(const fs::path& exe, const PeerRequest& q, int n, const std::string& shape, std::vector<PeerRow>& rows,
                std::vector<std::string>& missing) {
    const std::string what = fmt::format("W2 spheres={} shape={}", n, shape);
    fmt::print(stderr, "peers: Bullet, {} ...\n", what);
    const ProcResult p = run_process(
        {exe.string(), "--n", std::to_string(n), "--shape", shape, "--steps", "600", "--settle", "120"}, q.timeout_s);
    bool got = false;
    for (const json& j : p.lines) {
        if (j.value("bench", "") != "W2" || j.value("n", 0) != n) continue;
        json extra = j;
        extra["fall_ms_total"] = j.value("ms_first_120_steps_total", 0.0);
        extra["tunneled"] = j.value("tunneled_below_surface", 0);
        extra["penetrating_0_25"] = j.value("penetration_gt_quarter", 0);
        extra["outside"] = j.value("escaped_domain", 0);
        extra["active"] = j.value("active_at_end", 0);
        rows.push_back(PeerRow{.workload = "w2",
                               .peer = shape == "hf" ? "Bullet heightfield (1 thr)" : "Bullet trimesh (1 thr)",
                               .n = n,
                               .r = 0,
                               .median_ms = j.value("ms_step_median", 0.0),
                               .covers = "step",
                               .triangles = 0,
                               .extra = std::move(extra)});
        got = true;
    }
    if (!got) missing.push_back(failure_line("Bullet", what, p, q.timeout_s));
}

/// W3 with the PBF anchor: `particles=N avg_neighbors=A threads=T iters=I  nsearch=X ms
/// constraint_iters=Y ms  total=Z ms/step` (the mean over its 20 measured steps).
void run_anchor(const fs::path& exe, const PeerRequest& q, int nx, std::vector<PeerRow>& rows,
                std::vector<std::string>& missing) {
    const std::string what = fmt::format("W3 nx={}", nx);
    fmt::print(stderr, "peers: PBF anchor (CompactNSearch), {} ...\n", what);
    const int t = std::max(1, q.threads);
    const ProcResult p = run_process(
        {"env", fmt::format("OMP_NUM_THREADS={}", t), exe.string(), std::to_string(nx), "3"}, q.timeout_s);
    for (const std::string& line : p.text) {
        long n = 0;
        int threads = 0, iters = 0;
        double neighbours = 0, nsearch = 0, constraint = 0, total = 0;
        if (std::sscanf(line.c_str(), "particles=%ld avg_neighbors=%lf threads=%d iters=%d nsearch=%lf ms "
                                      "constraint_iters=%lf ms total=%lf",
                        &n, &neighbours, &threads, &iters, &nsearch, &constraint, &total) != 7)
            continue;
        rows.push_back(PeerRow{.workload = "w3",
                               .peer = fmt::format("PBF anchor ({} thr)", threads),
                               .n = int(n),
                               .r = nx,
                               .median_ms = total,
                               .covers = "step",
                               .triangles = 0,
                               .extra = {{"particles", n}, {"avg_neighbors", neighbours}, {"threads", threads},
                                         {"iterations", iters}, {"ms_nsearch_mean", nsearch},
                                         {"ms_constraint_iters_mean", constraint}, {"ms_step_mean", total},
                                         {"line", line}}});
        return;
    }
    missing.push_back(failure_line("PBF anchor", what, p, q.timeout_s));
}

std::string fmt_ms(double ms) {
    if (ms <= 0.0) return "-";
    return ms < 10.0 ? fmt::format("{:.2f}", ms) : ms < 1000.0 ? fmt::format("{:.1f}", ms) : fmt::format("{:.0f}", ms);
}

}  // namespace

std::vector<PeerRow> run_peers(const PeerRequest& req, std::vector<std::string>& missing) {
    std::vector<PeerRow> rows;
    PeerRequest request = req;
    // METARIVER_PEER_TIMEOUT=S overrides the per-driver limit (for tests and slow machines).
    if (const char* t = std::getenv("METARIVER_PEER_TIMEOUT"); t && std::atoi(t) > 0) request.timeout_s = std::atoi(t);
    std::fflush(stdout);  // the project's table first, then the peers' progress on stderr
    const fs::path dir = find_peers_dir(request.peers_dir);
    if (!request.w1_cases.empty()) {
        if (dir.empty()) {
            missing.push_back(fmt::format("three.js, VTK: drivers not found in '{}' (run from the repository root)",
                                          request.peers_dir));
        } else {
            bool three_ok = true, vtk_ok = true;
            for (auto [n, r] : request.w1_cases) {
                const size_t before = missing.size();
                if (three_ok) run_three(dir, request, n, r, rows, missing);
                // A peer that is not installed is reported once, not once per case.
                if (missing.size() > before && missing.back().find("setup.sh") != std::string::npos) three_ok = false;
                const size_t before_vtk = missing.size();
                if (vtk_ok) run_vtk(dir, request, n, r, rows, missing);
                if (missing.size() > before_vtk && missing.back().find("setup.sh") != std::string::npos) vtk_ok = false;
            }
        }
    }
    if (!request.w2_sizes.empty()) {
        const fs::path exe = find_built_driver(request.bullet_driver, kBulletDriver, "bench_w2_bullet");
        if (exe.empty()) {
            missing.push_back(
                "Bullet: driver bench_w2_bullet not built: run bash bench/peers/setup.sh (libbullet-dev), "
                "then cmake --build <build dir> --target bench_w2_bullet");
        } else {
            for (int n : request.w2_sizes) {
                const size_t before = missing.size();
                run_bullet(exe, request, n, "hf", rows, missing);
                if (request.bullet_mesh && n <= 10000 && missing.size() == before)
                    run_bullet(exe, request, n, "mesh", rows, missing);
            }
        }
    }
    if (!request.w3_nx.empty()) {
        const fs::path exe = find_built_driver(request.pbf_anchor, kPbfAnchor, "bench_pbf_anchor");
        if (exe.empty()) {
            missing.push_back(
                "PBF anchor: bench_pbf_anchor not built (CMake builds it when ../shared/peers/pbf_anchor and OpenMP "
                "are there: cmake --build <build dir> --target bench_pbf_anchor)");
        } else {
            for (int nx : request.w3_nx) run_anchor(exe, request, nx, rows, missing);
        }
    }
    return rows;
}

json print_peers_side_by_side(const std::vector<OursRow>& ours, const std::vector<PeerRow>& peers,
                              const std::vector<std::string>& missing, int threads) {
    json out;
    out["rows"] = json::array();
    out["missing"] = missing;
    fmt::print("\npeers: same workloads, same run; ratio = peer ms / ours ms (> 1: ours is faster); ours on {} "
               "thread{}\n",
               threads, threads == 1 ? "" : "s");
    fmt::print("  W1: three.js's full frame (field + surface) against our field + surface; VTK extracts from a ready\n"
               "      field, against our surface stage only. W2: one 1/60 s step, median over steps 121..600.\n"
               "  W3: the anchor's neighbour search + 3 constraint iterations (mean of 20 steps) against our full\n"
               "      PBF step (median of 20 steps after 3).\n");
    fmt::print("{:<4} {:<15} {:>9} {:<15} {:<28} {:>9} {:<15} {:>8} {:>10} {:>10}\n", "", "size", "ours ms",
               "ours covers", "peer", "peer ms", "peer covers", "ratio", "tris ours", "tris peer");
    std::string last_size;
    for (const PeerRow& p : peers) {
        const OursRow* o = nullptr;
        for (const OursRow& c : ours)
            if (c.workload == p.workload && c.n == p.n && c.r == p.r) o = &c;
        double ours_ms = 0.0;
        std::string ours_covers = "-";
        if (o) {
            if (p.covers == "field+surface") ours_ms = o->field_surface_ms, ours_covers = "field+surface";
            else if (p.covers == "surface only") ours_ms = o->surface_ms, ours_covers = "surface only";
            else ours_ms = o->step_ms, ours_covers = "step";
        }
        const double ratio = ours_ms > 0.0 ? p.median_ms / ours_ms : 0.0;
        const std::string size = p.workload == "w1"   ? fmt::format("N={} R={}", p.n, p.r)
                                 : p.workload == "w3" ? fmt::format("nx={} ({})", p.r, p.n)
                                                      : fmt::format("spheres={}", p.n);
        const bool first = size != last_size;
        last_size = size;
        std::string quality;
        if (p.workload == "w2")
            quality = fmt::format("  tunneled {} pen>0.25 {} outside {}", p.extra.value("tunneled", 0),
                                  p.extra.value("penetrating_0_25", 0), p.extra.value("outside", 0));
        fmt::print("{:<4} {:<15} {:>9} {:<15} {:<28} {:>9} {:<15} {:>8} {:>10} {:>10}{}\n",
                   first ? (p.workload == "w1" ? "W1" : p.workload == "w3" ? "W3" : "W2") : "", first ? size : "", fmt_ms(ours_ms), ours_covers,
                   p.peer, fmt_ms(p.median_ms), p.covers, ratio > 0.0 ? fmt::format("{:.1f}x", ratio) : "-",
                   o && p.workload == "w1" ? std::to_string(o->triangles) : "-",
                   p.workload == "w1" ? std::to_string(p.triangles) : "-", quality);
        json j = {{"workload", p.workload}, {"peer", p.peer},          {"n", p.n},
                  {"median_ms", p.median_ms}, {"covers", p.covers},    {"ours_ms", ours_ms},
                  {"ours_covers", ours_covers}, {"ratio_peer_over_ours", ratio}, {"driver", p.extra}};
        if (p.workload == "w1") {
            j["r"] = p.r;
            j["triangles"] = p.triangles;
            j["ours_triangles"] = o ? o->triangles : 0;
        }
        out["rows"].push_back(std::move(j));
    }
    if (peers.empty()) fmt::print("  (no peer ran)\n");
    for (const std::string& m : missing) fmt::print("  missing: {}\n", m);
    return out;
}

}  // namespace mr::app
