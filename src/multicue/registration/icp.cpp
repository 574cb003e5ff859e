#include "multicue/registration/icp.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue {
namespace {

// Point sums are taken in blocks of this many pairs, whatever the thread count, and the block
// sums are added in order: the result does not depend on the threads.
constexpr std::size_t kBlock = 512;

// RobustWeight, inlined into the per-pair loops.
inline double KernelWeight(RobustKernelType type, double r, double k) {
    const double a = std::abs(r);
    switch (type) {
        case RobustKernelType::kHuber:
            return a <= k ? 1.0 : k / a;
        case RobustKernelType::kTukey: {
            if (a >= k) return 0.0;
            const double u = 1.0 - (a / k) * (a / k);
            return u * u;
        }
        case RobustKernelType::kCauchy:
            return 1.0 / (1.0 + (a / k) * (a / k));
        case RobustKernelType::kNone:
            break;
    }
    return 1.0;
}

// The depth-noise weight of a pair (IcpParams::depth_noise), 1 when it is off.
struct DepthWeights {
    double k = 0.0;   // sigma = k d^2
    double s0 = 0.0;  // noise floor
    Eigen::Vector3f source_origin = Eigen::Vector3f::Zero();
    Eigen::Vector3f target_origin = Eigen::Vector3f::Zero();

    double operator()(const Eigen::Vector3f& p_source, const Eigen::Vector3f& q_target) const {
        if (k <= 0.0) return 1.0;
        return DepthNoiseWeight((p_source - source_origin).norm(),
                                (q_target - target_origin).norm(), k, s0);
    }
};

struct NormalSystem {
    Matrix6d H = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    double cost = 0.0;
};

Indices UsableSource(const PointCloud& source, bool need_normals, std::size_t max_points) {
    Indices subset;
    subset.reserve(source.size());
    for (std::size_t i = 0; i < source.size(); ++i) {
        if (!source.IsFinite(i)) continue;
        if (need_normals && !source.normals[i].allFinite()) continue;
        subset.push_back(static_cast<Index>(i));
    }
    return max_points > 0 ? EvenSubset(subset, max_points) : subset;
}

bool HasFiniteNormal(const PointCloud& cloud, std::size_t i) {
    return cloud.HasNormals() && cloud.normals[i].allFinite();
}

Eigen::Vector3d ResidualNormal(IcpMethod method, const PointCloud& source, const PointCloud& target,
                               const Correspondence& c, const Eigen::Matrix3d& R) {
    Eigen::Vector3d n = target.normals[c.target].cast<double>();
    if (method == IcpMethod::kSymmetric) {
        n += R * source.normals[c.source].cast<double>();
        const double len = n.norm();
        n = len > 1e-9 ? Eigen::Vector3d(n / len) : target.normals[c.target].cast<double>();
    }
    return n;
}

// One Gauss-Newton system of the point-to-plane (or symmetric) residuals about `center`.
NormalSystem PlaneSystem(IcpMethod method, const PointCloud& source, const PointCloud& target,
                         const std::vector<Correspondence>& corr, const Eigen::Isometry3d& T,
                         const Eigen::Vector3d& center, RobustKernelType kernel, double scale,
                         const DepthWeights& depth, int num_threads) {
    const std::size_t blocks = (corr.size() + kBlock - 1) / kBlock;
    std::vector<NormalSystem> partial(blocks);
    const Eigen::Matrix3d R = T.linear();
    ParallelFor(
        blocks, num_threads,
        [&](std::size_t b) {
            NormalSystem s;
            const std::size_t end = std::min(corr.size(), (b + 1) * kBlock);
            for (std::size_t k = b * kBlock; k < end; ++k) {
                const auto& c = corr[k];
                const Eigen::Vector3d p = T * source.points[c.source].cast<double>();
                const Eigen::Vector3d q = target.points[c.target].cast<double>();
                const Eigen::Vector3d n = ResidualNormal(method, source, target, c, R);
                if (!n.allFinite()) continue;  // a target pixel without a normal
                const double r = n.dot(p - q);
                const double w = KernelWeight(kernel, r, scale) *
                                 depth(source.points[c.source], target.points[c.target]);
                if (w <= 0.0) continue;
                Vector6d J;
                J.head<3>() = (p - center).cross(n);
                J.tail<3>() = n;
                const Vector6d wJ = w * J;
                // Upper triangle only: H is symmetric, the lower half is filled below.
                for (int col = 0; col < 6; ++col) {
                    for (int row = 0; row <= col; ++row) s.H(row, col) += wJ(row) * J(col);
                }
                s.g.noalias() += w * r * J;
                s.cost += w * r * r;
            }
            s.H.triangularView<Eigen::StrictlyLower>() = s.H.transpose();
            partial[b] = s;
        },
        1);
    NormalSystem total;
    for (const auto& s : partial) {
        total.H += s.H;
        total.g += s.g;
        total.cost += s.cost;
    }
    return total;
}

// Closed-form point-to-point step: the weighted rigid fit of the moved source to its partners.
bool PointStep(const PointCloud& source, const PointCloud& target,
               const std::vector<Correspondence>& corr, const Eigen::Isometry3d& T,
               RobustKernelType kernel, double scale, const DepthWeights& depth,
               Eigen::Isometry3d& delta) {
    std::vector<Eigen::Vector3d> a(corr.size());
    std::vector<Eigen::Vector3d> b(corr.size());
    std::vector<double> w(corr.size());
    for (std::size_t k = 0; k < corr.size(); ++k) {
        a[k] = T * source.points[corr[k].source].cast<double>();
        b[k] = target.points[corr[k].target].cast<double>();
        w[k] =
            KernelWeight(kernel, std::sqrt(static_cast<double>(corr[k].squared_distance)), scale) *
            depth(source.points[corr[k].source], target.points[corr[k].target]);
    }
    return FitRigidTransform(a, b, w, delta);
}

Eigen::Vector3d Centroid(const PointCloud& source, const std::vector<Correspondence>& corr,
                         const Eigen::Isometry3d& T) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const auto& k : corr) c += source.points[k.source].cast<double>();
    return corr.empty() ? c : Eigen::Vector3d(T * (c / static_cast<double>(corr.size())));
}

