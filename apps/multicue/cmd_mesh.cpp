// `multicue mesh`: optional robust MLS smoothing, then greedy projection triangulation (whole,
// per label, or appended to an existing mesh), written as a PLY mesh with a quality summary.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/ply.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/surface/greedy_triangulation.hpp"
#include "multicue/surface/mesh_quality.hpp"
#include "multicue/surface/mls.hpp"

namespace multicue::cli {
namespace {

struct MeshOptions {
    std::string in, out, append;
    bool smooth = false, plain = false, robust = false, per_label = false;
    float radius = 0.0f, mls_radius = 0.0f, resample = 0.0f, curvature_slope = 0.0f;
    int order = 2;
    GreedyTriangulationParams gp3;
};

/// Median distance from a sample of points to their nearest neighbour [m].
float MedianSpacing(const PointCloud& cloud) {
    const KdTree tree(cloud);
    std::vector<float> d;
    Indices idx;
    std::vector<float> d2;
    const std::size_t step = std::max<std::size_t>(1, cloud.size() / 2000);
    for (std::size_t i = 0; i < cloud.size(); i += step) {
        if (!cloud.IsFinite(i)) continue;
        if (tree.SearchKnn(cloud.points[i], 2, idx, d2) == 2 && d2[1] > 0.0f)
            d.push_back(std::sqrt(d2[1]));
    }
    if (d.empty()) throw DataError("cannot estimate the point spacing: no two distinct points");
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    return d[d.size() / 2];
}

void Run(MeshOptions& o, int threads) {
    if (o.plain && o.robust) throw InvalidArgument("--robust and --plain exclude each other");
    if (io::LowerExtension(o.out) != "ply")
        throw InvalidArgument(fmt::format("--out must be a .ply file, got '{}'", o.out));
    CheckDistinctPaths(o.in, o.out);
    if (o.radius < 0.0f || !std::isfinite(o.radius))
        throw InvalidArgument(fmt::format("--radius must be > 0, got {}", o.radius));
    if (o.mls_radius < 0.0f || !std::isfinite(o.mls_radius))
        throw InvalidArgument(fmt::format("--mls-radius must be > 0, got {}", o.mls_radius));
    o.gp3.num_threads = threads;
    o.gp3.per_label = o.per_label;
    o.gp3.search_radius = o.radius > 0.0f ? o.radius : 1.0f;  // validated before any reading
    o.gp3.Validate();

    TriangleMesh existing;
    if (!o.append.empty()) {
        existing = io::ReadPlyMesh(o.append);
        CheckDistinctPaths(o.in, o.append);
    }
    PointCloud cloud = ReadNonEmptyCloud(o.in);
    if (o.per_label && !cloud.HasLabels())
        throw DataError(fmt::format("{}: --per-label needs a label field", o.in));
    const bool auto_radius = o.radius == 0.0f;
    if (auto_radius) o.radius = 5.0f * MedianSpacing(cloud);

    if (o.smooth) {
        MlsParams mls;
        mls.radius = o.mls_radius > 0.0f ? o.mls_radius : o.radius;
        mls.polynomial_order = o.order;
        mls.resample_step = o.resample;
        mls.curvature_slope = o.curvature_slope;
        mls.plane_fit = o.plain ? MlsPlaneFit::kWeightedLeastSquares : MlsPlaneFit::kWeightedRansac;
        mls.num_threads = threads;
        const KdTree tree(cloud);
        MlsResult r = MovingLeastSquares(cloud, tree, mls);
        std::printf("smoothing (%s MLS, radius %g): %zu points, %zu dropped\n",
                    o.plain ? "plain" : "robust", static_cast<double>(mls.radius), r.cloud.size(),
                    r.dropped);
        if (r.cloud.empty()) throw DataError(fmt::format("{}: no point survived smoothing", o.in));
        cloud = std::move(r.cloud);
        // Resampling changes the density the triangulation must bridge.
        if (auto_radius && o.resample > 0.0f) o.radius = 5.0f * MedianSpacing(cloud);
    }
    if (auto_radius) LogInfo("--radius {} (5 x the median point spacing)", o.radius);
    o.gp3.search_radius = o.radius;

    TriangleMesh mesh;
    if (!o.append.empty()) {
        IncrementalTriangulation inc(existing, o.gp3);
        const auto added = inc.Add(cloud);
        std::printf(
            "appended to %s: %zu new vertices, %zu points already on the surface, %zu new "
            "triangles\n",
            o.append.c_str(), added.new_vertices, added.dropped_overlap, added.new_triangles);
        mesh = inc.mesh();
    } else {
        TriangulationResult r = GreedyProjectionTriangulation(cloud, o.gp3);
        std::printf(
            "triangulated: %zu unconnected points, %zu seeds, %zu gap and %zu hole "
            "triangles\n",
            r.unconnected, r.seeds, r.gap_triangles, r.hole_triangles);
        mesh = std::move(r.mesh);
    }
    const MeshQuality q = EvaluateMesh(mesh);
    std::printf("mesh: %zu vertices, %zu triangles (radius %g)\n", q.vertices, q.triangles,
                static_cast<double>(o.radius));
    std::printf(
        "quality: %zu non-manifold edges, %zu inconsistently oriented edges, %zu boundary "
        "loops, %zu boundary edges, %zu unreferenced vertices\n",
        q.non_manifold_edges, q.inconsistent_edges, q.boundary_loops, q.boundary_edges,
        q.unreferenced_vertices);
    io::WritePlyMesh(o.out, mesh);
}

}  // namespace

void AddMeshCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "mesh",
        "Surface reconstruction: optional robust MLS smoothing, then greedy projection "
        "triangulation (whole, per label, or appended to an existing mesh)");
    auto o = std::make_shared<MeshOptions>();
    cmd->add_option("IN", o->in, "input cloud (.pcd or .ply)")->required();
    cmd->add_option("--out", o->out, "output mesh (.ply)")->required();
    cmd->add_flag("--smooth", o->smooth, "resample the points with MLS before triangulating");
    cmd->add_flag("--robust", o->robust, "MLS with weighted RANSAC planes (default)");
    cmd->add_flag("--plain", o->plain, "MLS with weighted least-squares planes");
    cmd->add_option("--mls-radius", o->mls_radius,
                    "MLS neighbourhood radius [m] (default: --radius)");
    cmd->add_option("--order", o->order, "MLS polynomial order 0..3")->capture_default_str();
    cmd->add_option("--resample", o->resample,
                    "MLS resampling grid step [m] (Eq. 2.1; default: smooth the input points)");
    cmd->add_option("--curvature-slope", o->curvature_slope,
                    "with --resample: finer steps where the curvature is above the mean");
    cmd->add_flag("--per-label", o->per_label, "one mesh per label, built in parallel");
    cmd->add_option("--append", o->append,
                    "existing mesh (.ply) to grow with the input's points (a registered scan)");
    cmd->add_option("--radius", o->radius,
                    "longest edge / search radius [m] (default: 5 x the median point spacing)");
    cmd->add_option("--mu", o->gp3.mu, "neighbourhood = mu x nearest-neighbour distance")
        ->capture_default_str();
    cmd->add_option("--max-neighbors", o->gp3.max_neighbors, "neighbours per point")
        ->capture_default_str();
    cmd->add_option("--min-angle", o->gp3.min_angle_deg, "smallest triangle angle [deg]")
        ->capture_default_str();
    cmd->add_option("--max-angle", o->gp3.max_angle_deg, "largest triangle angle [deg]")
        ->capture_default_str();
    cmd->add_option("--max-surface-angle", o->gp3.max_surface_angle_deg,
                    "largest angle between connected normals [deg]")
        ->capture_default_str();
    cmd->add_option("--fill-holes", o->gp3.max_hole_edges,
                    "close boundary loops with at most this many edges (0 = off)")
        ->capture_default_str();
    cmd->callback([o, &global] { Run(*o, global.threads); });
}

}  // namespace multicue::cli
