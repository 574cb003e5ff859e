#include "multicue/segmentation/support_plane.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/filters/remove_non_finite.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/segmentation/polygonal_prism.hpp"
#include "multicue/segmentation/sac_plane.hpp"

namespace multicue {
namespace {

constexpr float kDegToRad = static_cast<float>(M_PI) / 180.0f;

void CheckParams(const SupportPlaneParams& p) {
    if (p.up && (!p.up->allFinite() || p.up->norm() < 1e-6f)) {
        throw InvalidArgument("support plane: up must be a finite non-zero vector");
    }
    auto angle_ok = [](float a) { return a >= 0.0f && a <= 90.0f; };
    if (!angle_ok(p.max_tilt_deg) || !angle_ok(p.camera_tilt_deg)) {
        throw InvalidArgument(
            fmt::format("support plane: tilt angles must be in [0, 90] degrees, got {} and {}",
                        p.max_tilt_deg, p.camera_tilt_deg));
    }
    if (!(p.distance_threshold > 0.0f) || !std::isfinite(p.distance_threshold)) {
        throw InvalidArgument(fmt::format("support plane: distance_threshold must be > 0, got {}",
                                          p.distance_threshold));
    }
    if (p.max_candidates < 1) {
        throw InvalidArgument(
            fmt::format("support plane: max_candidates must be >= 1, got {}", p.max_candidates));
    }
    if (!(p.min_inlier_fraction >= 0.0f && p.min_inlier_fraction <= 1.0f) ||
        !(p.size_ratio_to_compete >= 0.0f && p.size_ratio_to_compete <= 1.0f) ||
        !(p.raised_ratio >= 0.0f && p.raised_ratio <= 1.0f)) {
        throw InvalidArgument("support plane: fractions must be in [0, 1]");
    }
    if (!std::isfinite(p.raised_gap))
        throw InvalidArgument("support plane: raised_gap must be finite");
    if (p.max_samples < 3) {
        throw InvalidArgument(
            fmt::format("support plane: max_samples must be >= 3, got {}", p.max_samples));
    }
    if (!(p.min_supported_fraction >= 0.0f && p.min_supported_fraction <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("support plane: min_supported_fraction must be in [0, 1], got {}",
                        p.min_supported_fraction));
    }
    if (!(p.cluster_tolerance > 0.0f)) {
        throw InvalidArgument(fmt::format("support plane: cluster_tolerance must be > 0, got {}",
                                          p.cluster_tolerance));
    }
}

// Largest patch of the plane's inliers connected within `tolerance` in 3D (not in the image:
// the objects on a table cut its visible top into pieces that no pixel path joins). Other
// surfaces at the same height farther away (a second table, a shelf) are left out.
Indices LargestPatch(const PointCloud& cloud, const Indices& inliers, float tolerance) {
    ClusteringResult clusters =
        EuclideanClusteringGrid(cloud, {.tolerance = tolerance, .subset = inliers});
    if (clusters.clusters.empty()) return {};
    return std::move(clusters.clusters.front());
}

// The table of an organized frame: the same largest patch without clustering every point. The
// plane's pixels are first joined into pieces through neighbouring pixels (8-connected, within
// the tolerance), row by row as runs of consecutive pixels; two pieces belong to one patch when
// points of them lie within the tolerance, and for pieces of one plane the nearest points of two
// pieces lie on their borders, so only the border pixels (a 4-neighbour off the plane or outside
// the image) are clustered in 3D. Gives the patch and its border pixels, whose convex hull is the
// patch's.
struct Patch {
    Indices points;  // ascending
    Indices border;  // ascending
};

struct PixelRun {
    std::uint32_t v, u0, u1;  // row, first and last column (inclusive)
};

Patch LargestPatchOrganized(const PointCloud& cloud, const Indices& on_plane, float tolerance,
                            int num_threads) {
    const std::size_t w = cloud.width, h = cloud.height;
    constexpr std::size_t kRowGrain = 16;
    std::vector<std::uint8_t> in(cloud.size(), 0);
    ParallelFor(
        on_plane.size(), num_threads, [&](std::size_t k) { in[on_plane[k]] = 1; }, 16384);
    const float tol_sq = tolerance * tolerance;
    auto near = [&](std::size_t i, std::size_t j) {
        return (cloud.points[i] - cloud.points[j]).squaredNorm() <= tol_sq;
    };
    // Runs of plane pixels along each row, cut where two neighbours are too far apart (rows in
    // parallel, joined in row order).
    std::vector<std::vector<PixelRun>> row_runs(h);
    ParallelFor(
        h, num_threads,
        [&](std::size_t v) {
            std::vector<PixelRun>& out = row_runs[v];
            const std::size_t row = v * w;
            for (std::size_t u = 0; u < w; ++u) {
                if (in[row + u] == 0) continue;
                if (u > 0 && in[row + u - 1] != 0 && near(row + u - 1, row + u)) {
                    out.back().u1 = static_cast<std::uint32_t>(u);
                } else {
                    out.push_back({static_cast<std::uint32_t>(v), static_cast<std::uint32_t>(u),
                                   static_cast<std::uint32_t>(u)});
                }
            }
        },
        kRowGrain);
    std::vector<PixelRun> runs;
    std::vector<std::size_t> row_start(h + 1, 0);
    for (std::size_t v = 0; v < h; ++v) {
        row_start[v] = runs.size();
        runs.insert(runs.end(), row_runs[v].begin(), row_runs[v].end());
    }
    row_start[h] = runs.size();
    row_runs = {};
    // Runs of neighbouring rows touching diagonally or straight, with a pair of pixels within the
    // tolerance, are one piece. The pairs are found for each pair of rows in parallel and joined
    // afterwards (the pieces and their representatives do not depend on the order of joining).
    std::vector<std::vector<std::pair<Index, Index>>> row_links(h);
    ParallelFor(
        h > 0 ? h - 1 : 0, num_threads,
        [&](std::size_t v) {
            std::size_t b = row_start[v + 1];
            for (std::size_t a = row_start[v]; a < row_start[v + 1]; ++a) {
                const PixelRun& ra = runs[a];
                while (b < row_start[v + 2] && runs[b].u1 + 1 < ra.u0) ++b;
                for (std::size_t c = b; c < row_start[v + 2] && runs[c].u0 <= ra.u1 + 1; ++c) {
                    const PixelRun& rb = runs[c];
                    bool linked = false;
                    const std::uint32_t lo = std::max(ra.u0, rb.u0 > 0 ? rb.u0 - 1 : 0);
                    const std::uint32_t hi = std::min(ra.u1, rb.u1 + 1);
                    for (std::uint32_t u = lo; u <= hi && !linked; ++u) {
                        const std::size_t i = v * w + u;
                        for (std::uint32_t x = u > rb.u0 ? u - 1 : rb.u0;
                             x <= std::min(u + 1, rb.u1); ++x) {
                            if (near(i, (v + 1) * w + x)) {
                                linked = true;
                                break;
                            }
                        }
                    }
                    if (linked)
                        row_links[v].emplace_back(static_cast<Index>(a), static_cast<Index>(c));
                }
            }
        },
        kRowGrain);
    detail::DisjointSets pieces(runs.size());
    for (const auto& links : row_links)
        for (const auto& [a, c] : links) pieces.Unite(a, c);
    row_links = {};
    // Border pixels and their runs (rows in parallel, joined in row order: ascending).
    struct BorderPixel {
        Index pixel;
        std::uint32_t run;
    };
    std::vector<std::vector<BorderPixel>> row_border(h);
    ParallelFor(
        h, num_threads,
        [&](std::size_t v) {
            for (std::size_t r = row_start[v]; r < row_start[v + 1]; ++r) {
                const PixelRun& run = runs[r];
                const std::size_t row = v * w;
                for (std::uint32_t u = run.u0; u <= run.u1; ++u) {
                    const std::size_t i = row + u;
                    const bool inner = u > run.u0 && u < run.u1 && v > 0 && v + 1 < h &&
                                       in[i - w] != 0 && in[i + w] != 0;
                    if (!inner)
                        row_border[v].push_back(
                            {static_cast<Index>(i), static_cast<std::uint32_t>(r)});
                }
            }
        },
        kRowGrain);
    Indices border;
    std::vector<std::uint32_t> border_run;
    for (const auto& row : row_border) {
        for (const BorderPixel& b : row) {
            border.push_back(b.pixel);
            border_run.push_back(b.run);
        }
    }
    row_border = {};
    const ClusteringResult linked = EuclideanClusteringGrid(
        cloud, {.tolerance = tolerance, .subset = border, .compute_labels = true});
    // Border pixels of one 3D cluster join their pieces.
    std::vector<std::int64_t> first_run(linked.clusters.size(), -1);
    for (std::size_t k = 0; k < border.size(); ++k) {
        const std::int32_t c = linked.labels[border[k]];
        if (c < 0) continue;
        auto& f = first_run[static_cast<std::size_t>(c)];
        if (f < 0) {
            f = border_run[k];
        } else {
            pieces.Unite(static_cast<Index>(f), static_cast<Index>(border_run[k]));
        }
    }
    // The patch with the most points; ties: the one with the lowest pixel.
    std::vector<std::size_t> count(runs.size(), 0);
    for (std::size_t r = 0; r < runs.size(); ++r)
        count[pieces.Find(static_cast<Index>(r))] += runs[r].u1 - runs[r].u0 + 1;
    Index best = 0;
    for (std::size_t r = 0; r < runs.size(); ++r)
        if (count[r] > count[best]) best = static_cast<Index>(r);
    Patch patch;
    patch.points.reserve(count[best]);
    for (std::size_t r = 0; r < runs.size(); ++r) {
        if (pieces.Find(static_cast<Index>(r)) != best) continue;
        const std::size_t row = std::size_t{runs[r].v} * w;
        for (std::uint32_t u = runs[r].u0; u <= runs[r].u1; ++u)
            patch.points.push_back(static_cast<Index>(row + u));
    }
    for (std::size_t k = 0; k < border.size(); ++k)
        if (pieces.Find(border_run[k]) == best) patch.border.push_back(border[k]);
    return patch;
}

// Up direction and how strictly the table must follow it: the given one, else world z when the
// cloud has a sensor position, else the camera's -y with the looser camera tilt.
struct UpPrior {
    std::optional<Eigen::Vector3f> axis;
    float max_angle = 0.0f;
    UpSource source = UpSource::kDominant;
};

UpPrior ChooseUp(const PointCloud& cloud, const SupportPlaneParams& params) {
    UpPrior up;
    up.max_angle = params.max_tilt_deg * kDegToRad;
    if (params.up) {
        up.axis = params.up->normalized();
        up.source = UpSource::kGiven;
    } else if (cloud.HasSensorPosition()) {
        up.axis = Eigen::Vector3f::UnitZ();
        up.source = UpSource::kViewpoint;
    } else {
        up.axis = -Eigen::Vector3f::UnitY();
        up.max_angle = params.camera_tilt_deg * kDegToRad;
        up.source = UpSource::kCamera;
    }
    return up;
}

// The strided subsample of the finite points that the candidates are fitted and scored on.
Indices Subsample(const Indices& finite, std::size_t max_samples) {
    Indices sample;
    const std::size_t stride = (finite.size() + max_samples - 1) / max_samples;
    for (std::size_t k = 0; k < finite.size(); k += stride) sample.push_back(finite[k]);
    return sample;
}

// Candidate planes along up, extracted one after another from the subsample (each from the
// points the previous ones left), while they hold at least min_inlier_fraction of it.
class CandidateExtractor {
  public:
    CandidateExtractor(const PointCloud& cloud, const Indices& sample, const UpPrior& up,
                       const SupportPlaneParams& params)
        : cloud_(cloud),
          up_(up),
          params_(params),
          remaining_(sample),
          min_inliers_(static_cast<std::size_t>(
              std::max(3.0f, params.min_inlier_fraction * static_cast<float>(sample.size())))) {}

