/// \file bench_mesh: surface reconstruction timings and mesh quality, multicue beside PCL 1.13
/// (GreedyProjectionTriangulation, MovingLeastSquares) and Open3D 0.16 (ball pivoting) when built
/// with -DMULTICUE_BENCH_PEERS=ON. See bench/README.md ("bench_mesh").
///
/// Every library gets the same points with the same normals (multicue PCA, k = 20, computed
/// outside the timing) and the same parameters; search structures are built inside the timed
/// call. `bench_mesh --quality` prints the quality tables instead of timing.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "multicue/io/point_cloud_io.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/greedy_triangulation.hpp"
#include "multicue/surface/mesh_quality.hpp"
#include "multicue/surface/mls.hpp"
#include "multicue/surface/normals.hpp"

#if MULTICUE_BENCH_PEERS
#include <omp.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/gp3.h>
#include <pcl/surface/mls.h>
#endif

namespace multicue::bench {
namespace {

// ------------------------------------------------------------------------------------ inputs

struct Model {
    PointCloud cloud;  ///< finite points with PCA normals
    float spacing = 0.0f;
    float radius = 0.0f;  ///< GP3 search radius and MLS radius
};

std::filesystem::path DataDir() {
    if (const char* env = std::getenv("MULTICUE_DATA")) return env;
    return MULTICUE_DEFAULT_DATA_DIR;
}

float MedianSpacing(const PointCloud& c) {
    const KdTree tree(c);
    std::vector<float> d;
    Indices idx;
    std::vector<float> d2;
    for (std::size_t i = 0; i < c.size(); i += std::max<std::size_t>(1, c.size() / 5000)) {
        if (tree.SearchKnn(c.points[i], 2, idx, d2) == 2) d.push_back(std::sqrt(d2[1]));
    }
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    return d[d.size() / 2];
}

Model Prepare(PointCloud cloud, bool pca) {
    Indices finite;
    for (Index i = 0; i < cloud.size(); ++i)
        if (cloud.IsFinite(i)) finite.push_back(i);
    Model m;
    m.cloud = SelectByIndex(cloud, finite);
    m.cloud.colors.clear();
    m.cloud.intensity.clear();
    m.cloud.confidence.clear();
    m.cloud.extra_fields.clear();
    if (pca) {
        const KdTree tree(m.cloud);
        SetNormals(m.cloud, EstimateNormals(m.cloud, tree, {.k = 20}));
    }
    m.spacing = MedianSpacing(m.cloud);
    m.radius = 5.0f * m.spacing;
    return m;
}

const std::map<std::string, std::string>& ModelFiles() {
    static const std::map<std::string, std::string> files = {
        {"bunny", "meshes/benchmark/bun_zipper.ply"},
        {"parasaurolophus", "meshes/benchmark/parasaurolophus_6700.ply"},
        {"parasaurolophus_28k", "meshes/benchmark/parasaurolophus_low_normals2.ply"},
        {"mosd", "scans/mosd-learn/learn0.pcd"}};
    return files;
}

const Model* GetModel(const std::string& name) {
    static std::map<std::string, std::unique_ptr<Model>> cache;
    auto it = cache.find(name);
    if (it != cache.end()) return it->second.get();
    std::unique_ptr<Model> m;
    if (name.rfind("sphere", 0) == 0) {
        // sphereN: N points on a 10 cm sphere (Fibonacci spiral), exact normals.
        const std::size_t n = std::stoul(name.substr(6));
        PointCloud c;
        const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
        for (std::size_t i = 0; i < n; ++i) {
            const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
            const double r = std::sqrt(std::max(0.0, 1.0 - z * z)), t = golden * i;
            const Eigen::Vector3f d =
                Eigen::Vector3d(r * std::cos(t), r * std::sin(t), z).cast<float>();
            c.points.push_back(0.1f * d);
            c.normals.push_back(d);
        }
        c.SetUnorganized();
        m = std::make_unique<Model>(Prepare(std::move(c), false));
        m->radius = 4.0f * m->spacing;
    } else {
        const auto path = DataDir() / ModelFiles().at(name);
        if (!std::filesystem::exists(path)) return nullptr;
        m = std::make_unique<Model>(Prepare(io::ReadPointCloud(path), true));
    }
    return (cache[name] = std::move(m)).get();
}

GreedyTriangulationParams Gp3Params(const Model& m) {
    return {.search_radius = m.radius, .mu = 2.5f, .max_neighbors = 100, .num_threads = 1};
}

// ----------------------------------------------------------------------------------- peers

#if MULTICUE_BENCH_PEERS
pcl::PointCloud<pcl::PointNormal>::Ptr ToPcl(const PointCloud& c) {
    auto out = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
    out->resize(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        auto& p = (*out)[i];
        p.x = c.points[i].x();
        p.y = c.points[i].y();
        p.z = c.points[i].z();
        p.normal_x = c.normals[i].x();
        p.normal_y = c.normals[i].y();
        p.normal_z = c.normals[i].z();
    }
    return out;
}

std::vector<pcl::Vertices> PclGp3(const pcl::PointCloud<pcl::PointNormal>::Ptr& cloud,
                                  const Model& m) {
    auto tree = std::make_shared<pcl::search::KdTree<pcl::PointNormal>>();
    tree->setInputCloud(cloud);
    pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
    gp3.setSearchRadius(m.radius);
    gp3.setMu(2.5);
    gp3.setMaximumNearestNeighbors(100);
    gp3.setMaximumSurfaceAngle(std::numbers::pi / 4);
    gp3.setMinimumAngle(std::numbers::pi / 18);
    gp3.setMaximumAngle(2 * std::numbers::pi / 3);
    gp3.setNormalConsistency(false);
    gp3.setInputCloud(cloud);
    gp3.setSearchMethod(tree);
    std::vector<pcl::Vertices> polygons;
    gp3.reconstruct(polygons);
    return polygons;
}

std::shared_ptr<open3d::geometry::PointCloud> ToOpen3d(const PointCloud& c) {
    auto out = std::make_shared<open3d::geometry::PointCloud>();
    for (std::size_t i = 0; i < c.size(); ++i) {
        out->points_.push_back(c.points[i].cast<double>());
        out->normals_.push_back(c.normals[i].cast<double>());
    }
    return out;
}

std::vector<double> BallRadii(const Model& m) {
    return {1.0 * m.spacing, 2.0 * m.spacing, 4.0 * m.spacing};
}
#endif

// --------------------------------------------------------------------------------- timings

void Gp3Multicue(benchmark::State& state, const std::string& name) {
    const Model* m = GetModel(name);
    if (m == nullptr) return state.SkipWithError(("missing input " + name).c_str());
    std::size_t tris = 0;
    for (auto _ : state) {
        const TriangulationResult r = GreedyProjectionTriangulation(m->cloud, Gp3Params(*m));
        tris = r.mesh.triangles.size();
        benchmark::DoNotOptimize(tris);
    }
    state.counters["points"] = static_cast<double>(m->cloud.size());
    state.counters["triangles"] = static_cast<double>(tris);
}

void MlsMulticue(benchmark::State& state, const std::string& name, MlsPlaneFit fit) {
    const Model* m = GetModel(name);
    if (m == nullptr) return state.SkipWithError(("missing input " + name).c_str());
    const int threads = static_cast<int>(state.range(0));
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    std::size_t out = 0;
    for (auto _ : state) {
        const KdTree tree(m->cloud);
        const MlsResult r = MovingLeastSquares(
            m->cloud, tree,
            {.radius = m->radius, .polynomial_order = 2, .plane_fit = fit, .num_threads = threads});
        out = r.cloud.size();
        benchmark::DoNotOptimize(out);
    }
    state.counters["out"] = static_cast<double>(out);
}

#if MULTICUE_BENCH_PEERS
void Gp3Pcl(benchmark::State& state, const std::string& name) {
    const Model* m = GetModel(name);
    if (m == nullptr) return state.SkipWithError(("missing input " + name).c_str());
    const auto cloud = ToPcl(m->cloud);
    std::size_t tris = 0;
    for (auto _ : state) {
        tris = PclGp3(cloud, *m).size();
        benchmark::DoNotOptimize(tris);
    }
    state.counters["points"] = static_cast<double>(m->cloud.size());
    state.counters["triangles"] = static_cast<double>(tris);
}

void MlsPcl(benchmark::State& state, const std::string& name) {
    const Model* m = GetModel(name);
    if (m == nullptr) return state.SkipWithError(("missing input " + name).c_str());
    const int threads = static_cast<int>(state.range(0));
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    for (const auto& p : m->cloud.points) cloud->push_back({p.x(), p.y(), p.z()});
    std::size_t out = 0;
    for (auto _ : state) {
        auto tree = std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>();
        pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointNormal> mls;
        mls.setComputeNormals(true);
        mls.setInputCloud(cloud);
        mls.setPolynomialOrder(2);
        mls.setSearchMethod(tree);
        mls.setSearchRadius(m->radius);
        mls.setSqrGaussParam(m->radius * m->radius / 4.0);  // h = radius / 2 as multicue's
        mls.setNumberOfThreads(static_cast<unsigned>(threads));
        pcl::PointCloud<pcl::PointNormal> result;
        mls.process(result);
        out = result.size();
        benchmark::DoNotOptimize(out);
    }
    state.counters["out"] = static_cast<double>(out);
}

void BallPivotingOpen3d(benchmark::State& state, const std::string& name) {
    const Model* m = GetModel(name);
    if (m == nullptr) return state.SkipWithError(("missing input " + name).c_str());
    omp_set_num_threads(1);
    const auto cloud = ToOpen3d(m->cloud);
    std::size_t tris = 0;
    for (auto _ : state) {
        auto mesh =
            open3d::geometry::TriangleMesh::CreateFromPointCloudBallPivoting(*cloud, BallRadii(*m));
        tris = mesh->triangles_.size();
        benchmark::DoNotOptimize(tris);
    }
    state.counters["points"] = static_cast<double>(m->cloud.size());
    state.counters["triangles"] = static_cast<double>(tris);
}
#endif

/// Two overlapping halves of a model (split at the median x, 10 % of the width shared).
void Halves(const Model& m, PointCloud& a, PointCloud& b) {
    std::vector<float> xs;
    for (const auto& p : m.cloud.points) xs.push_back(p.x());
    std::sort(xs.begin(), xs.end());
    const float mid = xs[xs.size() / 2], w = 0.05f * (xs.back() - xs.front());
    Indices ia, ib;
    for (Index i = 0; i < m.cloud.size(); ++i) {
        if (m.cloud.points[i].x() < mid + w) ia.push_back(i);
        if (m.cloud.points[i].x() > mid - w) ib.push_back(i);
    }
    a = SelectByIndex(m.cloud, ia);
    b = SelectByIndex(m.cloud, ib);
}

void Incremental(benchmark::State& state, const std::string& name) {
    const Model* m = GetModel(name);
    if (m == nullptr) return state.SkipWithError(("missing input " + name).c_str());
    PointCloud a, b;
    Halves(*m, a, b);
    IncrementalTriangulation base(Gp3Params(*m));
    base.Add(a);
    const TriangleMesh first = base.mesh();
    std::size_t tris = 0;
    for (auto _ : state) {
        state.PauseTiming();
        IncrementalTriangulation inc(first, Gp3Params(*m));
        state.ResumeTiming();
        tris = inc.Add(b).new_triangles;
        benchmark::DoNotOptimize(tris);
    }
    state.counters["second_half_points"] = static_cast<double>(b.size());
    state.counters["new_triangles"] = static_cast<double>(tris);
}

/// Per-label meshes of a labelled scan (section 2.3.2, Figure 4.5), labels in parallel.
void PerLabel(benchmark::State& state, const std::string& name) {
    const Model* m = GetModel(name);
    if (m == nullptr) return state.SkipWithError(("missing input " + name).c_str());
    if (!m->cloud.HasLabels()) return state.SkipWithError((name + " has no labels").c_str());
    const int threads = static_cast<int>(state.range(0));
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    GreedyTriangulationParams p = Gp3Params(*m);
    p.per_label = true;
    p.num_threads = threads;
    std::size_t tris = 0;
    for (auto _ : state) {
        tris = GreedyProjectionTriangulation(m->cloud, p).mesh.triangles.size();
        benchmark::DoNotOptimize(tris);
    }
    state.counters["triangles"] = static_cast<double>(tris);
}

void RegisterTimings() {
    const std::vector<std::string> models = {"bunny", "parasaurolophus", "parasaurolophus_28k",
                                             "mosd"};
    auto reg = [](const std::string& n, auto fn) {
        benchmark::RegisterBenchmark(n.c_str(), fn)->Unit(benchmark::kMillisecond)->UseRealTime();
    };
    for (const auto& name : models) {
        reg("gp3/" + name + "/multicue", [name](benchmark::State& s) { Gp3Multicue(s, name); });
#if MULTICUE_BENCH_PEERS
        reg("gp3/" + name + "/pcl", [name](benchmark::State& s) { Gp3Pcl(s, name); });
        reg("ball_pivoting/" + name + "/open3d",
            [name](benchmark::State& s) { BallPivotingOpen3d(s, name); });
#endif
    }
    for (int n : {10000, 25000, 50000, 100000, 200000, 400000}) {
        const std::string name = "sphere" + std::to_string(n);
        reg("gp3/" + name + "/multicue", [name](benchmark::State& s) { Gp3Multicue(s, name); });
#if MULTICUE_BENCH_PEERS
        reg("gp3/" + name + "/pcl", [name](benchmark::State& s) { Gp3Pcl(s, name); });
#endif
    }
    for (const std::int64_t t : {1, 2}) {
        benchmark::RegisterBenchmark("gp3_per_label/mosd/multicue",
                                     [](benchmark::State& s) { PerLabel(s, "mosd"); })
            ->Arg(t)
            ->ArgName("threads")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
    }
    for (const auto& name : {std::string("bunny"), std::string("parasaurolophus_28k")}) {
        reg("gp3_append_half/" + name + "/multicue",
            [name](benchmark::State& s) { Incremental(s, name); });
    }
    for (const auto& name : {std::string("bunny"), std::string("mosd")}) {
        const std::vector<int64_t> threads = {1, 2};
        for (auto t : threads) {
            auto add = [&](const std::string& n, auto fn) {
                benchmark::RegisterBenchmark(n.c_str(), fn)
                    ->Arg(t)
                    ->ArgName("threads")
                    ->Unit(benchmark::kMillisecond)
                    ->UseRealTime();
            };
            add("mls/" + name + "/multicue_robust", [name](benchmark::State& s) {
                MlsMulticue(s, name, MlsPlaneFit::kWeightedRansac);
            });
            add("mls/" + name + "/multicue_plain", [name](benchmark::State& s) {
                MlsMulticue(s, name, MlsPlaneFit::kWeightedLeastSquares);
            });
#if MULTICUE_BENCH_PEERS
            add("mls/" + name + "/pcl", [name](benchmark::State& s) { MlsPcl(s, name); });
#endif
        }
    }
}

// ---------------------------------------------------------------------------------- quality

void PrintQuality(const char* model, const char* library, const TriangleMesh& mesh,
                  const PointCloud& reference) {
    const MeshQuality q = EvaluateMesh(mesh);
    const MeshDistance d = DistanceToCloud(mesh, reference);
    std::printf("| %s | %s | %zu | %zu | %zu | %zu | %zu | %zu | %.3g | %.3g |\n", model, library,
                q.vertices, q.triangles, q.unreferenced_vertices, q.non_manifold_edges,
                q.inconsistent_edges, q.boundary_loops, d.mean, d.max);
}

/// MLS quality on synthetic data with a known surface: RMS distance to a 10 cm sphere after
/// smoothing 1 mm noise, and the largest height above the plane z = 0 of surface points lying
/// under a patch of outliers 6 mm above it (Figure 2.4).
void MlsQuality() {
    std::mt19937 rng(3);
    std::normal_distribution<float> g(0.0f, 0.001f);
    PointCloud sphere;
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    const std::size_t n = 20000;
    for (std::size_t i = 0; i < n; ++i) {
        const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z)), t = golden * i;
        const Eigen::Vector3f d =
            Eigen::Vector3d(r * std::cos(t), r * std::sin(t), z).cast<float>();
        sphere.points.push_back(d * (0.1f + g(rng)));
    }
    sphere.SetUnorganized();
    PointCloud plane;
    std::uniform_real_distribution<float> u(-0.001f, 0.001f);
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 40; ++x)
            plane.points.emplace_back(0.005f * x + u(rng), 0.005f * y + u(rng), 0.0f);
    const std::size_t surface = plane.size();
    for (int y = 0; y < 13; ++y)
        for (int x = 0; x < 13; ++x)
            plane.points.emplace_back(0.07f + 0.005f * x + u(rng), 0.07f + 0.005f * y + u(rng),
                                      0.006f + u(rng));
    plane.SetUnorganized();
    plane.sensor_origin = {0.1f, 0.1f, 1.0f};

    auto rms = [](const std::vector<Eigen::Vector3f>& pts) {
        double s = 0.0;
        for (const auto& p : pts) s += std::pow(p.norm() - 0.1, 2);
        return std::sqrt(s / static_cast<double>(pts.size()));
    };
    auto under_patch = [&](const std::vector<Eigen::Vector3f>& pts) {
        float worst = 0.0f;
        for (std::size_t i = 0; i < std::min(pts.size(), surface); ++i) {
            const auto& q = pts[i];
            if (q.x() > 0.065f && q.x() < 0.135f && q.y() > 0.065f && q.y() < 0.135f)
                worst = std::max(worst, std::abs(q.z()));
        }
        return worst;
    };
    std::printf(
        "\n| MLS (radius 2 cm, order 2) | sphere: RMS distance [mm] | plane: max height under the "
        "outlier patch [mm] |\n|---|---|---|\n");
    std::printf("| input | %.3f | 0 |\n", 1000.0 * rms(sphere.points));
    for (const auto fit : {MlsPlaneFit::kWeightedRansac, MlsPlaneFit::kWeightedLeastSquares}) {
        const MlsParams p{.radius = 0.02f, .polynomial_order = 2, .plane_fit = fit};
        const MlsResult rs = MovingLeastSquares(sphere, KdTree(sphere), p);
        const MlsResult rp = MovingLeastSquares(plane, KdTree(plane), p);
        std::printf("| multicue %s | %.3f | %.2f |\n",
                    fit == MlsPlaneFit::kWeightedRansac ? "robust (weighted RANSAC)"
                                                        : "plain (weighted least squares)",
                    1000.0 * rms(rs.cloud.points), 1000.0 * under_patch(rp.cloud.points));
    }
