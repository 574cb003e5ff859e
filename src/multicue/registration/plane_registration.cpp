#include "multicue/registration/plane_registration.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <Eigen/LU>
#include <Eigen/SVD>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/core/params.hpp"

namespace multicue {
namespace {

double DegreesToRadians(double deg) { return deg * std::numbers::pi / 180.0; }

struct Hypothesis {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    double plane_score = 0.0;  // points of the source patches it explains
    double point_score = 0.0;  // share of the scored source points that overlap
};

// Source points (support of patches included) moved by each hypothesis and looked up in the
// target tree: the share within `distance`.
double OverlapScore(const PointCloud& source, const Indices& subset, const KdTree& tree,
                    const Eigen::Isometry3d& T, float distance) {
    const Eigen::Isometry3f Tf = T.cast<float>();
    const float limit = distance * distance;
    std::size_t hits = 0;
    Index j = 0;
    float d2 = 0.0f;
    for (Index i : subset) {
        if (tree.SearchNearestWithin(Tf * source.points[i], distance, j, d2) && d2 <= limit) ++hits;
    }
    return subset.empty() ? 0.0 : static_cast<double>(hits) / static_cast<double>(subset.size());
}

bool Similar(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
    const Eigen::Isometry3d d = a.inverse() * b;
    return RotationAngleDeg(d) < 2.0 && TranslationNorm(d) < 0.02;
}

}  // namespace

void PointPlaneParams::Validate() const {
    ValidateNode("icp", [&] { icp.Validate(); });
    ValidateNode("matching", [&] { matching.Validate(); });
    if (icp.method == IcpMethod::kPointToPoint) {
        throw InvalidArgument(
            "point and plane registration needs the point-to-plane or symmetric ICP method");
    }
    if (!(plane_weight >= 0.0) || !std::isfinite(plane_weight)) {
        throw InvalidArgument(fmt::format("plane_weight must be >= 0, got {}", plane_weight));
    }
}

RegistrationResult RegisterPointsAndPlanes(const PointCloud& source, const PointCloud& target,
                                           const KdTree* target_tree,
                                           const std::vector<PlanarPatch>& source_patches,
                                           const std::vector<PlanarPatch>& target_patches,
                                           const PointPlaneParams& params,
                                           const Eigen::Isometry3d& T_init) {
    params.Validate();
    std::size_t matched = 0;
    ExtraTerms planes;
    if (params.plane_weight > 0.0 && !source_patches.empty() && !target_patches.empty()) {
        planes = [&](const Eigen::Isometry3d& T, const Eigen::Vector3d& center, double sampling,
                     Matrix6d& H, Vector6d& g) {
            const auto pairs = MatchPlanes(source_patches, target_patches, T, params.matching);
            matched = pairs.size();
            // The depth-noise weights of the point pairs, at the patches' centroids: a far,
            // coarsely quantised floor must not outweigh the objects through its planes either.
            std::vector<double> weights;
            for (const auto& pair : pairs) {
                const double ds =
                    (source_patches[pair.source].centroid - source.sensor_origin.cast<double>())
                        .norm();
                const double dt =
                    (target_patches[pair.target].centroid - target.sensor_origin.cast<double>())
                        .norm();
                // A pair whose planes are still apart weighs less (Tukey on the offset of the
                // patch's centroid, scale max_offset): a pairing made at a wrong pose fades
                // instead of pulling.
                const PlanarPatch& tp = target_patches[pair.target];
                const double offset =
                    tp.normal.dot(T * source_patches[pair.source].centroid) + tp.d;
                weights.push_back(
                    params.plane_weight * sampling *
                    RobustWeight(RobustKernelType::kTukey, offset, params.matching.max_offset) *
                    DepthNoiseWeight(ds, dt, params.icp.depth_noise, params.icp.noise_floor));
            }
            return AddPlaneTerms(source_patches, target_patches, pairs, weights, T, center, H, g);
        };
    }
    RegistrationResult r = RegisterIcp(source, target, target_tree, params.icp, T_init, planes);
    if (planes) {
        const auto pairs =
            MatchPlanes(source_patches, target_patches, r.T_target_source, params.matching);
        matched = pairs.size();
        r.reason += fmt::format("; {} of {} source planes matched", matched, source_patches.size());
    }
    return r;
}

void PlaneGlobalParams::Validate() const {
    if (!(min_triple_angle_deg > 0.0f && min_triple_angle_deg <= 90.0f)) {
        throw InvalidArgument(
            fmt::format("min_triple_angle_deg must be in (0, 90], got {}", min_triple_angle_deg));
    }
    if (!(angle_tolerance_deg > 0.0f && angle_tolerance_deg <= 45.0f)) {
        throw InvalidArgument(
            fmt::format("angle_tolerance_deg must be in (0, 45], got {}", angle_tolerance_deg));
    }
    ValidateNode("matching", [&] { matching.Validate(); });
    if (max_point_scored < 1 || refine_best < 1) {
        throw InvalidArgument(
            fmt::format("max_point_scored and refine_best must be >= 1, got {} and {}",
                        max_point_scored, refine_best));
    }
    if (score_points < 10) {
        throw InvalidArgument(fmt::format("score_points must be >= 10, got {}", score_points));
    }
    if (!(score_distance > 0.0f) || !std::isfinite(score_distance)) {
        throw InvalidArgument(fmt::format("score_distance must be > 0, got {}", score_distance));
    }
    if (!(min_overlap >= 0.0 && min_overlap <= 1.0)) {
        throw InvalidArgument(fmt::format("min_overlap must be in [0, 1], got {}", min_overlap));
    }
    ValidateNode("refine", [&] { refine.Validate(); });
    if (num_threads < 0) {
        throw InvalidArgument(fmt::format("num_threads must be >= 0, got {}", num_threads));
    }
}

bool TransformFromPlaneTriple(const PlanarPatch* const source[3],
                              const PlanarPatch* const target[3], Eigen::Isometry3d& T) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d A;
    Eigen::Vector3d b;
    for (int k = 0; k < 3; ++k) {
        H.noalias() += source[k]->normal * target[k]->normal.transpose();
        A.row(k) = target[k]->normal.transpose();
        b(k) = source[k]->d - target[k]->d;
    }
    if (std::abs(A.determinant()) < 0.05) return false;
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0) D(2, 2) = -1.0;
    T = Eigen::Isometry3d::Identity();
    T.linear() = svd.matrixV() * D * svd.matrixU().transpose();
    T.translation() = A.partialPivLu().solve(b);
    return T.matrix().allFinite();
}

