#include "multicue/registration/register.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/params.hpp"

namespace multicue {
namespace {

double MsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

bool Better(const RegistrationResult& a, const RegistrationResult& b) {
    if (a.converged != b.converged) return a.converged;
    return a.overlap > b.overlap;
}

bool UsableForRgb(const PointCloud* frame) {
    return frame != nullptr && frame->IsOrganized() && frame->HasColors();
}

}  // namespace

const char* RegistrationMethodName(RegistrationMethod method) {
    switch (method) {
        case RegistrationMethod::kIcp:
            return "icp";
        case RegistrationMethod::kPointToPlane:
            return "point-to-plane";
        case RegistrationMethod::kSymmetric:
            return "symmetric";
        case RegistrationMethod::kPlane:
            return "plane";
        case RegistrationMethod::kGlobal:
            return "global";
        case RegistrationMethod::kAuto:
            break;
    }
    return "auto";
}

RegistrationMethod ParseRegistrationMethod(const std::string& name) {
    for (const auto m : {RegistrationMethod::kIcp, RegistrationMethod::kPointToPlane,
                         RegistrationMethod::kSymmetric, RegistrationMethod::kPlane,
                         RegistrationMethod::kGlobal, RegistrationMethod::kAuto}) {
        if (name == RegistrationMethodName(m)) return m;
    }
    throw InvalidArgument(fmt::format(
        "unknown registration method '{}' (choices: icp, point-to-plane, symmetric, plane, "
        "global, auto)",
        name));
}

RegistrationParams RegistrationParams::ForResolution(float r) {
    if (!(r > 0.0f) || !std::isfinite(r)) {
        throw InvalidArgument(fmt::format("registration resolution must be > 0, got {}", r));
    }
    RegistrationParams p;
    p.preprocess.voxel_size = r;
    // Chosen on the simulated validation sequences (seeds 1-3, docs/registration.md): a final
    // gate of 2 r, symmetric ICP, a depth-noise floor of r / 4.
    p.icp.method = IcpMethod::kSymmetric;
    p.icp.correspondences.max_distance = 2.0f * r;
    p.icp.noise_floor = 0.25f * r;
    p.icp.initial_max_distance = 15.0f * r;
    p.planes.radius = 3.0f * r;
    p.planes.max_rmse = r;
    p.planes.merge_distance = 1.5f * r;
    p.planes.min_extent = 2.0f * r;
    p.point_plane.matching.max_offset = 2.0f * r;
    p.point_plane.matching.centroid_slack = 15.0f * r;
    p.plane_global.score_distance = 2.0f * r;
    p.plane_global.matching.max_offset = 4.0f * r;
    p.plane_global.matching.centroid_slack = 15.0f * r;
    p.fpfh.fpfh.radius = 5.0f * r;
    p.fpfh.ransac.inlier_distance = 3.0f * r;
    p.fpfh.ransac.min_edge = 2.0f * r;
    p.fpfh.pruning.absolute = 2.0f * r;
    p.free_space.tolerance = 3.0f * r;
    p.free_space.max_gap = 10.0f * r;
    return p;
}

void RegistrationParams::Validate() const {
    ValidateNode("preprocess", [&] { preprocess.Validate(); });
    ValidateNode("icp", [&] { icp.Validate(); });
    ValidateNode("planes", [&] { planes.Validate(); });
    ValidateNode("point_plane", [&] { point_plane.Validate(); });
    ValidateNode("plane_global", [&] { plane_global.Validate(); });
    ValidateNode("fpfh", [&] { fpfh.Validate(); });
    ValidateNode("rgb", [&] { rgb.Validate(); });
    if (free_space.enabled) ValidateNode("free_space", [&] { free_space.Validate(); });
    if (num_threads < 0) {
        throw InvalidArgument(fmt::format("num_threads must be >= 0, got {}", num_threads));
    }
}

float SuggestResolution(const PointCloud& cloud) {
    Eigen::Vector3f lo, hi;
    if (cloud.CountFinite() < 3 || !ComputeBounds(cloud, lo, hi)) {
        throw DataError("the cloud has fewer than 3 finite points");
    }
    Indices finite;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (cloud.IsFinite(i)) finite.push_back(static_cast<Index>(i));
    }
    const KdTree tree(cloud, finite);
    std::vector<float> spacing;
    Indices nn;
    std::vector<float> d2;
    for (Index i : EvenSubset(finite, 2000)) {
        if (tree.SearchKnn(cloud.points[i], 2, nn, d2) == 2) spacing.push_back(std::sqrt(d2[1]));
    }
    std::nth_element(spacing.begin(),
                     spacing.begin() + static_cast<std::ptrdiff_t>(spacing.size() / 2),
                     spacing.end());
    const float median = spacing.empty() ? 0.0f : spacing[spacing.size() / 2];
    float r = std::max(median, (hi - lo).norm() / 300.0f);
    if (!(r > 0.0f)) throw DataError("all finite points of the cloud coincide");
    const float magnitude = std::pow(10.0f, std::floor(std::log10(r)) - 1.0f);
    return std::round(r / magnitude) * magnitude;
}

