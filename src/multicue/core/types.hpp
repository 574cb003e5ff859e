#pragma once
/// \file Basic value types shared by every module.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace multicue {

/// Index of a point in a cloud. 32 bits cover every sensor frame and keep index lists small.
using Index = std::uint32_t;
/// A list of point indices (a cluster, an inlier set, a neighbourhood).
using Indices = std::vector<Index>;

/// 8-bit colour with alpha; alpha is 255 for opaque colours (PCL's convention for `rgb`).
struct Color {
    std::uint8_t r = 0;
    std::uint8_t g = 0;
    std::uint8_t b = 0;
    std::uint8_t a = 255;

    friend bool operator==(const Color&, const Color&) = default;
};

/// Packs a colour as PCL does: uint32 = a<<24 | r<<16 | g<<8 | b.
inline std::uint32_t PackRgba(const Color& c) {
    return (std::uint32_t{c.a} << 24) | (std::uint32_t{c.r} << 16) | (std::uint32_t{c.g} << 8) |
           std::uint32_t{c.b};
}

/// Inverse of PackRgba.
inline Color UnpackRgba(std::uint32_t v) {
    return Color{static_cast<std::uint8_t>((v >> 16) & 0xffu),
                 static_cast<std::uint8_t>((v >> 8) & 0xffu), static_cast<std::uint8_t>(v & 0xffu),
                 static_cast<std::uint8_t>((v >> 24) & 0xffu)};
}

}  // namespace multicue
