#include "multicue/filters/crop_box.hpp"

#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {

Indices CropBox(const PointCloud& cloud, const CropBoxParams& params) {
    static constexpr char kAxis[] = "xyz";
    for (int a = 0; a < 3; ++a) {
        if (std::isnan(params.min[a]) || std::isnan(params.max[a])) {
            throw InvalidArgument(
                fmt::format("crop box corners must not be NaN, got min.{0} = {1}, "
                            "max.{0} = {2}",
                            kAxis[a], params.min[a], params.max[a]));
        }
        if (params.min[a] > params.max[a]) {
            throw InvalidArgument(fmt::format("crop box min.{0} must be <= max.{0}, got {1} > {2}",
                                              kAxis[a], params.min[a], params.max[a]));
        }
    }
    if (!params.T_box_cloud.matrix().allFinite()) {
        throw InvalidArgument("crop box transform T_box_cloud must be finite");
    }
    const Eigen::Matrix3f R = params.T_box_cloud.linear();
    const Eigen::Vector3f t = params.T_box_cloud.translation();
    const Eigen::Array3f lo = params.min.array(), hi = params.max.array();
    Indices out;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3f& p = cloud.points[i];
        if (!p.allFinite()) continue;
        const Eigen::Array3f q = (R * p + t).array();
        const bool inside = (q >= lo).all() && (q <= hi).all();
        if (inside != params.negative) out.push_back(static_cast<Index>(i));
    }
    return out;
}

}  // namespace multicue
