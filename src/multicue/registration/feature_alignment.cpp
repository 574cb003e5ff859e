#include "multicue/registration/feature_alignment.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/core/params.hpp"
#include "multicue/features/pfh.hpp"

namespace multicue {
namespace {

constexpr std::size_t kNoMatch = std::numeric_limits<std::size_t>::max();

// SplitMix64: the k-th sample's numbers depend on (seed, k) only.
std::uint64_t Mix(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

void CheckMatches(const PointCloud& source, const PointCloud& target, const PointMatches& m) {
    if (m.source.size() != m.target.size()) {
        throw InvalidArgument(fmt::format("matches: {} source and {} target indices",
                                          m.source.size(), m.target.size()));
    }
    for (std::size_t k = 0; k < m.size(); ++k) {
        if (m.source[k] >= source.size() || m.target[k] >= target.size()) {
            throw InvalidArgument(
                fmt::format("match {} ({}, {}) is out of range", k, m.source[k], m.target[k]));
        }
    }
}

// Row-wise nearest and second-nearest rows of `b` for every row of `a` (squared L2), by blocks of
// a matrix product. Rows with NaN get no match.
void NearestRows(const FeatureMatrix& a, const FeatureMatrix& b, std::vector<std::size_t>& best,
                 std::vector<float>& best_d2, std::vector<float>& second_d2, int num_threads) {
    constexpr Eigen::Index kRows = 128;
    best.assign(static_cast<std::size_t>(a.rows()), kNoMatch);
    best_d2.assign(best.size(), std::numeric_limits<float>::infinity());
    second_d2.assign(best.size(), std::numeric_limits<float>::infinity());
    std::vector<char> b_ok(static_cast<std::size_t>(b.rows()));
    Eigen::VectorXf b_norm(b.rows());
    for (Eigen::Index j = 0; j < b.rows(); ++j) {
        b_ok[static_cast<std::size_t>(j)] = b.row(j).allFinite();
        b_norm(j) = b_ok[static_cast<std::size_t>(j)] ? b.row(j).squaredNorm() : 0.0f;
    }
    // NaN rows would poison the product: zero them (they are skipped by b_ok).
    FeatureMatrix bz = b;
    for (Eigen::Index j = 0; j < b.rows(); ++j) {
        if (!b_ok[static_cast<std::size_t>(j)]) bz.row(j).setZero();
    }
    const auto blocks = static_cast<std::size_t>((a.rows() + kRows - 1) / kRows);
    ParallelFor(
        blocks, num_threads,
        [&](std::size_t blk) {
            const Eigen::Index r0 = static_cast<Eigen::Index>(blk) * kRows;
            const Eigen::Index n = std::min(kRows, a.rows() - r0);
            FeatureMatrix ablock = a.middleRows(r0, n);
            std::vector<char> a_ok(static_cast<std::size_t>(n));
            for (Eigen::Index i = 0; i < n; ++i) {
                a_ok[static_cast<std::size_t>(i)] = ablock.row(i).allFinite();
                if (!a_ok[static_cast<std::size_t>(i)]) ablock.row(i).setZero();
            }
            const Eigen::MatrixXf dots = ablock * bz.transpose();
            for (Eigen::Index i = 0; i < n; ++i) {
                if (!a_ok[static_cast<std::size_t>(i)]) continue;
                const float an = ablock.row(i).squaredNorm();
                const auto out = static_cast<std::size_t>(r0 + i);
                for (Eigen::Index j = 0; j < b.rows(); ++j) {
                    if (!b_ok[static_cast<std::size_t>(j)]) continue;
                    const float d2 = std::max(0.0f, an + b_norm(j) - 2.0f * dots(i, j));
                    if (d2 < best_d2[out]) {
                        second_d2[out] = best_d2[out];
                        best_d2[out] = d2;
                        best[out] = static_cast<std::size_t>(j);
                    } else if (d2 < second_d2[out]) {
                        second_d2[out] = d2;
                    }
                }
            }
        },
        1);
}

}  // namespace

void FeatureMatchParams::Validate() const {
    if (!(ratio > 0.0f && ratio <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("feature matching ratio must be in (0, 1], got {}", ratio));
    }
    if (num_threads < 0) {
        throw InvalidArgument(fmt::format("num_threads must be >= 0, got {}", num_threads));
    }
}

PointMatches MatchFeatureRows(const FeatureMatrix& source, const FeatureMatrix& target,
                              const FeatureMatchParams& params) {
    params.Validate();
    if (source.cols() != target.cols()) {
        throw InvalidArgument(fmt::format("feature matching: {} source and {} target columns",
                                          source.cols(), target.cols()));
    }
    PointMatches m;
    if (source.rows() == 0 || target.rows() == 0) return m;
    std::vector<std::size_t> fwd, back;
    std::vector<float> fwd_d2, fwd_second, back_d2, back_second;
    NearestRows(source, target, fwd, fwd_d2, fwd_second, params.num_threads);
    if (params.mutual) NearestRows(target, source, back, back_d2, back_second, params.num_threads);
    const float ratio2 = params.ratio * params.ratio;
    for (std::size_t i = 0; i < fwd.size(); ++i) {
        if (fwd[i] == kNoMatch) continue;
        if (params.mutual && back[fwd[i]] != i) continue;
        if (params.ratio < 1.0f && fwd_d2[i] > ratio2 * fwd_second[i]) continue;
        m.source.push_back(static_cast<Index>(i));
        m.target.push_back(static_cast<Index>(fwd[i]));
    }
    return m;
}

void LengthConsistencyParams::Validate() const {
    if (!(absolute >= 0.0f) || !(relative >= 0.0f) || !std::isfinite(absolute) ||
        !std::isfinite(relative)) {
        throw InvalidArgument(fmt::format(
            "length consistency tolerances must be >= 0, got {} and {}", absolute, relative));
    }
    if (num_threads < 0) {
        throw InvalidArgument(fmt::format("num_threads must be >= 0, got {}", num_threads));
    }
    if (partners < 1) {
        throw InvalidArgument(
            fmt::format("length consistency partners must be >= 1, got {}", partners));
    }
    if (!(keep_fraction > 0.0f && keep_fraction <= 1.0f)) {
        throw InvalidArgument(fmt::format(
            "length consistency keep_fraction must be in (0, 1], got {}", keep_fraction));
    }
}

std::vector<std::size_t> PruneByLengthConsistency(const PointCloud& source,
                                                  const PointCloud& target,
                                                  const PointMatches& matches,
                                                  const LengthConsistencyParams& params) {
    params.Validate();
    CheckMatches(source, target, matches);
    const std::size_t n = matches.size();
    std::vector<std::size_t> keep(n);
    for (std::size_t k = 0; k < n; ++k) keep[k] = k;
    if (n <= params.min_keep) return keep;
    const std::size_t partners =
        std::min<std::size_t>(n - 1, static_cast<std::size_t>(params.partners));
    std::vector<int> support(n, 0);
    ParallelFor(
        n, params.num_threads,
        [&](std::size_t i) {
            const Eigen::Vector3f& si = source.points[matches.source[i]];
            const Eigen::Vector3f& ti = target.points[matches.target[i]];
            int count = 0;
            for (std::size_t p = 0; p < partners; ++p) {
                const std::size_t j = (i + 1 + p * (n - 1) / partners) % n;  // never i
                const float ds = (source.points[matches.source[j]] - si).norm();
                const float dt = (target.points[matches.target[j]] - ti).norm();
                if (std::abs(ds - dt) <= params.absolute + params.relative * std::max(ds, dt))
                    ++count;
            }
            support[i] = count;
        },
        64);
    const std::size_t kept = std::max<std::size_t>(
        params.min_keep,
        static_cast<std::size_t>(std::ceil(params.keep_fraction * static_cast<float>(n))));
    std::stable_sort(keep.begin(), keep.end(),
                     [&](std::size_t a, std::size_t b) { return support[a] > support[b]; });
    keep.resize(std::min(n, kept));
    std::sort(keep.begin(), keep.end());
    return keep;
}

void RansacParams::Validate() const {
    if (max_iterations < 1) {
        throw InvalidArgument(
            fmt::format("RANSAC max_iterations must be >= 1, got {}", max_iterations));
    }
    if (!(p_success > 0.0 && p_success < 1.0)) {
        throw InvalidArgument(fmt::format("RANSAC p_success must be in (0, 1), got {}", p_success));
    }
    if (!(inlier_distance > 0.0f) || !std::isfinite(inlier_distance)) {
        throw InvalidArgument(
            fmt::format("RANSAC inlier_distance must be > 0, got {}", inlier_distance));
    }
    if (!(edge_tolerance > 0.0f && edge_tolerance < 1.0f)) {
        throw InvalidArgument(
            fmt::format("RANSAC edge_tolerance must be in (0, 1), got {}", edge_tolerance));
    }
    if (!(min_edge >= 0.0f) || !std::isfinite(min_edge)) {
        throw InvalidArgument(fmt::format("RANSAC min_edge must be >= 0, got {}", min_edge));
    }
    if (min_inliers < 3) {
        throw InvalidArgument(fmt::format("RANSAC min_inliers must be >= 3, got {}", min_inliers));
    }
    if (num_threads < 0) {
        throw InvalidArgument(fmt::format("RANSAC num_threads must be >= 0, got {}", num_threads));
    }
}

RegistrationResult AlignMatchesRansac(const PointCloud& source, const PointCloud& target,
                                      const PointMatches& matches, const RansacParams& params) {
    const auto start = std::chrono::steady_clock::now();
    params.Validate();
    CheckMatches(source, target, matches);
    RegistrationResult result;
    auto finish = [&](RegistrationStatus status, std::string reason) {
        result.status = status;
        result.converged = status == RegistrationStatus::kConverged;
        result.reason = std::move(reason);
        result.time_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        return result;
    };
    // Matches between finite points only.
    std::vector<Eigen::Vector3d> a, b;
    for (std::size_t k = 0; k < matches.size(); ++k) {
        const auto& s = source.points[matches.source[k]];
        const auto& t = target.points[matches.target[k]];
        if (s.allFinite() && t.allFinite()) {
            a.push_back(s.cast<double>());
            b.push_back(t.cast<double>());
        }
    }
    const std::size_t n = a.size();
    if (n < 3) return finish(RegistrationStatus::kEmptyInput, fmt::format("{} usable matches", n));
    const double limit2 = static_cast<double>(params.inlier_distance) * params.inlier_distance;
    auto count_inliers = [&](const Eigen::Isometry3d& T) {
        std::size_t c = 0;
        for (std::size_t k = 0; k < n; ++k) c += (T * a[k] - b[k]).squaredNorm() <= limit2;
        return c;
    };
    // Hypothesis of sample k: inlier count, or 0 when the sample is degenerate or inconsistent.
    auto evaluate = [&](std::uint64_t k, Eigen::Isometry3d& T) -> std::size_t {
        std::uint64_t state = Mix(params.seed ^ Mix(k + 1));
        std::size_t idx[3];
        for (int s = 0; s < 3; ++s) {
            state = Mix(state);
            idx[s] = static_cast<std::size_t>(state % n);
        }
        if (idx[0] == idx[1] || idx[0] == idx[2] || idx[1] == idx[2]) return 0;
        for (int s = 0; s < 3; ++s) {
            const std::size_t i = idx[s], j = idx[(s + 1) % 3];
            const double ds = (a[i] - a[j]).norm(), dt = (b[i] - b[j]).norm();
            if (ds < params.min_edge || dt < params.min_edge) return 0;
            if (std::abs(ds - dt) > params.edge_tolerance * std::max(ds, dt)) return 0;
        }
        const Eigen::Vector3d sa[3] = {a[idx[0]], a[idx[1]], a[idx[2]]};
        const Eigen::Vector3d sb[3] = {b[idx[0]], b[idx[1]], b[idx[2]]};
        if (!FitRigidTransform(sa, sb, {}, T)) return 0;
        return count_inliers(T);
    };
    constexpr std::size_t kBatch = 256;
    std::vector<std::size_t> counts(kBatch);
    std::vector<Eigen::Isometry3d> hyps(kBatch);
    std::size_t best = 0;
    Eigen::Isometry3d best_T = Eigen::Isometry3d::Identity();
    std::uint64_t needed = static_cast<std::uint64_t>(params.max_iterations);
    std::uint64_t drawn = 0;
    while (drawn < needed) {
        const std::size_t batch =
            static_cast<std::size_t>(std::min<std::uint64_t>(kBatch, needed - drawn));
        ParallelFor(
            batch, params.num_threads,
            [&](std::size_t k) { counts[k] = evaluate(drawn + k, hyps[k]); }, 8);
        for (std::size_t k = 0; k < batch && drawn < needed; ++k) {
            ++drawn;
            if (counts[k] <= best) continue;
            best = counts[k];
            best_T = hyps[k];
            // Eq. (4.6) of the thesis: samples needed for an all-inlier triple.
            const double w = static_cast<double>(best) / static_cast<double>(n);
            const double p_fail = 1.0 - w * w * w;
            if (p_fail <= 0.0) {
                needed = drawn;
            } else {
                const double t = std::log(1.0 - params.p_success) / std::log(p_fail);
                if (t < static_cast<double>(needed))
                    needed =
                        std::max<std::uint64_t>(drawn, static_cast<std::uint64_t>(std::ceil(t)));
            }
        }
    }
    result.iterations = static_cast<int>(drawn);
    if (best < params.min_inliers) {
        return finish(RegistrationStatus::kNoHypothesis,
                      fmt::format("best of {} samples has {} inliers among {} matches, {} needed",
                                  drawn, best, n, params.min_inliers));
    }
    // Refit to the inliers, twice (the inlier set grows as the fit improves).
    Eigen::Isometry3d T = best_T;
    for (int round = 0; round < 2; ++round) {
        std::vector<Eigen::Vector3d> ia, ib;
        for (std::size_t k = 0; k < n; ++k) {
            if ((T * a[k] - b[k]).squaredNorm() <= limit2) {
                ia.push_back(a[k]);
                ib.push_back(b[k]);
            }
        }
        Eigen::Isometry3d refit;
        if (ia.size() >= 3 && FitRigidTransform(ia, ib, {}, refit) &&
            count_inliers(refit) >= best) {
            T = refit;
            best = count_inliers(refit);
        }
    }
    double sum2 = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
        const double d2 = (T * a[k] - b[k]).squaredNorm();
        if (d2 <= limit2) sum2 += d2;
    }
    result.T_target_source = T;
    result.correspondences = best;
    result.fitness = static_cast<double>(best) / static_cast<double>(n);
    result.inlier_rmse = std::sqrt(sum2 / static_cast<double>(best));
    return finish(RegistrationStatus::kConverged,
                  fmt::format("{} of {} matches agree after {} samples", best, n, drawn));
}

void FpfhAlignParams::Validate() const {
    if (!(fpfh.radius > 0.0f) || !std::isfinite(fpfh.radius)) {
        throw InvalidArgument(fmt::format("fpfh.radius must be > 0, got {}", fpfh.radius));
    }
    if (max_points < 10) {
        throw InvalidArgument(fmt::format("max_points must be >= 10, got {}", max_points));
    }
    ValidateNode("matching", [&] { matching.Validate(); });
    ValidateNode("pruning", [&] { pruning.Validate(); });
    ValidateNode("ransac", [&] { ransac.Validate(); });
    if (num_threads < 0) {
        throw InvalidArgument(fmt::format("num_threads must be >= 0, got {}", num_threads));
    }
}

RegistrationResult AlignFpfh(const PointCloud& source, const KdTree& source_tree,
                             const PointCloud& target, const KdTree& target_tree,
                             const FpfhAlignParams& params) {
    const auto start = std::chrono::steady_clock::now();
    params.Validate();
    if (source.CountFinite() < 3 || target.CountFinite() < 3) {
        RegistrationResult r;
        r.status = RegistrationStatus::kEmptyInput;
        r.reason = "a cloud has fewer than 3 finite points";
        return r;
    }
    PairFeatureParams fp = params.fpfh;
    fp.num_threads = params.num_threads;
    // Descriptors of every point (each uses its full neighbourhood), matched on an even subset.
    auto described = [&](const PointCloud& cloud, const KdTree& tree, Indices& rows) {
        const FeatureMatrix all = ComputeFpfh(cloud, tree, fp);
        Indices defined;
        for (Eigen::Index i = 0; i < all.rows(); ++i) {
            if (all.row(i).allFinite()) defined.push_back(static_cast<Index>(i));
        }
        rows = EvenSubset(defined, params.max_points);
        FeatureMatrix out(static_cast<Eigen::Index>(rows.size()), all.cols());
        for (std::size_t k = 0; k < rows.size(); ++k) {
            out.row(static_cast<Eigen::Index>(k)) = all.row(rows[k]);
        }
        return out;
    };
    Indices source_rows, target_rows;
    const FeatureMatrix fs = described(source, source_tree, source_rows);
    const FeatureMatrix ft = described(target, target_tree, target_rows);
    FeatureMatchParams mp = params.matching;
    mp.num_threads = params.num_threads;
    PointMatches all = MatchFeatureRows(fs, ft, mp);
    for (auto& i : all.source) i = source_rows[i];
    for (auto& i : all.target) i = target_rows[i];
    LengthConsistencyParams lp = params.pruning;
    lp.num_threads = params.num_threads;
    const auto kept = PruneByLengthConsistency(source, target, all, lp);
    PointMatches pruned;
    for (std::size_t k : kept) {
        pruned.source.push_back(all.source[k]);
        pruned.target.push_back(all.target[k]);
    }
    RansacParams rp = params.ransac;
    rp.num_threads = params.num_threads;
    RegistrationResult r = AlignMatchesRansac(source, target, pruned, rp);
    r.reason = fmt::format("{} FPFH matches, {} after length pruning: {}", all.size(),
                           pruned.size(), r.reason);
    r.time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return r;
}

}  // namespace multicue
