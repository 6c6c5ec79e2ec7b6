#include "sidecar.h"

#include <metariver/terrain.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>

namespace mr::app {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kMetresPerDegree = 111320.0;  // one degree of latitude (and of longitude at the equator)

/// Reads the keys of one sidecar object; the first problem is kept as a one-line error.
class Keys {
public:
    Keys(const json& j, const std::string& name) : j_(j), name_(name) {}

    const std::optional<Error>& error() const { return error_; }
    bool has(const char* key) const { return j_.contains(key); }

    double number(const char* key) {
        const json* v = get(key);
        if (v && (!v->is_number() || !std::isfinite(v->get<double>())))
            fail(key, fmt::format("must be a finite number (got {})", v->dump()));
        return ok() ? v->get<double>() : 0.0;
    }

    int side(const char* key) {
        const json* v = get(key);
        if (v && (!v->is_number_integer() || v->get<double>() < 2.0 || v->get<double>() > kMaxHeightmapSide))
            fail(key, fmt::format("must be an integer in [2, {}] samples (got {})", kMaxHeightmapSide, v->dump()));
        return ok() ? v->get<int>() : 0;
    }

    /// A [low, high] pair of degrees within [lo, hi] with low < high.
    std::pair<double, double> span(const char* key, double lo, double hi) {
        const json* v = get(key);
        if (!v) return {0.0, 0.0};
        const bool pair = v->is_array() && v->size() == 2 && (*v)[0].is_number() && (*v)[1].is_number();
        const double a = pair ? (*v)[0].get<double>() : 0.0, b = pair ? (*v)[1].get<double>() : 0.0;
        if (!pair || !std::isfinite(a) || !std::isfinite(b) || a < lo || b > hi || !(a < b))
            fail(key, fmt::format("must be [low, high] degrees with {} <= low < high <= {} (got {})", lo, hi, v->dump()));
        return {a, b};
    }

    /// Fails unless 0 < v <= hi (metres), naming `key`.
    void check_range(const char* key, double v, double hi) {
        if (ok() && !(v > 0.0 && v <= hi)) fail(key, fmt::format("must be in (0, {}] metres (got {})", hi, v));
    }

private:
    bool ok() const { return !error_; }
    const json* get(const char* key) {
        if (!ok()) return nullptr;
        if (!j_.contains(key)) {
            fail(key, "missing");
            return nullptr;
        }
        return &j_.at(key);
    }
    void fail(const char* key, const std::string& what) {
        if (ok()) error_ = Error{fmt::format("{}: {}: {}", name_, key, what)};
    }

    const json& j_;
    const std::string& name_;
    std::optional<Error> error_;
};

/// "line L, column C" of a byte offset (nlohmann's parse_error::byte, 1-based).
std::string position(std::string_view text, size_t byte) {
    const size_t end = std::min(byte > 0 ? byte - 1 : 0, text.size());
    size_t line = 1, column = 1;
    for (size_t i = 0; i < end; ++i) {
        if (text[i] == '\n') ++line, column = 1;
        else ++column;
    }
    return fmt::format("line {}, column {}", line, column);
}

}  // namespace

std::string sidecar_path(const std::string& heightmap) {
    return fs::path(heightmap).replace_extension(".json").string();
}

Result<SidecarScale> parse_sidecar_scale(std::string_view text, const std::string& name) {
    json j;
    try {
        j = json::parse(text);
    } catch (const json::parse_error& e) {
        return Error{fmt::format("{}: not valid JSON ({})", name, position(text, e.byte))};
    }
    if (!j.is_object()) return Error{fmt::format("{}: must be a JSON object (got {})", name, j.type_name())};

    Keys k(j, name);
    SidecarScale s;
    const double lo = k.number("metres_min"), hi = k.number("metres_max");
    s.height_scale = hi - lo;
    k.check_range("metres_max - metres_min", s.height_scale, kMaxHeightScale);
    if (k.has("sample_spacing_m")) {
        s.area_scale = k.number("sample_spacing_m");
        k.check_range("sample_spacing_m", s.area_scale, kMaxAreaScale);
        if (k.has("width")) s.width = k.side("width");
        if (k.has("height")) s.height = k.side("height");
    } else {
        const auto [lat0, lat1] = k.span("lat", -90.0, 90.0);
        const auto [lon0, lon1] = k.span("lon", -360.0, 360.0);
        s.width = k.side("width");
        s.height = k.side("height");
        if (k.error()) return *k.error();
        const double dz = (lat1 - lat0) * kMetresPerDegree / (s.height - 1);
        const double cos_lat = std::cos(0.5 * (lat0 + lat1) * std::numbers::pi / 180.0);
        const double dx = (lon1 - lon0) * kMetresPerDegree * cos_lat / (s.width - 1);
        s.area_scale = 0.5 * (dx + dz);
        k.check_range("lat, lon: sample spacing", s.area_scale, kMaxAreaScale);
    }
    if (k.error()) return *k.error();
    return s;
}

Result<SidecarScale> read_sidecar_scale(const std::string& path) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (!fs::exists(st))
        return Error{fmt::format("{}: no such file (--real-scale reads the JSON beside the heightmap)", path)};
    if (!fs::is_regular_file(st)) return Error{fmt::format("{}: not a regular file", path)};
    const auto size = fs::file_size(path, ec);
    if (ec) return Error{fmt::format("{}: cannot read ({})", path, ec.message())};
    if (size > kMaxSidecarBytes)
        return Error{fmt::format("{}: too large for a sidecar ({} bytes, at most {})", path, size, kMaxSidecarBytes)};
    std::ifstream in(path, std::ios::binary);
    std::string text(static_cast<size_t>(size), '\0');
    if (!in || !in.read(text.data(), static_cast<std::streamsize>(text.size())))
        return Error{fmt::format("{}: cannot read", path)};
    return parse_sidecar_scale(text, path);
}

}  // namespace mr::app
