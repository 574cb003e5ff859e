#include "multicue/mapping/fronts.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <tuple>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/search/kdtree.hpp"

namespace multicue::mapping {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// Median and MAD of the values of `points` (skipping NaN).
std::pair<float, float> MedianMad(const std::vector<float>& a, const Indices& points) {
    std::vector<float> v;
    v.reserve(points.size());
    for (const Index i : points) {
        if (!std::isnan(a[i])) v.push_back(a[i]);
    }
    if (v.empty()) return {kNaN, kNaN};
    auto median = [](std::vector<float>& x) {
        const auto mid = x.begin() + static_cast<long>(x.size() / 2);
        std::nth_element(x.begin(), mid, x.end());
        return *mid;
    };
    const float m = median(v);
    for (auto& x : v) x = std::abs(x - m);
    return {m, median(v)};
}

/// The model of a front: appearance and offset from the face, each as median and MAD.
struct Model {
    float a = 0.0f, a_mad = 0.0f;  ///< appearance
    float h = 0.0f, h_mad = 0.0f;  ///< offset from the face plane [m]
};

/// Region of face points reachable from `seeds` through neighbours that fit the model.
Indices Grow(const PointCloud& cloud, const KdTree& tree, const std::vector<float>& a,
             const std::vector<float>& h, const Indices& seeds, const Model& m, float alpha,
             float h_alpha, float local_alpha, float radius, std::vector<std::uint32_t>& stamp,
             std::uint32_t round) {
    auto fits = [&](Index i) {
        return !std::isnan(a[i]) && std::abs(a[i] - m.a) <= alpha &&
               std::abs(h[i] - m.h) <= h_alpha;
    };
    Indices region;
    std::deque<Index> queue;
    for (const Index s : seeds) {
        if (stamp[s] == round || !fits(s)) continue;
        stamp[s] = round;
        queue.push_back(s);
    }
    Indices nbrs;
    std::vector<float> d2;
    while (!queue.empty()) {
        const Index i = queue.front();
        queue.pop_front();
        region.push_back(i);
        tree.SearchRadius(cloud.points[i], radius, nbrs, d2);
        for (const Index j : nbrs) {
            // The model, and no edge between the two points.
            if (stamp[j] == round || !fits(j) || std::abs(a[j] - a[i]) > local_alpha) continue;
            stamp[j] = round;
            queue.push_back(j);
        }
    }
    std::sort(region.begin(), region.end());
    return region;
}

/// Squared distance in face coordinates from q to the nearest footprint point.
float FootprintDistance2(const std::vector<Eigen::Vector2f>& footprint, const Eigen::Vector2f& q) {
    float best = std::numeric_limits<float>::infinity();
    for (const auto& f : footprint) best = std::min(best, (f - q).squaredNorm());
    return best;
}

/// Knobs in a row of at least three (a control panel): they open nothing on their own.
std::vector<bool> PanelKnobs(const std::vector<Fixture>& fixtures) {
    std::vector<bool> panel(fixtures.size(), false);
    for (std::size_t i = 0; i < fixtures.size(); ++i) {
        if (fixtures[i].type != FixtureType::kKnob) continue;
        int near = 0;
        for (std::size_t j = 0; j < fixtures.size(); ++j) {
            if (j == i || fixtures[j].type != FixtureType::kKnob ||
                fixtures[j].face != fixtures[i].face) {
                continue;
            }
            const Eigen::Vector3f d = fixtures[j].center - fixtures[i].center;
            near += d.norm() < 0.3f && std::abs(d.z()) < 0.04f;
        }
        panel[i] = near >= 2;
    }
    return panel;
}

}  // namespace

void FrontParams::Validate() const {
    auto positive = [](const char* name, float v) {
        if (!(v > 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("fronts: {} must be > 0, got {}", name, v));
        }
    };
    positive("intensity_scale", intensity_scale);
    positive("seed_max", seed_max);
    positive("grow_radius", grow_radius);
    positive("smooth_radius", smooth_radius);
    positive("local_alpha", local_alpha);
    positive("min_offset_alpha", min_offset_alpha);
    positive("alpha_mads", alpha_mads);
    positive("stable_change", stable_change);
    if (!(seed_min >= 0.0f && seed_min < seed_max)) {
        throw InvalidArgument(fmt::format("fronts: need 0 <= seed_min < seed_max, got {} and {}",
                                          seed_min, seed_max));
    }
    if (!(min_alpha >= 0.0f)) {
        throw InvalidArgument(fmt::format("fronts: min_alpha must be >= 0, got {}", min_alpha));
    }
    if (max_rounds < 1) {
        throw InvalidArgument(fmt::format("fronts: max_rounds must be >= 1, got {}", max_rounds));
    }
    if (!(overlap_share > 0.0f && overlap_share <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("fronts: overlap_share must be in (0, 1], got {}", overlap_share));
    }
    if (!(rect_percentile >= 0.0f && rect_percentile < 0.5f)) {
        throw InvalidArgument(
            fmt::format("fronts: rect_percentile must be in [0, 0.5), got {}", rect_percentile));
    }
    if (min_points < 3) {
        throw InvalidArgument(fmt::format("fronts: min_points must be >= 3, got {}", min_points));
    }
}

