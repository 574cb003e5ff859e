#include "multicue/segmentation/sample_consensus.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue {
namespace {

// Points per distance evaluation; keeps the buffers on the stack and the callbacks amortised.
constexpr std::size_t kChunk = 256;
// Below this many usable points a hypothesis is scored too fast for threads to pay off.
constexpr std::size_t kMinPointsForThreads = 4096;

struct Score {
    double cost = 0.0;        // lower is better: outlier count (RANSAC) or truncated cost (MSAC)
    std::size_t inliers = 0;  // points with d <= t
    double drawn_mass = 0.0;  // sampling weight of the inliers (only with sample weights)
};

// Adds min(d^2, t^2) of every distance to the sum (in order; t^2 for NaN) and counts those
// <= t. The squares of floats are exact in double, so d <= t exactly when d^2 <= t^2 and the
// minimum is the inlier's square or the threshold's, with no branch per point.
struct TruncatedSum {
    double sum = 0.0;
    std::size_t within = 0;
};
[[gnu::noinline]] TruncatedSum TruncatedSquares(const float* d, std::size_t n, float t, double t2,
                                                TruncatedSum start) {
    double sum = start.sum;
    std::size_t within = start.within;
    for (std::size_t k = 0; k < n; ++k) {
        const double dd = double{d[k]} * d[k];
        sum += std::min(t2, dd);  // NaN: t2
        within += static_cast<std::size_t>(d[k] <= t);
    }
    return {sum, within};
}

// The same for weighted points and for outlier counts (RANSAC): with `score_w` each point's
// cost is weighted (MSAC) or its weight is the cost of an outlier (RANSAC); with `sample_w` the
// inliers' sampling weights are summed. Adding 0 where the serial sums skip a point leaves them
// unchanged, so the sums are those of a branch per point.
struct WeightedSum {
    double cost = 0.0;
    double drawn_mass = 0.0;
    std::size_t within = 0;
};
[[gnu::noinline]] WeightedSum WeightedCosts(const float* d, std::size_t n, float t, double t2,
                                            bool msac, const float* score_w, const float* sample_w,
                                            WeightedSum start) {
    double cost = start.cost;
    double drawn_mass = start.drawn_mass;
    std::size_t within = start.within;
    for (std::size_t k = 0; k < n; ++k) {
        const bool inlier = d[k] <= t;
        within += static_cast<std::size_t>(inlier);
        if (sample_w != nullptr) drawn_mass += inlier ? double{sample_w[k]} : 0.0;
        const double w = score_w != nullptr ? double{score_w[k]} : 1.0;
        if (msac) {
            cost += w * std::min(t2, double{d[k]} * d[k]);  // NaN: t2
        } else if (score_w != nullptr) {
            cost += inlier ? 0.0 : w;
        }
    }
    return {cost, drawn_mass, within};
}

// Distances d of the usable points to one model, blended with the normal deviation when used.
class Evaluator {
  public:
    // score_w / sample_w: per usable point (aligned with `points`), or empty.
    Evaluator(const PointCloud& cloud, const Indices& points, const SacModel& model,
              const SacParams& params, bool blend_normals, const std::vector<float>& score_w,
              const std::vector<float>& sample_w)
        : cloud_(cloud),
          points_(points),
          model_(model),
          threshold_(params.distance_threshold),
          weight_(blend_normals ? params.normal_distance_weight : 0.0f),
          score_w_(score_w),
          sample_w_(sample_w) {}

