/// \file bench_features: multicue's feature estimators and, with -DMULTICUE_BENCH_PEERS=ON, PCL
/// 1.13's FPFHEstimation, RSDEstimation and VFHEstimation on the same clouds, normals and radii
/// in the same run. Names: `<feature>/<input>/<library>/threads:<n>` (bench/ratios.py reads them).
///
/// Inputs (from $MULTICUE_DATA, default the shared data folder): `mosd` = the object points
/// (label > 0) of scans/mosd-learn/learn0.pcd on a 3 mm voxel grid, `milk` = scans/milk.pcd,
/// `bunny` = scans/bunny.pcd. Normals are computed once by multicue (2 cm radius, 1.5 cm for the
/// bunny) outside the timing and given to both libraries. Each timed call builds its search
/// structure, as PCL's compute() does (PCL: a sorted pcl::search::KdTree; multicue: its KdTree).
/// VFH and GRSD- run on the whole input as one cluster; PCL's VFHEstimation builds a k-d tree in
/// compute() that VFH never queries, which is part of what calling it costs.

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "multicue/features/features.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/normals.hpp"

#if MULTICUE_BENCH_PEERS
#include <pcl/features/fpfh.h>
#include <pcl/features/fpfh_omp.h>
#include <pcl/features/rsd.h>
#include <pcl/features/vfh.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#endif

