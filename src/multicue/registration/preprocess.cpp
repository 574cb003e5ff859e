#include "multicue/registration/preprocess.hpp"

#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/filters/remove_non_finite.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue {

void PreprocessParams::Validate() const {
    if (!(voxel_size >= 0.0f) || !std::isfinite(voxel_size)) {
        throw InvalidArgument(
            fmt::format("preprocess voxel_size must be >= 0 (0 = none), got {}", voxel_size));
    }
    normals.Validate();
    organized_normals.Validate();
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("preprocess num_threads must be >= 0, got {}", num_threads));
    }
}

PointCloud PreprocessForRegistration(const PointCloud& cloud, const PreprocessParams& params) {
    params.Validate();
    cloud.Validate();
    if (params.keep_organized && cloud.IsOrganized()) {
        PointCloud frame = cloud;
        OrganizedNormalParams np = params.organized_normals;
        np.num_threads = params.num_threads;
        SetNormals(frame, EstimateNormalsOrganized(frame, np));
        return frame;
    }
    PointCloud out;
    if (params.voxel_size > 0.0f) {
        out = VoxelGrid(cloud, {.leaf_size = params.voxel_size, .num_threads = params.num_threads});
    } else {
        out = RemoveNonFinite(cloud);
    }
    if (out.empty()) return out;
    const KdTree tree(out);
    NormalParams np = params.normals;
    np.num_threads = params.num_threads;
    SetNormals(out, EstimateNormals(out, tree, np));
    return out;
}

}  // namespace multicue