    // Calls visit(begin, n, d, e) for the usable points [begin, begin + n), chunk by chunk in
    // order, with their distances d (blended with the normal's deviation when used) and their
    // Euclidean distances e; after each chunk, stops early when stop() says so. Returns whether
    // every point was visited.
    template <typename Visit, typename Stop>
    bool ForEachChunk(const SacCoefficients& c, Visit&& visit, Stop&& stop) const {
        std::array<float, kChunk> dist{};
        std::array<float, kChunk> blended{};
        for (std::size_t begin = 0; begin < points_.size(); begin += kChunk) {
            const std::size_t n = std::min(kChunk, points_.size() - begin);
            const std::span<const Index> idx(points_.data() + begin, n);
            model_.distances(cloud_, c, idx, std::span<float>(dist.data(), n));
            for (std::size_t k = 0; k < n; ++k) dist[k] = std::abs(dist[k]);
            if (weight_ > 0.0f) {
                // The normal's angle (an acos) only where it can still make an inlier: adding
                // the non-negative angle term never brings a point back under the threshold.
                std::array<Index, kChunk> near{};
                std::array<std::uint16_t, kChunk> slot{};
                std::size_t m = 0;
                for (std::size_t k = 0; k < n; ++k) {
                    if ((1.0f - weight_) * dist[k] <= threshold_) {
                        near[m] = idx[k];
                        slot[m++] = static_cast<std::uint16_t>(k);
                    }
                }
                std::array<float, kChunk> near_angle{};
                model_.normal_angles(cloud_, c, std::span<const Index>(near.data(), m),
                                     std::span<float>(near_angle.data(), m));
                std::array<float, kChunk> angle{};
                for (std::size_t j = 0; j < m; ++j) angle[slot[j]] = near_angle[j];
                for (std::size_t k = 0; k < n; ++k) {
                    blended[k] = (1.0f - weight_) * dist[k] + weight_ * angle[k];
                }
                visit(begin, n, blended.data(), dist.data());
            } else {
                visit(begin, n, dist.data(), dist.data());
            }
            if (begin + n < points_.size() && stop()) return false;
        }
        return true;
    }

    // The score of a hypothesis. Every point adds a non-negative amount to the cost, so once the
    // partial cost exceeds `bound` (the best cost so far) the hypothesis cannot win: it is left
    // unfinished with an infinite cost, which changes no decision of the sampling loop.
    Score Evaluate(const SacCoefficients& c, SacMethod method,
                   double bound = std::numeric_limits<double>::infinity()) const {
        Score s;
        const double t2 = double{threshold_} * threshold_;
        const float t = threshold_;
        const bool weighted = !score_w_.empty();
        const bool drawn = !sample_w_.empty();
        const bool count_outliers = method == SacMethod::kRansac && !weighted;
        const bool msac = method == SacMethod::kMsac;
        std::size_t seen = 0;
        const bool complete = ForEachChunk(
            c,
            [&](std::size_t begin, std::size_t n, const float* d, const float*) {
                // NaN distances (a model gone bad) count as outliers.
                if (msac && !weighted && !drawn) {
                    const TruncatedSum r = TruncatedSquares(d, n, t, t2, {s.cost, s.inliers});
                    s.cost = r.sum;
                    s.inliers = r.within;
                } else {
                    const WeightedSum r = WeightedCosts(
                        d, n, t, t2, msac, weighted ? score_w_.data() + begin : nullptr,
                        drawn ? sample_w_.data() + begin : nullptr,
                        {s.cost, s.drawn_mass, s.inliers});
                    s.cost = r.cost;
                    s.drawn_mass = r.drawn_mass;
                    s.inliers = r.within;
                }
                seen += n;
            },
            [&] {
                const double partial =
                    count_outliers ? static_cast<double>(seen - s.inliers) : s.cost;
                return partial > bound;
            });
        if (!complete) {
            s.cost = std::numeric_limits<double>::infinity();
        } else if (count_outliers) {
            s.cost = static_cast<double>(points_.size() - s.inliers);
        }
        return s;
    }

    // Inliers of `c` (cloud indices, input order), their Euclidean sum of squares, the truncated
    // quadratic cost over all usable points (score-weighted) and the inliers' score weight.
    void Inliers(const SacCoefficients& c, Indices& inliers, double& sum_sq, double& truncated,
                 double& inlier_weight) const {
        inliers.clear();
        sum_sq = 0.0;
        truncated = 0.0;
        inlier_weight = 0.0;
        const double t2 = double{threshold_} * threshold_;
        const bool weighted = !score_w_.empty();
        ForEachChunk(
            c,
            [&](std::size_t begin, std::size_t n, const float* d, const float* e) {
                for (std::size_t k = 0; k < n; ++k) {
                    const double w = weighted ? double{score_w_[begin + k]} : 1.0;
                    if (d[k] <= threshold_) {
                        inliers.push_back(points_[begin + k]);
                        sum_sq += double{e[k]} * e[k];
                        truncated += w * d[k] * d[k];
                        inlier_weight += w;
                    } else {
                        truncated += w * t2;
                    }
                }
            },
            [] { return false; });
    }

