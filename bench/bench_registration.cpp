/// \file bench_registration: multicue's registration and, with -DMULTICUE_BENCH_PEERS=ON, PCL
/// 1.13's ICP, GICP and NDT and Open3D 0.16's point-to-plane ICP, coloured ICP and FGR on the same
/// preprocessed clouds (same points, same normals) from the same initial guess, in the same run.
/// Names: `registration/<input>/<method>/threads:<n>`.
///
/// Inputs (from $MULTICUE_DATA, default the shared data folder; the simulated pair needs none):
///   capture  scans/capture0002.pcd -> capture0001.pcd, 1.3 cm voxels, guess identity
///   bunny    scans/bun4.pcd -> bun0.pcd, every point, guess identity (the PCL tutorial's pair)
///   room     scans/room_scan2.pcd -> room_scan1.pcd, 11 cm voxels, guess of PCL's NDT tutorial
///   sim      two simulated Kinect views 15 degrees apart around a table (seed 1), 1 cm voxels,
///            guess = truth perturbed by 5 degrees and 5 cm
/// Every method builds its search structures inside the timed call. Counters: `rmse_mm` and
/// `overlap` of the result under one measure (nearest neighbours within 2 voxels of the target,
/// EvaluateAlignment), and for `sim` the rotation / translation error against the truth
/// (`rot_deg`, `trans_mm`), so that speed and accuracy come from the same run.

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "multicue/io/point_cloud_io.hpp"
#include "multicue/registration/register.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"

#if MULTICUE_BENCH_PEERS
#include "registration_peers.hpp"
#endif

namespace {

using namespace multicue;

struct Pair {
    PointCloud source, target;              // preprocessed
    PointCloud source_frame, target_frame;  // raw
    RegistrationParams params;
    Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
    std::optional<Eigen::Isometry3d> truth;
    float resolution = 0.01f;
    std::unique_ptr<KdTree> target_tree;  // for the accuracy counters only
};

std::filesystem::path DataDir() {
    const char* env = std::getenv("MULTICUE_DATA");
    return env != nullptr ? env : MULTICUE_DEFAULT_DATA_DIR;
}

void Prepare(Pair& p) {
    p.source = PreprocessForRegistration(p.source_frame, p.params.preprocess);
    p.target = PreprocessForRegistration(p.target_frame, p.params.preprocess);
    p.target_tree = std::make_unique<KdTree>(p.target);
}

Pair FilePair(const std::string& source, const std::string& target, float resolution) {
    Pair p;
    p.source_frame = io::ReadPointCloud(DataDir() / "scans" / source);
    p.target_frame = io::ReadPointCloud(DataDir() / "scans" / target);
    p.resolution = resolution;
    p.params = RegistrationParams::ForResolution(resolution);
    if (EstimatePinhole(p.target_frame)) p.params.icp.depth_noise = 1.4e-3f;
    return p;
}

Pair SimPair() {
    const sim::Scene scene =
        sim::MakeTableScene(sim::TableSceneParamsFor(sim::TableSceneMode::kMixed), 1);
    const auto views = sim::TableViewpoints(scene, 24, {}, 1);
    const sim::RayCaster caster(scene);
    Pair p;
    p.source_frame = sim::ScanKinect(caster, views[0], {}, 11);
    p.target_frame = sim::ScanKinect(caster, views[1], {}, 12);
    p.truth = (views[1].inverse() * views[0]).cast<double>();
    Eigen::Isometry3d noise = Eigen::Isometry3d::Identity();
    noise.linear() = Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d(1, 1, 1).normalized())
                         .toRotationMatrix();
    noise.translation() = Eigen::Vector3d(0.05, 0.0, 0.0);
    p.guess = *p.truth * noise;
    p.params = RegistrationParams::ForResolution(0.01f);
    p.params.icp.depth_noise = 1.4e-3f;
    return p;
}

