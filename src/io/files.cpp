#include <metariver/io.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <unistd.h>

namespace mr {

Status write_file_atomic(const std::string& path, std::string_view contents) {
    const std::string tmp = fmt::format("{}.tmp{}", path, static_cast<long>(::getpid()));
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) return Error{fmt::format("{}: cannot write (check the folder exists and is writable)", path)};
        out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
        out.flush();
        if (!out) {
            out.close();
            std::remove(tmp.c_str());
            return Error{fmt::format("{}: write failed (disk full?)", path)};
        }
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        std::remove(tmp.c_str());
        return Error{fmt::format("{}: cannot write: {}", path, ec.message())};
    }
    return Ok{};
}

Percentiles percentiles(std::vector<double> s) {
    Percentiles p;
    if (s.empty()) return p;
    std::sort(s.begin(), s.end());
    const auto rank = [&](double q) {
        // nearest-rank: the smallest value with at least q of the sample at or below it
        size_t k = static_cast<size_t>(std::ceil(q * static_cast<double>(s.size())));
        return s[std::clamp<size_t>(k, 1, s.size()) - 1];
    };
    p.median = s.size() % 2 ? s[s.size() / 2] : 0.5 * (s[s.size() / 2 - 1] + s[s.size() / 2]);
    p.p95 = rank(0.95);
    p.mean = std::accumulate(s.begin(), s.end(), 0.0) / static_cast<double>(s.size());
    p.max = s.back();
    return p;
}

}  // namespace mr
