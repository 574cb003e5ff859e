// cloud_summary: reads a point cloud with an installed multicue and prints what a first look at a
// table-top scan needs: its points, a 1 cm voxel grid of it, how many of those get normals, and
// the support plane.
//
//   cloud_summary CLOUD.pcd|CLOUD.ply

#include <cstdio>
#include <exception>

#include "multicue/filters/remove_non_finite.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/segmentation/support_plane.hpp"
#include "multicue/surface/normals.hpp"
#include "multicue/version.hpp"

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s CLOUD.pcd|CLOUD.ply\n", argv[0]);
        return 2;
    }
    try {
        const multicue::PointCloud cloud = multicue::io::ReadPointCloud(argv[1]);
        const multicue::PointCloud finite = multicue::RemoveNonFinite(cloud);
        const multicue::PointCloud voxels =
            multicue::VoxelGrid(finite, multicue::VoxelGridParams{.leaf_size = 0.01f});
        const multicue::KdTree tree(voxels);
        const multicue::NormalsResult normals =
            multicue::EstimateNormals(voxels, tree, multicue::NormalParams{.k = 10});
        const multicue::SupportPlane support =
            multicue::FindSupportPlane(voxels, multicue::SupportPlaneParams{});
        std::printf("multicue %s\n", MULTICUE_VERSION_STRING);
        std::printf("points: %zu (finite %zu)\n", cloud.size(), finite.size());
        std::printf("voxels: %zu, with normals: %zu\n", voxels.size(),
                    voxels.size() - normals.undefined);
        if (support.found) {
            const auto& p = support.plane;
            std::printf("support plane: %.3f %.3f %.3f %.3f, %zu inliers\n", p.x(), p.y(), p.z(),
                        p.w(), support.inliers.size());
        } else {
            std::printf("support plane: none\n");
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cloud_summary: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