    /// The next candidate appended to `out`; false when there is none (then none follows).
    bool Next(std::vector<PlaneFit>& out) {
        if (done_ || extracted_ >= params_.max_candidates || remaining_.size() < min_inliers_) {
            done_ = true;
            return false;
        }
        PlaneFitParams fp;
        fp.sac.distance_threshold = params_.distance_threshold;
        fp.sac.seed = params_.seed + static_cast<std::uint64_t>(extracted_);
        fp.sac.num_threads = params_.num_threads;
        fp.axis = up_.axis;
        fp.max_angle = up_.max_angle;
        fp.viewpoint = cloud_.sensor_origin;
        PlaneFit fit = FitPlane(cloud_, remaining_, fp);
        if (!fit.found || fit.inliers.size() < min_inliers_) {
            done_ = true;
            return false;
        }
        ++extracted_;
        Indices rest;
        std::set_difference(remaining_.begin(), remaining_.end(), fit.inliers.begin(),
                            fit.inliers.end(), std::back_inserter(rest));
        remaining_ = std::move(rest);
        // Normal towards the viewpoint: objects stand on the side the sensor sees.
        if (fit.plane.head<3>().dot(cloud_.sensor_origin) + fit.plane.w() < 0.0f)
            fit.plane = -fit.plane;
        out.push_back(std::move(fit));
        return true;
    }

