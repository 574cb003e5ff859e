// registration_eval sim: pairs, trajectory and global registration on simulated sequences.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include "multicue/registration/incremental_map.hpp"
#include "multicue/registration/plane_registration.hpp"
#include "multicue/registration/planes.hpp"
#include "registration_eval.hpp"

namespace multicue::eval {
namespace {

constexpr double kSuccessDeg = 2.0;
constexpr double kSuccessM = 0.02;

struct Tally {
    Stats rot, trans, ms;
    int pairs = 0;
    int success = 0;
    int claimed = 0;        // reported converged
    int claimed_wrong = 0;  // reported converged but not a success
    int flagged = 0;        // reported not converged

    void Add(const RegistrationResult& r, double rot_err, double trans_err, double wall_ms) {
        ++pairs;
        rot.Add(rot_err);
        trans.Add(trans_err);
        ms.Add(wall_ms);
        const bool ok = rot_err < kSuccessDeg && trans_err < kSuccessM;
        success += ok;
        claimed += r.converged;
        claimed_wrong += r.converged && !ok;
        flagged += !r.converged;
    }
};

void PrintHeader(const char* title) {
    std::printf("\n%s\n", title);
    std::printf(
        "| method | pairs | success | converged but wrong | median rot [deg] | median trans "
        "[mm] | p90 rot / trans | worst rot / trans | median ms |\n|---|---|---|---|---|---|"
        "---|---|---|\n");
}

void PrintRow(const std::string& name, const Tally& t) {
    if (t.pairs == 0) return;
    std::printf("| %s | %d | %.1f %% | %d | %.3f | %.2f | %.2f / %.1f | %.2f / %.1f | %.1f |\n",
                name.c_str(), t.pairs, 100.0 * t.success / t.pairs, t.claimed_wrong, t.rot.Median(),
                1000.0 * t.trans.Median(), t.rot.Quantile(0.9), 1000.0 * t.trans.Quantile(0.9),
                t.rot.Max(), 1000.0 * t.trans.Max(), t.ms.Median());
}

// Whether the two prepared frames share three mutually non-parallel planes under the true pose.
bool SharesThreePlanes(const std::vector<PlanarPatch>& a, const std::vector<PlanarPatch>& b,
                       const Eigen::Isometry3d& T_true, const RegistrationParams& p) {
    const auto pairs = MatchPlanes(a, b, T_true, p.point_plane.matching);
    const double max_cos = std::cos(p.plane_global.min_triple_angle_deg * M_PI / 180.0);
    for (std::size_t i = 0; i < pairs.size(); ++i)
        for (std::size_t j = i + 1; j < pairs.size(); ++j)
            for (std::size_t k = j + 1; k < pairs.size(); ++k) {
                const auto& ni = b[pairs[i].target].normal;
                const auto& nj = b[pairs[j].target].normal;
                const auto& nk = b[pairs[k].target].normal;
                if (std::abs(ni.dot(nj)) > max_cos || std::abs(ni.dot(nk)) > max_cos ||
                    std::abs(nj.dot(nk)) > max_cos) {
                    continue;
                }
                Eigen::Matrix3d M;
                M << ni, nj, nk;
                if (std::abs(M.determinant()) >= 0.25) return true;
            }
    return false;
}

}  // namespace

int RunSim(const RegistrationEvalOptions& o) {
    const RegistrationParams params = EvalParams(o);
    std::printf(
        "registration_eval sim: %d scenes (%s, seeds %llu-%llu), %d views each, odometry "
        "noise %.0f mm / %.1f deg per step, resolution %.3f m, final gate %.3f m, "
        "threads %d\n",
        o.scenes, o.scene_mode.c_str(), static_cast<unsigned long long>(o.seed),
        static_cast<unsigned long long>(o.seed + o.scenes - 1), o.views, o.noise_m * 1000,
        o.noise_deg, o.resolution, params.icp.correspondences.max_distance, o.threads);
    const double fine = params.icp.correspondences.max_distance;
    const double coarse = params.icp.initial_max_distance;
    auto local = MakeMethods(o, params, {"plane", "point-to-plane", "symmetric", "icp", "auto"},
                             {fine, coarse}, false);
    auto global = MakeMethods(o, params, {"global"}, {fine}, true);
    std::map<std::string, Tally> pair_tally, global_tally;
    Tally odometry_pairs;
    Stats seq_rot, seq_trans, odo_rot, odo_trans;
    int seq_frames = 0, seq_in_map = 0, eligible = 0, global_pairs = 0;
    double seq_ms = 0.0;
    for (int s = 0; s < o.scenes; ++s) {
        const SimSequence seq = MakeSequence(o, s);
        std::vector<PointCloud> prepared;
        std::vector<std::vector<PlanarPatch>> patches;
        for (const auto& f : seq.frames) {
            PreprocessParams pre = params.preprocess;
            pre.num_threads = o.threads;
            prepared.push_back(PreprocessForRegistration(f, pre));
            const KdTree tree(prepared.back());
            patches.push_back(ExtractPlanarPatches(prepared.back(), tree, params.planes));
        }
        for (std::size_t k = 0; k + 1 < seq.frames.size(); ++k) {
            const Eigen::Isometry3d T_true = seq.truth[k + 1].inverse() * seq.truth[k];
            const Eigen::Isometry3d guess = seq.odometry[k + 1].inverse() * seq.odometry[k];
            odometry_pairs.Add(RegistrationResult{}, RotationError(T_true, guess),
                               TranslationError(T_true, guess), 0.0);
            for (const auto& m : local) {
                const auto start = std::chrono::steady_clock::now();
                const RegistrationResult r =
                    m.run(prepared[k], prepared[k + 1], &seq.frames[k], &seq.frames[k + 1], guess);
                const double ms = std::chrono::duration<double, std::milli>(
                                      std::chrono::steady_clock::now() - start)
                                      .count();
                const double re = RotationError(T_true, r.T_target_source);
                const double te = TranslationError(T_true, r.T_target_source);
                pair_tally[m.name].Add(r, re, te, ms);
                if (o.verbose) {
                    std::printf("scene %d pair %zu %s: %.3f deg %.1f mm %s %.0f ms %s\n", s, k,
                                m.name.c_str(), re, te * 1000, r.converged ? "conv" : "flag", ms,
                                r.reason.substr(0, 100).c_str());
                }
            }
            if (!SharesThreePlanes(patches[k], patches[k + 1], T_true, params)) continue;
            ++eligible;
            for (const auto& m : global) {
                const auto start = std::chrono::steady_clock::now();
                const RegistrationResult r = m.run(prepared[k], prepared[k + 1], &seq.frames[k],
                                                   &seq.frames[k + 1], std::nullopt);
                const double ms = std::chrono::duration<double, std::milli>(
                                      std::chrono::steady_clock::now() - start)
                                      .count();
                global_tally[m.name].Add(r, RotationError(T_true, r.T_target_source),
                                         TranslationError(T_true, r.T_target_source), ms);
            }
            ++global_pairs;
        }
        // Frame to map from the drifting odometry.
        MapParams mp;
        mp.registration = params;
        mp.registration.method = ParseRegistrationMethod(o.method);
        mp.occupancy.enabled = false;
        mp.mesh.enabled = false;
        mp.num_threads = o.threads;
        IncrementalMap map(mp);
        const auto start = std::chrono::steady_clock::now();
        for (std::size_t k = 0; k < seq.frames.size(); ++k) {
            const auto r = map.AddFrame(seq.frames[k], seq.odometry[k]);
            ++seq_frames;
            seq_in_map += r.in_map;
            if (k == 0) continue;
            seq_rot.Add(RotationError(seq.truth[k], r.T_world_sensor));
            seq_trans.Add(TranslationError(seq.truth[k], r.T_world_sensor));
            odo_rot.Add(RotationError(seq.truth[k], seq.odometry[k]));
            odo_trans.Add(TranslationError(seq.truth[k], seq.odometry[k]));
            if (o.verbose) {
                std::printf(
                    "scene %d frame %zu: %s %.3f deg %.1f mm (odometry %.2f deg %.1f mm) %s\n", s,
                    k, r.in_map ? "in map" : "left out", seq_rot.values.back(),
                    seq_trans.values.back() * 1000, odo_rot.values.back(),
                    odo_trans.values.back() * 1000, r.registration.reason.substr(0, 100).c_str());
            }
        }
        seq_ms +=
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
    }
    PrintHeader("Consecutive pairs from the odometry guess (success: < 2 deg and < 2 cm)");
    PrintRow("odometry guess", odometry_pairs);
    for (const auto& m : local) PrintRow(m.name, pair_tally[m.name]);
    std::printf(
        "\nGlobal registration without a guess: %d of %d pairs share three non-parallel "
        "planes\n",
        eligible, static_cast<int>(pair_tally.begin()->second.pairs));
    PrintHeader("Pairs sharing three or more planes, no initial guess");
    for (const auto& m : global) PrintRow(m.name, global_tally[m.name]);
    auto rmse = [](const Stats& s) {
        double sum = 0.0;
        for (double v : s.values) sum += v * v;
        return s.values.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(s.values.size()));
    };
    std::printf("\nTrajectory, frame to map (%s), %d frames, %d in the map, %.0f ms per frame:\n",
                o.method.c_str(), seq_frames, seq_in_map, seq_ms / std::max(1, seq_frames));
    std::printf(
        "| poses | translation RMSE (ATE) [mm] | median rot [deg] | median trans [mm] | "
        "worst rot [deg] | worst trans [mm] |\n|---|---|---|---|---|---|\n");
    std::printf("| odometry | %.1f | %.2f | %.1f | %.2f | %.1f |\n", 1000 * rmse(odo_trans),
                odo_rot.Median(), 1000 * odo_trans.Median(), odo_rot.Max(), 1000 * odo_trans.Max());
    std::printf("| registered | %.1f | %.3f | %.1f | %.3f | %.1f |\n", 1000 * rmse(seq_trans),
                seq_rot.Median(), 1000 * seq_trans.Median(), seq_rot.Max(), 1000 * seq_trans.Max());
    (void)global_pairs;
    return 0;
}

}  // namespace multicue::eval