namespace {

RegistrationResult Dispatch(const PointCloud& source, const KdTree* source_tree_or_null,
                            const PointCloud& target, const KdTree& target_tree,
                            const RegistrationParams& params,
                            const std::optional<Eigen::Isometry3d>& T_init,
                            const PointCloud* source_frame, const PointCloud* target_frame) {
    const auto start = std::chrono::steady_clock::now();
    RegistrationMethod method = params.method;
    if (method == RegistrationMethod::kAuto) {
        method = T_init ? RegistrationMethod::kPlane : RegistrationMethod::kGlobal;
    }
    const Eigen::Isometry3d init = T_init.value_or(Eigen::Isometry3d::Identity());
    IcpParams icp = params.icp;
    icp.num_threads = params.num_threads;
    if (method == RegistrationMethod::kIcp) icp.method = IcpMethod::kPointToPoint;
    if (method == RegistrationMethod::kPointToPlane) icp.method = IcpMethod::kPointToPlane;
    if (method == RegistrationMethod::kSymmetric) icp.method = IcpMethod::kSymmetric;
    if (method == RegistrationMethod::kIcp || method == RegistrationMethod::kPointToPlane ||
        method == RegistrationMethod::kSymmetric) {
        RegistrationResult r = RegisterIcp(source, target, &target_tree, icp, init);
        r.time_ms = MsSince(start);
        return r;
    }
    if (icp.method == IcpMethod::kPointToPoint) icp.method = IcpMethod::kPointToPlane;
    std::optional<KdTree> own_tree;
    if (source_tree_or_null == nullptr) own_tree.emplace(source);
    const KdTree& source_tree = own_tree ? *own_tree : *source_tree_or_null;
    PointPlaneParams point_plane = params.point_plane;
    point_plane.icp = icp;
    PlaneExtractionParams planes = params.planes;
    if (planes.depth_noise == 0.0f) planes.depth_noise = icp.depth_noise;
    const auto source_patches = ExtractPlanarPatches(source, source_tree, planes);
    const auto target_patches = ExtractPlanarPatches(target, target_tree, planes);
    if (method == RegistrationMethod::kPlane) {
        RegistrationResult r = RegisterPointsAndPlanes(source, target, &target_tree, source_patches,
                                                       target_patches, point_plane, init);
        r.time_ms = MsSince(start);
        return r;
    }

    // Global: planes first, then 3D features, then RGB keypoints; each hypothesis refined.
    PlaneGlobalParams global = params.plane_global;
    global.refine = point_plane;
    global.num_threads = params.num_threads;
    RegistrationResult best =
        RegisterPlanesGlobal(source, target, target_tree, source_patches, target_patches, global);
    std::string trail = "planes: " + best.reason;
    auto refine = [&](const RegistrationResult& coarse, const char* what) {
        if (!coarse.converged) {
            trail += fmt::format("; {}: {}", what, coarse.reason);
            return;
        }
        RegistrationResult r =
            RegisterPointsAndPlanes(source, target, &target_tree, source_patches, target_patches,
                                    point_plane, coarse.T_target_source);
        if (r.converged && r.overlap < global.min_overlap) {
            r.converged = false;
            r.status = RegistrationStatus::kLowOverlap;
            r.reason = fmt::format("overlap {:.3f} below {:.3f}", r.overlap, global.min_overlap);
        }
        trail += fmt::format("; {}: {}, refined: {}", what, coarse.reason, r.reason);
        if (Better(r, best)) best = std::move(r);
    };
    if (!best.converged) {
        FpfhAlignParams fpfh = params.fpfh;
        fpfh.num_threads = params.num_threads;
        refine(AlignFpfh(source, source_tree, target, target_tree, fpfh), "FPFH");
    }
    if (!best.converged && params.rgb_keypoints && UsableForRgb(source_frame) &&
        UsableForRgb(target_frame)) {
        const PointMatches m = MatchRgbKeypoints(*source_frame, *target_frame, params.rgb);
        RansacParams ransac = params.fpfh.ransac;
        ransac.num_threads = params.num_threads;
        refine(AlignMatchesRansac(*source_frame, *target_frame, m, ransac), "RGB keypoints");
    }
    best.reason = trail;
    best.time_ms = MsSince(start);
    return best;
}

}  // namespace