  private:
    const PointCloud& cloud_;
    const UpPrior& up_;
    const SupportPlaneParams& params_;
    Indices remaining_;
    std::size_t min_inliers_;
    int extracted_ = 0;
    bool done_ = false;
};

// The edges of a convex hull on a plane (counter-clockwise seen from its normal `up`), for
// signed distances of points from them.
class HullEdges {
  public:
    HullEdges(const std::vector<Eigen::Vector3f>& hull, const Eigen::Vector3f& up) : hull_(hull) {
        inward_.resize(hull.size());
        for (std::size_t k = 0; k < hull.size(); ++k)
            inward_[k] = up.cross(hull[(k + 1) % hull.size()] - hull[k]).normalized();
    }
    /// The largest distance of p outside an edge's line: negative inside the hull (minus the
    /// distance to the nearest edge), at most the distance to the hull outside it.
    float Outside(const Eigen::Vector3f& p) const {
        float out = -std::numeric_limits<float>::max();
        for (std::size_t k = 0; k < hull_.size(); ++k) out = std::max(out, Beyond(k, p));
        return out;
    }
    /// Whether Outside(p) <= -margin: p lies at least `margin` inside every edge (stops at the
    /// first edge it does not; like Outside, an edge giving NaN does not count).
    bool Inside(const Eigen::Vector3f& p, float margin) const {
        for (std::size_t k = 0; k < hull_.size(); ++k) {
            if (Beyond(k, p) > -margin) return false;
        }
        return true;
    }

