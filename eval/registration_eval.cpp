// registration_eval: how accurately multicue registers scans, side by side with PCL 1.13 and
// Open3D 0.16 (with -DMULTICUE_BENCH_PEERS=ON and --peers), on
//   sim   simulated Kinect sequences around table scenes or, with --scene-mode kitchen, along the
//         units of simulated kitchens (20+ views, odometry noise per step):
//         consecutive pairs from the odometry guess (rotation / translation error, success
//         < 2 deg and < 2 cm, wrong results reported as converged), the frame-to-map trajectory
//         against the true poses, and global registration without a guess on the pairs that
//         share three or more non-parallel planes;
//   real  the real scans without ground truth (capture0001-0005, room_scan1/2, bun0/bun4):
//         inlier RMSE and overlap of every pair, cycle consistency 1->2->3 against 1->3;
//   views multi-view categorisation (section 5.3) from exact, odometry and registered poses.
//
//   build/eval/registration_eval sim --seed 1 --scenes 3 [--peers]
//   build/eval/registration_eval real [--data DIR] [--peers]
//   build/eval/registration_eval views --seed 1 --scenes 5
//
// Seeds: parameters were chosen on seeds 1-3 (validation); the figures of docs/registration.md
// are of seeds 101-105 (test), never looked at while choosing.

#include "registration_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "driver_options.hpp"
#include "multicue/registration/incremental_map.hpp"
#include "multicue/registration/plane_registration.hpp"
#include "multicue/sim/kitchen_library.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/sensors.hpp"

#if MULTICUE_BENCH_PEERS
#include "registration_peers.hpp"
#endif