std::vector<float> AppearanceValues(const PointCloud& cloud, AppearanceCue cue,
                                    float intensity_scale) {
    if (cue == AppearanceCue::kAuto) {
        cue = cloud.HasColors() ? AppearanceCue::kColor : AppearanceCue::kIntensity;
    }
    std::vector<float> a(cloud.size(), kNaN);
    if (cue == AppearanceCue::kColor) {
        if (!cloud.HasColors())
            throw DataError("fronts: the colour cue needs a cloud with colours");
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const Color& c = cloud.colors[i];
            // Alpha 0 marks points without a colour (a laser scan merged with camera frames).
            a[i] = c.a == 0 ? kNaN : 0.299f * c.r + 0.587f * c.g + 0.114f * c.b;
        }
    } else {
        if (!cloud.HasIntensity()) {
            throw DataError("fronts: the intensity cue needs a cloud with intensity");
        }
        for (std::size_t i = 0; i < cloud.size(); ++i) a[i] = cloud.intensity[i] * intensity_scale;
    }
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.IsFinite(i) || !std::isfinite(a[i])) a[i] = kNaN;
    }
    return a;
}

std::vector<Front> SegmentFronts(const PointCloud& cloud, const RoomFrame& frame,
                                 const RoomStructure& s, const std::vector<Fixture>& fixtures,
                                 const FrontParams& p) {
    p.Validate();
    std::vector<Front> fronts;
    if (cloud.empty() || fixtures.empty()) return fronts;
    const std::vector<float> a_raw = AppearanceValues(cloud, p.cue, p.intensity_scale);
    std::vector<float> a(cloud.size(), kNaN), h(cloud.size(), kNaN);
    PointCloud flat;  // face points in face coordinates (u, v, 0)
    flat.points.assign(cloud.size(), Eigen::Vector3f::Constant(kNaN));
    const std::vector<bool> panel = PanelKnobs(fixtures);
    std::vector<std::uint32_t> stamp(cloud.size(), 0);
    std::uint32_t round = 0;
    for (std::size_t f = 0; f < s.components.size(); ++f) {
        const PlanarComponent& face = s.components[f];
        std::vector<int> mine;
        for (std::size_t x = 0; x < fixtures.size(); ++x) {
            if (fixtures[x].face == static_cast<int>(f) && !panel[x]) {
                mine.push_back(static_cast<int>(x));
            }
        }
        if (mine.empty()) continue;
        // Neighbours in the face plane: depth noise and the depth camera's quantisation steps
        // (centimetres at 2-3 m) must not cut a front into bands.
        for (const Index i : face.indices) {
            const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
            flat.points[i] = Eigen::Vector3f(q.x(), q.y(), 0.0f);
        }
        const KdTree tree(flat, face.indices);
        // Appearance and offset from the face, averaged over each point's neighbourhood: the
        // sensor's noise averages out, the edges between fronts and frames stay.
        {
            Indices nbrs;
            std::vector<float> d2;
            for (const Index i : face.indices) {
                tree.SearchRadius(flat.points[i], p.smooth_radius, nbrs, d2, 64);
                double sa = 0.0, sh = 0.0;
                std::size_t na = 0;
                for (const Index j : nbrs) {
                    sh += face.plane.head<3>().dot(cloud.points[j]) + face.plane.w();
                    if (!std::isnan(a_raw[j])) {
                        sa += a_raw[j];
                        ++na;
                    }
                }
                a[i] = na > 0 ? static_cast<float>(sa / static_cast<double>(na)) : kNaN;
                h[i] =
                    nbrs.empty() ? kNaN : static_cast<float>(sh / static_cast<double>(nbrs.size()));
            }
        }
        std::vector<Eigen::Vector2f> face_uv(face.indices.size());
        for (std::size_t k = 0; k < face.indices.size(); ++k) {
            face_uv[k] = PlaneCoordinates(face, frame, cloud.points[face.indices[k]]);
        }
        std::vector<std::vector<Eigen::Vector2f>> footprints;
        std::vector<Front> grown;
        for (const int x : mine) {
            const Fixture& fx = fixtures[static_cast<std::size_t>(x)];
            std::vector<Eigen::Vector2f> fp;
            for (const Index i : fx.indices)
                fp.push_back(PlaneCoordinates(face, frame, cloud.points[i]));
            // Seeds: face points in a ring around the footprint.
            Indices seeds;
            const float lo2 = p.seed_min * p.seed_min, hi2 = p.seed_max * p.seed_max;
            for (std::size_t k = 0; k < face.indices.size(); ++k) {
                const float d2 = FootprintDistance2(fp, face_uv[k]);
                if (d2 >= lo2 && d2 <= hi2) seeds.push_back(face.indices[k]);
            }
            Front front;
            front.face = static_cast<int>(f);
            front.fixtures = {x};
            Model m;
            std::tie(m.a, m.a_mad) = MedianMad(a, seeds);
            std::tie(m.h, m.h_mad) = MedianMad(h, seeds);
            if (seeds.empty() || std::isnan(m.a) || std::isnan(m.h)) continue;
            Indices region;
            for (int r = 0; r < p.max_rounds; ++r) {
                const float alpha = std::max(p.alpha_mads * m.a_mad, p.min_alpha);
                const float h_alpha = std::max(p.alpha_mads * m.h_mad, p.min_offset_alpha);
                region = Grow(flat, tree, a, h, seeds, m, alpha, h_alpha, p.local_alpha,
                              p.grow_radius, stamp, ++round);
                front.model_iterations = r + 1;
                Model next;
                std::tie(next.a, next.a_mad) = MedianMad(a, region);
                std::tie(next.h, next.h_mad) = MedianMad(h, region);
                if (std::isnan(next.a)) break;
                const bool stable = std::abs(next.a - m.a) < p.stable_change &&
                                    std::abs(next.a_mad - m.a_mad) < p.stable_change;
                m = next;
                if (stable) break;
            }
            const float mad = m.a_mad;
            front.appearance_median = m.a;
            front.appearance_mad = mad;
            front.indices = std::move(region);
            footprints.push_back(std::move(fp));
            grown.push_back(std::move(front));
        }
        // Overlapping regions: marked, merged into one set and split by the nearest footprint.
        const std::size_t g = grown.size();
        std::vector<int> group(g);
        for (std::size_t i = 0; i < g; ++i) group[i] = static_cast<int>(i);
        std::function<int(int)> find = [&](int i) {
            return group[static_cast<std::size_t>(i)] == i
                       ? i
                       : group[static_cast<std::size_t>(i)] =
                             find(group[static_cast<std::size_t>(i)]);
        };
        for (std::size_t i = 0; i < g; ++i) {
            for (std::size_t j = i + 1; j < g; ++j) {
                Indices common;
                std::set_intersection(grown[i].indices.begin(), grown[i].indices.end(),
                                      grown[j].indices.begin(), grown[j].indices.end(),
                                      std::back_inserter(common));
                const std::size_t smaller = std::max<std::size_t>(
                    1, std::min(grown[i].indices.size(), grown[j].indices.size()));
                if (static_cast<float>(common.size()) >=
                    p.overlap_share * static_cast<float>(smaller)) {
                    grown[i].overlapping = grown[j].overlapping = true;
                    group[static_cast<std::size_t>(find(static_cast<int>(i)))] =
                        find(static_cast<int>(j));
                }
            }
        }
        for (std::size_t root = 0; root < g; ++root) {
            if (find(static_cast<int>(root)) != static_cast<int>(root)) continue;
            std::vector<std::size_t> members;
            for (std::size_t i = 0; i < g; ++i) {
                if (find(static_cast<int>(i)) == static_cast<int>(root)) members.push_back(i);
            }
            if (members.size() > 1) {
                Indices all;
                for (const std::size_t i : members) {
                    all.insert(all.end(), grown[i].indices.begin(), grown[i].indices.end());
                }
                std::sort(all.begin(), all.end());
                all.erase(std::unique(all.begin(), all.end()), all.end());
                for (const std::size_t i : members) grown[i].indices.clear();
                for (const Index pt : all) {
                    const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[pt]);
                    std::size_t best = members[0];
                    float bd = std::numeric_limits<float>::infinity();
                    for (const std::size_t i : members) {
                        const float d = FootprintDistance2(footprints[i], q);
                        if (d < bd) {
                            bd = d;
                            best = i;
                        }
                    }
                    grown[best].indices.push_back(pt);
                }
            }
        }
        // Rectangles on the face plane.
        const Eigen::Vector3f u = PlaneU(face, frame), v = PlaneV(face, frame);
        for (Front& fr : grown) {
            if (fr.indices.size() < p.min_points) continue;
            std::vector<float> us, vs;
            for (const Index i : fr.indices) {
                const Eigen::Vector2f q = PlaneCoordinates(face, frame, cloud.points[i]);
                us.push_back(q.x());
                vs.push_back(q.y());
            }
            auto quantile = [](std::vector<float>& x, float q) {
                const auto k = static_cast<long>(std::floor(q * static_cast<float>(x.size() - 1)));
                std::nth_element(x.begin(), x.begin() + k, x.end());
                return x[static_cast<std::size_t>(k)];
            };
            fr.min = {quantile(us, p.rect_percentile), quantile(vs, p.rect_percentile)};
            fr.max = {quantile(us, 1.0f - p.rect_percentile),
                      quantile(vs, 1.0f - p.rect_percentile)};
            fr.u_axis = u;
            fr.v_axis = v;
            fr.normal = face.plane.head<3>();
            const Eigen::Vector2f c = (fr.min + fr.max) / 2;
            // The point of the plane at (u, v) = c: u * c.x + v * c.y + n * (-d).
            fr.center = u * c.x() + v * c.y() - fr.normal * face.plane.w();
            fronts.push_back(std::move(fr));
        }
    }
    return fronts;
}

}  // namespace multicue::mapping
