#include "multicue/io/image.hpp"

#include <algorithm>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"

namespace multicue::io {
namespace {

RgbImage FromBgr(const cv::Mat& bgr) {
    RgbImage out;
    out.width = static_cast<std::uint32_t>(bgr.cols);
    out.height = static_cast<std::uint32_t>(bgr.rows);
    out.pixels.resize(std::size_t{out.width} * out.height);
    for (int y = 0; y < bgr.rows; ++y) {
        const auto* row = bgr.ptr<cv::Vec3b>(y);
        for (int x = 0; x < bgr.cols; ++x) {
            out.pixels[static_cast<std::size_t>(y) * out.width + static_cast<std::size_t>(x)] =
                Color{row[x][2], row[x][1], row[x][0], 255};
        }
    }
    return out;
}

}  // namespace

RgbImage ReadRgbImage(const std::filesystem::path& path) {
    const std::string bytes = ReadFileBytes(path);
    const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
    cv::Mat bgr;
    try {
        bgr = cv::imdecode(raw, cv::IMREAD_COLOR);
    } catch (const cv::Exception& e) {
        throw FormatError(fmt::format("{}: cannot decode image: {}", path.string(), e.what()));
    }
    if (bgr.empty() || bgr.type() != CV_8UC3) {
        throw FormatError(fmt::format("{}: cannot decode image", path.string()));
    }
    return FromBgr(bgr);
}

RgbImage ShrinkImage(const RgbImage& image, std::uint32_t max_side) {
    if (max_side == 0) throw InvalidArgument("ShrinkImage: max_side must be > 0");
    if (image.width <= max_side && image.height <= max_side) return image;
    const double f = static_cast<double>(max_side) / std::max(image.width, image.height);
    const int w = std::max(1, static_cast<int>(image.width * f + 0.5));
    const int h = std::max(1, static_cast<int>(image.height * f + 0.5));
    cv::Mat bgr(static_cast<int>(image.height), static_cast<int>(image.width), CV_8UC3);
    for (std::uint32_t y = 0; y < image.height; ++y) {
        auto* row = bgr.ptr<cv::Vec3b>(static_cast<int>(y));
        for (std::uint32_t x = 0; x < image.width; ++x) {
            const Color& c = image.At(x, y);
            row[x] = cv::Vec3b(c.b, c.g, c.r);
        }
    }
    cv::Mat small;
    cv::resize(bgr, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    return FromBgr(small);
}

}  // namespace multicue::io