  private:
    /// Signed distance of p beyond edge k's line (negative on the hull's side).
    float Beyond(std::size_t k, const Eigen::Vector3f& p) const {
        return -inward_[k].dot(p - hull_[k]);
    }

    const std::vector<Eigen::Vector3f>& hull_;
    std::vector<Eigen::Vector3f> inward_;
};

// What a candidate supports (section 2.4, "by what it supports"): the subsample's points that
// stand above it, inside the hull of its largest patch of inliers (shrunk by a margin, so that a
// wall rising from its edge does not count), no higher than the prism reaches. The top of a box
// holds (almost) nothing; the table holds every object on it. A plane through which the sensor
// sees points below it (a plane through the tops of several objects, with the table seen between
// them) supports nothing: nothing is seen through a table top.
std::size_t CountSupported(const PointCloud& sample_cloud, const Indices& inliers,
                           const Eigen::Vector4f& plane, const Eigen::Vector3f& viewpoint,
                           const SupportPlaneParams& params, const PrismParams& prism) {
    const ClusteringResult patches = EuclideanClusteringGrid(
        sample_cloud, {.tolerance = params.cluster_tolerance, .subset = inliers});
    if (patches.clusters.empty()) return 0;
    const std::vector<Eigen::Vector3f> hull =
        PlaneConvexHull(sample_cloud, patches.clusters.front(), plane);
    if (hull.size() < 3) return 0;
    const Eigen::Vector3f up = plane.head<3>();
    const HullEdges edges(hull, up);
    const float margin = 2.0f * params.distance_threshold;
    auto inside = [&](const Eigen::Vector3f& p) { return edges.Inside(p, margin); };
    const float low = std::max(prism.min_height, params.distance_threshold);
    const float high = std::max(low, prism.max_height);
    const float eye = up.dot(viewpoint) + plane.w();  // > 0: the normal faces the viewpoint
    std::size_t above = 0, through = 0;
    for (const Eigen::Vector3f& p : sample_cloud.points) {
        const float h = up.dot(p) + plane.w();
        if (h >= low && h <= high) {
            above += inside(p) ? 1 : 0;
        } else if (h < -2.0f * params.distance_threshold && eye > 0.0f) {
            // Where the ray from the sensor to p crosses the plane.
            through += inside(viewpoint + (eye / (eye - h)) * (p - viewpoint)) ? 1 : 0;
        }
    }
    return through * 4 > above ? 0 : above;
}

float ViewDistance(const PlaneFit& c, const PointCloud& cloud) {
    return std::abs(c.plane.head<3>().dot(cloud.sensor_origin) + c.plane.w());
}

// A table standing on the floor (SupportPlaneParams::raised_gap): among the candidates
// `eligible` to be one, parallel to candidates[base] and at least raised_gap nearer the
// viewpoint, the one with the highest `score`; `base` when there is none or raised_gap <= 0.
template <typename Eligible, typename Score>
std::size_t RaisedAbove(const std::vector<PlaneFit>& candidates, const PointCloud& cloud,
                        std::size_t base, const SupportPlaneParams& params, Eligible eligible,
                        Score score) {
    if (params.raised_gap <= 0.0f) return base;
    const float base_distance = ViewDistance(candidates[base], cloud);
    std::size_t best = base;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        if (k == base || !eligible(k)) continue;
        const bool parallel =
            std::abs(candidates[k].plane.head<3>().dot(candidates[base].plane.head<3>())) > 0.95f;
        if (parallel && ViewDistance(candidates[k], cloud) <= base_distance - params.raised_gap &&
            (best == base || score(k) > score(best))) {
            best = k;
        }
    }
    return best;
}

// Without support evidence: the largest plane nearest the viewpoint, unless a raised table stands
// on it (see SupportPlaneParams::raised_gap).
std::size_t ChooseByView(const std::vector<PlaneFit>& candidates, const PointCloud& cloud,
                         const SupportPlaneParams& params) {
    std::size_t largest = 0;
    for (const auto& c : candidates) largest = std::max(largest, c.inliers.size());
    std::size_t best = candidates.size();
    float best_distance = 0.0f;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const PlaneFit& c = candidates[k];
        if (static_cast<float>(c.inliers.size()) <
            params.size_ratio_to_compete * static_cast<float>(largest)) {
            continue;
        }
        const float d = ViewDistance(c, cloud);
        if (best == candidates.size() || d < best_distance) {
            best = k;
            best_distance = d;
        }
    }
    // A robot sees the floor around a small table: the largest such candidate wins.
    const auto size = [&](std::size_t k) { return candidates[k].inliers.size(); };
    return RaisedAbove(
        candidates, cloud, best, params,
        [&](std::size_t k) {
            return static_cast<float>(size(k)) >= params.raised_ratio * static_cast<float>(largest);
        },
        size);
}

