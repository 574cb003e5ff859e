#include "multicue/mapping/front_edges.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/mapping/fronts.hpp"

#include "multicue/mapping/front_grid_internal.hpp"

namespace multicue::mapping {

using namespace front_grid_internal;

namespace {

/// Squared distance from q to the nearest point of a footprint.
float Distance2(const std::vector<Eigen::Vector2f>& footprint, const Eigen::Vector2f& q) {
    float best = std::numeric_limits<float>::infinity();
    for (const auto& f : footprint) best = std::min(best, (f - q).squaredNorm());
    return best;
}

float RectIou(const Eigen::Vector2f& a0, const Eigen::Vector2f& a1, const Eigen::Vector2f& b0,
              const Eigen::Vector2f& b1) {
    const Eigen::Vector2f lo = a0.cwiseMax(b0), hi = a1.cwiseMin(b1);
    const float inter = std::max(0.0f, hi.x() - lo.x()) * std::max(0.0f, hi.y() - lo.y());
    const float area = (a1 - a0).prod() + (b1 - b0).prod() - inter;
    return area > 0.0f ? inter / area : 0.0f;
}

}  // namespace

void ImageEdgeParams::Validate() const {
    if (!(low >= 0.0f) || !(high >= low) ||
        !(stretch_quantile >= 0.0f && stretch_quantile < 0.5f)) {
        throw InvalidArgument(fmt::format(
            "image edges: need 0 <= low <= high and stretch_quantile in [0, 0.5), got {}, {}, {}",
            low, high, stretch_quantile));
    }
}

std::vector<std::uint8_t> ImageEdges(const PointCloud& scan, const ImageEdgeParams& p) {
    p.Validate();
    std::vector<std::uint8_t> out(scan.size(), 0);
    if (!scan.IsOrganized() || (!scan.HasColors() && !scan.HasIntensity())) return out;
    const int w = static_cast<int>(scan.width), h = static_cast<int>(scan.height);
    cv::Mat grey(h, w, CV_8UC1, cv::Scalar(0));
    if (scan.HasColors()) {
        for (std::size_t i = 0; i < scan.size(); ++i) {
            const Color& c = scan.colors[i];
            if (!scan.IsFinite(i) || c.a == 0) continue;
            grey.data[i] = static_cast<std::uint8_t>(
                std::clamp(0.299f * c.r + 0.587f * c.g + 0.114f * c.b, 0.0f, 255.0f));
        }
    } else {
        std::vector<float> v;
        for (std::size_t i = 0; i < scan.size(); ++i) {
            if (scan.IsFinite(i) && std::isfinite(scan.intensity[i]))
                v.push_back(scan.intensity[i]);
        }
        if (v.empty()) return out;
        auto quantile = [&](float q) {
            const auto k = static_cast<long>(q * static_cast<float>(v.size() - 1));
            std::nth_element(v.begin(), v.begin() + k, v.end());
            return v[static_cast<std::size_t>(k)];
        };
        const float lo = quantile(p.stretch_quantile), hi = quantile(1.0f - p.stretch_quantile);
        const float scale = hi > lo ? 254.0f / (hi - lo) : 1.0f;
        for (std::size_t i = 0; i < scan.size(); ++i) {
            if (!scan.IsFinite(i) || !std::isfinite(scan.intensity[i])) continue;
            grey.data[i] = static_cast<std::uint8_t>(
                std::clamp(1.0f + (scan.intensity[i] - lo) * scale, 1.0f, 255.0f));
        }
    }
    cv::Mat edges;
    cv::Canny(grey, edges, p.low, p.high);
    for (std::size_t i = 0; i < scan.size(); ++i) out[i] = edges.data[i] ? 1 : 0;
    return out;
}

void FrontEdgeParams::Validate() const {
    auto positive = [](const char* name, float v) {
        if (!(v > 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("front edges: {} must be > 0, got {}", name, v));
        }
    };
    positive("cell", cell);
    positive("recess", recess);
    positive("step", step);
    positive("face_end", face_end);
    positive("min_size", min_size);
    positive("start_reach", start_reach);
    positive("max_extend", max_extend);
    positive("appearance_step", appearance_step);
    if (!(min_support > 0.0f && min_support <= 1.0f) ||
        !(min_coverage >= 0.0f && min_coverage <= 1.0f) || !(margin >= 0.0f) ||
        !(shadow_factor >= 0.0f) || hole_reach < 0 || rounds < 1 ||
        !(same_front_iou > 0.0f && same_front_iou <= 1.0f) || min_points < 1 ||
        !(extend_support > 0.0f && extend_support <= 1.0f)) {
        throw InvalidArgument(fmt::format(
            "front edges: need min_support in (0, 1], min_coverage in [0, 1], margin >= 0, "
            "shadow_factor >= 0, hole_reach >= 0, rounds >= 1, same_front_iou in (0, 1], "
            "min_points >= 1, extend_support in (0, 1] (got {}, {}, {}, {}, {}, {}, {}, {}, {})",
            min_support, min_coverage, margin, shadow_factor, hole_reach, rounds, same_front_iou,
            min_points, extend_support));
    }
}

std::vector<Front> FrontsFromEdges(const PointCloud& cloud, const RoomFrame& frame,
                                   const RoomStructure& s, const std::vector<Fixture>& fixtures,
                                   const FrontEvidence& ev, const FrontEdgeParams& p) {
    p.Validate();
    CheckEvidence(ev, cloud.size());
    std::vector<Front> fronts;
    if (cloud.empty() || fixtures.empty()) return fronts;
    const std::vector<bool> panel = PanelKnobs(fixtures);
    const std::vector<std::uint8_t> is_fixture = FixturePoints(cloud.size(), fixtures);
    // The points measured against each face.
    const std::vector<Indices> face_points = FacePoints(cloud.size(), s, ev);
    for (std::size_t f = 0; f < s.components.size(); ++f) {
        const PlanarComponent& face = s.components[f];
        std::vector<int> mine;
        for (std::size_t x = 0; x < fixtures.size(); ++x) {
            if (fixtures[x].face == static_cast<int>(f) && !panel[x])
                mine.push_back(static_cast<int>(x));
        }
        if (mine.empty() || face_points[f].empty()) continue;
        OutlineGrid g = BuildGrid(cloud, frame, face, face_points[f], ev, is_fixture, p);
        if (g.nu == 0) continue;
        MaskFixtures(g, cloud, frame, face, static_cast<int>(f), fixtures, p);
        struct Rect {
            Eigen::Vector2f lo, hi;
            std::vector<int> fixtures;
            std::vector<Eigen::Vector2f> footprint;
        };
        std::vector<Rect> rects;
        const int margin = static_cast<int>(std::ceil(p.margin / g.cell));
        const int reach = static_cast<int>(std::ceil(p.start_reach / g.cell));
        for (const int x : mine) {
            const Fixture& fx = fixtures[static_cast<std::size_t>(x)];
            std::vector<Eigen::Vector2f> fp;
            Eigen::Vector2f flo = Eigen::Vector2f::Constant(std::numeric_limits<float>::infinity());
            Eigen::Vector2f fhi = -flo;
            for (const Index i : fx.indices) {
                fp.push_back(PlaneCoordinates(face, frame, cloud.points[i]));
                flo = flo.cwiseMin(fp.back());
                fhi = fhi.cwiseMax(fp.back());
            }
            const int u0 = g.U(flo.x()), u1 = g.U(fhi.x()), v0 = g.V(flo.y()), v1 = g.V(fhi.y());
            int left = u0 - reach, right = u1 + reach, bottom = v0 - reach, top = v1 + reach;
            // Across the handle's bar first: its nearest sides (a drawer's top and bottom).
            const bool vertical = std::abs(fx.direction.dot(PlaneV(face, frame))) >
                                  std::abs(fx.direction.dot(PlaneU(face, frame)));
            bool sides_first = fx.type != FixtureType::kHandle || vertical;
            for (int r = 0; r < 2 * p.rounds; ++r, sides_first = !sides_first) {
                if (sides_first) {
                    left = FindSide(g, true, u0 - margin, -1, bottom, top, p);
                    right = FindSide(g, true, u1 + margin, 1, bottom, top, p);
                } else {
                    bottom = FindSide(g, false, v0 - margin, -1, left, right, p);
                    top = FindSide(g, false, v1 + margin, 1, left, right, p);
                }
            }
            Rect rect{{g.UAt(left), g.VAt(bottom)}, {g.UAt(right), g.VAt(top)}, {x}, std::move(fp)};
            if ((rect.hi - rect.lo).minCoeff() < p.min_size) continue;
            bool merged = false;
            for (Rect& other : rects) {
                if (RectIou(rect.lo, rect.hi, other.lo, other.hi) >= p.same_front_iou) {
                    other.fixtures.push_back(x);
                    other.footprint.insert(other.footprint.end(), rect.footprint.begin(),
                                           rect.footprint.end());
                    merged = true;
                    break;
                }
            }
            if (!merged) rects.push_back(std::move(rect));
        }
        // The face's points inside each rectangle; a point in several goes to the nearest
        // fixture.
        std::vector<Indices> members(rects.size());
        std::vector<bool> overlapping(rects.size(), false);
        for (const Index i : face_points[f]) {
            if (is_fixture[i]) continue;
            const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
            int best = -1, inside = 0;
            float bd = std::numeric_limits<float>::infinity();
            for (std::size_t r = 0; r < rects.size(); ++r) {
                if ((q.array() < rects[r].lo.array()).any() ||
                    (q.array() > rects[r].hi.array()).any()) {
                    continue;
                }
                ++inside;
                const float d = Distance2(rects[r].footprint, q);
                if (d < bd) {
                    bd = d;
                    best = static_cast<int>(r);
                }
            }
            if (best < 0) continue;
            members[static_cast<std::size_t>(best)].push_back(i);
            if (inside > 1) overlapping[static_cast<std::size_t>(best)] = true;
        }
        for (std::size_t r = 0; r < rects.size(); ++r) {
            if (members[r].size() < p.min_points) continue;
            Front fr;
            fr.face = static_cast<int>(f);
            fr.fixtures = rects[r].fixtures;
            std::sort(members[r].begin(), members[r].end());
            fr.indices = std::move(members[r]);
            SetFrontRectangle(fr, face, frame, rects[r].lo, rects[r].hi);
            fr.overlapping = overlapping[r];
            fr.model_iterations = p.rounds;
            fronts.push_back(std::move(fr));
        }
    }
    return fronts;
}

}  // namespace multicue::mapping
