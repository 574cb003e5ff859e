#pragma once
/// \file Candidate neighbours packed as sortable keys, and a bounded sorted list of the nearest,
/// shared by the organized (pixel window) searches. Internal helper: not part of the stable API.

#include <bit>
#include <cstddef>
#include <cstdint>

#include "multicue/core/types.hpp"

namespace multicue::detail {

/// A candidate packed as (squared distance bits, index): for non-negative floats the bit pattern
/// orders like the value, so packed keys order by distance, then by index.
inline std::uint64_t PackNeighbour(float squared_distance, Index i) {
    return (std::uint64_t{std::bit_cast<std::uint32_t>(squared_distance)} << 32) | i;
}

inline Index PackedIndex(std::uint64_t key) { return static_cast<Index>(key); }

inline float PackedSquaredDistance(std::uint64_t key) {
    return std::bit_cast<float>(static_cast<std::uint32_t>(key >> 32));
}

/// Inserts `key` into best[0, count), kept ascending and at most `cap` (> 0) long: once full, a
/// key that does not beat the last is dropped, else the last drops out.
inline void InsertNearest(std::uint64_t key, std::uint64_t* best, std::size_t& count,
                          std::size_t cap) {
    std::size_t j = count;
    if (count < cap) {
        ++count;
    } else if (key < best[cap - 1]) {
        j = cap - 1;
    } else {
        return;
    }
    for (; j > 0 && best[j - 1] > key; --j) best[j] = best[j - 1];
    best[j] = key;
}

}  // namespace multicue::detail
