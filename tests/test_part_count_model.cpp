#include <cmath>

#include <gtest/gtest.h>

#include "multicue/reconstruction/part_count_model.hpp"

namespace multicue {
namespace {

TEST(PartCountModel, PoissonOfEquationFiveOne) {
    // lambda^k e^-lambda / k! by hand for the flat type.
    const double l = 0.876;
    EXPECT_NEAR(PartCountProbability(ObjectType::kFlat, 0), std::exp(-l), 1e-12);
    EXPECT_NEAR(PartCountProbability(ObjectType::kFlat, 3), l * l * l * std::exp(-l) / 6.0, 1e-12);
    double sum = 0.0;
    for (std::size_t k = 0; k < 60; ++k) sum += PartCountProbability(ObjectType::kOther, k);
    EXPECT_NEAR(sum, 1.0, 1e-9);
    EXPECT_TRUE(std::isfinite(PartCountProbability(ObjectType::kRound, 500)));
}

TEST(PartCountModel, TypesAndTheSplitDecision) {
    EXPECT_EQ(ObjectTypeOf(Category::kPlate), ObjectType::kFlat);
    EXPECT_EQ(ObjectTypeOf(Category::kCylinder), ObjectType::kRound);
    EXPECT_EQ(ObjectTypeOf(Category::kOther), ObjectType::kOther);
    EXPECT_DOUBLE_EQ(MeanPartCount(ObjectType::kRound), 2.166);
    // One flat part is one object; five flat parts are more likely two objects.
    EXPECT_LT(TwoObjectsLikelihoodRatio(ObjectType::kFlat, 1), 1.0);
    EXPECT_GT(TwoObjectsLikelihoodRatio(ObjectType::kFlat, 5), 1.0);
    // "Other" objects break into more parts, so the same count says less.
    EXPECT_LT(TwoObjectsLikelihoodRatio(ObjectType::kOther, 5),
              TwoObjectsLikelihoodRatio(ObjectType::kFlat, 5));
}

}  // namespace
}  // namespace multicue
