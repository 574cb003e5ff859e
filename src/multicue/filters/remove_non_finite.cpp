#include "multicue/filters/remove_non_finite.hpp"

#include "multicue/core/parallel.hpp"

namespace multicue {

Indices FiniteIndices(const PointCloud& cloud, int num_threads) {
    return ParallelSelect(cloud.size(), num_threads,
                          [&](std::size_t i) { return cloud.IsFinite(i); });
}

PointCloud RemoveNonFinite(const PointCloud& cloud) {
    cloud.Validate();  // SelectByIndex reads every field at the kept indices
    return SelectByIndex(cloud, FiniteIndices(cloud));
}

}  // namespace multicue