// The inputs, prepared once; nullptr when a file is missing.
const Pair* GetPair(benchmark::State& state, const std::string& name) {
    static std::map<std::string, std::unique_ptr<Pair>> cache;
    auto found = cache.find(name);
    if (found == cache.end()) {
        std::unique_ptr<Pair> p;
        try {
            if (name == "capture") {
                p = std::make_unique<Pair>(FilePair("capture0002.pcd", "capture0001.pcd", 0.013f));
            } else if (name == "bunny") {
                p = std::make_unique<Pair>(FilePair("bun4.pcd", "bun0.pcd", 0.0062f));
                p->params.preprocess.voxel_size = 0.0f;
            } else if (name == "room") {
                p = std::make_unique<Pair>(FilePair("room_scan2.pcd", "room_scan1.pcd", 0.11f));
                p->guess.linear() =
                    Eigen::AngleAxisd(0.6931, Eigen::Vector3d::UnitZ()).toRotationMatrix();
                p->guess.translation() = Eigen::Vector3d(1.79387, 0.720047, 0.0);
            } else {
                p = std::make_unique<Pair>(SimPair());
            }
            Prepare(*p);
        } catch (const std::exception& e) {
            state.SkipWithError(e.what());
            return nullptr;
        }
        found = cache.emplace(name, std::move(p)).first;
    }
    return found->second.get();
}

using Run = std::function<Eigen::Isometry3d(const Pair&, int threads)>;

void Time(benchmark::State& state, const std::string& input, const Run& run) {
    const Pair* p = GetPair(state, input);
    if (p == nullptr) return;
    const int threads = static_cast<int>(state.range(0));
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (auto _ : state) {
        T = run(*p, threads);
        benchmark::DoNotOptimize(T);
    }
    const auto q = EvaluateAlignment(p->source, *p->target_tree, T, 2.0 * p->resolution, 0, 0);
    state.counters["rmse_mm"] = 1000.0 * q.inlier_rmse;
    state.counters["overlap"] = q.fitness;
    if (p->truth) {
        state.counters["rot_deg"] = RotationAngleDeg(p->truth->inverse() * T);
        state.counters["trans_mm"] = 1000.0 * TranslationNorm(p->truth->inverse() * T);
    }
}

Run Multicue(RegistrationMethod method) {
    return [method](const Pair& p, int threads) {
        RegistrationParams params = p.params;
        params.method = method;
        params.num_threads = threads;
        const KdTree tt(p.target);  // the source's tree is built inside where needed
        const bool global = method == RegistrationMethod::kGlobal;
        return RegisterPrepared(p.source, nullptr, p.target, tt, params,
                                global ? std::nullopt : std::optional(p.guess), &p.source_frame,
                                &p.target_frame)
            .T_target_source;
    };
}

void RegisterAll() {
    std::vector<int> threads = {1};
    const int cores = static_cast<int>(std::thread::hardware_concurrency());
    if (cores > 1) threads.push_back(cores);
    std::vector<std::pair<std::string, Run>> methods = {
        {"multicue-symmetric", Multicue(RegistrationMethod::kSymmetric)},
        {"multicue-point-to-plane", Multicue(RegistrationMethod::kPointToPlane)},
        {"multicue-plane", Multicue(RegistrationMethod::kPlane)},
        {"multicue-icp", Multicue(RegistrationMethod::kIcp)},
        {"multicue-global", Multicue(RegistrationMethod::kGlobal)},
    };
#if MULTICUE_BENCH_PEERS
    for (const auto peer : peers::AllPeers()) {
        methods.emplace_back(peers::PeerName(peer), [peer](const Pair& p, int n) {
            peers::PeerParams pp;
            pp.max_distance = p.params.icp.correspondences.max_distance;
            pp.resolution = p.resolution;
            pp.num_threads = n;
            return peers::RunPeer(peer, p.source, p.target, p.guess, pp).T_target_source;
        });
    }
#endif
    for (const std::string input : {"sim", "capture", "bunny", "room"}) {
        for (const auto& [name, run] : methods) {
            auto* b = benchmark::RegisterBenchmark(
                ("registration/" + input + "/" + name).c_str(),
                [input, run = run](benchmark::State& s) { Time(s, input, run); });
            for (int n : threads) b->Arg(n);
            b->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    RegisterAll();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
