#pragma once
/// \file A 64-bit key of an integer 3D cell, for hash maps and sets of sparse grid cells.
/// Internal helper: not part of the stable API.

#include <cstdint>

#include <Eigen/Core>

namespace multicue::detail {

/// 21 bits per axis (x highest), each coordinate biased by 2^20: distinct keys for coordinates
/// in (-2^20, 2^20); callers keep their cells in that range.
inline std::uint64_t PackCellKey(const Eigen::Vector3i& c) {
    constexpr std::int64_t kBias = std::int64_t{1} << 20;
    return (static_cast<std::uint64_t>(c.x() + kBias) << 42) |
           (static_cast<std::uint64_t>(c.y() + kBias) << 21) |
           static_cast<std::uint64_t>(c.z() + kBias);
}

}  // namespace multicue::detail
