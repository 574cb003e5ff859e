/// \file mosd_peers: segments mOSD scenes with three standard PCL 1.13 table-top pipelines and
/// writes OUT_DIR/<scene>/labels.pcd in the format of `multicue perceive` (fields x y z label
/// object category, same WIDTH/HEIGHT and point order as the input, label = object, 0 = no object,
/// category 0), so that the mOSD scorer (osd_eval.py) scores PCL on exactly the scenes multicue is
/// scored on.
///
/// usage: mosd_peers --method euclidean|region_growing|lccp INPUT_DIR OUT_DIR
///                   [--scenes learn0,learn1,...]
///
/// The pipelines use the parameters of PCL's own tutorials and examples (see eval/README.md):
///  - euclidean: the "Euclidean Cluster Extraction" tutorial (cluster_extraction.cpp);
///  - region_growing: the "Region growing segmentation" tutorial (region_growing_segmentation.cpp);
///  - lccp: PCL's LCCP example program (examples/segmentation/example_lccp_segmentation.cpp).
/// The time printed per scene is the wall time of the segmentation alone (from the loaded cloud to
/// the per-point object ids), without reading and writing files.

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <pcl/ModelCoefficients.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/PointIndices.h>
#include <pcl/common/point_tests.h>
#include <pcl/console/print.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/lccp_segmentation.h>
#include <pcl/segmentation/region_growing.h>
#include <pcl/segmentation/sac_segmentation.h>
#include <pcl/segmentation/supervoxel_clustering.h>
#include "driver_options.hpp"

namespace {

namespace fs = std::filesystem;

using Point = pcl::PointXYZRGBA;  // the mOSD files hold label x y z rgba; label is not read
using Cloud = pcl::PointCloud<Point>;

// ---------------------------------------------------------------------------------------------
// Parameters, each as given in the PCL tutorial or example the pipeline follows.

// Euclidean Cluster Extraction tutorial.
constexpr float kEuclideanLeaf = 0.01f;          // VoxelGrid leaf size
constexpr double kTutorialPlaneDistance = 0.02;  // SACSegmentation distance threshold
constexpr int kTutorialPlaneIterations = 100;    // SACSegmentation max iterations
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

struct Segmentation {
    std::vector<std::uint32_t> object;  // per input point, 0 = no object
    std::size_t objects = 0;
};

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
Segmentation NumberObjects(const Cloud& cloud, std::vector<pcl::Indices> segments,
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
    Segmentation result;
    result.object.assign(cloud.size(), 0);
    for (const auto& segment : segments) {
        if (segment.empty()) continue;
        ++result.objects;
        for (const auto i : segment) result.object[i] = static_cast<std::uint32_t>(result.objects);
    }
    return result;
}

// 1. Euclidean Cluster Extraction tutorial: 1 cm VoxelGrid, repeated RANSAC plane removal while
// more than 30 % of the voxels remain, Euclidean clustering of the rest. Every input point gets
// the cluster of the voxel it fell into (the voxel grid's leaf layout maps a point to its voxel),
// so no nearest-neighbour search is needed to carry the labels back.
Segmentation Euclidean(const Cloud::ConstPtr& cloud) {
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

    Segmentation result;
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
Segmentation RegionGrowing(const Cloud::ConstPtr& cloud) {
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
Segmentation Lccp(const Cloud::ConstPtr& cloud) {
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

// labels.pcd: x y z (F4) label (U4) object (U4) category (U1), binary_compressed, input layout
// and order; label and object are the same id (result format 2).
bool WriteLabels(const fs::path& path, const Cloud& cloud,
                 const std::vector<std::uint32_t>& object) {
    pcl::PCLPointCloud2 out;
    out.width = cloud.width;
    out.height = cloud.height;
    out.is_dense = cloud.is_dense;
    auto field = [](const char* name, std::uint32_t offset, std::uint8_t type) {
        pcl::PCLPointField f;
        f.name = name;
        f.offset = offset;
        f.datatype = type;
        f.count = 1;
        return f;
    };
    out.fields = {field("x", 0, pcl::PCLPointField::FLOAT32),
                  field("y", 4, pcl::PCLPointField::FLOAT32),
                  field("z", 8, pcl::PCLPointField::FLOAT32),
                  field("label", 12, pcl::PCLPointField::UINT32),
                  field("object", 16, pcl::PCLPointField::UINT32),
                  field("category", 20, pcl::PCLPointField::UINT8)};
    out.point_step = 21;
    out.row_step = out.point_step * out.width;
    out.data.assign(static_cast<std::size_t>(out.point_step) * cloud.size(), 0);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        std::uint8_t* dst = out.data.data() + i * out.point_step;
        const Point& p = cloud[i];
        std::memcpy(dst, &p.x, 4);
        std::memcpy(dst + 4, &p.y, 4);
        std::memcpy(dst + 8, &p.z, 4);
        std::memcpy(dst + 12, &object[i], 4);
        std::memcpy(dst + 16, &object[i], 4);
        // category (byte 20) stays 0: the peers do not categorise.
    }
    pcl::PCDWriter writer;
    return writer.writeBinaryCompressed(path.string(), out, cloud.sensor_origin_,
                                        cloud.sensor_orientation_) == 0;
}

std::vector<std::string> SplitComma(const std::string& s) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    while (start <= s.size()) {
        const std::size_t end = std::min(s.find(',', start), s.size());
        if (end > start) parts.push_back(s.substr(start, end - start));
        start = end + 1;
    }
    return parts;
}

// learn2 before learn10: prefix, then the trailing number.
bool SceneLess(const std::string& a, const std::string& b) {
    auto split = [](const std::string& s) {
        std::size_t d = s.size();
        while (d > 0 && std::isdigit(static_cast<unsigned char>(s[d - 1]))) --d;
        const long number = d < s.size() ? std::stol(s.substr(d)) : -1;
        return std::make_pair(s.substr(0, d), number);
    };
    return split(a) < split(b);
}

}  // namespace

int main(int argc, char** argv) {
    std::string method;
    std::string scenes_arg;
    std::string input_arg, out_arg;
    CLI::App app{
        "mosd_peers: mOSD scenes segmented by PCL's table-top pipelines; reads "
        "INPUT_DIR/<scene>.pcd and writes OUT_DIR/<scene>/labels.pcd for the mOSD scorer"};
    app.add_option("--method", method, "PCL pipeline")
        ->required()
        ->check(CLI::IsMember({"euclidean", "region_growing", "lccp"}));
    app.add_option("--scenes", scenes_arg, "scenes to segment, learn0,learn1,... (default: all)");
    app.add_option("INPUT_DIR", input_arg, "folder of the scenes' .pcd files")->required();
    app.add_option("OUT_DIR", out_arg, "output folder")->required();
    if (auto code =
            multicue::eval::ParseDriverOptions(app, "mosd_peers", [&] { app.parse(argc, argv); }))
        return *code;
    Segmentation (*segment)(const Cloud::ConstPtr&) = method == "euclidean"        ? Euclidean
                                                      : method == "region_growing" ? RegionGrowing
                                                                                   : Lccp;
    const fs::path input_dir = input_arg;
    const fs::path out_dir = out_arg;

    std::vector<std::string> scenes = SplitComma(scenes_arg);
    if (scenes.empty()) {
        std::error_code ec;
        for (const auto& entry : fs::directory_iterator(input_dir, ec)) {
            if (entry.is_regular_file() && entry.path().extension() == ".pcd")
                scenes.push_back(entry.path().stem().string());
        }
        if (ec) {
            std::fprintf(stderr, "cannot list %s: %s\n", input_dir.c_str(), ec.message().c_str());
            return 1;
        }
        std::sort(scenes.begin(), scenes.end(), SceneLess);
    }
    if (scenes.empty()) {
        std::fprintf(stderr, "no scenes in %s\n", input_dir.c_str());
        return 1;
    }

    // PCL's warnings (e.g. about the unread label field) would drown the timings.
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);

