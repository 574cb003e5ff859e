#include "peers/segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <unordered_map>
#include <utility>

#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/common/point_tests.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/lccp_segmentation.h>
#include <pcl/segmentation/region_growing.h>
#include <pcl/segmentation/sac_segmentation.h>
#include <pcl/segmentation/supervoxel_clustering.h>

namespace multicue::peers {
namespace {

using Point = PeerPoint;
using Cloud = PeerCloud;

// ---------------------------------------------------------------------------------------------
// Parameters, each as given in the PCL tutorial or example the pipeline follows.

// Euclidean Cluster Extraction tutorial.
constexpr float kEuclideanLeaf = 0.01f;          // VoxelGrid leaf size
constexpr double kTutorialPlaneDistance = 0.02;  // SACPeerSegmentation distance threshold
constexpr int kTutorialPlaneIterations = 100;    // SACPeerSegmentation max iterations
constexpr double kPlaneRemovalStop = 0.3;        // remove planes while > 30 % of points remain
constexpr double kEuclideanTolerance = 0.02;     // cluster tolerance
constexpr int kEuclideanMinSize = 100;           // min cluster size
constexpr int kEuclideanMaxSize = 25000;         // max cluster size

// Region growing segmentation tutorial.
constexpr int kRegionNormalK = 50;            // NormalEstimation k
constexpr int kRegionMinSize = 50;            // min cluster size
constexpr int kRegionMaxSize = 1000000;       // max cluster size
constexpr int kRegionNeighbours = 30;         // number of neighbours
constexpr float kRegionSmoothnessDeg = 3.0f;  // smoothness threshold
constexpr float kRegionCurvature = 1.0f;      // curvature threshold

// LCCP example program defaults.
constexpr float kLccpVoxel = 0.0075f;         // voxel resolution
constexpr float kLccpSeed = 0.03f;            // seed resolution
constexpr float kLccpColor = 0.0f;            // color importance
constexpr float kLccpSpatial = 1.0f;          // spatial importance
constexpr float kLccpNormal = 4.0f;           // normal importance
constexpr float kLccpConcavityDeg = 10.0f;    // concavity tolerance threshold
constexpr float kLccpSmoothness = 0.1f;       // smoothness threshold
constexpr std::uint32_t kLccpMinSegment = 0;  // min segment size
constexpr std::uint32_t kLccpKFactor = 0;     // k-factor (no extended convexity)
constexpr bool kLccpSanity = true;            // sanity criterion (the example's -sc)

// Table removal for region growing and LCCP (ours, not from a tutorial): a segment whose points
// lie mostly within kTableBand of the dominant RANSAC plane is the table.
constexpr float kTableBand = 0.015f;
constexpr double kTableShare = 0.5;

// ---------------------------------------------------------------------------------------------

pcl::IndicesPtr FiniteIndices(const Cloud& cloud) {
    auto indices = std::make_shared<pcl::Indices>();
    indices->reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (pcl::isXYZFinite(cloud[i])) indices->push_back(static_cast<pcl::index_t>(i));
    }
    return indices;
}

// One RANSAC plane with the settings of the cluster extraction tutorial. Returns the inliers
// (indices into cloud) and the plane coefficients with a unit normal.
struct Plane {
    pcl::Indices inliers;
    Eigen::Vector4f coefficients = Eigen::Vector4f::Zero();
};

std::optional<Plane> FitPlane(const Cloud::ConstPtr& cloud, const pcl::IndicesConstPtr& indices) {
    pcl::SACSegmentation<Point> seg;
    seg.setOptimizeCoefficients(true);
    seg.setModelType(pcl::SACMODEL_PLANE);
    seg.setMethodType(pcl::SAC_RANSAC);
    seg.setMaxIterations(kTutorialPlaneIterations);
    seg.setDistanceThreshold(kTutorialPlaneDistance);
    seg.setInputCloud(cloud);
    seg.setIndices(indices);
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coefficients;
    seg.segment(inliers, coefficients);
    if (inliers.indices.empty() || coefficients.values.size() != 4) return std::nullopt;
    Plane plane;
    plane.inliers = std::move(inliers.indices);
    plane.coefficients = Eigen::Vector4f(coefficients.values[0], coefficients.values[1],
                                         coefficients.values[2], coefficients.values[3]);
    const float norm = plane.coefficients.head<3>().norm();
    if (norm > 0.0f) plane.coefficients /= norm;
    return plane;
}

// Drops the segments that are mostly on the table plane and numbers the others 1..K, largest
// first.
PeerSegmentation NumberObjects(const Cloud& cloud, std::vector<pcl::Indices> segments,
                               const std::optional<Plane>& table) {
    if (table) {
        const Eigen::Vector4f& c = table->coefficients;
        std::erase_if(segments, [&](const pcl::Indices& segment) {
            std::size_t on_plane = 0;
            for (const auto i : segment) {
                const Point& p = cloud[i];
                if (std::abs(c[0] * p.x + c[1] * p.y + c[2] * p.z + c[3]) <= kTableBand) ++on_plane;
            }
            return static_cast<double>(on_plane) >
                   kTableShare * static_cast<double>(segment.size());
        });
    }
    std::stable_sort(segments.begin(), segments.end(),
                     [](const auto& a, const auto& b) { return a.size() > b.size(); });
    PeerSegmentation result;
    result.object.assign(cloud.size(), 0);
    for (const auto& segment : segments) {
        if (segment.empty()) continue;
        ++result.objects;
        for (const auto i : segment) result.object[i] = static_cast<std::uint32_t>(result.objects);
    }
    return result;
}

}  // namespace

