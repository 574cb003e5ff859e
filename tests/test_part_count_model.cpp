#include <cmath>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/reconstruction/part_count_model.hpp"

namespace multicue {
namespace {

TEST(PartCountModel, PoissonOfEquationFiveOne) {
    // lambda^k e^-lambda / k! by hand for the flat type.
    const PartCountParams thesis = PartCountParams::Thesis();
    const double l = 0.876;
    EXPECT_NEAR(PartCountProbability(ObjectType::kFlat, 0, thesis), std::exp(-l), 1e-12);
    EXPECT_NEAR(PartCountProbability(ObjectType::kFlat, 3, thesis), l * l * l * std::exp(-l) / 6.0,
                1e-12);
    const double m = PartCountParams{}.flat_mean;
    EXPECT_NEAR(PartCountProbability(ObjectType::kFlat, 4), std::pow(m, 4) * std::exp(-m) / 24.0,
                1e-12);
    double sum = 0.0;
    for (std::size_t k = 0; k < 60; ++k) sum += PartCountProbability(ObjectType::kOther, k);
    EXPECT_NEAR(sum, 1.0, 1e-9);
    EXPECT_TRUE(std::isfinite(PartCountProbability(ObjectType::kRound, 500)));
}

TEST(PartCountModel, TypesAndTheSplitDecision) {
    EXPECT_EQ(ObjectTypeOf(Category::kPlate), ObjectType::kFlat);
    EXPECT_EQ(ObjectTypeOf(Category::kCylinder), ObjectType::kRound);
    EXPECT_EQ(ObjectTypeOf(Category::kOther), ObjectType::kOther);
    EXPECT_DOUBLE_EQ(MeanPartCount(ObjectType::kRound, PartCountParams::Thesis()), 2.166);
    EXPECT_DOUBLE_EQ(MeanPartCount(ObjectType::kRound), 5.67);
    // 2^k e^-lambda.
    EXPECT_NEAR(TwoObjectsLikelihoodRatio(ObjectType::kFlat, 6), 64.0 * std::exp(-3.60), 1e-9);
    // One flat part is one object; six flat parts are more likely two objects.
    EXPECT_LT(TwoObjectsLikelihoodRatio(ObjectType::kFlat, 1), 1.0);
    EXPECT_GT(TwoObjectsLikelihoodRatio(ObjectType::kFlat, 6), 1.0);
    // "Other" objects break into more parts, so the same count says less.
    EXPECT_LT(TwoObjectsLikelihoodRatio(ObjectType::kOther, 5),
              TwoObjectsLikelihoodRatio(ObjectType::kFlat, 5));
}

TEST(PartCountModel, BadMeansThrow) {
    EXPECT_THROW(MeanPartCount(ObjectType::kFlat, {.flat_mean = 0.0}), InvalidArgument);
    EXPECT_THROW(PartCountProbability(ObjectType::kRound, 2, {.round_mean = -1.0}),
                 InvalidArgument);
    EXPECT_THROW(TwoObjectsLikelihoodRatio(ObjectType::kOther, 2, {.other_mean = NAN}),
                 InvalidArgument);
}

}  // namespace
}  // namespace multicue