    std::printf("%-10s %12s %8s   (method %s)\n", "scene", "segment_ms", "objects", method.c_str());
    std::vector<double> times_ms;
    int failures = 0;
    for (const auto& scene : scenes) {
        const fs::path in_path = input_dir / (scene + ".pcd");
        auto cloud = std::make_shared<Cloud>();
        if (pcl::io::loadPCDFile(in_path.string(), *cloud) < 0) {
            std::fprintf(stderr, "%s: cannot read %s\n", scene.c_str(), in_path.c_str());
            ++failures;
            continue;
        }
        Segmentation result;
        const auto start = std::chrono::steady_clock::now();
        try {
            result = segment(cloud);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "%s: segmentation failed: %s\n", scene.c_str(), e.what());
            ++failures;
            continue;
        }
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        times_ms.push_back(ms);

        const fs::path scene_dir = out_dir / scene;
        std::error_code ec;
        fs::create_directories(scene_dir, ec);
        if (ec || !WriteLabels(scene_dir / "labels.pcd", *cloud, result.object)) {
            std::fprintf(stderr, "%s: cannot write %s\n", scene.c_str(),
                         (scene_dir / "labels.pcd").c_str());
            ++failures;
            continue;
        }
        std::printf("%-10s %12.1f %8zu\n", scene.c_str(), ms, result.objects);
        std::fflush(stdout);
    }
    if (!times_ms.empty()) {
        std::vector<double> sorted = times_ms;
        std::sort(sorted.begin(), sorted.end());
        const std::size_t n = sorted.size();
        const double median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
        std::printf("median segmentation time: %.1f ms over %zu scenes (method %s)\n", median, n,
                    method.c_str());
    }
    return failures == 0 ? 0 : 1;
}