// Normals of the target points of the final pairs for the constraint analysis: the target's
// own, else the source's rotated, else a PCA of the partner's neighbourhood in the tree.
ConstraintAnalysis Analyze(const PointCloud& source, const PointCloud& target, const KdTree* tree,
                           const std::vector<Correspondence>& corr, const Eigen::Isometry3d& T) {
    std::vector<Eigen::Vector3d> points;
    std::vector<Eigen::Vector3d> normals;
    points.reserve(corr.size());
    normals.reserve(corr.size());
    Indices nn;
    std::vector<float> d2;
    for (const auto& c : corr) {
        Eigen::Vector3d n;
        if (HasFiniteNormal(target, c.target)) {
            n = target.normals[c.target].cast<double>();
        } else if (HasFiniteNormal(source, c.source)) {
            n = T.linear() * source.normals[c.source].cast<double>();
        } else if (tree != nullptr && tree->SearchKnn(target.points[c.target], 10, nn, d2) >= 3) {
            Eigen::Vector3d mean = Eigen::Vector3d::Zero();
            for (Index j : nn) mean += target.points[j].cast<double>();
            mean /= static_cast<double>(nn.size());
            Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
            for (Index j : nn) {
                const Eigen::Vector3d d = target.points[j].cast<double>() - mean;
                C.noalias() += d * d.transpose();
            }
            n = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C).eigenvectors().col(0);
        } else {
            continue;
        }
        if (!n.allFinite()) continue;
        points.push_back(T * source.points[c.source].cast<double>());
        normals.push_back(n.normalized());
    }
    return AnalyzeConstraints(points, normals);
}

std::string DescribeDirection(const Vector6d& v) {
    const bool rotation = v.head<3>().norm() > v.tail<3>().norm();
    const Eigen::Vector3d d = (rotation ? v.head<3>() : v.tail<3>()).normalized();
    return fmt::format("{} ({:.2f}, {:.2f}, {:.2f})",
                       rotation ? "rotation about" : "translation along", d.x(), d.y(), d.z());
}

}  // namespace

const char* IcpMethodName(IcpMethod method) {
    switch (method) {
        case IcpMethod::kPointToPoint:
            return "point-to-point";
        case IcpMethod::kSymmetric:
            return "symmetric";
        case IcpMethod::kPointToPlane:
            break;
    }
    return "point-to-plane";
}

