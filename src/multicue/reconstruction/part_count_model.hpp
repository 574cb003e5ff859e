#pragma once
/// \file How many parts an object of a type breaks into (thesis section 5.4.1, Equation 5.1):
/// a Poisson distribution per object type, with the means the thesis measured on its training
/// data — 0.876 for flat objects (plates, flat boxes, boxes), 2.166 for round ones (spheres,
/// cylinders) and 3.317 for others. Used to judge whether a group of parts of one category is one
/// object or several.

#include <cstddef>

#include "multicue/recognition/geometric_category.hpp"

namespace multicue {

enum class ObjectType { kFlat, kRound, kOther };

/// The type of a geometric category: box, flat and plate are flat; sphere and cylinder round;
/// other (and none) other.
ObjectType ObjectTypeOf(Category category);

/// The thesis's mean number of parts of the type (lambda of Eq. 5.1).
double MeanPartCount(ObjectType type);

/// P(k parts form a single object) = lambda^k e^-lambda / k! (Eq. 5.1).
double PartCountProbability(ObjectType type, std::size_t k);

/// The likelihood ratio of `parts` parts of one type coming from two objects (each Poisson, so
/// their sum is Poisson with twice the mean) against coming from one. Above 1 favours two objects.
double TwoObjectsLikelihoodRatio(ObjectType type, std::size_t parts);

}  // namespace multicue