  private:
    const PointCloud& cloud_;
    const Indices& points_;
    const SacModel& model_;
    float threshold_;
    float weight_;
    const std::vector<float>& score_w_;
    const std::vector<float>& sample_w_;
};

// Uniform integer in [0, n) from a 64-bit engine, by rejection: unbiased and the same on every
// standard library (std::uniform_int_distribution is not specified bit for bit).
std::size_t UniformBelow(std::mt19937_64& rng, std::size_t n) {
    const std::uint64_t range = n;
    const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() -
                                std::numeric_limits<std::uint64_t>::max() % range;
    std::uint64_t x = rng();
    while (x >= limit) x = rng();
    return static_cast<std::size_t>(x % range);
}

// Uniform double in [0, 1) from the top 53 bits of one engine output (the same everywhere).
double UnitUniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// Draws minimal samples of distinct usable points, uniformly or proportionally to weights.
class Sampler {
  public:
    // weights: per usable point (aligned with `points`), or empty for uniform sampling.
    Sampler(const Indices& points, const std::vector<float>& weights) : points_(points) {
        if (weights.empty()) return;
        ends_.resize(weights.size());
        double sum = 0.0;
        for (std::size_t k = 0; k < weights.size(); ++k) {
            sum += double{weights[k]};
            ends_[k] = sum;
        }
    }

    // Usable points that can be drawn at all.
    std::size_t Drawable(const std::vector<float>& weights) const {
        if (ends_.empty()) return points_.size();
        return static_cast<std::size_t>(
            std::count_if(weights.begin(), weights.end(), [](float w) { return w > 0.0f; }));
    }

    void Draw(std::mt19937_64& rng, std::vector<std::size_t>& positions,
              std::vector<Index>& sample) const {
        for (std::size_t j = 0; j < sample.size(); ++j) {
            const auto chosen_end = positions.begin() + static_cast<std::ptrdiff_t>(j);
            std::size_t pos = 0;
            do {
                pos = ends_.empty() ? UniformBelow(rng, points_.size())
                                    : WeightedPosition(rng, j, positions);
            } while (std::find(positions.begin(), chosen_end, pos) != chosen_end);
            positions[j] = pos;
            sample[j] = points_[pos];
        }
    }

  private:
    double Start(std::size_t k) const { return k == 0 ? 0.0 : ends_[k - 1]; }

    // One position drawn from the weights with the first `taken` positions removed: a uniform
    // value in the remaining mass is mapped onto the full cumulative sum by stepping over the
    // removed intervals in ascending order. Rounding can still land on a removed point; the
    // caller then draws again.
    std::size_t WeightedPosition(std::mt19937_64& rng, std::size_t taken,
                                 const std::vector<std::size_t>& positions) const {
        std::array<std::size_t, 16> sorted_small{};
        std::vector<std::size_t> sorted_large;
        std::size_t* sorted = sorted_small.data();
        if (taken > sorted_small.size()) {
            sorted_large.resize(taken);
            sorted = sorted_large.data();
        }
        double removed = 0.0;
        for (std::size_t j = 0; j < taken; ++j) {
            sorted[j] = positions[j];
            removed += ends_[positions[j]] - Start(positions[j]);
        }
        std::sort(sorted, sorted + taken);
        const double remaining = ends_.back() - removed;
        double x = UnitUniform(rng) * remaining;
        for (std::size_t j = 0; j < taken; ++j) {
            if (x >= Start(sorted[j])) x += ends_[sorted[j]] - Start(sorted[j]);
        }
        // First point whose interval [start, end) holds x; zero-weight points have empty
        // intervals and are never selected.
        const auto it = std::upper_bound(ends_.begin(), ends_.end(), x);
        if (it == ends_.end()) {
            // x rounded up to the total: the last point with a positive weight.
            std::size_t k = ends_.size() - 1;
            while (k > 0 && !(ends_[k] > Start(k))) --k;
            return k;
        }
        return static_cast<std::size_t>(it - ends_.begin());
    }