void CheckAgainstFreeSpace(const PointCloud& source, const PointCloud& target,
                           const PointCloud* source_frame, const PointCloud* target_frame,
                           const FreeSpaceParams& params, RegistrationResult& result) {
    double worst = 0.0;
    if (target_frame != nullptr) {
        worst = std::max(
            worst, CheckFreeSpace(source, *target_frame, result.T_target_source, params).ratio);
    }
    if (source_frame != nullptr) {
        worst = std::max(
            worst,
            CheckFreeSpace(target, *source_frame, result.T_target_source.inverse(), params).ratio);
    }
    result.free_space_violation = worst;
    if (result.converged && worst > params.max_violation) {
        result.converged = false;
        result.status = RegistrationStatus::kInconsistent;
        result.reason = fmt::format(
            "{:.1f} % of the points lie where the other frame saw free space (at most {:.1f} %): "
            "{}",
            100.0 * worst, 100.0 * params.max_violation, result.reason);
    }
}

RegistrationResult RegisterPrepared(const PointCloud& source, const KdTree* source_tree,
                                    const PointCloud& target, const KdTree& target_tree,
                                    const RegistrationParams& params,
                                    const std::optional<Eigen::Isometry3d>& T_init,
                                    const PointCloud* source_frame,
                                    const PointCloud* target_frame) {
    params.Validate();
    const auto start = std::chrono::steady_clock::now();
    const auto run = [&](const RegistrationParams& p, const std::optional<Eigen::Isometry3d>& T) {
        RegistrationResult r =
            Dispatch(source, source_tree, target, target_tree, p, T, source_frame, target_frame);
        if (p.free_space.enabled) {
            CheckAgainstFreeSpace(source, target, source_frame, target_frame, p.free_space, r);
        }
        return r;
    };
    RegistrationResult r = run(params, T_init);
    if (params.method == RegistrationMethod::kAuto && T_init && !r.converged) {
        // The guess led into a wrong minimum (repeated structure: a row of identical cupboard
        // doors) or too far off: align without it.
        RegistrationParams global = params;
        global.method = RegistrationMethod::kGlobal;
        RegistrationResult g = run(global, std::nullopt);
        if (g.converged) {
            g.reason = fmt::format("from the guess: {}; without it: {}", r.reason, g.reason);
            r = std::move(g);
        }
        r.time_ms = MsSince(start);
    }
    return r;
}

RegistrationParams SuggestRegistrationParams(const PointCloud& cloud) {
    if (EstimatePinhole(cloud)) {
        RegistrationParams p = RegistrationParams::ForResolution(0.01f);
        p.icp.depth_noise = 1.4e-3f;  // Khoshelham and Elberink 2012: sigma = 1.4e-3 z^2
        return p;
    }
    return RegistrationParams::ForResolution(SuggestResolution(cloud));
}

RegistrationResult Register(const PointCloud& source, const PointCloud& target,
                            const RegistrationParams& params,
                            const std::optional<Eigen::Isometry3d>& T_init) {
    const auto start = std::chrono::steady_clock::now();
    params.Validate();
    if (T_init && !T_init->matrix().allFinite()) {
        throw InvalidArgument("registration initial transform is not finite");
    }
    PreprocessParams pre = params.preprocess;
    pre.num_threads = params.num_threads;
    const PointCloud s = PreprocessForRegistration(source, pre);
    const PointCloud t = PreprocessForRegistration(target, pre);
    if (s.empty() || t.empty()) {
        RegistrationResult r;
        r.T_target_source = T_init.value_or(Eigen::Isometry3d::Identity());
        r.status = RegistrationStatus::kEmptyInput;
        r.reason = s.empty() ? "source has no finite point" : "target has no finite point";
        return r;
    }
    const KdTree tt(t);
    RegistrationResult r = RegisterPrepared(s, nullptr, t, tt, params, T_init, &source, &target);
    r.time_ms = MsSince(start);
    return r;
}

}  // namespace multicue