RegistrationResult RegisterPlanesGlobal(const PointCloud& source, const PointCloud& target,
                                        const KdTree& target_tree,
                                        const std::vector<PlanarPatch>& source_patches,
                                        const std::vector<PlanarPatch>& target_patches,
                                        const PlaneGlobalParams& params) {
    const auto start = std::chrono::steady_clock::now();
    params.Validate();
    RegistrationResult result;
    auto fail = [&](std::string reason) {
        result.status = RegistrationStatus::kNoHypothesis;
        result.converged = false;
        result.reason = std::move(reason);
        result.time_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        return result;
    };
    if (!source.HasFinite() || !target.HasFinite()) {
        result.status = RegistrationStatus::kEmptyInput;
        result.reason = "a cloud has no finite point";
        return result;
    }
    // Triples of mutually non-parallel normals, spanning space (three walls' normals are
    // pairwise apart yet coplanar: the height would be free).
    const double max_cos = std::cos(DegreesToRadians(params.min_triple_angle_deg));
    auto triples = [&](const std::vector<PlanarPatch>& p) {
        std::vector<std::array<std::size_t, 3>> out;
        for (std::size_t i = 0; i < p.size(); ++i)
            for (std::size_t j = i + 1; j < p.size(); ++j) {
                if (std::abs(p[i].normal.dot(p[j].normal)) > max_cos) continue;
                for (std::size_t k = j + 1; k < p.size(); ++k) {
                    if (std::abs(p[i].normal.dot(p[k].normal)) > max_cos ||
                        std::abs(p[j].normal.dot(p[k].normal)) > max_cos) {
                        continue;
                    }
                    Eigen::Matrix3d M;
                    M << p[i].normal, p[j].normal, p[k].normal;
                    if (std::abs(M.determinant()) < 0.25) continue;
                    out.push_back({i, j, k});
                }
            }
        return out;
    };
    const auto target_triples = triples(target_patches);
    const auto source_triples = triples(source_patches);
    if (target_triples.empty() || source_triples.empty()) {
        return fail(fmt::format(
            "fewer than three non-parallel planes ({} source, {} target planar patches)",
            source_patches.size(), target_patches.size()));
    }
    const double tol = DegreesToRadians(params.angle_tolerance_deg);
    auto angle = [](const PlanarPatch& a, const PlanarPatch& b) {
        return std::acos(std::clamp(a.normal.dot(b.normal), -1.0, 1.0));
    };
    static constexpr std::array<std::array<int, 3>, 6> kPermutations = {
        {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
    std::vector<Hypothesis> hypotheses;
    for (const auto& tt : target_triples) {
        const PlanarPatch* const t[3] = {&target_patches[tt[0]], &target_patches[tt[1]],
                                         &target_patches[tt[2]]};
        const double t01 = angle(*t[0], *t[1]), t02 = angle(*t[0], *t[2]),
                     t12 = angle(*t[1], *t[2]);
        for (const auto& st : source_triples) {
            for (const auto& perm : kPermutations) {
                const PlanarPatch* const s[3] = {&source_patches[st[perm[0]]],
                                                 &source_patches[st[perm[1]]],
                                                 &source_patches[st[perm[2]]]};
                if (std::abs(angle(*s[0], *s[1]) - t01) > tol ||
                    std::abs(angle(*s[0], *s[2]) - t02) > tol ||
                    std::abs(angle(*s[1], *s[2]) - t12) > tol) {
                    continue;
                }
                Hypothesis h;
                if (!TransformFromPlaneTriple(s, t, h.T)) continue;
                for (const auto& pair :
                     MatchPlanes(source_patches, target_patches, h.T, params.matching)) {
                    h.plane_score += static_cast<double>(source_patches[pair.source].size());
                }
                hypotheses.push_back(h);
            }
        }
    }
    result.iterations = static_cast<int>(hypotheses.size());
    if (hypotheses.empty()) {
        return fail(
            fmt::format("no triple of source planes matches a triple of target planes "
                        "({} source, {} target triples)",
                        source_triples.size(), target_triples.size()));
    }
    // Stable sorts keep the enumeration order among equal scores: deterministic.
    std::stable_sort(hypotheses.begin(), hypotheses.end(),
                     [](const auto& a, const auto& b) { return a.plane_score > b.plane_score; });
    if (hypotheses.size() > static_cast<std::size_t>(params.max_point_scored)) {
        hypotheses.resize(static_cast<std::size_t>(params.max_point_scored));
    }
    Indices finite;
    for (std::size_t i = 0; i < source.size(); ++i) {
        if (source.IsFinite(i)) finite.push_back(static_cast<Index>(i));
    }
    const Indices scored = EvenSubset(finite, params.score_points);
    ParallelFor(
        hypotheses.size(), params.num_threads,
        [&](std::size_t k) {
            hypotheses[k].point_score =
                OverlapScore(source, scored, target_tree, hypotheses[k].T, params.score_distance);
        },
        4);
    std::stable_sort(hypotheses.begin(), hypotheses.end(),
                     [](const auto& a, const auto& b) { return a.point_score > b.point_score; });

    // Refine the best distinct hypotheses with points and planes; keep the best outcome.
    PointPlaneParams refine = params.refine;
    refine.icp.num_threads = params.num_threads;
    std::vector<Eigen::Isometry3d> tried;
    RegistrationResult best;
    bool have_best = false;
    for (const auto& h : hypotheses) {
        if (static_cast<int>(tried.size()) >= params.refine_best) break;
        if (std::any_of(tried.begin(), tried.end(),
                        [&](const auto& T) { return Similar(T, h.T); })) {
            continue;
        }
        tried.push_back(h.T);
        RegistrationResult r = RegisterPointsAndPlanes(source, target, &target_tree, source_patches,
                                                       target_patches, refine, h.T);
        const bool better = !have_best || (r.converged && !best.converged) ||
                            (r.converged == best.converged && r.overlap > best.overlap);
        if (better) {
            best = std::move(r);
            have_best = true;
        }
    }
    best.iterations = result.iterations;
    if (best.converged && best.overlap < params.min_overlap) {
        best.converged = false;
        best.status = RegistrationStatus::kLowOverlap;
        best.reason =
            fmt::format("best plane hypothesis overlaps {:.3f} of the source, below {:.3f}",
                        best.overlap, params.min_overlap);
    } else {
        best.reason = fmt::format("{} plane hypotheses, best of {} refined: {}", result.iterations,
                                  tried.size(), best.reason);
    }
    best.time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return best;
}

}  // namespace multicue
