// Filters, normals and segmentation: each a call of the library function with its Params built
// from keyword arguments. Index lists come back as uint32 arrays, usable with select().

#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/filters/crop_box.hpp"
#include "multicue/filters/outlier_removal.hpp"
#include "multicue/filters/remove_non_finite.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/segmentation/support_plane.hpp"
#include "multicue/surface/normals.hpp"

namespace py = pybind11;

namespace multicue::python {
namespace {

py::array_t<std::uint32_t> IndexArray(const Indices& indices) {
    return py::array_t<std::uint32_t>(static_cast<py::ssize_t>(indices.size()), indices.data());
}

Indices ToIndices(const py::object& any, const char* what) {
    const auto a =
        py::array_t<std::uint32_t, py::array::c_style | py::array::forcecast>::ensure(any);
    if (!a || a.ndim() != 1) {
        throw InvalidArgument(fmt::format("{} must be a 1-D array of point indices", what));
    }
    return Indices(a.data(), a.data() + a.shape(0));
}

Eigen::Vector3f ToVector3(const std::vector<float>& v, const char* what) {
    if (v.size() != 3) {
        throw InvalidArgument(fmt::format("{} must have 3 values, got {}", what, v.size()));
    }
    return Eigen::Vector3f(v[0], v[1], v[2]);
}

py::array_t<float> Vectors(const std::vector<Eigen::Vector3f>& v) {
    py::array_t<float> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
    if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(v[0]));
    return out;
}

}  // namespace