#if MULTICUE_BENCH_PEERS
    auto pcl_mls = [](const PointCloud& c) {
        auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
        for (const auto& p : c.points) cloud->push_back({p.x(), p.y(), p.z()});
        pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointNormal> mls;
        mls.setInputCloud(cloud);
        mls.setPolynomialOrder(2);
        mls.setSearchMethod(std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
        mls.setSearchRadius(0.02);
        mls.setSqrGaussParam(0.0001);
        pcl::PointCloud<pcl::PointNormal> out;
        mls.process(out);
        std::vector<Eigen::Vector3f> pts;
        for (const auto& p : out) pts.emplace_back(p.x, p.y, p.z);
        return pts;
    };
    std::printf("| PCL MovingLeastSquares | %.3f | %.2f |\n", 1000.0 * rms(pcl_mls(sphere)),
                1000.0 * under_patch(pcl_mls(plane)));
#endif
}

int Quality() {
    std::printf(
        "| model | library | vertices | triangles | unconnected | non-manifold edges | "
        "inconsistent edges | boundary loops | mean dist | max dist |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n");
    for (const std::string name :
         {"bunny", "parasaurolophus", "parasaurolophus_28k", "mosd", "sphere100000"}) {
        const Model* m = GetModel(name);
        if (m == nullptr) {
            std::printf("| %s | missing input | | | | | | | | |\n", name.c_str());
            continue;
        }
        const TriangulationResult ours = GreedyProjectionTriangulation(m->cloud, Gp3Params(*m));
        PrintQuality(name.c_str(), "multicue", ours.mesh, m->cloud);
#if MULTICUE_BENCH_PEERS
        TriangleMesh pcl_mesh;
        pcl_mesh.vertices = m->cloud.points;
        for (const auto& poly : PclGp3(ToPcl(m->cloud), *m))
            pcl_mesh.triangles.emplace_back(poly.vertices[0], poly.vertices[1], poly.vertices[2]);
        PrintQuality(name.c_str(), "PCL gp3", pcl_mesh, m->cloud);
        omp_set_num_threads(1);
        const auto bpa = open3d::geometry::TriangleMesh::CreateFromPointCloudBallPivoting(
            *ToOpen3d(m->cloud), BallRadii(*m));
        TriangleMesh o3d_mesh;
        for (const auto& v : bpa->vertices_) o3d_mesh.vertices.push_back(v.cast<float>());
        for (const auto& t : bpa->triangles_)
            o3d_mesh.triangles.emplace_back(static_cast<std::uint32_t>(t.x()),
                                            static_cast<std::uint32_t>(t.y()),
                                            static_cast<std::uint32_t>(t.z()));
        PrintQuality(name.c_str(), "Open3D ball pivoting", o3d_mesh, m->cloud);
#endif
    }
    std::printf("\nsearch radius per model (5 x median spacing; sphere: 4 x): ");
    for (const std::string name : {"bunny", "parasaurolophus", "parasaurolophus_28k", "mosd"})
        if (const Model* m = GetModel(name))
            std::printf("%s %zu points %.4g; ", name.c_str(), m->cloud.size(), m->radius);
    std::printf("\n");
    MlsQuality();
    return 0;
}

}  // namespace
}  // namespace multicue::bench

int main(int argc, char** argv) {
#if MULTICUE_BENCH_PEERS
    // Open3D 0.16 honours omp_set_num_threads only when OMP_NUM_THREADS is set (see main.cpp).
    setenv("OMP_NUM_THREADS", "2", 0);
#endif
    for (int i = 1; i < argc; ++i)
        if (std::strcmp(argv[i], "--quality") == 0) return multicue::bench::Quality();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    multicue::bench::RegisterTimings();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