IcpMethod ParseIcpMethod(const std::string& name) {
    if (name == "point-to-point") return IcpMethod::kPointToPoint;
    if (name == "point-to-plane") return IcpMethod::kPointToPlane;
    if (name == "symmetric") return IcpMethod::kSymmetric;
    throw InvalidArgument(fmt::format(
        "unknown ICP method '{}' (choices: point-to-point, point-to-plane, symmetric)", name));
}

const char* RobustKernelName(RobustKernelType type) {
    switch (type) {
        case RobustKernelType::kHuber:
            return "huber";
        case RobustKernelType::kTukey:
            return "tukey";
        case RobustKernelType::kCauchy:
            return "cauchy";
        case RobustKernelType::kNone:
            break;
    }
    return "none";
}

RobustKernelType ParseRobustKernel(const std::string& name) {
    if (name == "none") return RobustKernelType::kNone;
    if (name == "huber") return RobustKernelType::kHuber;
    if (name == "tukey") return RobustKernelType::kTukey;
    if (name == "cauchy") return RobustKernelType::kCauchy;
    throw InvalidArgument(
        fmt::format("unknown robust kernel '{}' (choices: none, huber, tukey, cauchy)", name));
}

double RobustWeight(RobustKernelType type, double r, double k) { return KernelWeight(type, r, k); }

double DepthNoiseWeight(double d_source, double d_target, double depth_noise, double noise_floor) {
    if (depth_noise <= 0.0) return 1.0;
    const double ss = depth_noise * d_source * d_source;
    const double st = depth_noise * d_target * d_target;
    const double floor2 = 2.0 * noise_floor * noise_floor;
    return floor2 / (floor2 + ss * ss + st * st);
}

void IcpParams::Validate() const {
    correspondences.Validate();
    if (!(kernel_scale >= 0.0f) || !std::isfinite(kernel_scale)) {
        throw InvalidArgument(fmt::format("ICP kernel_scale must be >= 0, got {}", kernel_scale));
    }
    if (!(initial_max_distance >= 0.0f) || !std::isfinite(initial_max_distance)) {
        throw InvalidArgument(
            fmt::format("ICP initial_max_distance must be >= 0, got {}", initial_max_distance));
    }
    if (!(gate_decay > 0.0f && gate_decay < 1.0f)) {
        throw InvalidArgument(fmt::format("ICP gate_decay must be in (0, 1), got {}", gate_decay));
    }
    if (max_iterations < 1) {
        throw InvalidArgument(
            fmt::format("ICP max_iterations must be >= 1, got {}", max_iterations));
    }
    if (!(translation_tolerance > 0.0) || !(rotation_tolerance_deg > 0.0)) {
        throw InvalidArgument(
            fmt::format("ICP tolerances must be > 0, got translation {} and rotation {}",
                        translation_tolerance, rotation_tolerance_deg));
    }
    if (min_correspondences < 3) {
        throw InvalidArgument(
            fmt::format("ICP min_correspondences must be >= 3, got {}", min_correspondences));
    }
    if (!(min_fitness >= 0.0 && min_fitness <= 1.0)) {
        throw InvalidArgument(
            fmt::format("ICP min_fitness must be in [0, 1], got {}", min_fitness));
    }
    if (!(min_condition >= 0.0 && min_condition < 1.0)) {
        throw InvalidArgument(
            fmt::format("ICP min_condition must be in [0, 1), got {}", min_condition));
    }
    if (!(depth_noise >= 0.0f) || !std::isfinite(depth_noise) || !(noise_floor > 0.0f) ||
        !std::isfinite(noise_floor)) {
        throw InvalidArgument(
            fmt::format("ICP depth_noise must be >= 0 and noise_floor > 0, got {} and {}",
                        depth_noise, noise_floor));
    }
    if (!(overlap_distance >= 0.0f) || !std::isfinite(overlap_distance)) {
        throw InvalidArgument(
            fmt::format("ICP overlap_distance must be >= 0, got {}", overlap_distance));
    }
    if (num_threads < 0) {
        throw InvalidArgument(fmt::format("ICP num_threads must be >= 0, got {}", num_threads));
    }
}

