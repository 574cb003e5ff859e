#include "multicue/segmentation/border_classifier.hpp"

#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {

void BorderClassifierParams::Validate() const {
    if (!(threshold > 0.0f && threshold < 1.0f)) {
        throw InvalidArgument(fmt::format("threshold must be in (0, 1), got {}", threshold));
    }
    if (!std::isfinite(bias))
        throw InvalidArgument(fmt::format("bias must be finite, got {}", bias));
    for (std::size_t k = 0; k < kBorderFeatureCount; ++k) {
        if (!std::isfinite(weights[k])) {
            throw InvalidArgument(fmt::format("weights.{} must be finite, got {}",
                                              kBorderFeatureNames[k], weights[k]));
        }
    }
}

float JoinProbability(const BorderFeatures& f, const BorderClassifierParams& params) {
    double z = params.bias;
    for (std::size_t k = 0; k < kBorderFeatureCount; ++k) z += params.weights[k] * f[k];
    return static_cast<float>(1.0 / (1.0 + std::exp(-z)));
}

}  // namespace multicue