namespace {

using namespace multicue;

constexpr float kFpfhRadius = 0.03f;
constexpr float kRsdRadius = 0.02f;

struct Input {
    std::string name;
    std::string file;
    float normal_radius;
};

const std::vector<Input> kInputs = {{"mosd", "scans/mosd-learn/learn0.pcd", 0.02f},
                                    {"milk", "scans/milk.pcd", 0.02f},
                                    {"bunny", "scans/bunny.pcd", 0.015f}};

std::filesystem::path DataDir() {
    const char* env = std::getenv("MULTICUE_DATA");
    return env != nullptr ? env : MULTICUE_DEFAULT_DATA_DIR;
}

// The input with normals, read and prepared once; nullptr (benchmark skipped) if missing.
const PointCloud* Cloud(benchmark::State& state, const Input& input) {
    static std::map<std::string, PointCloud> cache;
    auto found = cache.find(input.name);
    if (found == cache.end()) {
        const auto path = DataDir() / input.file;
        if (!std::filesystem::exists(path)) {
            state.SkipWithError(("missing " + path.string() + " (set MULTICUE_DATA)").c_str());
            return nullptr;
        }
        PointCloud raw = io::ReadPointCloud(path);
        Indices keep;
        for (std::size_t i = 0; i < raw.size(); ++i) {
            if (!raw.IsFinite(i)) continue;
            if (raw.HasLabels() && raw.labels[i] == 0) continue;  // mOSD: objects only
            keep.push_back(static_cast<Index>(i));
        }
        PointCloud c = SelectByIndex(raw, keep);
        // mOSD objects: 180k points at close range; a 3 mm grid keeps the object surfaces at
        // Kinect density for 1 m.
        if (raw.HasLabels()) c = VoxelGrid(c, {.leaf_size = 0.003f});
        const KdTree tree(c);
        SetNormals(c, EstimateNormals(c, tree, {.radius = input.normal_radius}));
        Indices usable;
        for (std::size_t i = 0; i < c.size(); ++i) {
            if (c.normals[i].allFinite()) usable.push_back(static_cast<Index>(i));
        }
        found = cache.emplace(input.name, SelectByIndex(c, usable)).first;
    }
    return &found->second;
}

void Multicue(benchmark::State& state, const Input& input, const std::string& feature) {
    const PointCloud* c = Cloud(state, input);
    if (c == nullptr) return;
    const int threads = static_cast<int>(state.range(0));
    for (auto _ : state) {
        if (feature == "fpfh") {
            const KdTree tree(*c);
            auto f = ComputeFpfh(*c, tree, {.radius = kFpfhRadius, .num_threads = threads});
            benchmark::DoNotOptimize(f.data());
        } else if (feature == "rsd") {
            const KdTree tree(*c);
            auto f = ComputeRsd(*c, tree, {.radius = kRsdRadius, .num_threads = threads});
            benchmark::DoNotOptimize(f.data());
        } else if (feature == "vfh") {
            auto f = ComputeVfh(*c);
            benchmark::DoNotOptimize(f.data());
        } else {
            GrsdParams p;
            p.voxels.rsd.num_threads = threads;
            auto f = ComputeGrsdMinus(*c, p);
            benchmark::DoNotOptimize(f.data());
        }
    }
    state.counters["points"] = static_cast<double>(c->size());
}

#if MULTICUE_BENCH_PEERS
using PclPoint = pcl::PointXYZ;

struct PclInput {
    pcl::PointCloud<PclPoint>::Ptr points;
    pcl::PointCloud<pcl::Normal>::Ptr normals;
};

const PclInput* PclCloud(benchmark::State& state, const Input& input) {
    static std::map<std::string, PclInput> cache;
    auto found = cache.find(input.name);
    if (found == cache.end()) {
        const PointCloud* c = Cloud(state, input);
        if (c == nullptr) return nullptr;
        PclInput in{std::make_shared<pcl::PointCloud<PclPoint>>(),
                    std::make_shared<pcl::PointCloud<pcl::Normal>>()};
        for (std::size_t i = 0; i < c->size(); ++i) {
            in.points->push_back(PclPoint(c->points[i].x(), c->points[i].y(), c->points[i].z()));
            in.normals->push_back(
                pcl::Normal(c->normals[i].x(), c->normals[i].y(), c->normals[i].z()));
        }
        found = cache.emplace(input.name, in).first;
    }
    return &found->second;
}

template <typename Estimator, typename Output>
void RunPcl(Estimator& est, const PclInput& in, double radius) {
    est.setInputCloud(in.points);
    est.setInputNormals(in.normals);
    est.setSearchMethod(std::make_shared<pcl::search::KdTree<PclPoint>>());
    if (radius > 0.0) est.setRadiusSearch(radius);
    pcl::PointCloud<Output> out;
    est.compute(out);
    benchmark::DoNotOptimize(out.points.data());
}

void Pcl(benchmark::State& state, const Input& input, const std::string& feature) {
    const PclInput* in = PclCloud(state, input);
    if (in == nullptr) return;
    const int threads = static_cast<int>(state.range(0));
    for (auto _ : state) {
        if (feature == "fpfh") {
            if (threads == 1) {
                pcl::FPFHEstimation<PclPoint, pcl::Normal, pcl::FPFHSignature33> est;
                RunPcl<decltype(est), pcl::FPFHSignature33>(est, *in, kFpfhRadius);
            } else {
                pcl::FPFHEstimationOMP<PclPoint, pcl::Normal, pcl::FPFHSignature33> est(
                    static_cast<unsigned>(threads));
                RunPcl<decltype(est), pcl::FPFHSignature33>(est, *in, kFpfhRadius);
            }
        } else if (feature == "rsd") {
            pcl::RSDEstimation<PclPoint, pcl::Normal, pcl::PrincipalRadiiRSD> est;
            RunPcl<decltype(est), pcl::PrincipalRadiiRSD>(est, *in, kRsdRadius);
        } else {
            pcl::VFHEstimation<PclPoint, pcl::Normal, pcl::VFHSignature308> est;
            RunPcl<decltype(est), pcl::VFHSignature308>(est, *in, 0.0);
        }
    }
    state.counters["points"] = static_cast<double>(in->points->size());
}
#endif

void Register() {
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    std::vector<int> threads = {1, 2};
    if (cores > 2) threads.push_back(static_cast<int>(cores));
    for (const std::string feature : {"fpfh", "rsd", "vfh", "grsd-minus"}) {
        for (const Input& input : kInputs) {
            auto* b = benchmark::RegisterBenchmark(
                (feature + "/" + input.name + "/multicue").c_str(),
                [feature, input](benchmark::State& s) { Multicue(s, input, feature); });
            for (int t : threads) b->Arg(t);
            b->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);
#if MULTICUE_BENCH_PEERS
            if (feature == "grsd-minus") continue;
            auto* p = benchmark::RegisterBenchmark(
                (feature + "/" + input.name + "/pcl").c_str(),
                [feature, input](benchmark::State& s) { Pcl(s, input, feature); });
            // PCL's RSD and VFH are serial; FPFH has an OpenMP variant.
            if (feature == "fpfh") {
                for (int t : threads) p->Arg(t);
            } else {
                p->Arg(1);
            }
            p->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);
#endif
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    Register();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
