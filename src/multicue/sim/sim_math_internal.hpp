#pragma once
/// \file Constants and a random draw the sim module's generators share. Internal to the sim
/// module, not part of its API.

#include <cstdint>
#include <numbers>

#include "multicue/sim/rng.hpp"

namespace multicue::sim::math_internal {

inline constexpr float kPi = std::numbers::pi_v<float>;

/// First random stream of the objects of a table-top scene (object k draws from stream 1000 + k).
inline constexpr std::uint64_t kObjectStream = 1000;

/// A uniform draw from [lo, hi) as a float.
inline float U(StreamRng& rng, float lo, float hi) {
    return static_cast<float>(rng.Uniform(lo, hi));
}

}  // namespace multicue::sim::math_internal
