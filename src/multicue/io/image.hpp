#pragma once
/// \file Colour images (PNG through libpng, JPEG through libjpeg): the textures that
/// mesh materials name.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "multicue/core/types.hpp"

namespace multicue::io {

/// An 8-bit RGB image, row-major, top row first.
struct RgbImage {
    std::uint32_t width = 0;
    std::uint32_t height = 0;
    std::vector<Color> pixels;  ///< width * height, alpha 255

    bool empty() const { return pixels.empty(); }
    const Color& At(std::uint32_t x, std::uint32_t y) const {
        return pixels[std::size_t{y} * width + x];
    }
};

/// Reads an image file as RGB (grey images are expanded, alpha is dropped). Throws IoError when the
/// file is missing and FormatError when it cannot be decoded, naming the file.
RgbImage ReadRgbImage(const std::filesystem::path& path);

/// The image shrunk by area averaging so that neither side exceeds `max_side` (kept as it is when
/// it is already that small). Throws InvalidArgument when max_side is 0.
RgbImage ShrinkImage(const RgbImage& image, std::uint32_t max_side);

}  // namespace multicue::io