namespace multicue::eval {

double Stats::Quantile(double q) const {
    if (values.empty()) return 0.0;
    std::vector<double> v = values;
    std::sort(v.begin(), v.end());
    const auto k =
        static_cast<std::size_t>(std::min<double>(v.size() - 1, std::floor(q * v.size())));
    return v[k];
}
double Stats::Max() const {
    return values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
}
double Stats::Mean() const {
    double s = 0.0;
    for (double v : values) s += v;
    return values.empty() ? 0.0 : s / static_cast<double>(values.size());
}

RegistrationParams EvalParams(const RegistrationEvalOptions& o) {
    RegistrationParams p = RegistrationParams::ForResolution(o.resolution);
    if (o.gate > 0.0f) p.icp.correspondences.max_distance = o.gate;
    if (o.initial_gate >= 0.0f) p.icp.initial_max_distance = o.initial_gate;
    if (o.depth_noise >= 0.0f) p.icp.depth_noise = o.depth_noise;
    if (o.noise_floor > 0.0f) p.icp.noise_floor = o.noise_floor;
    if (o.plane_weight >= 0.0) p.point_plane.plane_weight = o.plane_weight;
    p.num_threads = o.threads;
    return p;
}

Eigen::Isometry3d RandomPerturbation(std::uint64_t seed, double deg, double m) {
    sim::StreamRng rng(seed);
    auto unit = [&] {
        // Uniform on the sphere: z uniform in [-1, 1], azimuth uniform.
        const double z = rng.Uniform(-1.0, 1.0);
        const double a = rng.Uniform(0.0, 2.0 * std::numbers::pi);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        return Eigen::Vector3d(r * std::cos(a), r * std::sin(a), z);
    };
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(deg * std::numbers::pi / 180.0, unit()).toRotationMatrix();
    T.translation() = m * unit();
    return T;
}

double RotationError(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B) {
    return RotationAngleDeg(A.inverse() * B);
}
double TranslationError(const Eigen::Isometry3d& A, const Eigen::Isometry3d& B) {
    return TranslationNorm(A.inverse() * B);
}

namespace {

// A robot's head walking along the longest row of units of a kitchen, 1.5 m high, looking at the
// units 2-2.8 m away (clear of the other rows, as sim::KitchenCameraPoses stands), its gaze
// swinging 0.4 m left and right of straight ahead.
std::vector<Eigen::Isometry3f> KitchenWalk(const sim::KitchenScene& kitchen, int views,
                                           std::uint64_t seed) {
    if (kitchen.runs.empty()) throw std::runtime_error("the kitchen has no row of units");
    const auto& run = *std::max_element(
        kitchen.runs.begin(), kitchen.runs.end(),
        [](const auto& a, const auto& b) { return a.end - a.begin < b.end - b.begin; });
    sim::StreamRng rng(seed, 17);
    const Eigen::Vector3f& n = run.normal;
    const float depth = std::abs(n.x()) > 0.5f ? kitchen.size.x() : kitchen.size.y();
    const float dist = std::min(2.8f, depth - 0.95f) - static_cast<float>(rng.Uniform(0.0, 0.15));
    const float first = run.begin + 0.3f, last = std::max(first, run.end - 0.3f);
    std::vector<Eigen::Isometry3f> poses;
    for (int k = 0; k < views; ++k) {
        const float t = static_cast<float>(k) / static_cast<float>(std::max(1, views - 1));
        const float along = first + (last - first) * t;
        Eigen::Vector3f eye = run.origin + run.tangent * along + n * dist;
        for (const auto& other : kitchen.runs) {
            const float clear = std::max(other.depth, 0.85f) + 0.3f;
            const float d = other.normal.dot(eye - other.origin);
            if (d < clear) eye += other.normal * (clear - d);
        }
        eye.x() = std::clamp(eye.x(), 0.3f, kitchen.size.x() - 0.3f);
        eye.y() = std::clamp(eye.y(), 0.3f, kitchen.size.y() - 0.3f);
        eye.z() = 1.5f;
        const float swing = 0.4f * std::sin(3.0f * std::numbers::pi_v<float> * t);
        Eigen::Vector3f target = run.origin + run.tangent * (along + swing) + n * 0.5f;
        target.z() = 0.95f;
        poses.push_back(sim::LookAt(eye, target));
    }
    return poses;
}

}  // namespace

SimSequence MakeSequence(const RegistrationEvalOptions& o, int index) {
    const std::uint64_t seed = o.seed + static_cast<std::uint64_t>(index);
    SimSequence s;
    std::vector<Eigen::Isometry3f> views;
    if (o.scene_mode == "kitchen") {
        static const auto library = sim::ReadKitchenLibrary(DataFolder(o) / "meshes" / "kitchen");
        static sim::KitchenModelCache cache;
        const sim::KitchenScene kitchen = sim::MakeKitchenScene(library, cache, {}, seed);
        s.scene = kitchen.scene;
        views = KitchenWalk(kitchen, o.views, seed);
    } else {
        const auto mode = sim::ParseTableSceneMode(o.scene_mode);
        s.scene = sim::MakeTableScene(sim::TableSceneParamsFor(mode), seed);
        views = sim::TableViewpoints(s.scene, o.views, sim::TableViewpointParamsFor(mode), seed);
    }
    const sim::RayCaster caster(s.scene);
    sim::KinectParams kinect;
    kinect.num_threads = o.threads;
    for (std::size_t k = 0; k < views.size(); ++k) {
        s.truth.push_back(views[k].cast<double>());
        s.frames.push_back(sim::ScanKinect(caster, views[k], kinect, sim::SubSeed(seed, 1000 + k)));
        if (k == 0) {
            s.odometry.push_back(s.truth[0]);
        } else {
            const Eigen::Isometry3d step = s.truth[k - 1].inverse() * s.truth[k];
            s.odometry.push_back(
                s.odometry.back() * step *
                RandomPerturbation(sim::SubSeed(seed, 5000 + k), o.noise_deg, o.noise_m));
        }
    }
    return s;
}

std::vector<Method> MakeMethods(const RegistrationEvalOptions& o, const RegistrationParams& params,
                                const std::vector<std::string>& names,
                                const std::vector<double>& peer_gates, bool peers_global) {
    std::vector<Method> methods;
    for (const auto& name : names) {
        RegistrationParams p = params;
        p.method = ParseRegistrationMethod(name);
        Method m;
        m.name = "multicue " + name;
        m.global = p.method == RegistrationMethod::kGlobal;
        m.run = [p](const PointCloud& s, const PointCloud& t, const PointCloud* s_frame,
                    const PointCloud* t_frame, const std::optional<Eigen::Isometry3d>& guess) {
            const KdTree tt(t);
            return RegisterPrepared(s, nullptr, t, tt, p, guess, s_frame, t_frame);
        };
        methods.push_back(std::move(m));
    }
#if MULTICUE_BENCH_PEERS
    if (o.peers) {
        for (const auto peer : peers::AllPeers()) {
            if (peers::IsGlobalPeer(peer) != peers_global) continue;
            const std::vector<double> gates =
                peers::IsGlobalPeer(peer) ? std::vector<double>{peer_gates.front()} : peer_gates;
            for (double gate : gates) {
                peers::PeerParams pp;
                pp.max_distance = gate;
                pp.resolution = o.resolution;
                pp.num_threads = std::max(1, o.threads);
                Method m;
                m.name = std::string(peers::PeerName(peer));
                if (gates.size() > 1)
                    m.name += " (gate " + std::to_string(int(gate * 100 + 0.5)) + " cm)";
                m.global = peers::IsGlobalPeer(peer);
                m.run = [peer, pp](const PointCloud& s, const PointCloud& t, const PointCloud*,
                                   const PointCloud*,
                                   const std::optional<Eigen::Isometry3d>& guess) {
                    const auto pr = peers::RunPeer(
                        peer, s, t, guess.value_or(Eigen::Isometry3d::Identity()), pp);
                    RegistrationResult r;
                    r.T_target_source = pr.T_target_source;
                    r.converged = pr.ran && pr.converged;
                    r.reason = pr.note;
                    r.status =
                        pr.ran ? RegistrationStatus::kConverged : RegistrationStatus::kEmptyInput;
                    r.time_ms = pr.time_ms;
                    return r;
                };
                methods.push_back(std::move(m));
            }
        }
    }
#else
    (void)o;
    (void)peer_gates;
    (void)peers_global;
#endif
    return methods;
}

}  // namespace multicue::eval

