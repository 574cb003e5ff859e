#include "multicue/features/colour.hpp"

#include <algorithm>
#include <cmath>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

int Bin(float x, int bins) { return std::clamp(static_cast<int>(x * bins), 0, bins - 1); }

}  // namespace

Eigen::Vector3f RgbToHsv(const Color& c) {
    const float r = c.r / 255.0f, g = c.g / 255.0f, b = c.b / 255.0f;
    const float hi = std::max({r, g, b});
    const float lo = std::min({r, g, b});
    const float chroma = hi - lo;
    float h = 0.0f;
    if (chroma > 0.0f) {
        if (hi == r) {
            h = 60.0f * std::fmod((g - b) / chroma + 6.0f, 6.0f);
        } else if (hi == g) {
            h = 60.0f * ((b - r) / chroma + 2.0f);
        } else {
            h = 60.0f * ((r - g) / chroma + 4.0f);
        }
        if (h >= 360.0f) h -= 360.0f;
    }
    const float s = hi > 0.0f ? chroma / hi : 0.0f;
    return {h, s, hi};
}

FeatureVector ComputeColourHistogram(const PointCloud& cloud, const ColourHistogramParams& params) {
    if (!(params.min_saturation >= 0.0f && params.min_saturation <= 1.0f)) {
        throw InvalidArgument("colour histogram: min_saturation must be in [0, 1]");
    }
    if (!(params.min_value >= 0.0f && params.min_value <= 1.0f)) {
        throw InvalidArgument("colour histogram: min_value must be in [0, 1]");
    }
    FeatureVector h = FeatureVector::Zero(kColourHistogramSize);
    if (cloud.empty()) return h;
    if (!cloud.HasColors()) {
        throw InvalidArgument("colour histogram: the cloud has no colours (rgb field)");
    }
    std::size_t n = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.points[i].allFinite()) continue;
        const Eigen::Vector3f hsv = RgbToHsv(cloud.colors[i]);
        ++n;
        if (hsv.y() >= params.min_saturation && hsv.z() >= params.min_value) {
            h[Bin(hsv.x() / 360.0f, kColourHueBins)] += 1.0f;
        }
        h[kColourHueBins + Bin(hsv.y(), kColourSatBins)] += 1.0f;
        h[kColourHueBins + kColourSatBins + Bin(hsv.z(), kColourValBins)] += 1.0f;
    }
    if (n > 0) h /= static_cast<float>(n);
    return h;
}

}  // namespace multicue