    const Indices& points_;
    std::vector<double> ends_;  // cumulative weights: point k covers [ends_[k-1], ends_[k])
};

// Weights of the usable points, aligned with them (empty when `weights` is empty).
std::vector<float> Gather(const std::vector<float>& weights, const Indices& points) {
    std::vector<float> out;
    if (weights.empty()) return out;
    out.reserve(points.size());
    for (Index i : points) out.push_back(weights[i]);
    return out;
}

// The usable points: finite, inside the cloud, with a finite normal when normals are used.
Indices UsablePoints(const PointCloud& cloud, const Indices& indices, bool use_normals) {
    Indices points;
    auto usable = [&](Index i) {
        return cloud.points[i].allFinite() && (!use_normals || cloud.normals[i].allFinite());
    };
    if (indices.empty()) {
        points.reserve(cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (usable(static_cast<Index>(i))) points.push_back(static_cast<Index>(i));
        }
        return points;
    }
    points.reserve(indices.size());
    for (Index i : indices) {
        if (i >= cloud.size()) {
            throw InvalidArgument(
                fmt::format("index {} is out of range for a cloud of {} points", i, cloud.size()));
        }
        if (usable(i)) points.push_back(i);
    }
    return points;
}

// Throws InvalidArgument for a model that cannot be sampled or scored.
void CheckModel(const SacModel& model) {
    if (model.sample_size < 1) {
        throw InvalidArgument(fmt::format("sample consensus model sample_size must be >= 1, got {}",
                                          model.sample_size));
    }
    if (!model.fit_sample || !model.distances) {
        throw InvalidArgument("sample consensus model needs fit_sample and distances");
    }
}

// Where the hypotheses are scored in parallel: nowhere (serially), in an arena of their own, or
// in the arena of an enclosing parallel loop (objects fitted in parallel), isolated from its
// other tasks.
struct ScoringThreads {
    bool parallel = false;
    std::optional<tbb::task_arena> arena;
};

// Scores the valid ones of the first n hypotheses (each score depends on its hypothesis alone,
// so the order of evaluation does not matter).
void ScoreBatch(const Evaluator& evaluator, SacMethod method, ScoringThreads& threads,
                std::size_t n, const std::vector<SacCoefficients>& hypotheses,
                const std::vector<char>& valid, double bound, std::vector<Score>& scores) {
    auto score = [&](std::size_t j) {
        if (valid[j] != 0) scores[j] = evaluator.Evaluate(hypotheses[j], method, bound);
    };
    if (!threads.parallel || n < 2) {
        for (std::size_t j = 0; j < n; ++j) score(j);
        return;
    }
#if defined(MULTICUE_TSAN_PLAIN_THREADS)
    detail::RunOnThreads(n, score);  // see core/parallel.hpp
#else
    auto loop = [&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t j = r.begin(); j < r.end(); ++j) score(j);
                          });
    };
    if (threads.arena) {
        threads.arena->execute(loop);
    } else {
        tbb::this_task_arena::isolate(loop);
    }
#endif
}

// The best hypothesis of the sampling loop and the loop's count of iterations, with the number
// still needed by Eq. (4.6) (section 4.2.4.3) for the best one's inlier ratio.
struct Consensus {
    bool have_best = false;
    Score best;
    SacCoefficients coefficients;
    int needed = std::numeric_limits<int>::max();  // unknown (infinite) at first
    int iterations = 0;
};