// CountSupported of candidates over the subsample, which it holds as a cloud of its own so that
// hulls and prisms touch only its points.
class SupportCounter {
  public:
    SupportCounter(const PointCloud& cloud, const Indices& sample, const SupportPlaneParams& params,
                   const PrismParams& prism)
        : cloud_(cloud), sample_(sample), params_(params), prism_(prism) {
        sample_cloud_.points.reserve(sample.size());
        for (Index i : sample) sample_cloud_.points.push_back(cloud.points[i]);
        sample_cloud_.SetUnorganized();
    }

    std::size_t Count(const PlaneFit& candidate) const {
        // The inliers' positions in the sample (both ascending).
        Indices local;
        local.reserve(candidate.inliers.size());
        auto at = sample_.begin();
        for (Index i : candidate.inliers) {
            at = std::lower_bound(at, sample_.end(), i);
            local.push_back(static_cast<Index>(at - sample_.begin()));
        }
        return CountSupported(sample_cloud_, local, candidate.plane, cloud_.sensor_origin, params_,
                              prism_);
    }

  private:
    const PointCloud& cloud_;
    const Indices& sample_;
    const SupportPlaneParams& params_;
    const PrismParams& prism_;
    PointCloud sample_cloud_;
};

// The candidates and what each supports: while the first (the largest plane) is counted, the
// others are extracted beside it; then they are counted in parallel.
std::vector<PlaneFit> CandidatesAndSupport(const PointCloud& cloud, const Indices& sample,
                                           const UpPrior& up, const SupportPlaneParams& params,
                                           const PrismParams& prism,
                                           std::vector<std::size_t>& supported) {
    CandidateExtractor extractor(cloud, sample, up, params);
    std::vector<PlaneFit> candidates;
    supported.clear();
    if (!extractor.Next(candidates)) return candidates;
    const SupportCounter counter(cloud, sample, params, prism);
    std::vector<PlaneFit> others;
    std::size_t first = 0;
    ParallelInvoke(
        params.num_threads, [&] { first = counter.Count(candidates.front()); },
        [&] {
            while (extractor.Next(others)) {
            }
        });
    supported.assign(1 + others.size(), first);
    ParallelFor(
        others.size(), params.num_threads,
        [&](std::size_t k) { supported[k + 1] = counter.Count(others[k]); }, 1);
    for (PlaneFit& fit : others) candidates.push_back(std::move(fit));
    return candidates;
}

