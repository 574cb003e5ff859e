#include "multicue/features/feature_common.hpp"

#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {

std::size_t CountDefinedRows(const FeatureMatrix& features) {
    std::size_t defined = 0;
    for (Eigen::Index r = 0; r < features.rows(); ++r) {
        if (features.row(r).allFinite()) ++defined;
    }
    return defined;
}

FeatureVector MeanOfDefinedRows(const FeatureMatrix& features) {
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(features.cols());
    std::size_t defined = 0;
    for (Eigen::Index r = 0; r < features.rows(); ++r) {
        if (!features.row(r).allFinite()) continue;
        sum += features.row(r).transpose().cast<double>();
        ++defined;
    }
    if (defined > 0) sum /= static_cast<double>(defined);
    return sum.cast<float>();
}

namespace detail {

void CheckPositive(float value, const char* what) {
    if (!(value > 0.0f) || !std::isfinite(value)) {
        throw InvalidArgument(fmt::format("{} must be > 0 and finite, got {}", what, value));
    }
}

void CheckThreads(int num_threads) {
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("num_threads must be >= 0 (0 = all cores), got {}", num_threads));
    }
}

void CheckNormals(const PointCloud& cloud, const char* feature) {
    if (cloud.empty()) return;
    if (!cloud.HasNormals()) {
        throw InvalidArgument(
            fmt::format("{} needs normals: the cloud has none (estimate them first)", feature));
    }
    if (cloud.normals.size() != cloud.size()) {
        throw DataError(fmt::format("{}: the cloud has {} normals for {} points", feature,
                                    cloud.normals.size(), cloud.size()));
    }
}

void CheckTree(const PointCloud& cloud, const KdTree& tree) {
    if (tree.size() > cloud.size()) {
        throw InvalidArgument(fmt::format(
            "the k-d tree indexes {} points but the cloud has {}: build it from this cloud",
            tree.size(), cloud.size()));
    }
}

void RadiusNeighbours(const KdTree& tree, const Eigen::Vector3f& query, float radius,
                      Indices& indices, std::vector<float>& squared_distances) {
    indices.clear();
    squared_distances.clear();
    const auto& nodes = tree.Nodes();
    if (nodes.empty()) return;
    const auto& points = tree.TreePoints();
    const auto& to_cloud = tree.TreeToCloud();
    const float r2 = radius * radius;
    // Depth-first walk with an explicit stack; a tree of 2^32 points is at most 64 levels deep.
    Index stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const KdTree::Node& node = nodes[stack[--top]];
        float gap2 = 0.0f;
        float reach2 = 0.0f;
        for (int a = 0; a < 3; ++a) {
            const float lo = node.min[a] - query[a];
            const float hi = query[a] - node.max[a];
            const float gap = std::max(0.0f, std::max(lo, hi));
            gap2 += gap * gap;
            const float reach = std::max(std::abs(lo), std::abs(hi));
            reach2 += reach * reach;
        }
        if (gap2 > r2) continue;
        if (reach2 < r2 * 0.999f) {
            // The whole node lies inside the sphere (with a margin against rounding): copy it.
            for (Index i = node.begin; i < node.end; ++i) {
                indices.push_back(to_cloud[i]);
                squared_distances.push_back((points[i] - query).squaredNorm());
            }
            continue;
        }
        if (node.IsLeaf()) {
            for (Index i = node.begin; i < node.end; ++i) {
                const float d2 = (points[i] - query).squaredNorm();
                if (d2 <= r2) {
                    indices.push_back(to_cloud[i]);
                    squared_distances.push_back(d2);
                }
            }
            continue;
        }
        const Index self = static_cast<Index>(&node - nodes.data());
        stack[top++] = node.second_child;
        stack[top++] = self + 1;
    }
}

bool PairFeatures(const Eigen::Vector3f& p1, const Eigen::Vector3f& n1, const Eigen::Vector3f& p2,
                  const Eigen::Vector3f& n2, float& f1, float& f2, float& f3, float& f4) {
    Eigen::Vector3f d = p2 - p1;
    f4 = d.norm();
    if (f4 == 0.0f) {
        f1 = f2 = f3 = f4 = 0.0f;
        return false;
    }
    const float angle1 = n1.dot(d) / f4;
    const float angle2 = n2.dot(d) / f4;
    const Eigen::Vector3f* u = &n1;
    const Eigen::Vector3f* other = &n2;
    // The source is the point whose normal is closer to the joining line: larger |cos|.
    if (std::abs(angle1) < std::abs(angle2)) {
        u = &n2;
        other = &n1;
        d = -d;
        f3 = -angle2;
    } else {
        f3 = angle1;
    }
    Eigen::Vector3f v = d.cross(*u);
    const float v_norm = v.norm();
    if (v_norm == 0.0f) {
        f1 = f2 = f3 = f4 = 0.0f;
        return false;
    }
    v /= v_norm;
    const Eigen::Vector3f w = u->cross(v);
    f2 = v.dot(*other);
    f1 = std::atan2(w.dot(*other), u->dot(*other));
    return true;
}

}  // namespace detail
}  // namespace multicue
