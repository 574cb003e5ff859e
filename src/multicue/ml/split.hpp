#pragma once
/// \file Training/test partitions of a dataset (section 3.1.4, 3.3.4, 3.3.5.1). Splits return row
/// indices; apply them with SelectRows. Splits "by group" never put rows of one object instance
/// (Dataset::groups) on both sides; rows with group -1 count as instances of their own. All splits
/// are stratified by class (each class's instances are spread over the parts) and deterministic
/// for a seed.

#include <cstdint>
#include <vector>

#include "multicue/ml/dataset.hpp"

namespace multicue::ml {

struct Split {
    std::vector<std::size_t> train;
    std::vector<std::size_t> test;
};

/// The three parts of the stacking variant of section 3.3.4: level-0 training, level-1 training
/// (level-0 evaluation) and the final test set.
struct ThreeWaySplit {
    std::vector<std::size_t> level0_train;
    std::vector<std::size_t> level1_train;
    std::vector<std::size_t> test;
};

/// Random rows to the test part (fraction in (0, 1)), stratified by class.
Split RandomSplit(const Dataset& data, double test_fraction, std::uint32_t seed);
/// Whole object instances to the test part, stratified by class.
Split GroupSplit(const Dataset& data, double test_fraction, std::uint32_t seed);
/// k folds (k >= 2); by_group keeps each instance inside one fold. Fold i's test part is fold i.
std::vector<Split> KFold(const Dataset& data, std::size_t k, std::uint32_t seed, bool by_group);
/// One split per instance: that instance is the test part.
std::vector<Split> LeaveOneGroupOut(const Dataset& data);
/// Section 3.3.5.1: per class, instances in ascending group id; every second instance goes to
/// level-0 training, of the others every second to level-1 training and the rest to the test
/// part (about 50/25/25 %). With seed != 0 the instances are shuffled first.
ThreeWaySplit SplitThreeWay(const Dataset& data, std::uint32_t seed = 0);

/// Group key per row: the group id, or a unique negative key for rows with group -1.
std::vector<std::int64_t> GroupKeys(const Dataset& data);

}  // namespace multicue::ml
