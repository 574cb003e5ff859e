#pragma once
/// \file Furniture pieces and their container types (thesis section 4.1.3): fronts are grouped
/// into pieces by their arrangement (stacked fronts of one width, a pair of doors hinged at their
/// outer edges), each piece is described by its parts and their relations (how many drawers and
/// doors, how they are hinged, handles and knobs, size, height above the floor, a table or
/// worktop above it) and typed as a cupboard, drawer unit, oven, dishwasher, fridge, microwave or
/// table, by a classifier trained on simulated kitchens or, without one, by rules. Pieces along
/// one wall form a kitchenette.

#include <string>
#include <vector>

#include "multicue/mapping/semantic_map.hpp"
#include "multicue/ml/classifier.hpp"

namespace multicue::mapping {

/// "cupboard", "drawer_unit", "oven", "dishwasher", "fridge", "microwave", "table".
const std::vector<std::string>& ContainerTypeNames();

struct ContainerParams {
    float stack_gap = 0.06f;       ///< fronts of one piece lie at most this far apart [m]
    float stack_overlap = 0.5f;    ///< stacked fronts share this share of the narrower width [-]
    float pair_tolerance = 0.08f;  ///< a door pair's tops and bottoms agree within this [m]
    float default_depth = 0.6f;    ///< depth of a piece with no wall behind it [m]
    float knob_reach = 0.25f;      ///< knobs this far above or beside a piece belong to it [m]
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// Groups the map's fronts into furniture pieces and kitchenettes (fills map.furniture,
/// map.kitchenettes and Front::furniture); types stay "cupboard" until TypeContainers.
void GroupFurniture(KitchenMap& map, const ContainerParams& params = {});

/// Names of the container features, in the order of ContainerFeatures.
const std::vector<std::string>& ContainerFeatureNames();
/// The features of piece `index` of `map`.
std::vector<float> ContainerFeatures(const KitchenMap& map, std::size_t index,
                                     const ContainerParams& params = {});

/// Throws InvalidArgument unless `classifier` is trained, on ContainerFeatureNames columns, and
/// predicts classes among ContainerTypeNames.
void CheckContainerClassifier(const ml::Classifier& classifier);

/// Types every piece: with `classifier` (trained on ContainerFeatures rows, classes among
/// ContainerTypeNames(); CheckContainerClassifier) its most confident class, else the rules of
/// TypeByRules.
void TypeContainers(KitchenMap& map, const ml::Classifier* classifier,
                    const ContainerParams& params = {});

/// The rule-based type of a piece from its features: a bottom-hinged door is an oven (with knobs)
/// or a dishwasher; a small door above the floor a microwave; drawers only a drawer unit; fronts
/// under a table a table; a tall door a fridge; else a cupboard.
std::string TypeByRules(const std::vector<float>& features);

}  // namespace multicue::mapping
