#include "multicue/reconstruction/part_count_model.hpp"

#include <cmath>

namespace multicue {
namespace {

double Poisson(double lambda, std::size_t k) {
    // In logs: k! overflows long before the probabilities stop mattering.
    return std::exp(static_cast<double>(k) * std::log(lambda) - lambda -
                    std::lgamma(static_cast<double>(k) + 1.0));
}

}  // namespace

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

double MeanPartCount(ObjectType type) {
    switch (type) {
        case ObjectType::kFlat:
            return 0.876;
        case ObjectType::kRound:
            return 2.166;
        default:
            return 3.317;
    }
}

double PartCountProbability(ObjectType type, std::size_t k) {
    return Poisson(MeanPartCount(type), k);
}

double TwoObjectsLikelihoodRatio(ObjectType type, std::size_t parts) {
    const double lambda = MeanPartCount(type);
    return Poisson(2.0 * lambda, parts) / Poisson(lambda, parts);
}

}  // namespace multicue
