#pragma once
// Ground truth of simulated kitchen scans for the kitchen evaluation: per-point fields, true
// fronts and fixtures, joint axes from the kitchen's ground-truth URDF, and the matching of a
// map's fronts and furniture to them.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/io/urdf.hpp"
#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/sim/kitchen_scene.hpp"

namespace multicue::eval {

using sim::KitchenClass;

/// The ground-truth fields of a scan made by the kitchen simulator.
struct ScanTruth {
    std::vector<std::uint8_t> semantic;
    std::vector<std::uint16_t> model, link, joint;

    explicit ScanTruth(const PointCloud& c) {
        semantic = Read<std::uint8_t>(c, "semantic");
        model = Read<std::uint16_t>(c, "model");
        link = Read<std::uint16_t>(c, "link");
        joint = Read<std::uint16_t>(c, "joint");
    }
    template <typename T>
    static std::vector<T> Read(const PointCloud& c, const char* name) {
        std::vector<T> out(c.size(), 0);
        const ExtraField* f = c.FindExtraField(name);
        if (f && f->data.size() == c.size() * sizeof(T)) {
            std::memcpy(out.data(), f->data.data(), f->data.size());
        }
        return out;
    }
    KitchenClass Class(std::size_t i) const { return static_cast<KitchenClass>(semantic[i]); }
    bool IsFront(std::size_t i) const {
        return Class(i) == KitchenClass::kDoor || Class(i) == KitchenClass::kDrawer;
    }
    /// Key of a point's (instance, link), 0 for none.
    std::uint32_t Key(std::size_t i) const {
        return model[i] == 0 ? 0u : (std::uint32_t{model[i]} << 16) | link[i];
    }
};

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

/// A true front: the door or drawer points of one (instance, link).
struct TrueFront {
    std::uint32_t key = 0;
    std::size_t points = 0;
    std::size_t fixture_points = 0;  ///< visible handle or knob points of the same link
    int joint = -1;                  ///< index into the kitchen's joints, -1 for none
};

inline std::map<std::uint32_t, TrueFront> TrueFronts(const PointCloud& cloud, const ScanTruth& t) {
    std::map<std::uint32_t, TrueFront> out;
    std::map<std::uint32_t, std::map<int, std::size_t>> joints;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.IsFinite(i) || t.model[i] == 0) continue;
        const KitchenClass c = t.Class(i);
        const std::uint32_t k = t.Key(i);
        if (t.IsFront(i)) {
            out[k].key = k;
            ++out[k].points;
            ++joints[k][static_cast<int>(t.joint[i]) - 1];
        } else if (c == KitchenClass::kHandle || c == KitchenClass::kKnob) {
            out[k].key = k;
            ++out[k].fixture_points;
        }
    }
    for (auto& [k, f] : out) {
        std::size_t best = 0;
        for (const auto& [j, n] : joints[k]) {
            if (n > best) {
                best = n;
                f.joint = j;
            }
        }
    }
    return out;
}

/// Matches predicted fronts to true fronts greedily by IoU; returns per true front key the
/// predicted front index and the IoU (fronts without a match are absent).
inline std::map<std::uint32_t, std::pair<int, float>> MatchFronts(
    const mapping::KitchenMap& map, const ScanTruth& t,
    const std::map<std::uint32_t, TrueFront>& truth, std::size_t offset = 0) {
    struct Pair {
        float iou;
        int pred;
        std::uint32_t key;
    };
    std::vector<Pair> pairs;
    for (std::size_t f = 0; f < map.fronts.size(); ++f) {
        std::map<std::uint32_t, std::size_t> hits;
        std::size_t size = 0;
        for (const Index gi : map.fronts[f].indices) {
            if (gi < offset || gi - offset >= t.semantic.size()) continue;
            const std::size_t i = gi - offset;
            ++size;
            if (t.IsFront(i)) ++hits[t.Key(i)];
        }
        for (const auto& [k, n] : hits) {
            const auto it = truth.find(k);
            if (it == truth.end() || it->second.points == 0) continue;
            const float iou =
                static_cast<float>(n) / static_cast<float>(size + it->second.points - n);
            pairs.push_back({iou, static_cast<int>(f), k});
        }
    }
    std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
        return a.iou != b.iou ? a.iou > b.iou : a.pred < b.pred;
    });
    std::map<std::uint32_t, std::pair<int, float>> out;
    std::vector<bool> used(map.fronts.size(), false);
    for (const Pair& p : pairs) {
        if (used[static_cast<std::size_t>(p.pred)] || out.count(p.key)) continue;
        used[static_cast<std::size_t>(p.pred)] = true;
        out[p.key] = {p.pred, p.iou};
    }
    return out;
}

}  // namespace multicue::eval
