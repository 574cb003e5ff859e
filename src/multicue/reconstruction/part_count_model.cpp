#include "multicue/reconstruction/part_count_model.hpp"

#include <math.h>

#include <cmath>
#include <string>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

// log k!, without std::lgamma: glibc's lgamma writes the global signgam, a data race when objects
// are modelled in parallel (found by ThreadSanitizer). lgamma_r returns the sign instead.
double LogFactorial(std::size_t k) {
    int sign = 0;
    return ::lgamma_r(static_cast<double>(k) + 1.0, &sign);
}

double Poisson(double lambda, std::size_t k) {
    // In logs: k! overflows long before the probabilities stop mattering.
    return std::exp(static_cast<double>(k) * std::log(lambda) - lambda - LogFactorial(k));
}

}  // namespace

void PartCountParams::Validate() const {
    for (const double mean : {flat_mean, round_mean, other_mean}) {
        if (!(mean > 0.0) || !std::isfinite(mean)) {
            throw InvalidArgument("part count means must be > 0 and finite, got " +
                                  std::to_string(mean));
        }
    }
}

ObjectType ObjectTypeOf(Category category) {
    switch (category) {
        case Category::kBox:
        case Category::kFlat:
        case Category::kPlate:
            return ObjectType::kFlat;
        case Category::kSphere:
        case Category::kCylinder:
            return ObjectType::kRound;
        default:
            return ObjectType::kOther;
    }
}

double MeanPartCount(ObjectType type, const PartCountParams& params) {
    const double mean = type == ObjectType::kFlat    ? params.flat_mean
                        : type == ObjectType::kRound ? params.round_mean
                                                     : params.other_mean;
    if (!(mean > 0.0) || !std::isfinite(mean)) {
        throw InvalidArgument("part count means must be > 0 and finite, got " +
                              std::to_string(mean));
    }
    return mean;
}

double PartCountProbability(ObjectType type, std::size_t k, const PartCountParams& params) {
    return Poisson(MeanPartCount(type, params), k);
}

double TwoObjectsLikelihoodRatio(ObjectType type, std::size_t parts,
                                 const PartCountParams& params) {
    const double lambda = MeanPartCount(type, params);
    return Poisson(2.0 * lambda, parts) / Poisson(lambda, parts);
}

}  // namespace multicue