int main(int argc, char** argv) {
    using namespace multicue;
    eval::RegistrationEvalOptions o;
    CLI::App app{"registration_eval: registration accuracy on simulated and real scans"};
    app.add_option("MODE", o.mode, "sim, real or views")
        ->check(CLI::IsMember({"sim", "real", "views"}))
        ->capture_default_str();
    app.add_option("--seed", o.seed, "first scene seed (scene s: seed + s)")->capture_default_str();
    app.add_option("--scenes", o.scenes, "simulated scenes")
        ->capture_default_str()
        ->check(CLI::Range(1, 1000));
    app.add_option("--views", o.views, "views per scene")
        ->capture_default_str()
        ->check(CLI::Range(2, 200));
    app.add_option("--scene-mode", o.scene_mode,
                   "table scene mode (boxes, mixed, cylindric, ...) or kitchen")
        ->capture_default_str();
    app.add_option("--noise-m", o.noise_m, "odometry noise per step: translation [m]")
        ->capture_default_str();
    app.add_option("--noise-deg", o.noise_deg, "odometry noise per step: rotation [deg]")
        ->capture_default_str();
    app.add_option("--resolution", o.resolution, "voxel of the simulated evaluations [m]")
        ->capture_default_str();
    app.add_option("--gate", o.gate, "final correspondence gate [m] (default 3 resolutions)");
    app.add_option("--initial-gate", o.initial_gate, "initial gate [m] (default 15 resolutions)");
    app.add_option("--depth-noise", o.depth_noise, "ICP depth noise coefficient [1/m]");
    app.add_option("--noise-floor", o.noise_floor, "ICP noise floor [m]");
    app.add_option("--plane-weight", o.plane_weight, "weight of a plane point against a pair");
    app.add_option("--method", o.method,
                   "multicue method of the sequence (plane, point-to-plane, ...)")
        ->capture_default_str();
    app.add_flag(
        "--peers", o.peers,
        "run PCL's and Open3D's registration too (needs a build with -DMULTICUE_BENCH_PEERS=ON)");
    app.add_option("-j,--threads", o.threads, "threads (1: single-threaded timings)")
        ->capture_default_str()
        ->check(CLI::Range(0, 1024));
    app.add_option("--data", o.data,
                   "shared data folder (real mode; default $MULTICUE_DATA or the configured one)");
    app.add_flag("-v,--verbose", o.verbose, "one line per pair and frame");
    if (auto code = multicue::eval::ParseDriverOptions(app, "registration_eval", [&] {
            app.parse(argc, argv);
#if !MULTICUE_BENCH_PEERS
            if (o.peers)
                throw CLI::ValidationError(
                    "--peers",
                    "this build has no peers (configure with -DMULTICUE_BENCH_PEERS=ON)");
#endif
        })) {
        return *code;
    }
    try {
        if (o.mode == "sim") return eval::RunSim(o);
        if (o.mode == "real") return eval::RunReal(o);
        return eval::RunViews(o);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "registration_eval: %s\n", e.what());
        return 1;
    }
}
