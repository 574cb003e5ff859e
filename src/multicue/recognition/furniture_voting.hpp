#pragma once
/// \file Probabilistic Hough voting for furniture (thesis section 4.2.4): every part activates
/// vocabulary words (Eq. 4.3), every element of an activated word votes for an object centre
/// x_v = l + d with weight p(A_i | f) / #(A_i, o) (Eqs. 4.1, 4.2, 4.4), the votes are summed over
/// all parts (Eq. 4.5) on the floor plane, local maxima are found in windows as wide as the
/// class, thresholded per class, and same-class hypotheses whose footprints overlap are reduced
/// to the strongest (section 4.2.4.2). Votes of several registered views are merged before the
/// selection (section 4.2.5.3).

#include <cstddef>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "multicue/recognition/furniture_model.hpp"
#include "multicue/recognition/furniture_parts.hpp"

namespace multicue {

/// One vote for an object centre.
struct FurnitureVote {
    Eigen::Vector3f x = Eigen::Vector3f::Zero();  ///< voted centre, world frame [m]
    float weight = 0.0f;                          ///< p(o, x | f, l) of Eq. (4.2)
    int cls = 0;                                  ///< class index
    int part = 0;                                 ///< part index in its view
    int view = 0;                                 ///< view index
};

/// How an activated word's weight is shared among its elements (Eq. 4.4).
enum class FurnitureVoteNormalization {
    kPerClass,  ///< 1 / #(A_i, o): each class present in the word gets the whole weight (Eq. 4.4)
    kPerWord,   ///< 1 / #(A_i): classes share it by their elements (Leibe et al. 2008)
    kBalanced,  ///< per word, each class's elements weighted by 1 / its share of all training
                ///< parts, so that classes with more training parts do not outvote the others
};
/// "per-class", "per-word", "balanced"; and back (InvalidArgument naming the choices).
const char* FurnitureVoteNormalizationName(FurnitureVoteNormalization n);
FurnitureVoteNormalization ParseFurnitureVoteNormalization(std::string_view name);

struct FurnitureVotingParams {
    FurnitureActivation activation = FurnitureActivation::kWords;
    std::size_t activations = 2;  ///< words a part activates (section 4.2.5: two), >= 1
    FurnitureVoteNormalization normalization = FurnitureVoteNormalization::kPerClass;
    /// Parts longer than this times the longest training part vote for nothing (walls) [-], > 0
    float extent_margin = 1.25f;
    /// Parts reaching higher than the tallest training piece plus this vote for nothing [m]
    float height_margin = 0.15f;
    /// Votes whose centre lies further than this above or below the centre of the training
    /// piece they come from are dropped (the part stands at another height than the training
    /// part): the votes are 3D, only their selection is on the floor [m]; 0 = keep all
    float max_height_error = 0.25f;
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// The votes of the parts of one view. Throws InvalidArgument for bad parameters or an untrained
/// model.
std::vector<FurnitureVote> CastFurnitureVotes(const FurnitureParts& parts,
                                              const FurnitureModel& model, int view,
                                              const FurnitureVotingParams& params);

struct FurnitureSelectionParams {
    float cell = 0.05f;  ///< cell of the vote grid on the floor [m], > 0
    /// Side of the search window = this times the class width [-], > 0
    float window_scale = 1.0f;
    /// Multiplies every class threshold [-], >= 0 (0 keeps every local maximum with a vote)
    float threshold_scale = 1.0f;
    /// A part supports a hypothesis when its votes there reach this share of the strongest
    /// supporting part's [-], in [0, 1]
    float min_part_share = 0.1f;
    /// Drop same-class hypotheses whose footprints (discs of the class width) overlap a
    /// stronger one's (section 4.2.4.2)
    bool hull_consistency = true;
    /// Apply the footprint test across classes too (by normalised score): one place, one piece
    bool cross_class = false;
    /// Every class at every strong hypothesis: where a hypothesis reaches other_classes_from of
    /// its class threshold and no hypothesis of another class lies within half that class's
    /// width, a hypothesis of that class is added at its centre, with that class's votes there
    /// as its score (often none) and the parts of the hypothesis that proposed it. For a CAD fit
    /// to name the piece that the votes of another class found (a sideboard voted for as a
    /// table). Off by default; FurnitureDetectionParams::other_classes turns it on
    bool other_classes = false;
    float other_classes_from = 1.0f;  ///< [-], >= 0
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// A selected hypothesis.
struct FurnitureHypothesis {
    int cls = 0;
    Eigen::Vector2f centre = Eigen::Vector2f::Zero();  ///< weighted mean of its votes [m]
    float score = 0.0f;       ///< V(o, x): the votes in the window (per view when merged)
    float normalized = 0.0f;  ///< score / class threshold (inf for a zero threshold)
    /// Supporting parts: (view, part) with the weight of their votes in the window, strongest
    /// first.
    std::vector<std::pair<int, int>> parts;
    std::vector<float> part_weights;
    /// Proposed (FurnitureSelectionParams::other_classes): the class whose hypothesis proposed
    /// it; -1 for a hypothesis of its own votes
    int proposed_by = -1;
    /// The normalised score of the votes that found the place: its own, or when proposed the
    /// proposing hypothesis's
    float found = 0.0f;
};

/// Hypotheses from the votes of `views` views (the weights of merged views are divided by their
/// number, so that an object seen in every view keeps its single-view score and one seen in a
/// single view loses), strongest first. Throws InvalidArgument for bad parameters, views < 1 or
/// a vote of an unknown class.
std::vector<FurnitureHypothesis> SelectFurnitureHypotheses(const std::vector<FurnitureVote>& votes,
                                                           int views, const FurnitureModel& model,
                                                           const FurnitureSelectionParams& params);

}  // namespace multicue
