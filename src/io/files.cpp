#include <metariver/io.h>

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <numeric>
#include <unistd.h>

namespace mr {

Status write_file_atomic(const std::string& path, std::string_view contents) {
    // The temporary sibling is on the same file system, so the rename is atomic: readers
    // see the old file or the whole new one, never a prefix. Any failure (a full disk
    // shows up in write() or close()) removes the temporary and names `path`.
    const std::string tmp = fmt::format("{}.tmp{}", path, static_cast<long>(::getpid()));
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0)
        return Error{fmt::format("{}: cannot write: {} (check the folder exists and is writable)", path,
                                 std::strerror(errno))};
    auto fail = [&](const char* what, int err) -> Status {
        std::remove(tmp.c_str());
        return Error{fmt::format("{}: {}: {}", path, what, std::strerror(err))};
    };
    const char* p = contents.data();
    size_t left = contents.size();
    while (left > 0) {
        const ssize_t n = ::write(fd, p, left);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            const int err = n < 0 ? errno : EIO;
            ::close(fd);
            return fail("write failed", err);
        }
        p += n;
        left -= static_cast<size_t>(n);
    }
    if (::close(fd) != 0) return fail("write failed", errno);
    if (::rename(tmp.c_str(), path.c_str()) != 0) return fail("cannot write", errno);
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
