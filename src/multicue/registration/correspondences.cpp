#include "multicue/registration/correspondences.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/search/organized.hpp"

namespace multicue {
namespace {

constexpr Index kNone = std::numeric_limits<Index>::max();

double Median(std::vector<double>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

}  // namespace

const char* CorrespondenceSearchName(CorrespondenceSearch search) {
    switch (search) {
        case CorrespondenceSearch::kKdTree:
            return "kdtree";
        case CorrespondenceSearch::kProjective:
            return "projective";
        case CorrespondenceSearch::kAuto:
            break;
    }
    return "auto";
}

CorrespondenceSearch ParseCorrespondenceSearch(const std::string& name) {
    if (name == "auto") return CorrespondenceSearch::kAuto;
    if (name == "kdtree") return CorrespondenceSearch::kKdTree;
    if (name == "projective") return CorrespondenceSearch::kProjective;
    throw InvalidArgument(fmt::format(
        "unknown correspondence search '{}' (choices: auto, kdtree, projective)", name));
}

void CorrespondenceParams::Validate() const {
    if (!(max_distance > 0.0f) || !std::isfinite(max_distance)) {
        throw InvalidArgument(
            fmt::format("correspondence max_distance must be > 0, got {}", max_distance));
    }
    if (!(max_normal_angle_deg > 0.0f && max_normal_angle_deg <= 180.0f)) {
        throw InvalidArgument(
            fmt::format("correspondence max_normal_angle_deg must be in (0, 180], got {}",
                        max_normal_angle_deg));
    }
    if (projective_half_window < 0 || projective_half_window > 20) {
        throw InvalidArgument(fmt::format("projective_half_window must be in [0, 20], got {}",
                                          projective_half_window));
    }
}

std::optional<PinholeModel> EstimatePinhole(const PointCloud& organized) {
    if (!organized.IsOrganized() || organized.HasSensorPosition()) return std::nullopt;
    float f = 0.0f;
    try {
        f = EstimateFocalLength(organized);
    } catch (const Error&) {
        return std::nullopt;
    }
    if (!(f > 0.0f) || !std::isfinite(f)) return std::nullopt;
    // Principal point: the median offset u - f x / z over (a stride of) the valid pixels.
    std::vector<double> cu;
    std::vector<double> cv;
    const std::size_t step = std::max<std::size_t>(1, organized.size() / 20000);
    for (std::size_t i = 0; i < organized.size(); i += step) {
        const auto& p = organized.points[i];
        if (!p.allFinite() || !(p.z() > 0.0f)) continue;
        const double u = static_cast<double>(i % organized.width);
        const double v = static_cast<double>(i / organized.width);
        cu.push_back(u - f * p.x() / p.z());
        cv.push_back(v - f * p.y() / p.z());
    }
    if (cu.size() < 100) return std::nullopt;
    PinholeModel m{f, f, Median(cu), Median(cv)};
    // Accept only when the points really lie on their pixels (a tilting laser's organized scan
    // does not).
    std::size_t on_pixel = 0;
    std::size_t checked = 0;
    for (std::size_t i = 0; i < organized.size(); i += step) {
        const auto& p = organized.points[i];
        if (!p.allFinite() || !(p.z() > 0.0f)) continue;
        ++checked;
        const double du = m.fx * p.x() / p.z() + m.cx - static_cast<double>(i % organized.width);
        const double dv = m.fy * p.y() / p.z() + m.cy - static_cast<double>(i / organized.width);
        if (std::abs(du) < 0.5 && std::abs(dv) < 0.5) ++on_pixel;
    }
    if (on_pixel < checked * 9 / 10) return std::nullopt;
    return m;
}

bool CorrespondenceSearcher::NeedsTree(const PointCloud& target,
                                       const CorrespondenceParams& params) {
    if (params.search == CorrespondenceSearch::kKdTree) return true;
    return !EstimatePinhole(target).has_value();
}

CorrespondenceSearcher::CorrespondenceSearcher(const PointCloud& target, const KdTree* tree,
                                               const CorrespondenceParams& params)
    : target_(target), tree_(tree), params_(params) {
    params_.Validate();
    if (params_.search != CorrespondenceSearch::kKdTree) pinhole_ = EstimatePinhole(target);
    if (params_.search == CorrespondenceSearch::kProjective && !pinhole_) {
        throw InvalidArgument(
            "projective correspondences need an organized target frame in its sensor frame "
            "(pinhole camera at the origin, looking along +z)");
    }
    if (!pinhole_ && tree_ == nullptr) {
        throw InvalidArgument("k-d tree correspondences need a k-d tree of the target");
    }
}

bool CorrespondenceSearcher::SearchCached(const Eigen::Vector3f& p, float gate,
                                          NearestCache::Entry& e, Index& index,
                                          float& squared_distance) const {
    // Distances move by at most the query's displacement (triangle inequality); the slack
    // covers the rounding of the single-precision distances.
    constexpr double kSlack = 1e-5;
    const double moved = static_cast<double>((p - e.query).norm());  // NaN when never searched
    // A fresh search looks twice as far as the gate: a point without a partner then learns
    // how far outside the gate it is, and is not searched again until it has moved that far.
    double radius = 2.0 * gate;
    if (moved >= 0.0) {
        if (e.nearest != kNone) {
            const double upper = (e.nearest_distance + moved) * (1.0 + kSlack);
            const double others = (e.second_distance - moved) * (1.0 - kSlack);
            if (upper < others) {
                // Still the strict nearest: only its distance changes.
                squared_distance = KdTree::SquaredDistance(target_.points[e.nearest], p);
                index = e.nearest;
                return squared_distance <= gate * gate;
            }
            // The two old points are still candidates: the farther of them bounds the new
            // search (a positive bound: duplicate points may both lie on the query).
            if (e.second != kNone) {
                const float bound2 = std::max(KdTree::SquaredDistance(target_.points[e.nearest], p),
                                              KdTree::SquaredDistance(target_.points[e.second], p));
                if (bound2 > 0.0f) {
                    radius =
                        std::min(radius, std::sqrt(static_cast<double>(bound2)) * (1.0 + kSlack));
                }
            }
        } else if ((e.nearest_distance - moved) * (1.0 - kSlack) > gate) {
            return false;  // nothing was within a wider ball
        }
    }
    Index found[2];
    float d2[2];
    std::size_t n = tree_->SearchKnnWithin(p, 2, static_cast<float>(radius), found, d2);
    if (radius < 2.0 * gate && n < 2) {  // rounding defeated the bound
        radius = 2.0 * gate;
        n = tree_->SearchKnnWithin(p, 2, static_cast<float>(radius), found, d2);
    }
    e.query = p;
    e.nearest = n > 0 ? found[0] : kNone;
    e.nearest_distance = n > 0 ? std::sqrt(d2[0]) : static_cast<float>(radius);
    e.second = n > 1 ? found[1] : kNone;
    e.second_distance = n > 1 ? std::sqrt(d2[1]) : static_cast<float>(radius);
    if (n == 0 || !(d2[0] <= gate * gate)) return false;
    index = found[0];
    squared_distance = d2[0];
    return true;
}

void CorrespondenceSearcher::Find(const PointCloud& source, const Indices& subset,
                                  const Eigen::Isometry3d& T_target_source, float max_distance,
                                  std::vector<Correspondence>& out, int num_threads,
                                  NearestCache* cache) const {
    const float gate = max_distance > 0.0f ? max_distance : params_.max_distance;
    const float gate2 = gate * gate;
    const bool normal_gate =
        params_.max_normal_angle_deg < 180.0f && source.HasNormals() && target_.HasNormals();
    const float min_cos =
        std::cos(params_.max_normal_angle_deg * static_cast<float>(std::numbers::pi) / 180.0f);
    const Eigen::Isometry3f T = T_target_source.cast<float>();
    const Eigen::Matrix3f R = T.linear();
    std::vector<Index> partner(subset.size(), kNone);
    std::vector<float> dist2(subset.size(), 0.0f);
    const int h = params_.projective_half_window;
    const auto W = static_cast<int>(target_.width);
    const auto H = static_cast<int>(target_.height);
    if (cache != nullptr && cache->entries.size() != subset.size()) {
        cache->entries.assign(subset.size(), NearestCache::Entry{});
    }
    ParallelForChunks(
        subset.size(), num_threads,
        [&](std::size_t begin, std::size_t end) {
            for (std::size_t k = begin; k < end; ++k) {
                const Index i = subset[k];
                const Eigen::Vector3f p = T * source.points[i];
                Index best = kNone;
                float best_d2 = gate2;
                if (pinhole_) {
                    if (!(p.z() > 0.0f)) continue;
                    const double u = pinhole_->fx * p.x() / p.z() + pinhole_->cx;
                    const double v = pinhole_->fy * p.y() / p.z() + pinhole_->cy;
                    const int uc = static_cast<int>(std::lround(u));
                    const int vc = static_cast<int>(std::lround(v));
                    if (uc < -h || vc < -h || uc >= W + h || vc >= H + h) continue;
                    for (int y = std::max(0, vc - h); y <= std::min(H - 1, vc + h); ++y) {
                        const std::size_t row = static_cast<std::size_t>(y) * target_.width;
                        for (int x = std::max(0, uc - h); x <= std::min(W - 1, uc + h); ++x) {
                            const auto& q = target_.points[row + static_cast<std::size_t>(x)];
                            const float d2 = (q - p).squaredNorm();  // NaN compares false
                            if (d2 < best_d2) {
                                best_d2 = d2;
                                best = static_cast<Index>(row + static_cast<std::size_t>(x));
                            }
                        }
                    }
                } else {
                    Index j = 0;
                    float d2 = 0.0f;
                    if ((cache != nullptr ? SearchCached(p, gate, cache->entries[k], j, d2)
                                          : tree_->SearchNearestWithin(p, gate, j, d2))) {
                        best = j;
                        best_d2 = d2;
                    }
                }
                if (best == kNone) continue;
                if (normal_gate) {
                    const auto& ns = source.normals[i];
                    const auto& nt = target_.normals[best];
                    // Points without a normal pass: the gate only rejects what it can judge.
                    if (ns.allFinite() && nt.allFinite() && (R * ns).dot(nt) < min_cos) continue;
                }
                partner[k] = best;
                dist2[k] = best_d2;
            }
        },
        256);
    out.clear();
    for (std::size_t k = 0; k < subset.size(); ++k) {
        if (partner[k] != kNone) out.push_back({subset[k], partner[k], dist2[k]});
    }
}

}  // namespace multicue