void BindAlgorithms(py::module_& m) {
    m.def(
        "select",
        [](const PointCloud& cloud, const py::object& indices) {
            const Indices idx = ToIndices(indices, "indices");
            py::gil_scoped_release release;
            return SelectByIndex(cloud, idx);
        },
        py::arg("cloud"), py::arg("indices"),
        "A new unorganized cloud of the given points (in that order) with all their fields.");
    m.def(
        "remove_non_finite",
        [](const PointCloud& cloud) {
            py::gil_scoped_release release;
            return RemoveNonFinite(cloud);
        },
        py::arg("cloud"), "The points with three finite coordinates, with all their fields.");
    m.def(
        "voxel_grid",
        [](const PointCloud& cloud, float leaf_size, int min_points_per_voxel, int threads) {
            const VoxelGridParams params{.leaf_size = leaf_size,
                                         .min_points_per_voxel = min_points_per_voxel,
                                         .num_threads = threads};
            py::gil_scoped_release release;
            return VoxelGrid(cloud, params);
        },
        py::arg("cloud"), py::arg("leaf_size") = 0.01f, py::arg("min_points_per_voxel") = 1,
        py::arg("threads") = 0,
        "One point per occupied voxel of edge leaf_size [m], at the centroid of its points\n"
        "(fields averaged; labels by majority). threads: 0 = all cores; the result does not\n"
        "depend on it.");
    m.def(
        "crop_box",
        [](const PointCloud& cloud, const std::vector<float>& min, const std::vector<float>& max,
           bool negative) {
            const CropBoxParams params{
                .min = ToVector3(min, "min"), .max = ToVector3(max, "max"), .negative = negative};
            return IndexArray(CropBox(cloud, params));
        },
        py::arg("cloud"), py::arg("min"), py::arg("max"), py::arg("negative") = false,
        "Indices of the finite points inside the axis-aligned box [min, max] (bounds included),\n"
        "or outside it with negative=True.");
    m.def(
        "statistical_outlier_removal",
        [](const PointCloud& cloud, int k, float std_ratio, int threads) {
            const StatisticalOutlierParams params{
                .k = k, .std_ratio = std_ratio, .num_threads = threads};
            Indices keep;
            {
                py::gil_scoped_release release;
                const KdTree tree(cloud);
                keep = StatisticalOutlierRemoval(cloud, tree, params);
            }
            return IndexArray(keep);
        },
        py::arg("cloud"), py::arg("k") = 50, py::arg("std_ratio") = 1.0f, py::arg("threads") = 0,
        "Indices of the points to keep (ascending): mean distance to the k nearest neighbours\n"
        "at most mean + std_ratio * stddev over the cloud (as PCL).");
    m.def(
        "radius_outlier_removal",
        [](const PointCloud& cloud, float radius, int min_neighbors, int threads) {
            const RadiusOutlierParams params{
                .radius = radius, .min_neighbors = min_neighbors, .num_threads = threads};
            Indices keep;
            {
                py::gil_scoped_release release;
                const KdTree tree(cloud);
                keep = RadiusOutlierRemoval(cloud, tree, params);
            }
            return IndexArray(keep);
        },
        py::arg("cloud"), py::arg("radius") = 0.05f, py::arg("min_neighbors") = 2,
        py::arg("threads") = 0,
        "Indices of the finite points with at least min_neighbors others within radius [m].");
    m.def(
        "estimate_normals",
        [](PointCloud& cloud, int k, float radius, bool organized, int threads) {
            NormalsResult result;
            {
                py::gil_scoped_release release;
                if (organized) {
                    if (k != 0 || radius != 0.0f) {
                        throw InvalidArgument(
                            "organized normals use an image window: give neither k nor radius");
                    }
                    result = EstimateNormalsOrganized(
                        cloud, OrganizedNormalParams{.num_threads = threads});
                } else {
                    const NormalParams params{.k = k, .radius = radius, .num_threads = threads};
                    params.Validate();
                    const KdTree tree(cloud);
                    result = EstimateNormals(cloud, tree, params);
                }
            }
            const std::size_t undefined = result.undefined;
            SetNormals(cloud, std::move(result));
            return undefined;
        },
        py::arg("cloud"), py::kw_only(), py::arg("k") = 0, py::arg("radius") = 0.0f,
        py::arg("organized") = false, py::arg("threads") = 0,
        "Sets cloud.normals and cloud.curvature (in place) by PCA of each point's\n"
        "neighbourhood: the k nearest (default 20), or all within radius [m], or with\n"
        "organized=True the 19x19 pixel window of an organized cloud. Normals face the sensor.\n"
        "Returns the number of points left without a normal (NaN).");
    m.def(
        "find_support_plane",
        [](const PointCloud& cloud, std::optional<std::vector<float>> up, float distance_threshold,
           std::uint64_t seed, int threads) {
            SupportPlaneParams params;
            if (up) params.up = ToVector3(*up, "up");
            params.distance_threshold = distance_threshold;
            params.seed = seed;
            params.num_threads = threads;
            SupportPlane s;
            {
                py::gil_scoped_release release;
                s = FindSupportPlane(cloud, params);
            }
            py::dict d;
            d["found"] = s.found;
            d["plane"] = py::array_t<float>(4, s.plane.data());
            d["inliers"] = IndexArray(s.inliers);
            d["hull"] = Vectors(s.hull);
            d["up"] = py::array_t<float>(3, s.up.data());
            return d;
        },
        py::arg("cloud"), py::kw_only(), py::arg("up") = py::none(),
        py::arg("distance_threshold") = 0.012f, py::arg("seed") = 1, py::arg("threads") = 0,
        "The table plane (thesis section 2.4): among the near-horizontal planes, the one the\n"
        "most points stand on; where none supports anything, the largest nearest the\n"
        "viewpoint. Returns a dict: found (bool), plane (a, b, c, d) with the unit normal\n"
        "pointing up, inliers (uint32 indices), hull (H, 3) and the up direction used.");
    m.def(
        "euclidean_clustering",
        [](const PointCloud& cloud, float tolerance, std::size_t min_cluster_size,
           std::optional<std::size_t> max_cluster_size, const py::object& subset) {
            EuclideanClusteringParams params;
            params.tolerance = tolerance;
            params.min_cluster_size = min_cluster_size;
            if (max_cluster_size) params.max_cluster_size = *max_cluster_size;
            if (!subset.is_none()) params.subset = ToIndices(subset, "subset");
            ClusteringResult result;
            {
                py::gil_scoped_release release;
                const KdTree tree(cloud);
                result = EuclideanClustering(cloud, tree, params);
            }
            py::list clusters;
            for (const auto& c : result.clusters) clusters.append(IndexArray(c));
            return clusters;
        },
        py::arg("cloud"), py::kw_only(), py::arg("tolerance") = 0.02f,
        py::arg("min_cluster_size") = 1, py::arg("max_cluster_size") = py::none(),
        py::arg("subset") = py::none(),
        "Connected components of the finite points (of subset, if given) under 'at most\n"
        "tolerance [m] apart': a list of uint32 index arrays, largest first.");
}

}  // namespace multicue::python
