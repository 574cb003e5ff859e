#pragma once
// Shared parts of registration_eval: options, statistics, simulated sequences, the methods
// compared (multicue's and, with -DMULTICUE_BENCH_PEERS=ON, PCL's and Open3D's).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/registration/register.hpp"
#include "multicue/sim/scene_gen.hpp"

namespace multicue::eval {

struct RegistrationEvalOptions {
    std::string mode = "sim";  // sim, real, views
    std::uint64_t seed = 1;    // first scene seed (scene s uses seed + s)
    int scenes = 3;
    int views = 24;
    std::string scene_mode = "mixed";  // a table scene mode, or "kitchen"
    double noise_m = 0.05;             // odometry noise per step: translation [m] ...
    double noise_deg = 5.0;            // ... and rotation [deg]
    float resolution = 0.01f;          // voxel of the sim evaluations [m]
    // Overrides of the registration parameters (negative: keep ForResolution's).
    float gate = -1.0f;
    float initial_gate = -1.0f;
    float depth_noise = -1.0f;
    float noise_floor = -1.0f;
    double plane_weight = -1.0;
    std::string method = "plane";
    bool peers = false;
    int threads = 1;
    std::string data;  // shared data folder (real mode)
    bool verbose = false;
};

/// Median, quantiles and the worst value of a list.
struct Stats {
    std::vector<double> values;
    void Add(double v) { values.push_back(v); }
    double Quantile(double q) const;
    double Median() const { return Quantile(0.5); }
    double Max() const;
    double Mean() const;
};

/// Registration parameters of the evaluation: ForResolution(resolution) with the overrides.
RegistrationParams EvalParams(const RegistrationEvalOptions& o);

/// A simulated scene and its views: true poses, noisy odometry, the frames.
struct SimSequence {
    sim::Scene scene;
    std::vector<Eigen::Isometry3d> truth;     // T_world_camera per view
    std::vector<Eigen::Isometry3d> odometry;  // drifting: truth of view 0, then noisy steps
    std::vector<PointCloud> frames;           // organized Kinect frames, camera frame
};

/// Scene `index` of the options: the table scene of seed + index and views around it, or for
/// scene_mode "kitchen" a simulated kitchen of the shared articulated models and views of a
/// robot walking along its longest row of units; Kinect frames, and odometry whose every step is
/// the true step times a perturbation of exactly noise_deg about a random axis and noise_m along a
/// random direction.
SimSequence MakeSequence(const RegistrationEvalOptions& o, int index);

/// A perturbation of exactly `deg` about a random axis and `m` along a random direction.
Eigen::Isometry3d RandomPerturbation(std::uint64_t seed, double deg, double m);

/// Rotation [deg] and translation [m] of A^-1 B.
double RotationError(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B);
double TranslationError(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B);

/// One method of the comparison: its name and how it registers prepared clouds (with normals
/// and, for the peers, colours) from a guess (nothing: no guess). The raw frames (null: none)
/// serve multicue's free-space check.
struct Method {
    std::string name;
    bool global = false;  // needs no guess
    std::function<RegistrationResult(const PointCloud& source, const PointCloud& target,
                                     const PointCloud* source_frame, const PointCloud* target_frame,
                                     const std::optional<Eigen::Isometry3d>& guess)>
        run;
};

/// multicue's methods (`names`: plane, point-to-plane, symmetric, icp, global) and, when built
/// with the peers and asked for, PCL's and Open3D's with gates `peer_gates`.
std::vector<Method> MakeMethods(const RegistrationEvalOptions& o, const RegistrationParams& params,
                                const std::vector<std::string>& names,
                                const std::vector<double>& peer_gates, bool peers_global);

/// The shared data folder: --data, else $MULTICUE_DATA, else the configured one.
std::filesystem::path DataFolder(const RegistrationEvalOptions& o);

/// Modes.
int RunSim(const RegistrationEvalOptions& o);
int RunReal(const RegistrationEvalOptions& o);
int RunViews(const RegistrationEvalOptions& o);

}  // namespace multicue::eval