// The sampling loop: minimal samples drawn serially from one engine, scored in batches (in
// parallel for large point sets), and decided in drawing order exactly as a serial loop would,
// so that the result does not depend on the thread count.
Consensus SearchHypotheses(const PointCloud& cloud, const SacModel& model, const SacParams& params,
                           const Indices& points, const Sampler& sampler,
                           const Evaluator& evaluator, const std::vector<float>& sample_w) {
    const auto k = static_cast<std::size_t>(model.sample_size);
    double total_mass = 0.0;  // sampling weight of all usable points
    for (float w : sample_w) total_mass += double{w};
    const int threads = ArenaThreadCount(params.num_threads);
    ScoringThreads scoring;
    scoring.parallel = threads > 1 && points.size() >= kMinPointsForThreads;
    const bool nested =
        tbb::this_task_arena::current_thread_index() != tbb::task_arena::not_initialized &&
        tbb::this_task_arena::max_concurrency() <= threads;
    if (scoring.parallel && !nested) scoring.arena.emplace(threads);
    const std::size_t batch = scoring.parallel ? 2 * static_cast<std::size_t>(threads) : 1;

    std::mt19937_64 rng(params.seed);
    std::vector<std::size_t> positions(k);
    std::vector<Index> sample(k);
    std::vector<SacCoefficients> hypotheses(batch);
    std::vector<char> valid(batch, 0);
    std::vector<Score> scores(batch);

    Consensus c;
    while (c.iterations < std::min(c.needed, params.max_iterations)) {
        // Draw (serially, in order) as many samples as the serial loop could still draw.
        const auto remaining =
            static_cast<std::size_t>(std::min(c.needed, params.max_iterations) - c.iterations);
        const std::size_t n = std::min(batch, remaining);
        for (std::size_t j = 0; j < n; ++j) {
            sampler.Draw(rng, positions, sample);
            valid[j] = model.fit_sample(cloud, sample, hypotheses[j]) ? 1 : 0;
        }
        // Hypotheses of the batch costlier than the best before it are left unfinished.
        const double bound = c.have_best ? c.best.cost : std::numeric_limits<double>::infinity();
        ScoreBatch(evaluator, params.method, scoring, n, hypotheses, valid, bound, scores);
        // Decide in drawing order, exactly as the serial loop does; samples drawn past its stop
        // are discarded.
        for (std::size_t j = 0; j < n; ++j) {
            ++c.iterations;
            if (valid[j] != 0 && (!c.have_best || scores[j].cost < c.best.cost)) {
                c.have_best = true;
                c.best = scores[j];
                c.coefficients = hypotheses[j];
                // The chance that one draw is an inlier.
                const double ratio = sample_w.empty() ? static_cast<double>(c.best.inliers) /
                                                            static_cast<double>(points.size())
                                                      : c.best.drawn_mass / total_mass;
                c.needed = AdaptiveIterationCount(params.p_success, ratio, model.sample_size);
            }
            if (c.iterations >= std::min(c.needed, params.max_iterations)) break;
        }
    }
    return c;
}

// The inliers of a model and what the refinement compares (see Evaluator::Inliers).
struct InlierSet {
    Indices inliers;
    double sum_sq = 0.0;
    double truncated = 0.0;
    double inlier_weight = 0.0;
};

// Least-squares refinement. Accepting a refit only when the truncated quadratic cost does not
// grow keeps the result at least as good as the sample's model; for an exact least-squares refit
// the cost cannot grow (old inliers: min(d^2, t^2) <= d^2 <= old d^2 summed; old outliers: at
// most t^2 each). Stops when the inliers no longer change.
void RefineConsensus(const PointCloud& cloud, const SacModel& model, const Evaluator& evaluator,
                     int max_refine_rounds, SacCoefficients& coefficients, InlierSet& set) {
    const auto k = static_cast<std::size_t>(model.sample_size);
    Indices refit_inliers;
    double refit_sum_sq = 0.0;
    double refit_truncated = 0.0;
    double refit_weight = 0.0;
    SacCoefficients refined;
    for (int round = 0; round < max_refine_rounds; ++round) {
        if (set.inliers.size() < k) break;
        if (!model.refine(cloud, set.inliers, coefficients, refined)) break;
        evaluator.Inliers(refined, refit_inliers, refit_sum_sq, refit_truncated, refit_weight);
        if (!(refit_truncated <= set.truncated * (1.0 + 1e-6) + 1e-12)) break;
        coefficients = refined;
        set.truncated = refit_truncated;
        set.sum_sq = refit_sum_sq;
        set.inlier_weight = refit_weight;
        const bool stable = refit_inliers == set.inliers;
        set.inliers.swap(refit_inliers);
        if (stable) break;
    }
}

}  // namespace

void ValidateSacParams(const SacParams& params) {
    if (!(params.distance_threshold > 0.0f) || !std::isfinite(params.distance_threshold)) {
        throw InvalidArgument(fmt::format("sample consensus distance_threshold must be > 0, got {}",
                                          params.distance_threshold));
    }
    if (!(params.p_success > 0.0 && params.p_success < 1.0)) {
        throw InvalidArgument(
            fmt::format("sample consensus p_success must be in (0, 1), got {}", params.p_success));
    }
    if (params.max_iterations < 1) {
        throw InvalidArgument(fmt::format("sample consensus max_iterations must be >= 1, got {}",
                                          params.max_iterations));
    }
    if (params.max_refine_rounds < 0) {
        throw InvalidArgument(fmt::format("sample consensus max_refine_rounds must be >= 0, got {}",
                                          params.max_refine_rounds));
    }
    if (!(params.normal_distance_weight >= 0.0f && params.normal_distance_weight <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("sample consensus normal_distance_weight must be in [0, 1], got {}",
                        params.normal_distance_weight));
    }
    ResolveThreadCount(params.num_threads);  // throws on negative values
}

