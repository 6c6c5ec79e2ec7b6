// A small tmpfs mounted for one test, to fill the disk part-way through a write (issue
// 13: atomic writes on a full disk). Mounting needs root (CAP_SYS_ADMIN); where it is
// not permitted, mounted() is false and the test skips with why().
#pragma once

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <sys/mount.h>

namespace mr::test {

class SmallDisk {
public:
    /// Mounts a tmpfs of `bytes` (rounded up to whole 4 KiB pages) at `dir`, created if missing.
    SmallDisk(const std::filesystem::path& dir, size_t bytes) : dir_(dir) {
        std::filesystem::create_directories(dir_);
        const std::string options = "size=" + std::to_string(bytes) + ",mode=0777";
        if (::mount("metariver-test", dir_.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) == 0) mounted_ = true;
        else why_ = std::string("cannot mount a tmpfs for the full-disk test (") + std::strerror(errno) +
                    "; needs root): skipped";
    }
    ~SmallDisk() {
        if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
    }
    SmallDisk(const SmallDisk&) = delete;
    SmallDisk& operator=(const SmallDisk&) = delete;

    bool mounted() const { return mounted_; }
    const std::string& why() const { return why_; }
    const std::filesystem::path& dir() const { return dir_; }

    /// Bytes a tmpfs charges for a file of `size` bytes: whole pages.
    static size_t charged(size_t size) { return (size + 4095) / 4096 * 4096; }

private:
    std::filesystem::path dir_;
    bool mounted_ = false;
    std::string why_;
};

}  // namespace mr::test