// 1. Euclidean Cluster Extraction tutorial: 1 cm VoxelGrid, repeated RANSAC plane removal while
// more than 30 % of the voxels remain, Euclidean clustering of the rest. Every input point gets
// the cluster of the voxel it fell into (the voxel grid's leaf layout maps a point to its voxel),
// so no nearest-neighbour search is needed to carry the labels back.
PeerSegmentation SegmentEuclidean(const Cloud::ConstPtr& cloud) {
    pcl::VoxelGrid<Point> grid;
    grid.setInputCloud(cloud);
    grid.setLeafSize(kEuclideanLeaf, kEuclideanLeaf, kEuclideanLeaf);
    grid.setSaveLeafLayout(true);
    auto voxels = std::make_shared<Cloud>();
    grid.filter(*voxels);

    // The tutorial extracts each plane into a new cloud; the same is done here with index lists
    // into the voxel cloud, which keeps voxel indices valid for the mapping back.
    auto remaining = std::make_shared<pcl::Indices>(voxels->size());
    for (std::size_t i = 0; i < voxels->size(); ++i) (*remaining)[i] = static_cast<pcl::index_t>(i);
    const double total = static_cast<double>(voxels->size());
    while (static_cast<double>(remaining->size()) > kPlaneRemovalStop * total) {
        const auto plane = FitPlane(voxels, remaining);
        if (!plane) break;
        std::vector<char> is_inlier(voxels->size(), 0);
        for (const auto i : plane->inliers) is_inlier[i] = 1;
        std::erase_if(*remaining, [&](pcl::index_t i) { return is_inlier[i] != 0; });
    }

    std::vector<pcl::PointIndices> clusters;
    if (!remaining->empty()) {
        auto tree = std::make_shared<pcl::search::KdTree<Point>>();
        pcl::EuclideanClusterExtraction<Point> ec;
        ec.setClusterTolerance(kEuclideanTolerance);
        ec.setMinClusterSize(kEuclideanMinSize);
        ec.setMaxClusterSize(kEuclideanMaxSize);
        ec.setSearchMethod(tree);
        ec.setInputCloud(voxels);
        ec.setIndices(remaining);
        ec.extract(clusters);  // sorted largest first
    }
    std::vector<std::uint32_t> voxel_object(voxels->size(), 0);
    for (std::size_t k = 0; k < clusters.size(); ++k) {
        for (const auto i : clusters[k].indices)
            voxel_object[i] = static_cast<std::uint32_t>(k + 1);
    }

    PeerSegmentation result;
    result.objects = clusters.size();
    result.object.assign(cloud->size(), 0);
    for (std::size_t i = 0; i < cloud->size(); ++i) {
        const Point& p = (*cloud)[i];
        if (!pcl::isXYZFinite(p)) continue;
        const int voxel = grid.getCentroidIndex(p);
        if (voxel >= 0) result.object[i] = voxel_object[static_cast<std::size_t>(voxel)];
    }
    return result;
}