// The chosen candidate: the one that supports the most points, when any supports at least
// min_supported of the subsample (ties: the one nearer the viewpoint); else the choice by view.
std::size_t ChooseCandidate(const std::vector<PlaneFit>& candidates, const PointCloud& cloud,
                            const Indices& sample, const SupportPlaneParams& params,
                            const std::vector<std::size_t>& supported) {
    const std::size_t enough = std::max<std::size_t>(
        1, static_cast<std::size_t>(
               std::ceil(params.min_supported_fraction * static_cast<float>(sample.size()))));
    std::size_t best = candidates.size();
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        if (supported[k] < enough) continue;
        if (best == candidates.size() || supported[k] > supported[best] ||
            (supported[k] == supported[best] &&
             ViewDistance(candidates[k], cloud) < ViewDistance(candidates[best], cloud))) {
            best = k;
        }
    }
    if (best == candidates.size()) return ChooseByView(candidates, cloud, params);
    // A supporting plane well above the winner is the table standing on the floor, whatever the
    // floor holds (its legs, chairs): the one that supports the most.
    return RaisedAbove(
        candidates, cloud, best, params, [&](std::size_t k) { return supported[k] >= enough; },
        [&](std::size_t k) { return supported[k]; });
}

// All points of the full cloud within the distance threshold of the plane.
Indices PointsOnPlane(const PointCloud& cloud, const Indices& finite, const Eigen::Vector4f& plane,
                      float distance_threshold, int num_threads) {
    Indices on_plane = ParallelSelect(finite.size(), num_threads, [&](std::size_t k) {
        return std::abs(plane.head<3>().dot(cloud.points[finite[k]]) + plane.w()) <=
               distance_threshold;
    });
    for (Index& k : on_plane) k = finite[k];
    return on_plane;
}

}  // namespace

void SupportPlaneParams::Validate() const { CheckParams(*this); }

