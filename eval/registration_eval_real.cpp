// registration_eval real: the real scans without ground truth. Every method registers the same
// preprocessed clouds from the same guess; every result is scored by the same measure
// (EvaluateAlignment: nearest-neighbour inlier RMSE and overlap within two resolutions), and the
// capture sequence by cycle consistency (1->2->3 composed against 1->3 direct). The bunny pair
// also has reference poses: each scan registered to the full-resolution Stanford mesh, where the
// dense target removes the sampling error of a 400-point partner, by several methods (peers
// included) so that no method is scored against its own reference alone.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>

#include "multicue/io/point_cloud_io.hpp"
#include "registration_eval.hpp"

namespace multicue::eval {
namespace {

struct RealPair {
    std::string source, target;
    std::optional<Eigen::Isometry3d> guess;  // nothing: identity for local methods
};

// References for bun0 -> bun4: each scan registered to the full-resolution mesh from the
// identity (bun0 is in the mesh's frame, bun4 about 35 degrees from it) by multicue's symmetric
// and point-to-plane ICP and, with --peers, PCL's ICP and Open3D's point-to-plane ICP (gate 15
// mesh resolutions); a method is left out where either registration fails, all of them when
// the mesh is missing.
std::vector<std::pair<std::string, Eigen::Isometry3d>> BunnyReferences(
    const RegistrationEvalOptions& o) {
    const std::filesystem::path data = DataFolder(o);
    const auto mesh_path = data / "meshes" / "benchmark" / "bun_zipper.ply";
    if (!std::filesystem::exists(mesh_path)) return {};
    const PointCloud mesh = io::ReadPointCloud(mesh_path);
    RegistrationEvalOptions ro = o;
    ro.resolution = SuggestResolution(mesh);
    const RegistrationParams params = RegistrationParams::ForResolution(ro.resolution);
    const PointCloud t = PreprocessForRegistration(mesh, params.preprocess);
    PointCloud scans[2];
    const char* names[2] = {"bun0.pcd", "bun4.pcd"};
    for (int i = 0; i < 2; ++i) {
        scans[i] = PreprocessForRegistration(io::ReadPointCloud(data / "scans" / names[i]),
                                             params.preprocess);
    }
    std::vector<std::pair<std::string, Eigen::Isometry3d>> references;
    for (const auto& m :
         MakeMethods(ro, params, {"symmetric", "point-to-plane"}, {15.0 * ro.resolution}, false)) {
        if (m.name.rfind("multicue", 0) != 0 && m.name != "pcl-icp" &&
            m.name != "o3d-point-to-plane") {
            continue;
        }
        Eigen::Isometry3d to_mesh[2];
        bool converged = true;
        for (int i = 0; i < 2 && converged; ++i) {
            const auto r = m.run(scans[i], t, nullptr, nullptr, Eigen::Isometry3d::Identity());
            converged = r.converged;
            to_mesh[i] = r.T_target_source;
        }
        if (converged) references.emplace_back(m.name, to_mesh[1].inverse() * to_mesh[0]);
    }
    return references;
}

}  // namespace

std::filesystem::path DataFolder(const RegistrationEvalOptions& o) {
    if (!o.data.empty()) return o.data;
    if (const char* env = std::getenv("MULTICUE_DATA")) return env;
    return MULTICUE_SHARED_DATA_DIR;
}

int RunReal(const RegistrationEvalOptions& o) {
    const auto scans = DataFolder(o) / "scans";
    // PCL's NDT tutorial starts room_scan2 -> room_scan1 from this guess.
    Eigen::Isometry3d room = Eigen::Isometry3d::Identity();
    room.linear() = Eigen::AngleAxisd(0.6931, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    room.translation() = Eigen::Vector3d(1.79387, 0.720047, 0.0);
    const std::vector<RealPair> pairs = {{"capture0001", "capture0002", {}},
                                         {"capture0002", "capture0003", {}},
                                         {"capture0003", "capture0004", {}},
                                         {"capture0004", "capture0005", {}},
                                         {"capture0001", "capture0003", {}},
                                         {"room_scan2", "room_scan1", room},
                                         {"bun0", "bun4", {}}};
    std::printf(
        "registration_eval real: %s, threads %d; RMSE and overlap within 2 resolutions "
        "of the target, same measure for every method\n",
        scans.string().c_str(), o.threads);
    std::printf(
        "| pair | resolution | method | converged | inlier RMSE [mm] | overlap | ms |\n"
        "|---|---|---|---|---|---|---|\n");
    // method -> pair name -> transform, for the cycle check.
    std::map<std::string, std::map<std::string, Eigen::Isometry3d>> found;
    std::vector<std::string> order;
    for (const auto& pair : pairs) {
        const auto sp = scans / (pair.source + ".pcd");
        const auto tp = scans / (pair.target + ".pcd");
        if (!std::filesystem::exists(sp) || !std::filesystem::exists(tp)) {
            std::printf("| %s -> %s | skipped: file missing |\n", pair.source.c_str(),
                        pair.target.c_str());
            continue;
        }
        const PointCloud source = io::ReadPointCloud(sp);
        const PointCloud target = io::ReadPointCloud(tp);
        const float r = SuggestResolution(target);
        RegistrationEvalOptions ro = o;
        ro.resolution = r;
        RegistrationParams params = EvalParams(ro);
        // Kinect frames: depth noise grows with the square of the distance.
        if (target.IsOrganized() && o.depth_noise < 0.0f) params.icp.depth_noise = 1.4e-3f;
        PreprocessParams pre = params.preprocess;
        pre.num_threads = o.threads;
        const PointCloud s = PreprocessForRegistration(source, pre);
        const PointCloud t = PreprocessForRegistration(target, pre);
        const KdTree tt(t);
        const double fine = params.icp.correspondences.max_distance;
        auto methods = MakeMethods(
            ro, params, {"auto", "symmetric", "plane", "point-to-plane", "icp", "global"}, {fine},
            false);
        auto globals = MakeMethods(ro, params, {}, {fine}, true);
        methods.insert(methods.end(), globals.begin(), globals.end());
        const std::string name = pair.source + " -> " + pair.target;
        for (const auto& m : methods) {
            const std::optional<Eigen::Isometry3d> guess =
                m.global ? std::nullopt
                         : std::optional<Eigen::Isometry3d>(
                               pair.guess.value_or(Eigen::Isometry3d::Identity()));
            const auto start = std::chrono::steady_clock::now();
            const RegistrationResult res = m.run(s, t, &source, &target, guess);
            const double ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                    .count();
            const AlignmentQuality q =
                EvaluateAlignment(s, tt, res.T_target_source, 2.0 * r, 0, o.threads);
            std::printf("| %s | %.3f | %s | %s | %.2f | %.3f | %.0f |\n", name.c_str(), r,
                        m.name.c_str(), res.converged ? "yes" : "no", 1000.0 * q.inlier_rmse,
                        q.fitness, ms);
            found[m.name][pair.source + ">" + pair.target] = res.T_target_source;
            if (std::find(order.begin(), order.end(), m.name) == order.end())
                order.push_back(m.name);
        }
    }
    const auto references = BunnyReferences(o);
    if (!references.empty()) {
        std::printf(
            "\nbun0 -> bun4 against references from the full-resolution mesh (each scan "
            "registered to bun_zipper.ply by the method of the column): rotation [deg] / "
            "translation [mm]\n| method |");
        for (const auto& r : references) std::printf(" %s reference |", r.first.c_str());
        std::printf("\n|---|");
        for (std::size_t k = 0; k < references.size(); ++k) std::printf("---|");
        std::printf("\n");
        for (const auto& name : order) {
            const auto f = found[name].find("bun0>bun4");
            if (f == found[name].end()) continue;
            std::printf("| %s |", name.c_str());
            for (const auto& r : references) {
                std::printf(" %.3f / %.2f |", RotationError(f->second, r.second),
                            1000.0 * TranslationError(f->second, r.second));
            }
            std::printf("\n");
        }
        std::printf("| (the references against the first) |");
        for (const auto& r : references) {
            std::printf(" %.3f / %.2f |", RotationError(r.second, references.front().second),
                        1000.0 * TranslationError(r.second, references.front().second));
        }
        std::printf("\n");
    }
    std::printf(
        "\nCycle consistency: capture0001 -> 0002 -> 0003 composed against 0001 -> 0003\n"
        "| method | rotation [deg] | translation [mm] |\n|---|---|---|\n");
    for (const auto& name : order) {
        const auto& f = found[name];
        const auto a = f.find("capture0001>capture0002");
        const auto b = f.find("capture0002>capture0003");
        const auto c = f.find("capture0001>capture0003");
        if (a == f.end() || b == f.end() || c == f.end()) continue;
        const Eigen::Isometry3d composed = b->second * a->second;
        std::printf("| %s | %.3f | %.1f |\n", name.c_str(), RotationError(composed, c->second),
                    1000.0 * TranslationError(composed, c->second));
    }
    return 0;
}

}  // namespace multicue::eval