// 2. Region growing segmentation tutorial: k = 50 normals, region growing with the tutorial's
// settings on all finite points; the segment that lies mostly on the dominant RANSAC plane is the
// table and is dropped, all other segments are objects.
PeerSegmentation SegmentRegionGrowing(const Cloud::ConstPtr& cloud) {
    auto tree = std::make_shared<pcl::search::KdTree<Point>>();
    auto normals = std::make_shared<pcl::PointCloud<pcl::Normal>>();
    pcl::NormalEstimation<Point, pcl::Normal> estimator;
    estimator.setSearchMethod(tree);
    estimator.setInputCloud(cloud);
    estimator.setKSearch(kRegionNormalK);
    estimator.compute(*normals);  // NaN normals for NaN points

    // The tutorial restricts the input with a z pass-through fitted to its own scene; here all
    // points with a finite position and normal are segmented.
    auto indices = std::make_shared<pcl::Indices>();
    indices->reserve(cloud->size());
    for (std::size_t i = 0; i < cloud->size(); ++i) {
        if (pcl::isXYZFinite((*cloud)[i]) && pcl::isNormalFinite((*normals)[i]))
            indices->push_back(static_cast<pcl::index_t>(i));
    }

    pcl::RegionGrowing<Point, pcl::Normal> reg;
    reg.setMinClusterSize(kRegionMinSize);
    reg.setMaxClusterSize(kRegionMaxSize);
    reg.setSearchMethod(tree);
    reg.setNumberOfNeighbours(kRegionNeighbours);
    reg.setInputCloud(cloud);
    reg.setIndices(indices);
    reg.setInputNormals(normals);
    reg.setSmoothnessThreshold(kRegionSmoothnessDeg / 180.0f * std::numbers::pi_v<float>);
    reg.setCurvatureThreshold(kRegionCurvature);
    std::vector<pcl::PointIndices> clusters;
    reg.extract(clusters);

    std::vector<pcl::Indices> segments;
    segments.reserve(clusters.size());
    for (auto& c : clusters) segments.push_back(std::move(c.indices));
    return NumberObjects(*cloud, std::move(segments), FitPlane(cloud, FiniteIndices(*cloud)));
}

// 3. LCCP example program: supervoxels, LCCP merging, supervoxel labels carried to the points
// (getLabeledCloud + relabelCloud); segments mostly on the dominant RANSAC plane are dropped.
PeerSegmentation SegmentLccp(const Cloud::ConstPtr& cloud) {
    pcl::SupervoxelClustering<Point> super(kLccpVoxel, kLccpSeed);
    // setUseSingleCameraTransform is not called: PCL's default then uses the single-camera
    // (depth-dependent) voxel transform for organized input, as the mOSD frames are.
    super.setInputCloud(cloud);
    super.setColorImportance(kLccpColor);
    super.setSpatialImportance(kLccpSpatial);
    super.setNormalImportance(kLccpNormal);
    std::map<std::uint32_t, pcl::Supervoxel<Point>::Ptr> supervoxels;
    super.extract(supervoxels);
    std::multimap<std::uint32_t, std::uint32_t> adjacency;
    super.getSupervoxelAdjacency(adjacency);

    pcl::LCCPSegmentation<Point> lccp;
    lccp.setConcavityToleranceThreshold(kLccpConcavityDeg);
    lccp.setSanityCheck(kLccpSanity);
    lccp.setSmoothnessCheck(true, kLccpVoxel, kLccpSeed, kLccpSmoothness);
    lccp.setKFactor(kLccpKFactor);
    lccp.setInputSupervoxels(supervoxels, adjacency);
    lccp.setMinSegmentSize(kLccpMinSegment);
    lccp.segment();

    const pcl::PointCloud<pcl::PointXYZL>::Ptr labeled = super.getLabeledCloud();
    lccp.relabelCloud(*labeled);

    // Label 0 marks points without a supervoxel (NaN points among them).
    std::unordered_map<std::uint32_t, std::size_t> segment_of_label;
    std::vector<pcl::Indices> segments;
    for (std::size_t i = 0; i < labeled->size() && i < cloud->size(); ++i) {
        const std::uint32_t label = (*labeled)[i].label;
        if (label == 0 || !pcl::isXYZFinite((*cloud)[i])) continue;
        auto [it, inserted] = segment_of_label.try_emplace(label, segments.size());
        if (inserted) segments.emplace_back();
        segments[it->second].push_back(static_cast<pcl::index_t>(i));
    }
    return NumberObjects(*cloud, std::move(segments), FitPlane(cloud, FiniteIndices(*cloud)));
}

// ---------------------------------------------------------------------------------------------

}  // namespace multicue::peers