RegistrationResult RegisterIcp(const PointCloud& source, const PointCloud& target,
                               const KdTree* target_tree, const IcpParams& params,
                               const Eigen::Isometry3d& T_init, const ExtraTerms& extra_terms) {
    const auto start = std::chrono::steady_clock::now();
    params.Validate();
    if (!T_init.matrix().allFinite()) throw InvalidArgument("ICP initial transform is not finite");
    source.Validate();
    target.Validate();
    const bool gauss_newton = params.method != IcpMethod::kPointToPoint || bool(extra_terms);
    if (gauss_newton && !target.HasNormals()) {
        throw DataError(fmt::format("{} ICP needs target normals (estimate them first)",
                                    IcpMethodName(params.method)));
    }
    if (params.method == IcpMethod::kSymmetric && !source.HasNormals()) {
        throw DataError("symmetric ICP needs source normals (estimate them first)");
    }
    RegistrationResult result;
    result.T_target_source = T_init;
    auto finish = [&](RegistrationStatus status, std::string reason) {
        result.status = status;
        result.converged = status == RegistrationStatus::kConverged;
        result.reason = std::move(reason);
        result.time_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        return result;
    };
    const Indices subset =
        UsableSource(source, params.method == IcpMethod::kSymmetric, params.max_source_points);
    if (subset.empty())
        return finish(RegistrationStatus::kEmptyInput, "source has no usable point");
    if (!target.HasFinite()) {
        return finish(RegistrationStatus::kEmptyInput, "target has no finite point");
    }
    const CorrespondenceSearcher searcher(target, target_tree, params.correspondences);
    const DepthWeights depth{params.depth_noise, params.noise_floor, source.sensor_origin,
                             target.sensor_origin};

    const float final_gate = params.correspondences.max_distance;
    float gate = std::max(final_gate, params.initial_max_distance);
    std::vector<Correspondence> corr;
    Eigen::Isometry3d T = T_init;
    Eigen::Isometry3d T_last = T_init;         // the estimate one iteration ago
    Eigen::Isometry3d T_before_last = T_init;  // and two iterations ago
    bool settled = false;
    bool too_few = false;
    int it = 0;
    const Indices coarse =
        params.coarse_source_points > 0 ? EvenSubset(subset, params.coarse_source_points) : subset;
    // What each point's previous search found: most searches of the later iterations are
    // skipped.
    NearestCache coarse_cache, cache;
    while (it < params.max_iterations) {
        ++it;
        const bool coarse_subset = gate > final_gate && coarse.size() < subset.size();
        searcher.Find(source, coarse_subset ? coarse : subset, T, gate, corr, params.num_threads,
                      coarse_subset ? &coarse_cache : &cache);
        if (corr.size() < params.min_correspondences) {
            too_few = true;
            break;
        }
        const double scale = params.kernel_scale > 0.0f ? params.kernel_scale : gate;
        Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
        if (!gauss_newton) {
            if (!PointStep(source, target, corr, T, params.kernel, scale, depth, delta)) {
                too_few = true;
                break;
            }
        } else {
            const Eigen::Vector3d center = Centroid(source, corr, T);
            NormalSystem s = PlaneSystem(params.method, source, target, corr, T, center,
                                         params.kernel, scale, depth, params.num_threads);
            if (extra_terms) {
                const double sampling = gate > final_gate ? static_cast<double>(coarse.size()) /
                                                                static_cast<double>(subset.size())
                                                          : 1.0;
                s.cost += extra_terms(T, center, sampling, s.H, s.g);
            }
            // A tiny Levenberg term keeps the solve defined in unconstrained directions; the
            // constraint analysis below reports them.
            s.H.diagonal().array() += 1e-9 * std::max(s.H.trace(), 1e-12);
            Vector6d x = s.H.ldlt().solve(-s.g);
            if (!x.allFinite()) break;
            // Trust region: no step moves farther than the gate or turns more than 10 degrees;
            // beyond them the linearisation and the pairs are not to be trusted.
            const double step = std::max(x.tail<3>().norm() / gate,
                                         x.head<3>().norm() / (10.0 * std::numbers::pi / 180.0));
            if (step > 1.0) x /= step;
            Eigen::Isometry3d to_center = Eigen::Isometry3d::Identity();
            to_center.translation() = center;
            delta = to_center * TwistToTransform(x) * to_center.inverse();
        }
        T = delta * T;
        // Re-orthonormalise: hundreds of products of rotations drift from SO(3).
        T.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
        // Settled when the update is below the tolerances, or when the estimate came back to
        // where it was two iterations before: pairs flipping between two sets (few points, a
        // tight gate) make a 2-cycle whose states differ by less than the noise.
        const Eigen::Isometry3d back = T_before_last.inverse() * T;
        const bool small = (RotationAngleDeg(delta) < params.rotation_tolerance_deg &&
                            TranslationNorm(delta) < params.translation_tolerance) ||
                           (it > 2 && RotationAngleDeg(back) < params.rotation_tolerance_deg &&
                            TranslationNorm(back) < params.translation_tolerance);
        T_before_last = T_last;
        T_last = T;
        if (small && gate <= final_gate) {
            settled = true;
            break;
        }
        // Coarse to fine: the gate shrinks once the estimate has settled at the current gate
        // (it moved less than a tenth of the gate), so a far initial guess is first brought
        // within reach, then refined with fewer wrong pairs.
        if (gate > final_gate && (small || TranslationNorm(delta) < 0.1 * gate)) {
            gate = std::max(final_gate, gate * params.gate_decay);
        }
    }
    result.iterations = it;
    if (!T.matrix().allFinite()) {
        result.T_target_source = T_init;
        return finish(RegistrationStatus::kDegenerate, "the estimate became non-finite");
    }
    result.T_target_source = T;

    // Final pairs at the final gate: fitness, RMSE, overlap and the constraint analysis.
    searcher.Find(source, subset, T, final_gate, corr, params.num_threads, &cache);
    const float overlap_distance =
        params.overlap_distance > 0.0f ? params.overlap_distance : 0.5f * final_gate;
    double sum2 = 0.0;
    std::size_t overlapping = 0;
    for (const auto& c : corr) {
        sum2 += c.squared_distance;
        if (c.squared_distance <= overlap_distance * overlap_distance) ++overlapping;
    }
    result.correspondences = corr.size();
    result.fitness = static_cast<double>(corr.size()) / static_cast<double>(subset.size());
    result.overlap = static_cast<double>(overlapping) / static_cast<double>(subset.size());
    result.inlier_rmse = corr.empty() ? 0.0 : std::sqrt(sum2 / static_cast<double>(corr.size()));
    result.constraints = Analyze(source, target, target_tree, corr, T);

    if (too_few || corr.size() < params.min_correspondences) {
        return finish(RegistrationStatus::kTooFewCorrespondences,
                      fmt::format("{} pairs within {:.3g} m, {} needed", corr.size(), final_gate,
                                  params.min_correspondences));
    }
    if (result.fitness < params.min_fitness) {
        return finish(RegistrationStatus::kLowOverlap,
                      fmt::format("fitness {:.3f} below {:.3f}: too little of the source overlaps "
                                  "the target",
                                  result.fitness, params.min_fitness));
    }
    if (result.constraints.condition < params.min_condition) {
        return finish(RegistrationStatus::kDegenerate,
                      fmt::format("condition {:.2e} below {:.2e}: the geometry does not constrain "
                                  "the {}",
                                  result.constraints.condition, params.min_condition,
                                  DescribeDirection(result.constraints.weakest_direction)));
    }
    if (!settled) {
        return finish(RegistrationStatus::kMaxIterations,
                      fmt::format("no convergence in {} iterations", params.max_iterations));
    }
    return finish(RegistrationStatus::kConverged,
                  fmt::format("converged in {} iterations, fitness {:.3f}, RMSE {:.4f} m", it,
                              result.fitness, result.inlier_rmse));
}

RegistrationResult RegisterIcp(const PointCloud& source, const PointCloud& target,
                               const IcpParams& params, const Eigen::Isometry3d& T_init) {
    params.Validate();
    std::optional<KdTree> tree;
    if (CorrespondenceSearcher::NeedsTree(target, params.correspondences) ||
        (params.method == IcpMethod::kPointToPoint && !target.HasNormals())) {
        tree.emplace(target);
    }
    return RegisterIcp(source, target, tree ? &*tree : nullptr, params, T_init);
}

}  // namespace multicue
