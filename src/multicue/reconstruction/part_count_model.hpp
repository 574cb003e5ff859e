#pragma once
/// \file How many parts an object of a type breaks into (thesis section 5.4.1, Equation 5.1):
/// a Poisson distribution per object type. The thesis measured means of 0.876 for flat objects
/// (plates, flat boxes, boxes), 2.166 for round ones (spheres, cylinders) and 3.317 for others on
/// its own segmentation (PartCountParams::Thesis()). The means depend on how finely objects are
/// cut into parts, so the defaults are those of this library's normal-angle region growing,
/// measured on simulated Kinect frames by eval/part_counts. Used to
/// judge whether a group of parts of one category is one object or several.

#include <cstddef>

#include "multicue/recognition/geometric_category.hpp"

namespace multicue {

enum class ObjectType { kFlat, kRound, kOther };

/// Poisson means (lambda of Eq. 5.1) of the number of parts per object type; each > 0.
struct PartCountParams {
    /// 3.60, 5.67 and 7.19: 83, 70 and 58 simulated objects segmented as one object each
    /// (60 frames of `multicue simulate scenes --scenes 30 --views 2 --seed 7`).
    double flat_mean = 3.60;
    double round_mean = 5.67;
    double other_mean = 7.19;

    /// The thesis's means (its segmentation makes fewer parts).
    static PartCountParams Thesis() { return {0.876, 2.166, 3.317}; }
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("flat_mean", flat_mean, "Poisson mean of parts of flat objects");
        v("round_mean", round_mean, "Poisson mean of parts of round objects");
        v("other_mean", other_mean, "Poisson mean of parts of other objects");
    }
};

/// The type of a geometric category: box, flat and plate are flat; sphere and cylinder round;
/// other (and none) other.
ObjectType ObjectTypeOf(Category category);

/// The mean number of parts of the type (lambda of Eq. 5.1). Throws InvalidArgument for a mean
/// that is not positive and finite.
double MeanPartCount(ObjectType type, const PartCountParams& params = {});

/// P(k parts form a single object) = lambda^k e^-lambda / k! (Eq. 5.1).
double PartCountProbability(ObjectType type, std::size_t k, const PartCountParams& params = {});

/// The likelihood ratio of `parts` parts of one type coming from two objects (each Poisson, so
/// their sum is Poisson with twice the mean) against coming from one, 2^k e^-lambda. Above 1
/// favours two objects.
double TwoObjectsLikelihoodRatio(ObjectType type, std::size_t parts,
                                 const PartCountParams& params = {});

}  // namespace multicue
