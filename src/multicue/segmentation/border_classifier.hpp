#pragma once
/// \file The learned decision whether two neighbouring parts of an object hypothesis belong to
/// one object: a logistic regression on the border's features (border_features.hpp),
/// p(same object) = 1 / (1 + exp(-(bias + sum_i w_i f_i))). The default weights were fitted by
/// `build/eval/border_training` on borders of simulated table-top clutter (meshes of the `tune`
/// half of the mesh library, every scene mode, procedural objects) and of the mOSD learn frames,
/// with ground truth; eval/README.md says how, docs/segmentation.md what it reaches.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "multicue/segmentation/border_features.hpp"

namespace multicue {

struct BorderClassifierParams {
    /// Weight of each feature, in the order of kBorderFeatureNames (per unit of the feature).
    std::array<float, kBorderFeatureCount> weights = {
        -0.086663f, 0.93856f,     -1.3241f,   0.0908728f, -0.579708f, -0.393987f, -17.1899f,
        0.477076f,  -0.0927817f,  -0.512823f, -0.366259f, 0.0314374f, -1.61957f,  -1.04806f,
        0.75419f,   -6.93915f,    -0.867562f, -1.76022f,  0.850425f,  0.84735f,   -0.111783f,
        0.0234965f, -0.00257402f, -0.971308f, -2.02867f,  3.61801f};
    float bias = 9.0306f;
    float threshold = 0.8f;  ///< parts join when p(same object) reaches this [-], in (0, 1)
    /// Parts with at least this many points are grouped by the classifier; smaller ones then
    /// join the neighbour whose border scores best (a small part never bridges two objects)
    /// [points]
    std::size_t large_part_points = 150;
    /// Throws InvalidArgument naming the first out-of-range or non-finite value.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("threshold", threshold, "parts join when p(same object) reaches this");
        v("large_part_points", large_part_points,
          "parts this large are grouped by the classifier, smaller ones join their best "
          "neighbour [points]");
        v("bias", bias, "bias of the logistic regression");
        auto w = v.Section("weights");
        for (std::size_t k = 0; k < kBorderFeatureCount; ++k) {
            w(std::string(kBorderFeatureNames[k]), weights[k], "weight of this border feature");
        }
    }
};

/// p(same object) of a border with features `f`.
float JoinProbability(const BorderFeatures& f, const BorderClassifierParams& params);

/// One labelled border to learn from.
struct BorderExample {
    BorderFeatures features{};
    bool same = false;    ///< the two parts belong to one object
    double weight = 1.0;  ///< the row's weight in the fit [-], >= 0
};

/// Fits the bias and weights of a logistic regression to `rows`: the features standardised
/// (weighted mean and standard deviation), an L2 penalty `l2` on the standardised weights (not
/// on the bias), Newton steps until they stop changing; returned in the features' own units, with
/// the threshold and large_part_points of `start`. Deterministic. Throws InvalidArgument when l2
/// is negative or not finite, a feature or weight is not finite or a weight negative, or the
/// rows do not hold both kinds with positive weight.
BorderClassifierParams FitBorderClassifier(const std::vector<BorderExample>& rows, double l2,
                                           BorderClassifierParams start = {});

}  // namespace multicue
