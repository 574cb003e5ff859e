#include "multicue/filters/remove_non_finite.hpp"

namespace multicue {

Indices FiniteIndices(const PointCloud& cloud) {
    Indices out;
    out.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (cloud.points[i].allFinite()) out.push_back(static_cast<Index>(i));
    }
    return out;
}

PointCloud RemoveNonFinite(const PointCloud& cloud) {
    cloud.Validate();  // SelectByIndex reads every field at the kept indices
    return SelectByIndex(cloud, FiniteIndices(cloud));
}

}  // namespace multicue
