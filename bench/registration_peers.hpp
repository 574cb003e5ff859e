#pragma once
/// \file The peers of multicue's registration, for the benchmark (bench_registration) and the
/// accuracy driver (registration_eval): PCL 1.13's ICP, GICP and NDT and Open3D 0.16's
/// point-to-plane ICP, coloured ICP and fast global registration (FGR), each run on multicue's
/// preprocessed clouds (same points, same normals) with the same gates. Built only with
/// -DMULTICUE_BENCH_PEERS=ON; never part of the library.

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"

namespace multicue::peers {

enum class PeerMethod {
    kPclIcp,         ///< pcl::IterativeClosestPoint (point-to-point, SVD)
    kPclGicp,        ///< pcl::GeneralizedIterativeClosestPoint
    kPclNdt,         ///< pcl::NormalDistributionsTransform
    kOpen3dPlane,    ///< open3d RegistrationICP with TransformationEstimationPointToPlane
    kOpen3dColored,  ///< open3d RegistrationColoredICP (needs colours)
    kOpen3dFgr,      ///< open3d FastGlobalRegistrationBasedOnFeatureMatching on FPFH
};

/// "pcl-icp", "pcl-gicp", "pcl-ndt", "o3d-point-to-plane", "o3d-colored-icp", "o3d-fgr".
const char* PeerName(PeerMethod method);
/// Every peer, in the order above.
std::vector<PeerMethod> AllPeers();
/// True for the peers that need no initial guess (FGR).
bool IsGlobalPeer(PeerMethod method);

struct PeerParams {
    double max_distance = 0.03;  ///< correspondence gate [m] (FGR: its maximum distance)
    int max_iterations = 60;     ///< ICP iterations (NDT: 35 as its tutorial)
    double resolution = 0.01;    ///< NDT cell size / 5, FPFH radius / 5 for FGR [m]
    int num_threads = 1;         ///< OpenMP threads of the peers that use them
};

struct PeerResult {
    Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
    bool ran = false;        ///< false when the peer cannot run on this input (no colours)
    bool converged = false;  ///< the peer's own convergence flag
    double time_ms = 0.0;    ///< wall time of the call, conversions excluded [ms]
    std::string note;        ///< why it did not run
};

/// Runs `method` on clouds with normals (colours for coloured ICP) from `T_init` (ignored by FGR).
PeerResult RunPeer(PeerMethod method, const PointCloud& source, const PointCloud& target,
                   const Eigen::Isometry3d& T_init, const PeerParams& params);

}  // namespace multicue::peers
