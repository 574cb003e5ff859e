#include "multicue/ml/split.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "multicue/core/exceptions.hpp"

namespace multicue::ml {

namespace {

// Instances (group keys with their rows) listed per class, classes and instances in ascending
// order; an instance belongs to the class of its first row.
struct Instance {
    std::int64_t key;
    std::vector<std::size_t> rows;
};
std::vector<std::vector<Instance>> InstancesPerClass(const std::vector<std::int64_t>& keys,
                                                     const Dataset& data) {
    std::map<std::int64_t, std::vector<std::size_t>> rows_of;
    for (std::size_t r = 0; r < keys.size(); ++r) rows_of[keys[r]].push_back(r);
    std::map<int, std::vector<Instance>> per_class;
    for (auto& [key, rows] : rows_of) per_class[data.labels[rows.front()]].push_back({key, rows});
    std::vector<std::vector<Instance>> out;
    for (auto& [label, inst] : per_class) out.push_back(std::move(inst));
    return out;
}

std::vector<std::int64_t> RowKeys(const Dataset& data) {
    std::vector<std::int64_t> keys(data.rows());
    for (std::size_t r = 0; r < keys.size(); ++r) keys[r] = static_cast<std::int64_t>(r);
    return keys;
}

void CheckFraction(double f) {
    if (!(f > 0.0 && f < 1.0)) {
        throw InvalidArgument("test fraction must be in (0, 1), got " + std::to_string(f));
    }
}

Split FractionSplit(const Dataset& data, const std::vector<std::int64_t>& keys, double fraction,
                    std::uint32_t seed) {
    CheckFraction(fraction);
    std::mt19937 rng(seed);
    Split s;
    for (auto& instances : InstancesPerClass(keys, data)) {
        std::shuffle(instances.begin(), instances.end(), rng);
        std::size_t n_test = static_cast<std::size_t>(std::lround(fraction * instances.size()));
        if (instances.size() >= 2)
            n_test = std::clamp<std::size_t>(n_test, 1, instances.size() - 1);
        for (std::size_t i = 0; i < instances.size(); ++i) {
            auto& part = i < n_test ? s.test : s.train;
            part.insert(part.end(), instances[i].rows.begin(), instances[i].rows.end());
        }
    }
    std::sort(s.train.begin(), s.train.end());
    std::sort(s.test.begin(), s.test.end());
    return s;
}

}  // namespace

std::vector<std::int64_t> GroupKeys(const Dataset& data) {
    std::vector<std::int64_t> keys(data.rows());
    std::int64_t next_unique = -1;
    for (std::size_t r = 0; r < keys.size(); ++r) {
        keys[r] = data.groups[r] >= 0 ? data.groups[r] : --next_unique;
    }
    return keys;
}

Split RandomSplit(const Dataset& data, double test_fraction, std::uint32_t seed) {
    return FractionSplit(data, RowKeys(data), test_fraction, seed);
}

Split GroupSplit(const Dataset& data, double test_fraction, std::uint32_t seed) {
    return FractionSplit(data, GroupKeys(data), test_fraction, seed);
}

std::vector<Split> KFold(const Dataset& data, std::size_t k, std::uint32_t seed, bool by_group) {
    if (k < 2) throw InvalidArgument("k-fold needs k >= 2, got " + std::to_string(k));
    const auto keys = by_group ? GroupKeys(data) : RowKeys(data);
    std::mt19937 rng(seed);
    std::vector<std::size_t> fold_of_row(data.rows());
    std::size_t next = 0, used = 0;
    for (auto& instances : InstancesPerClass(keys, data)) {
        std::shuffle(instances.begin(), instances.end(), rng);
        for (const auto& inst : instances) {
            for (std::size_t r : inst.rows) fold_of_row[r] = next;
            next = (next + 1) % k;
            ++used;
        }
    }
    if (used < k) {
        throw DataError("k-fold with k = " + std::to_string(k) + " needs at least k " +
                        (by_group ? "instances" : "rows") + ", got " + std::to_string(used));
    }
    std::vector<Split> folds(k);
    for (std::size_t r = 0; r < data.rows(); ++r) {
        for (std::size_t f = 0; f < k; ++f)
            (f == fold_of_row[r] ? folds[f].test : folds[f].train).push_back(r);
    }
    return folds;
}

std::vector<Split> LeaveOneGroupOut(const Dataset& data) {
    const auto keys = GroupKeys(data);
    std::map<std::int64_t, std::size_t> index;
    for (auto key : keys) index.emplace(key, 0);
    if (index.size() < 2) throw DataError("leave-one-instance-out needs at least 2 instances");
    std::size_t i = 0;
    for (auto& [key, idx] : index) idx = i++;
    std::vector<Split> splits(index.size());
    for (std::size_t r = 0; r < keys.size(); ++r) {
        const std::size_t g = index[keys[r]];
        for (std::size_t s = 0; s < splits.size(); ++s)
            (s == g ? splits[s].test : splits[s].train).push_back(r);
    }
    return splits;
}

ThreeWaySplit SplitThreeWay(const Dataset& data, std::uint32_t seed) {
    std::mt19937 rng(seed);
    ThreeWaySplit s;
    for (auto& instances : InstancesPerClass(GroupKeys(data), data)) {
        if (seed != 0) std::shuffle(instances.begin(), instances.end(), rng);
        for (std::size_t i = 0; i < instances.size(); ++i) {
            auto& part = i % 2 == 0 ? s.level0_train : (i % 4 == 1 ? s.level1_train : s.test);
            part.insert(part.end(), instances[i].rows.begin(), instances[i].rows.end());
        }
    }
    std::sort(s.level0_train.begin(), s.level0_train.end());
    std::sort(s.level1_train.begin(), s.level1_train.end());
    std::sort(s.test.begin(), s.test.end());
    return s;
}

}  // namespace multicue::ml
