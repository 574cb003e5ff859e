#include "multicue/search/occupancy_map.hpp"

#include <cmath>
#include <sstream>
#include <string>

#include <fmt/format.h>
// OctoMap's templates print debug lines while trees are read and written; compiled here, they
// are silenced (library code does not print). The .bt header is written and parsed here too,
// because the library's own readBinary / writeBinary print.
#define OCTOMAP_NODEBUGOUT
#include <octomap/OcTree.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

void CheckOpen(double value, double lo, double hi, const char* name) {
    if (!(value > lo && value < hi)) {
        throw InvalidArgument(
            fmt::format("occupancy map {} must be in ({}, {}), got {}", name, lo, hi, value));
    }
}

void Configure(octomap::OcTree& tree, const OccupancyMapParams& p) {
    tree.setProbHit(p.prob_hit);
    tree.setProbMiss(p.prob_miss);
    tree.setClampingThresMin(p.clamp_min);
    tree.setClampingThresMax(p.clamp_max);
    tree.setOccupancyThres(p.occupied_threshold);
}

octomap::point3d ToOcto(const Eigen::Vector3f& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

const char* OccupancyName(Occupancy state) {
    switch (state) {
        case Occupancy::kFree:
            return "free";
        case Occupancy::kOccupied:
            return "occupied";
        case Occupancy::kUnknown:
            break;
    }
    return "unknown";
}

void OccupancyMapParams::Validate() const {
    if (!(resolution > 0.0) || !std::isfinite(resolution)) {
        throw InvalidArgument(
            fmt::format("occupancy map resolution must be > 0, got {}", resolution));
    }
    if (!(max_range >= 0.0) || !std::isfinite(max_range)) {
        throw InvalidArgument(
            fmt::format("occupancy map max_range must be >= 0 (0 = no limit), got {}", max_range));
    }
    CheckOpen(prob_hit, 0.5, 1.0, "prob_hit");
    CheckOpen(prob_miss, 0.0, 0.5, "prob_miss");
    if (!(clamp_min > 0.0 && clamp_min <= prob_miss)) {
        throw InvalidArgument(
            fmt::format("occupancy map clamp_min must be in (0, prob_miss = {}], got {}", prob_miss,
                        clamp_min));
    }
    if (!(clamp_max >= prob_hit && clamp_max < 1.0)) {
        throw InvalidArgument(fmt::format(
            "occupancy map clamp_max must be in [prob_hit = {}, 1), got {}", prob_hit, clamp_max));
    }
    CheckOpen(occupied_threshold, 0.0, 1.0, "occupied_threshold");
}

struct OccupancyMap::Impl {
    explicit Impl(const OccupancyMapParams& p) : params(p), tree(p.resolution) {
        Configure(tree, p);
    }
    OccupancyMapParams params;
    octomap::OcTree tree;
};

OccupancyMap::OccupancyMap(const OccupancyMapParams& params) {
    params.Validate();
    impl_ = std::make_unique<Impl>(params);
}
OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

void OccupancyMap::InsertScan(const PointCloud& points, const Eigen::Vector3f& sensor_origin) {
    if (!sensor_origin.allFinite()) {
        throw InvalidArgument(
            fmt::format("occupancy map sensor origin must be finite, got ({}, {}, {})",
                        sensor_origin.x(), sensor_origin.y(), sensor_origin.z()));
    }
    octomap::Pointcloud scan;
    scan.reserve(points.size());
    for (const auto& p : points.points) {
        if (p.allFinite()) scan.push_back(p.x(), p.y(), p.z());
    }
    if (scan.size() == 0) return;
    const double range = impl_->params.max_range > 0.0 ? impl_->params.max_range : -1.0;
    // discretize: rays of points in one voxel are cast once (the result is the same up to the
    // voxel, and dense frames insert several times faster).
    impl_->tree.insertPointCloud(scan, ToOcto(sensor_origin), range, /*lazy_eval=*/false,
                                 /*discretize=*/true);
}

Occupancy OccupancyMap::Query(const Eigen::Vector3f& point) const {
    if (!point.allFinite()) return Occupancy::kUnknown;
    const octomap::OcTreeNode* node = impl_->tree.search(ToOcto(point));
    if (node == nullptr) return Occupancy::kUnknown;
    return impl_->tree.isNodeOccupied(node) ? Occupancy::kOccupied : Occupancy::kFree;
}

double OccupancyMap::Probability(const Eigen::Vector3f& point) const {
    if (!point.allFinite()) return 0.5;
    const octomap::OcTreeNode* node = impl_->tree.search(ToOcto(point));
    return node == nullptr ? 0.5 : node->getOccupancy();
}

OccupancyCounts OccupancyMap::Counts() const {
    OccupancyCounts c;
    for (auto it = impl_->tree.begin_leafs(), end = impl_->tree.end_leafs(); it != end; ++it) {
        const double size = it.getSize();
        const double volume = size * size * size;
        if (impl_->tree.isNodeOccupied(*it)) {
            ++c.occupied_leaves;
            c.occupied_volume += volume;
        } else {
            ++c.free_leaves;
            c.free_volume += volume;
        }
    }
    return c;
}

std::vector<Eigen::Vector3f> OccupancyMap::OccupiedCenters() const {
    std::vector<Eigen::Vector3f> centers;
    for (auto it = impl_->tree.begin_leafs(), end = impl_->tree.end_leafs(); it != end; ++it) {
        if (!impl_->tree.isNodeOccupied(*it)) continue;
        const auto c = it.getCoordinate();
        centers.emplace_back(c.x(), c.y(), c.z());
    }
    return centers;
}

bool OccupancyMap::Bounds(Eigen::Vector3f& min, Eigen::Vector3f& max) const {
    if (impl_->tree.size() == 0) return false;
    double x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0;
    impl_->tree.getMetricMin(x0, y0, z0);
    impl_->tree.getMetricMax(x1, y1, z1);
    min = Eigen::Vector3d(x0, y0, z0).cast<float>();
    max = Eigen::Vector3d(x1, y1, z1).cast<float>();
    return true;
}

double OccupancyMap::resolution() const { return impl_->tree.getResolution(); }
bool OccupancyMap::empty() const { return impl_->tree.size() == 0; }
const OccupancyMapParams& OccupancyMap::params() const { return impl_->params; }

namespace {
constexpr const char* kBinaryHeader = "# Octomap OcTree binary file";
}  // namespace

void OccupancyMap::WriteBinary(std::ostream& out) const {
    // OctoMap's .bt layout: header lines, then two bits per child of every inner node.
    out << kBinaryHeader << "\n# written by multicue\nid " << impl_->tree.getTreeType() << "\nsize "
        << impl_->tree.size() << "\nres " << impl_->tree.getResolution() << "\ndata\n";
    impl_->tree.writeBinaryData(out);
    if (!out) throw IoError("occupancy map: writing the binary tree failed");
}

OccupancyMap OccupancyMap::ReadBinary(std::istream& in, const char* source,
                                      const OccupancyMapParams& params) {
    std::string line;
    std::getline(in, line);
    if (line.rfind(kBinaryHeader, 0) != 0) {
        throw FormatError(fmt::format("{}: not an OctoMap binary tree (.bt)", source));
    }
    std::string id;
    std::size_t size = 0;
    double resolution = 0.0;
    bool data = false;
    std::string token;
    while (!data && in >> token) {
        if (token.front() == '#') {
            std::getline(in, line);
        } else if (token == "id") {
            in >> id;
        } else if (token == "size") {
            in >> size;
        } else if (token == "res") {
            in >> resolution;
        } else if (token == "data") {
            std::getline(in, line);
            data = true;
        } else {
            throw FormatError(fmt::format("{}: unknown header entry '{}'", source, token));
        }
    }
    if (!data || !in) throw FormatError(fmt::format("{}: truncated .bt header", source));
    if (id != "OcTree") {
        throw FormatError(fmt::format("{}: tree type '{}', expected OcTree", source, id));
    }
    OccupancyMapParams p = params;
    p.resolution = resolution;
    try {
        p.Validate();
    } catch (const InvalidArgument& e) {
        throw FormatError(fmt::format("{}: {}", source, e.what()));
    }
    OccupancyMap map(p);
    if (size > 0) map.impl_->tree.readBinaryData(in);
    if (map.impl_->tree.size() != size || (size > 0 && !in)) {
        throw FormatError(fmt::format("{}: truncated or malformed tree ({} of {} nodes)", source,
                                      map.impl_->tree.size(), size));
    }
    return map;
}

}  // namespace multicue
