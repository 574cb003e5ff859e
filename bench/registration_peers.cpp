/// \file PCL 1.13 and Open3D 0.16 registration on multicue's clouds (registration_peers.hpp).
/// Conversions happen before the clock starts; search trees are built inside the timed call,
/// as multicue's own registration builds its tree inside its call.

#include "registration_peers.hpp"

#include <chrono>
#include <memory>

#include <omp.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/pipelines/registration/ColoredICP.h>
#include <open3d/pipelines/registration/FastGlobalRegistration.h>
#include <open3d/pipelines/registration/Feature.h>
#include <open3d/pipelines/registration/Registration.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/ndt.h>

#include "multicue/adapters/open3d.hpp"

namespace multicue::peers {
namespace {

using Clock = std::chrono::steady_clock;

pcl::PointCloud<pcl::PointXYZ>::Ptr ToPclXyz(const PointCloud& c) {
    auto out = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    out->reserve(c.size());
    for (const auto& p : c.points) {
        if (p.allFinite()) out->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
    return out;
}

// The points with finite coordinates and normals (Open3D's point-to-plane has no NaN check).
PointCloud Usable(const PointCloud& c) {
    Indices keep;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (c.IsFinite(i) && (!c.HasNormals() || c.normals[i].allFinite())) {
            keep.push_back(static_cast<Index>(i));
        }
    }
    PointCloud out = SelectByIndex(c, keep);
    out.extra_fields.clear();
    return out;
}

template <typename Reg>
PeerResult RunPcl(Reg& reg, const PointCloud& source, const PointCloud& target,
                  const Eigen::Isometry3d& T_init) {
    const auto s = ToPclXyz(source);
    const auto t = ToPclXyz(target);
    pcl::PointCloud<pcl::PointXYZ> aligned;
    PeerResult r;
    const auto start = Clock::now();
    reg.setInputSource(s);
    reg.setInputTarget(t);
    reg.align(aligned, T_init.matrix().cast<float>());
    r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    r.ran = true;
    r.converged = reg.hasConverged();
    r.T_target_source.matrix() = reg.getFinalTransformation().template cast<double>();
    return r;
}

}  // namespace

const char* PeerName(PeerMethod method) {
    switch (method) {
        case PeerMethod::kPclIcp:
            return "pcl-icp";
        case PeerMethod::kPclGicp:
            return "pcl-gicp";
        case PeerMethod::kPclNdt:
            return "pcl-ndt";
        case PeerMethod::kOpen3dPlane:
            return "o3d-point-to-plane";
        case PeerMethod::kOpen3dColored:
            return "o3d-colored-icp";
        case PeerMethod::kOpen3dFgr:
            return "o3d-fgr";
    }
    return "?";
}

std::vector<PeerMethod> AllPeers() {
    return {PeerMethod::kPclIcp,      PeerMethod::kPclGicp,       PeerMethod::kPclNdt,
            PeerMethod::kOpen3dPlane, PeerMethod::kOpen3dColored, PeerMethod::kOpen3dFgr};
}

bool IsGlobalPeer(PeerMethod method) { return method == PeerMethod::kOpen3dFgr; }

PeerResult RunPeer(PeerMethod method, const PointCloud& source, const PointCloud& target,
                   const Eigen::Isometry3d& T_init, const PeerParams& params) {
    omp_set_num_threads(params.num_threads);
    namespace reg = open3d::pipelines::registration;
    switch (method) {
        case PeerMethod::kPclIcp: {
            pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp;
            icp.setMaxCorrespondenceDistance(params.max_distance);
            icp.setMaximumIterations(params.max_iterations);
            icp.setTransformationEpsilon(1e-10);
            icp.setEuclideanFitnessEpsilon(1e-10);
            return RunPcl(icp, source, target, T_init);
        }
        case PeerMethod::kPclGicp: {
            pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
            gicp.setMaxCorrespondenceDistance(params.max_distance);
            gicp.setMaximumIterations(params.max_iterations);
            gicp.setTransformationEpsilon(1e-10);
            return RunPcl(gicp, source, target, T_init);
        }
        case PeerMethod::kPclNdt: {
            // The tutorial's settings, cells of 5 resolutions.
            pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ> ndt;
            ndt.setTransformationEpsilon(0.01 * params.resolution);
            ndt.setStepSize(10.0 * params.resolution);
            ndt.setResolution(static_cast<float>(5.0 * params.resolution));
            ndt.setMaximumIterations(35);
            return RunPcl(ndt, source, target, T_init);
        }
        case PeerMethod::kOpen3dPlane:
        case PeerMethod::kOpen3dColored:
        case PeerMethod::kOpen3dFgr:
            break;
    }
    PeerResult r;
    if (method == PeerMethod::kOpen3dColored && (!source.HasColors() || !target.HasColors())) {
        r.note = "no colours";
        return r;
    }
    const open3d::geometry::PointCloud s = adapters::ToOpen3d(Usable(source));
    const open3d::geometry::PointCloud t = adapters::ToOpen3d(Usable(target));
    const reg::ICPConvergenceCriteria criteria(1e-6, 1e-6, params.max_iterations);
    const auto start = Clock::now();
    reg::RegistrationResult o;
    if (method == PeerMethod::kOpen3dPlane) {
        o = reg::RegistrationICP(s, t, params.max_distance, T_init.matrix(),
                                 reg::TransformationEstimationPointToPlane(), criteria);
    } else if (method == PeerMethod::kOpen3dColored) {
        o = reg::RegistrationColoredICP(s, t, params.max_distance, T_init.matrix(),
                                        reg::TransformationEstimationForColoredICP(), criteria);
    } else {
        const double radius = 5.0 * params.resolution;
        const auto fs =
            reg::ComputeFPFHFeature(s, open3d::geometry::KDTreeSearchParamHybrid(radius, 100));
        const auto ft =
            reg::ComputeFPFHFeature(t, open3d::geometry::KDTreeSearchParamHybrid(radius, 100));
        o = reg::FastGlobalRegistrationBasedOnFeatureMatching(
            s, t, *fs, *ft,
            reg::FastGlobalRegistrationOption(1.4, false, true, params.max_distance));
    }
    r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    r.ran = true;
    // Open3D has no convergence flag: a result with correspondences counts.
    r.converged = o.fitness_ > 0.0;
    r.T_target_source.matrix() = o.transformation_;
    return r;
}

}  // namespace multicue::peers