void ValidateSacWeights(std::span<const float> weights, std::size_t cloud_size, const char* name) {
    if (weights.empty()) return;
    if (weights.size() != cloud_size) {
        throw InvalidArgument(
            fmt::format("sample consensus {} must have one value per cloud point "
                        "({}), got {}",
                        name, cloud_size, weights.size()));
    }
    for (std::size_t i = 0; i < weights.size(); ++i) {
        if (!(weights[i] >= 0.0f) || !std::isfinite(weights[i])) {
            throw InvalidArgument(
                fmt::format("sample consensus {} must be finite and >= 0, got {} at point {}", name,
                            weights[i], i));
        }
    }
}

int AdaptiveIterationCount(double p_success, double inlier_ratio, int sample_size) {
    constexpr int kInfinite = std::numeric_limits<int>::max();
    if (!(p_success > 0.0 && p_success < 1.0)) {
        throw InvalidArgument(fmt::format("p_success must be in (0, 1), got {}", p_success));
    }
    if (sample_size < 1) {
        throw InvalidArgument(fmt::format("sample_size must be >= 1, got {}", sample_size));
    }
    const double w = std::clamp(inlier_ratio, 0.0, 1.0);
    const double p_good = std::pow(w, sample_size);
    if (p_good >= 1.0) return 1;
    const double log_bad = std::log1p(-p_good);  // log(1 - p_good), accurate for small p_good
    if (!(log_bad < 0.0)) return kInfinite;
    const double t = std::ceil(std::log1p(-p_success) / log_bad);
    if (!(t < static_cast<double>(kInfinite))) return kInfinite;
    return std::max(1, static_cast<int>(t));
}

SacResult RunSampleConsensus(const PointCloud& cloud, const Indices& indices, const SacModel& model,
                             const SacParams& params) {
    ValidateSacParams(params);
    CheckModel(model);
    ValidateSacWeights(params.sample_weights, cloud.size(), "sample_weights");
    ValidateSacWeights(params.score_weights, cloud.size(), "score_weights");
    SacResult result;
    if (cloud.empty()) return result;

    const bool blend_normals = params.normal_distance_weight > 0.0f && model.normal_angles;
    const bool use_normals = model.needs_normals || blend_normals;
    if (use_normals && cloud.normals.size() != cloud.size()) {
        throw DataError(
            fmt::format("sample consensus needs one normal per point (the model samples normals or "
                        "normal_distance_weight = {} > 0), got {} normals for {} points",
                        params.normal_distance_weight, cloud.normals.size(), cloud.size()));
    }
    const Indices points = UsablePoints(cloud, indices, use_normals);
    const auto k = static_cast<std::size_t>(model.sample_size);
    if (points.size() < k) return result;

    const std::vector<float> sample_w = Gather(params.sample_weights, points);
    const std::vector<float> score_w = Gather(params.score_weights, points);
    const Sampler sampler(points, sample_w);
    if (sampler.Drawable(sample_w) < k) return result;
    const Evaluator evaluator(cloud, points, model, params, blend_normals, score_w, sample_w);
    Consensus c = SearchHypotheses(cloud, model, params, points, sampler, evaluator, sample_w);
    result.iterations = c.iterations;
    if (!c.have_best) return result;

    InlierSet set;
    evaluator.Inliers(c.coefficients, set.inliers, set.sum_sq, set.truncated, set.inlier_weight);
    if (model.refine) {
        RefineConsensus(cloud, model, evaluator, params.max_refine_rounds, c.coefficients, set);
    }
    if (set.inliers.size() < k) return result;
    result.found = true;
    result.converged = c.iterations >= c.needed;
    result.coefficients = std::move(c.coefficients);
    result.rmse =
        static_cast<float>(std::sqrt(set.sum_sq / static_cast<double>(set.inliers.size())));
    result.inliers = std::move(set.inliers);
    result.inlier_weight = set.inlier_weight;
    return result;
}

}  // namespace multicue
