#pragma once
/// \file Colour histogram of a cluster or part in HSV space (the colour cue of section 2.5 and
/// Table 3.1, where colour-based descriptors are compared with geometric ones).
///
/// Layout (20 values):
///   0..11   hue, 12 bins of 30 degrees starting at red (0 degrees), over the *chromatic* points
///           (saturation >= min_saturation and value >= min_value); the block sums to the fraction
///           of chromatic points, so a grey or black object has an all-zero hue block
///   12..15  saturation, 4 equal bins over [0, 1]; sums to 1
///   16..19  value (max(r, g, b) / 255), 4 equal bins over [0, 1]; sums to 1
/// Hard binning; a value exactly 1 falls into the last bin. Points that are not finite are skipped.
/// Without finite points every value is 0.

#include "multicue/core/point_cloud.hpp"
#include "multicue/features/feature_common.hpp"

namespace multicue {

inline constexpr int kColourHueBins = 12;
inline constexpr int kColourSatBins = 4;
inline constexpr int kColourValBins = 4;
inline constexpr int kColourHistogramSize = kColourHueBins + kColourSatBins + kColourValBins;

struct ColourHistogramParams {
    float min_saturation = 0.15f;  ///< below: achromatic, no hue vote [0, 1]
    float min_value = 0.1f;        ///< below: too dark for a hue vote [0, 1]
};

/// HSV of one colour: hue in [0, 360), saturation and value in [0, 1].
Eigen::Vector3f RgbToHsv(const Color& c);

/// The 20-bin histogram above. Throws InvalidArgument when the cloud has no colours or a
/// threshold is outside [0, 1].
FeatureVector ComputeColourHistogram(const PointCloud& cloud,
                                     const ColourHistogramParams& params = {});

}  // namespace multicue
