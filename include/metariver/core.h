// metariver core: small value types shared by every layer.
//
// Vec3 is glm::vec3 (metres, y up). Result<T> carries a value or an Error whose
// message names the file or field at fault and the allowed range; loaders and
// builders return it instead of asserting (bad input is never a crash).
#pragma once

#include <glm/vec3.hpp>
#include <glm/geometric.hpp>

#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <variant>

namespace mr {

using Vec3 = glm::vec3;

/// Whether the AVX2 paths run: the CPU has AVX2 and METARIVER_NO_AVX2 is not set (set it
/// to run the scalar twins, e.g. to compare the two). Decided once per process; false
/// where the compiler cannot ask the CPU.
inline bool avx2_enabled() {
#if defined(__x86_64__) && defined(__GNUC__)
    static const bool yes = __builtin_cpu_supports("avx2") && std::getenv("METARIVER_NO_AVX2") == nullptr;
    return yes;
#else
    return false;
#endif
}

/// An error with a one-line, user-facing message ("nile.png: not a PNG image").
struct Error {
    std::string message;
};

/// A value or an Error. Minimal stand-in for std::expected (C++23, not in g++ 12).
template <class T>
class [[nodiscard]] Result {
public:
    Result(T value) : data_(std::move(value)) {}
    Result(Error error) : data_(std::move(error)) {}

    bool ok() const { return data_.index() == 0; }
    explicit operator bool() const { return ok(); }
    T& value() & { return std::get<0>(data_); }
    const T& value() const& { return std::get<0>(data_); }
    T&& value() && { return std::get<0>(std::move(data_)); }
    const Error& error() const { return std::get<1>(data_); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }
    T& operator*() & { return value(); }
    const T& operator*() const& { return value(); }

private:
    std::variant<T, Error> data_;
};

/// Result for operations that return nothing on success.
struct Ok {};
using Status = Result<Ok>;

/// Axis-aligned box. An empty box has min > max.
struct Aabb {
    Vec3 min{std::numeric_limits<float>::max()};
    Vec3 max{std::numeric_limits<float>::lowest()};

    void grow(const Vec3& p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    void grow(const Aabb& b) {
        min = glm::min(min, b.min);
        max = glm::max(max, b.max);
    }
    bool empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
    bool contains(const Vec3& p) const {
        return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y && p.z >= min.z &&
               p.z <= max.z;
    }
    Vec3 center() const { return 0.5f * (min + max); }
    Vec3 extent() const { return max - min; }
};

/// The 32-bit LCG with Numerical Recipes constants. Pinned (not std::minstd)
/// so every platform, and the peer drivers in bench/, draw the same numbers.
class Lcg {
public:
    explicit Lcg(uint32_t seed = 12345u) : state_(seed) {}
    uint32_t next_u32() {
        state_ = 1664525u * state_ + 1013904223u;
        return state_;
    }
    /// Uniform double in [0, 1), exact: state / 2^32.
    double next() { return static_cast<double>(next_u32()) / 4294967296.0; }
    /// Uniform float in [lo, hi).
    float uniform(float lo, float hi) {
        return lo + static_cast<float>(next()) * (hi - lo);
    }
    uint32_t state() const { return state_; }

private:
    uint32_t state_;
};

}  // namespace mr
