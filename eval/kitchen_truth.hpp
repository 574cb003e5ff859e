#pragma once
// Ground truth of simulated kitchen scans for the kitchen evaluation, beyond the per-point
// fields and front matching of multicue/training/kitchen_scan_truth.hpp: true fixtures and
// joint axes from the kitchen's ground-truth URDF.

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/io/urdf.hpp"
#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/training/kitchen_scan_truth.hpp"

namespace multicue::eval {

using sim::KitchenClass;

using training::MatchFronts;
using training::ScanTruth;
using training::TrueFront;
using training::TrueFronts;

/// A line in the world: a point and a unit direction.
struct Axis {
    Eigen::Vector3f point = Eigen::Vector3f::Zero();
    Eigen::Vector3f direction = Eigen::Vector3f::UnitZ();
};

/// World axes of every joint of a URDF with all joints at zero (the state it was written in).
inline std::map<std::string, Axis> UrdfJointAxes(const io::UrdfModel& urdf) {
    std::map<std::string, Eigen::Isometry3d> link_pose;
    link_pose[urdf.root] = Eigen::Isometry3d::Identity();
    std::map<std::string, Axis> out;
    for (std::size_t pass = 0; pass < urdf.joints.size() + 1; ++pass) {
        bool changed = false;
        for (const auto& j : urdf.joints) {
            if (!link_pose.count(j.parent) || link_pose.count(j.child)) continue;
            const Eigen::Isometry3d T = link_pose[j.parent] * j.origin;
            link_pose[j.child] = T;
            Axis a;
            a.point = T.translation().cast<float>();
            a.direction = (T.linear() * j.axis.normalized()).cast<float>();
            out[j.name] = a;
            changed = true;
        }
        if (!changed) break;
    }
    return out;
}

/// Angle between two lines [deg] (directions of either sign).
inline float LineAngleDeg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return std::acos(std::clamp(std::abs(a.normalized().dot(b.normalized())), 0.0f, 1.0f)) *
           57.29578f;
}

/// The point of line `pred` nearest to `at` [m].
inline Eigen::Vector3f LinePointNear(const Axis& pred, const Eigen::Vector3f& at) {
    const Eigen::Vector3f d = pred.direction.normalized();
    return pred.point + d * d.dot(at - pred.point);
}

/// From the point of line `pred` nearest to `at` to the nearest point of line `truth` [m].
inline Eigen::Vector3f LineOffsetAt(const Axis& pred, const Axis& truth,
                                    const Eigen::Vector3f& at) {
    const Eigen::Vector3f t = truth.direction.normalized();
    const Eigen::Vector3f r = truth.point - LinePointNear(pred, at);
    return r - t * t.dot(r);
}

/// Distance from the point of line `pred` nearest to `at` to the line `truth` [m].
inline float LineDistanceAt(const Axis& pred, const Axis& truth, const Eigen::Vector3f& at) {
    return LineOffsetAt(pred, truth, at).norm();
}

/// A true fixture: connected points of one handle or knob.
struct TrueFixture {
    bool handle = true;
    std::uint32_t key = 0;
    Indices points;
};

inline std::vector<TrueFixture> TrueFixtures(const PointCloud& cloud, const ScanTruth& t,
                                             std::size_t min_points) {
    std::map<std::pair<std::uint32_t, int>, Indices> groups;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.IsFinite(i)) continue;
        const KitchenClass c = t.Class(i);
        if (c != KitchenClass::kHandle && c != KitchenClass::kKnob) continue;
        groups[{t.Key(i), c == KitchenClass::kHandle ? 1 : 0}].push_back(static_cast<Index>(i));
    }
    std::vector<TrueFixture> out;
    for (const auto& [key, pts] : groups) {
        EuclideanClusteringParams cp;
        cp.tolerance = 0.03f;
        cp.subset = pts;
        cp.min_cluster_size = min_points;
        for (auto& cl : EuclideanClusteringGrid(cloud, cp).clusters) {
            out.push_back(TrueFixture{key.second == 1, key.first, std::move(cl)});
        }
    }
    return out;
}

}  // namespace multicue::eval