SupportPlane FindSupportPlane(const PointCloud& cloud, const SupportPlaneParams& params,
                              const PrismParams& prism) {
    CheckParams(params);
    prism.Validate();
    SupportPlane result;
    const Indices finite = FiniteIndices(cloud, params.num_threads);
    if (finite.size() < 3) return result;

    const UpPrior up = ChooseUp(cloud, params);
    result.up_source = up.source;
    const Indices sample = Subsample(finite, params.max_samples);
    std::vector<std::size_t> supported;
    const std::vector<PlaneFit> candidates =
        CandidatesAndSupport(cloud, sample, up, params, prism, supported);
    result.candidates = static_cast<int>(candidates.size());
    if (candidates.empty()) return result;
    const std::size_t chosen = ChooseCandidate(candidates, cloud, sample, params, supported);
    const Eigen::Vector4f plane = candidates[chosen].plane;

    // All points of the full cloud on the plane, then its largest connected patch.
    const Indices on_plane =
        PointsOnPlane(cloud, finite, plane, params.distance_threshold, params.num_threads);
    Patch table;
    if (cloud.IsOrganized() && !on_plane.empty()) {
        table =
            LargestPatchOrganized(cloud, on_plane, params.cluster_tolerance, params.num_threads);
    } else {
        table.points = LargestPatch(cloud, on_plane, params.cluster_tolerance);
        table.border = table.points;
    }
    if (table.points.size() < 3) return result;
    result.found = true;
    result.plane = plane;
    result.up = plane.head<3>();
    result.hull = PlaneConvexHull(cloud, table.border, plane);
    result.inliers = std::move(table.points);
    result.supported = supported[chosen];
    LogDebug(
        "support plane ({:.3f}, {:.3f}, {:.3f}, {:.3f}) with {} points, supporting {} of {} "
        "sampled points, from {} candidates",
        plane.x(), plane.y(), plane.z(), plane.w(), result.inliers.size(), result.supported,
        sample.size(), result.candidates);
    return result;
}

namespace {

// Objects standing beyond the visible hull (PrismParams::edge_reach), appended to `region`.
void AddObjectsBeyondTheHull(const PointCloud& cloud, const SupportPlane& s,
                             const PrismParams& prism, int num_threads, Indices& region) {
    constexpr float kTouch = 0.03f;       // a cluster reaches this close to the hull [m]
    constexpr float kTolerance = 0.015f;  // points of one cluster [m]
    constexpr float kRise = 0.10f;        // looked at above max_height, to see what rises [m]
    constexpr std::size_t kMinPoints = 50;
    const Eigen::Vector3f up = s.plane.head<3>();
    const HullEdges edges(s.hull, up);
    std::vector<std::uint8_t> in_region(cloud.size(), 0);
    for (Index i : region) in_region[i] = 1;
    std::vector<float> outside_by(cloud.size(), 0.0f);
    const Indices beyond = ParallelSelect(cloud.size(), num_threads, [&](std::size_t i) {
        if (in_region[i] != 0 || !cloud.IsFinite(i)) return false;
        const Eigen::Vector3f& p = cloud.points[i];
        const float h = up.dot(p) + s.plane.w();
        if (h < prism.min_height || h > prism.max_height + kRise) return false;
        const float out = edges.Outside(p);  // outside: at most the distance to the hull
        if (out <= 0.0f || out > prism.edge_reach) return false;
        outside_by[i] = out;
        return true;
    });
    if (beyond.empty()) return;
    const ClusteringResult clusters = EuclideanClusteringGrid(
        cloud, {.tolerance = kTolerance, .min_cluster_size = kMinPoints, .subset = beyond});
    for (const Indices& c : clusters.clusters) {
        bool touches = false, rises = false;
        for (Index i : c) {
            touches = touches || outside_by[i] <= kTouch;
            rises = rises || up.dot(cloud.points[i]) + s.plane.w() > prism.max_height;
        }
        if (touches && !rises) region.insert(region.end(), c.begin(), c.end());
    }
    std::sort(region.begin(), region.end());
}

}  // namespace

TableRegion FindTableRegion(const PointCloud& cloud, const SupportPlaneParams& support,
                            const PrismParams& prism) {
    support.Validate();
    prism.Validate();
    TableRegion region;
    region.support = FindSupportPlane(cloud, support, prism);
    const SupportPlane& s = region.support;
    // A plane that supports nothing (see-through, or nothing stands on it) is no table.
    if (s.found && s.hull.size() >= 3 && s.supported > 0) {
        region.points = PolygonalPrism(cloud, s.plane, s.hull, prism, support.num_threads);
        if (prism.edge_reach > 0.0f && !region.points.empty())
            AddObjectsBeyondTheHull(cloud, s, prism, support.num_threads, region.points);
    }
    if (region.points.empty()) {
        region.support = SupportPlane{};
        region.points = FiniteIndices(cloud, support.num_threads);
    }
    return region;
}

}  // namespace multicue
