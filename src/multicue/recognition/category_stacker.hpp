#pragma once
/// \file Stacking of the category experts (thesis section 3.3.4): a level-1 classifier that takes
/// the distributions of the rule-based categoriser, the part-graph votes and the whole-object
/// k-NN, together with the rules' geometric evidence (box extents and ratios, fit scores), and
/// returns one category distribution. The level-1 classifier is a multinomial logistic
/// regression on standardised inputs, trained by full-batch gradient descent (deterministic).

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "multicue/core/types.hpp"
#include "multicue/recognition/category_distribution.hpp"
#include "multicue/recognition/geometric_category.hpp"

namespace multicue {

/// Number of stacker inputs: 3 x 6 expert log-probabilities and 18 geometric values.
inline constexpr std::size_t kStackerInputSize = 36;

/// The stacker's inputs for one object: log(p + 0.01) of each expert's six categories (sphere
/// .. other; an all-zero expert, e.g. a model without cluster rows, gives log(0.01) throughout),
/// then the logs of the rules' extents e1, e2, e3 (+1 mm), log(e2/e3), log(e1/e3), the height,
/// box score, axis area, planar part ratio, cylinder side, cap and coverage ratios, cylinder
/// radius, sphere ratio and radius, footprint fill, side face ratio and 1 if upright. Non-finite
/// values become 0.
std::array<float, kStackerInputSize> StackerInputs(const CategoryResult& rules,
                                                   const CategoryDistribution& part_graph,
                                                   const CategoryDistribution& cluster);

struct CategoryStackerParams {
    float l2 = 0.01f;              ///< L2 penalty on the weights, >= 0 [-]
    std::size_t iterations = 400;  ///< gradient steps, >= 1
    float step = 0.5f;             ///< gradient step on the mean loss, > 0 [-]
};

class CategoryStacker {
  public:
    /// Trains on one input row per object and its true category (not kNone). Every category
    /// without rows keeps probability near zero. Throws InvalidArgument for no rows, a size
    /// mismatch, a kNone truth or bad parameters.
    void Fit(const std::vector<std::array<float, kStackerInputSize>>& inputs,
             const std::vector<Category>& truth, const CategoryStackerParams& params = {});

    /// Category distribution (index 0, kNone, stays 0); throws InvalidArgument when not trained.
    CategoryDistribution Predict(const std::array<float, kStackerInputSize>& input) const;

    bool trained() const { return !weights_.empty(); }
    std::size_t train_rows() const { return train_rows_; }

    /// The trained state as floats (rows, mean, scale, weights, bias); empty when not trained.
    std::vector<float> Parameters() const;
    /// The stacker of Parameters() (empty: untrained). Throws FormatError naming `what` for a
    /// wrong length or non-finite values.
    static CategoryStacker FromParameters(const std::vector<float>& values,
                                          const std::string& what);

  private:
    static constexpr std::size_t kClasses = kNumCategories - 1;
    std::vector<float> mean_, scale_;  ///< per input
    std::vector<float> weights_;       ///< kStackerInputSize x kClasses, row-major
    std::vector<float> bias_;          ///< kClasses
    std::size_t train_rows_ = 0;
};

}  // namespace multicue
