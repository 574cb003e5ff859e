// registration_eval views: multi-view categorisation (thesis section 5.3) as `perceive
// --manifest` does it (each frame perceived, object votes fused in 5 mm voxels of the common
// frame), with the exact poses, the drifting odometry and the registered poses. Per-point
// accuracy over the object points with a ground-truth category.

#include <cstdio>

#include "multicue/recognition/geometric_category.hpp"
#include "multicue/registration/incremental_map.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_views.hpp"
#include "registration_eval.hpp"

namespace multicue::eval {
namespace {

struct Count {
    std::size_t right = 0;
    std::size_t total = 0;
    double Accuracy() const { return total == 0 ? 0.0 : static_cast<double>(right) / total; }
};

// Per-point accuracy of the frames' point categories against the scans' `category` field.
Count Score(const std::vector<PointCloud>& frames, const std::vector<PerceiveResult>& results) {
    Count c;
    for (std::size_t f = 0; f < frames.size(); ++f) {
        const ExtraField* truth = frames[f].FindExtraField("category");
        if (truth == nullptr) continue;
        for (std::size_t i = 0; i < frames[f].size(); ++i) {
            const int t = truth->data[i];
            if (t < 1 || t >= static_cast<int>(kNumCategories)) continue;
            ++c.total;
            c.right += results[f].point_categories[i] == t;
        }
    }
    return c;
}

}  // namespace

int RunViews(const RegistrationEvalOptions& o) {
    const RegistrationParams params = EvalParams(o);
    std::printf(
        "registration_eval views: %d scenes (%s, seeds %llu-%llu), %d views each, "
        "odometry noise %.0f mm / %.1f deg per step\n",
        o.scenes, o.scene_mode.c_str(), static_cast<unsigned long long>(o.seed),
        static_cast<unsigned long long>(o.seed + o.scenes - 1), o.views, o.noise_m * 1000,
        o.noise_deg);
    PerceiveParams perceive;
    perceive.num_threads = o.threads;
    const char* names[] = {"single views (no fusion)", "exact poses", "odometry poses",
                           "registered poses"};
    Count total[4];
    double worst_loss = 0.0;
    for (int s = 0; s < o.scenes; ++s) {
        const SimSequence seq = MakeSequence(o, s);
        std::vector<PerceiveResult> single;
        std::vector<const PointCloud*> ptrs;
        for (const auto& f : seq.frames) {
            single.push_back(Perceive(f, perceive));
            ptrs.push_back(&f);
        }
        MapParams mp;
        mp.registration = params;
        mp.registration.method = ParseRegistrationMethod(o.method);
        mp.num_threads = o.threads;
        std::vector<std::optional<Eigen::Isometry3d>> odometry(seq.odometry.begin(),
                                                               seq.odometry.end());
        const auto aligned = AlignFrameSequence(ptrs, odometry, mp);
        std::vector<std::vector<Eigen::Isometry3f>> poses(3);
        for (std::size_t k = 0; k < seq.frames.size(); ++k) {
            poses[0].push_back(seq.truth[k].cast<float>());
            poses[1].push_back(seq.odometry[k].cast<float>());
            poses[2].push_back(aligned[k].T_world_sensor.cast<float>());
        }
        Count scene[4];
        scene[0] = Score(seq.frames, single);
        for (int p = 0; p < 3; ++p) {
            std::vector<PerceiveResult> fused = single;
            FuseViewCategories(ptrs, poses[p], fused, perceive);
            scene[p + 1] = Score(seq.frames, fused);
        }
        for (int p = 0; p < 4; ++p) {
            total[p].right += scene[p].right;
            total[p].total += scene[p].total;
        }
        worst_loss = std::max(worst_loss, scene[1].Accuracy() - scene[3].Accuracy());
        if (o.verbose) {
            std::printf("scene %d: single %.3f exact %.3f odometry %.3f registered %.3f\n", s,
                        scene[0].Accuracy(), scene[1].Accuracy(), scene[2].Accuracy(),
                        scene[3].Accuracy());
        }
    }
    std::printf("| poses | per-point accuracy | object points |\n|---|---|---|\n");
    for (int p = 0; p < 4; ++p) {
        std::printf("| %s | %.4f | %zu |\n", names[p], total[p].Accuracy(), total[p].total);
    }
    std::printf("registered against exact: %+.2f points overall, worst scene %+.2f points\n",
                100.0 * (total[3].Accuracy() - total[1].Accuracy()), -100.0 * worst_loss);
    return 0;
}

}  // namespace multicue::eval
