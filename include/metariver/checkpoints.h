// Checkpoints: a series fed once per frame, kept in constant memory, for statistics over
// runs of any length (issue 13: `run --frames 100000000` grew by about 2.5 GB in its
// outflow meters and stage times before; the soak in scripts/soak.sh checks it stays flat).
#pragma once

#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

namespace mr {

/// Records of `width` doubles fed once per frame: at most `capacity` evenly spaced
/// records are kept (frames 0, s, 2s, ...; when they are full every other one is dropped
/// and the stride s doubles), and the latest record always is. Exact (every record kept)
/// while at most `capacity` were fed. The storage is allocated and written in the
/// constructor: resident memory does not grow with the number of frames.
class Checkpoints {
public:
    Checkpoints() = default;
    /// capacity >= 2 records of `width` >= 1 doubles.
    Checkpoints(size_t capacity, size_t width)
        : capacity_(std::max<size_t>(capacity, 2)), width_(std::max<size_t>(width, 1)),
          data_(capacity_ * width_, 0.0), latest_(width_, 0.0) {}

    /// Feeds one frame's record (`width` values; missing ones are 0).
    void push(std::span<const double> record) {
        if (fed_ % stride_ == 0) {
            if (kept_ == capacity_) {  // thin: records 0, 2, 4, ... become 0, 1, 2, ...
                for (size_t k = 1; 2 * k < kept_; ++k)
                    std::copy_n(data_.begin() + static_cast<std::ptrdiff_t>(2 * k * width_), width_,
                                data_.begin() + static_cast<std::ptrdiff_t>(k * width_));
                kept_ = (kept_ + 1) / 2;
                stride_ *= 2;
            }
            if (fed_ % stride_ == 0) store(data_.data() + kept_++ * width_, record);
        }
        store(latest_.data(), record);
        ++fed_;
    }

    /// Records available: the kept ones, then the latest if it is not the last kept one.
    size_t size() const { return kept_ + (latest_extra() ? 1 : 0); }
    /// Record k of size(), in frame order; the last one is the latest frame's.
    std::span<const double> operator[](size_t k) const {
        if (k >= kept_) return latest_;
        return {data_.data() + k * width_, width_};
    }
    /// Value `c` of every record available, in frame order.
    std::vector<double> column(size_t c) const {
        std::vector<double> v(size());
        for (size_t k = 0; k < v.size(); ++k) v[k] = c < width_ ? (*this)[k][c] : 0.0;
        return v;
    }
    /// Frames fed so far.
    size_t fed() const { return fed_; }
    /// Frames between kept records (1 while every record is kept).
    size_t stride() const { return stride_; }
    size_t capacity() const { return capacity_; }

private:
    bool latest_extra() const { return fed_ > 0 && (kept_ == 0 || (kept_ - 1) * stride_ != fed_ - 1); }
    void store(double* out, std::span<const double> record) const {
        const size_t n = std::min(record.size(), width_);
        std::copy_n(record.begin(), n, out);
        std::fill(out + n, out + width_, 0.0);
    }

    size_t capacity_ = 2;
    size_t width_ = 1;
    std::vector<double> data_;
    std::vector<double> latest_;
    size_t kept_ = 0;
    size_t stride_ = 1;
    size_t fed_ = 0;
};

}  // namespace mr
