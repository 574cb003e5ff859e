// Grouping by models (thesis section 5.4.1): merges of objects seen as several surfaces and
// splits of touching objects, decided by how well their models explain the points.

#include "multicue/reconstruction/model_grouping.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>

#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/reconstruction/part_count_model.hpp"

namespace multicue {
namespace {

constexpr float kDegToRad = 3.14159265f / 180.0f;

// The objects after a split stage: kept ones as they were, new ones (Add) to be categorised and
// modelled again.
struct Regrouped {
    std::vector<PerceivedObject> objects;
    GroupingResult result;
    void Keep(PerceivedObject&& o) { objects.push_back(std::move(o)); }
    void Add(PerceivedObject&& o) {
        result.changed.push_back(objects.size());
        objects.push_back(std::move(o));
    }
};

GroupingResult Finish(Regrouped& r, std::vector<PerceivedObject>& objects,
                      std::vector<Category> allowed, const char* what) {
    r.result.split = r.result.changed.size() / 2;
    if (r.result.split > 0) {
        r.result.allowed = std::move(allowed);
        LogDebug("perceive: {} {} split", r.result.split, what);
    }
    objects = std::move(r.objects);
    return std::move(r.result);
}

// Appends b's points (keeping them ascending) and parts to a.
void Absorb(PerceivedObject& a, PerceivedObject& b) {
    Indices both;
    std::merge(a.indices.begin(), a.indices.end(), b.indices.begin(), b.indices.end(),
               std::back_inserter(both));
    a.indices = std::move(both);
    for (auto& part : b.parts) a.parts.push_back(std::move(part));
}

// Share of `points` within `threshold` of a model's surface.
template <typename Distance>
float Explained(const PointCloud& cloud, const Indices& points, float threshold,
                Distance&& distance) {
    std::size_t n = 0;
    for (Index i : points) n += distance(cloud.points[i]) <= threshold;
    return points.empty() ? 0.0f : static_cast<float>(n) / static_cast<float>(points.size());
}

// Whether a point lies inside a container's accepted cylinder or surface of revolution, grown by
// `margin`.
bool InsideModel(const ObjectModel& m, const Eigen::Vector3f& point, float margin) {
    if (m.rotational && m.rotational->found && !m.rotational->heights.empty()) {
        const RotationalModel& r = *m.rotational;
        const Eigen::Vector3f p = point - r.origin;
        const float h = p.dot(r.axis);
        const float h0 = r.heights.front(), h1 = r.heights.back();
        if (h < h0 - margin || h > h1 + margin) return false;
        return (p - h * r.axis).norm() <= r.RadiusAt(std::clamp(h, h0, h1)) + margin;
    }
    if (m.cylinder && m.cylinder->found) {
        const CylinderModel& c = *m.cylinder;
        const Eigen::Vector3f p = point - c.center;
        const Eigen::Vector3f axis = c.axis.normalized();
        const float h = p.dot(axis);
        return std::abs(h) <= 0.5f * c.height + margin &&
               (p - h * axis).norm() <= c.radius + margin;
    }
    return false;
}

// Share of the solid `a` inside the solid `b`, from a 6 x 6 x 6 grid of cell centres in `a`.
float BoxOverlap(const BoxModel& a, const BoxModel& b) {
    constexpr int kSteps = 6;
    int inside = 0;
    const Eigen::Vector3f half_b = 0.5f * b.extents;
    for (int i = 0; i < kSteps; ++i) {
        for (int j = 0; j < kSteps; ++j) {
            for (int k = 0; k < kSteps; ++k) {
                const Eigen::Vector3f u((i + 0.5f) / kSteps - 0.5f, (j + 0.5f) / kSteps - 0.5f,
                                        (k + 0.5f) / kSteps - 0.5f);
                const Eigen::Vector3f p = a.center + a.axes * u.cwiseProduct(a.extents);
                const Eigen::Vector3f q = (b.axes.transpose() * (p - b.center)).cwiseAbs();
                if ((q.array() <= half_b.array()).all()) ++inside;
            }
        }
    }
    return static_cast<float>(inside) / (kSteps * kSteps * kSteps);
}

// Median heights above the plane of an object's horizontal faces (parts of at least
// `min_face_points` whose summed normal is within 10 degrees of up), ascending.
std::vector<float> HorizontalFaceHeights(const PointCloud& cloud, const PerceivedObject& o,
                                         const Eigen::Vector4f& plane,
                                         std::size_t min_face_points) {
    const Eigen::Vector3f up = plane.head<3>();
    const float scale = 1.0f / up.norm();
    const float cos_up = std::cos(10.0f * kDegToRad);
    std::vector<float> faces;
    for (const auto& part : o.parts) {
        if (part.size() < min_face_points) continue;
        Eigen::Vector3f n = Eigen::Vector3f::Zero();
        for (Index i : part) {
            if (cloud.normals[i].allFinite()) n += cloud.normals[i];
        }
        if (!(n.norm() > 0.0f) || std::abs(n.normalized().dot(up * scale)) < cos_up) continue;
        std::vector<float> h;
        h.reserve(part.size());
        for (Index i : part) h.push_back((up.dot(cloud.points[i]) + plane.w()) * scale);
        std::nth_element(h.begin(), h.begin() + static_cast<std::ptrdiff_t>(h.size() / 2), h.end());
        faces.push_back(h[h.size() / 2]);
    }
    std::sort(faces.begin(), faces.end());
    return faces;
}

// The two boxes of the best split of an object's largest parts `big` (sorted by size, at least
// two) when they explain more than `better_than` of `sample`.
struct BoxPair {
    bool found = false;
    BoxModel a, b;
};

BoxPair BestBoxPair(const PointCloud& cloud, const PerceivedObject& o,
                    const std::vector<std::size_t>& big, const Indices& sample,
                    const Eigen::Vector4f& plane, const ModelParams& params, float one_ratio) {
    const TouchingSplitParams& t = params.touching;
    const float threshold = params.box.inlier_threshold;
    auto explained = [&](const BoxModel& box, const Indices& points) {
        return Explained(cloud, points, threshold,
                         [&](const Eigen::Vector3f& p) { return BoxSurfaceDistance(box, p); });
    };
    const std::size_t m = big.size();
    // The parts' points once in ascending order, each with the position of its part in `big`:
    // every split's two groups are then read off in order by one pass.
    std::vector<std::pair<Index, std::uint32_t>> tagged;
    for (std::size_t k = 0; k < m; ++k) {
        for (Index i : o.parts[big[k]]) tagged.emplace_back(i, static_cast<std::uint32_t>(k));
    }
    std::sort(tagged.begin(), tagged.end());
    // Part big[0] is always in group a; mask `s + 1` picks group b among the others. The splits
    // are tried in parallel and judged in order.
    struct Trial {
        bool valid = false;
        BoxModel a, b;
        std::size_t na = 0, nb = 0;
        float both = 0.0f;
    };
    const std::size_t splits = (std::size_t{1} << (m - 1)) - 1;
    std::vector<Trial> trials(splits);
    ParallelFor(
        splits, params.num_threads,
        [&](std::size_t s) {
            const auto mask = static_cast<std::uint32_t>(s + 1);
            Indices ga, gb;
            for (const auto& [i, k] : tagged) {
                const bool in_b = k > 0 && (mask >> (k - 1)) & 1u;
                (in_b ? gb : ga).push_back(i);
            }
            ga = EvenSubset(ga, t.max_points / 2);
            gb = EvenSubset(gb, t.max_points / 2);
            Trial& trial = trials[s];
            trial.na = ga.size();
            trial.nb = gb.size();
            trial.a = FitUprightBox(cloud, ga, plane, params.box);
            if (!trial.a.found || explained(trial.a, ga) < params.min_inlier_ratio) return;
            trial.b = FitUprightBox(cloud, gb, plane, params.box);
            if (!trial.b.found || explained(trial.b, gb) < params.min_inlier_ratio) return;
            if (std::max(BoxOverlap(trial.a, trial.b), BoxOverlap(trial.b, trial.a)) >
                t.max_overlap) {
                return;
            }
            std::size_t n = 0;
            for (Index i : sample) {
                n += std::min(BoxSurfaceDistance(trial.a, cloud.points[i]),
                              BoxSurfaceDistance(trial.b, cloud.points[i])) <= threshold;
            }
            trial.both = static_cast<float>(n) / static_cast<float>(sample.size());
            trial.valid = true;
        },
        1);
    float best = one_ratio + t.min_gain;
    BoxPair pair;
    for (const Trial& trial : trials) {
        if (!trial.valid) continue;
        LogDebug("perceive: touching boxes {} | {}: {:.2f} (one box {:.2f})", trial.na, trial.nb,
                 trial.both, one_ratio);
        if (trial.both > best) {
            best = trial.both;
            pair = {true, trial.a, trial.b};
        }
    }
    return pair;
}

// The object split between two boxes: whole parts go to the box nearer to most of their points,
// loose points to the nearer box.
std::pair<PerceivedObject, PerceivedObject> AssignToBoxes(const PointCloud& cloud,
                                                          PerceivedObject& o,
                                                          const BoxPair& boxes) {
    auto nearer_a = [&](Index i) {
        return BoxSurfaceDistance(boxes.a, cloud.points[i]) <=
               BoxSurfaceDistance(boxes.b, cloud.points[i]);
    };
    std::vector<bool> part_to_a(o.parts.size());
    std::vector<std::pair<Index, bool>> owner;  // part point -> goes to a
    for (std::size_t k = 0; k < o.parts.size(); ++k) {
        std::size_t to_a = 0;
        for (Index i : o.parts[k]) to_a += nearer_a(i);
        part_to_a[k] = 2 * to_a >= o.parts[k].size();
        for (Index i : o.parts[k]) owner.emplace_back(i, part_to_a[k]);
    }
    std::sort(owner.begin(), owner.end());
    PerceivedObject pa, pb;
    for (Index i : o.indices) {
        const auto it = std::lower_bound(owner.begin(), owner.end(), std::pair{i, false});
        const bool to_a = it != owner.end() && it->first == i ? it->second : nearer_a(i);
        (to_a ? pa : pb).indices.push_back(i);
    }
    for (std::size_t k = 0; k < o.parts.size(); ++k) {
        (part_to_a[k] ? pa : pb).parts.push_back(o.parts[k]);
    }
    return {std::move(pa), std::move(pb)};
}

// The merged objects of the groups of `objects` in `groups`: each group takes the place of its
// first member; `changed` lists the groups that grew.
GroupingResult MergeGroups(std::vector<PerceivedObject>& objects, detail::DisjointSets& groups) {
    const std::size_t n = objects.size();
    std::vector<PerceivedObject> merged;
    std::vector<std::size_t> slot(n, n);
    GroupingResult result;
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t r = groups.Find(static_cast<Index>(k));
        if (slot[r] == n) {
            slot[r] = merged.size();
            merged.push_back(std::move(objects[k]));
            continue;
        }
        Absorb(merged[slot[r]], objects[k]);
        result.changed.push_back(slot[r]);
    }
    std::sort(result.changed.begin(), result.changed.end());
    result.changed.erase(std::unique(result.changed.begin(), result.changed.end()),
                         result.changed.end());
    result.merged = n - merged.size();
    objects = std::move(merged);
    return result;
}

}  // namespace

bool CoaxialSameRadius(const CylinderModel& a, const CylinderModel& b,
                       const ConcentricMergeParams& params) {
    const Eigen::Vector3f axis = a.axis.normalized();
    const Eigen::Vector3f d = b.center - a.center;
    return std::abs(axis.dot(b.axis.normalized())) >= std::cos(params.angle_deg * kDegToRad) &&
           (d - d.dot(axis) * axis).norm() <= params.distance &&
           std::abs(a.radius - b.radius) <= params.radius_ratio * std::max(a.radius, b.radius);
}

GroupingResult MergeConcentricObjects(std::vector<PerceivedObject>& objects,
                                      const ConcentricMergeParams& params) {
    params.Validate();
    const std::size_t n = objects.size();
    if (!params.enabled || n < 2) return {};
    auto cylinder = [&](std::size_t k) -> const CylinderModel* {
        const auto& m = objects[k].model;
        return m.cylinder && m.cylinder->found ? &*m.cylinder : nullptr;
    };
    detail::DisjointSets groups(n);
    bool any = false;
    for (std::size_t i = 0; i < n; ++i) {
        const CylinderModel* a = cylinder(i);
        if (a == nullptr) continue;
        for (std::size_t j = i + 1; j < n; ++j) {
            const CylinderModel* b = cylinder(j);
            if (b == nullptr || !CoaxialSameRadius(*a, *b, params)) continue;
            const float along = (b->center - a->center).dot(a->axis.normalized());
            if (std::abs(along) > 0.5f * (a->height + b->height)) continue;  // stacked
            groups.Unite(static_cast<Index>(i), static_cast<Index>(j));
            any = true;
        }
    }
    if (!any) return {};
    GroupingResult result = MergeGroups(objects, groups);
    LogDebug("perceive: {} concentric objects merged", result.merged);
    return result;
}

GroupingResult MergeContainedObjects(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                                     const ContainedMergeParams& params) {
    params.Validate();
    const std::size_t n = objects.size();
    if (!params.enabled || n < 2) return {};
    std::vector<std::size_t> order(n);
    for (std::size_t k = 0; k < n; ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return objects[a].indices.size() > objects[b].indices.size();
    });
    std::vector<std::size_t> into(n, n);
    for (std::size_t x = 0; x < n; ++x) {
        const std::size_t a = order[x];
        const ObjectModel& m = objects[a].model;
        if (into[a] != n || !m.accepted) continue;
        if (!(m.rotational && m.rotational->found) && !(m.cylinder && m.cylinder->found)) continue;
        for (std::size_t y = x + 1; y < n; ++y) {
            const std::size_t b = order[y];
            if (into[b] != n) continue;
            std::size_t in = 0;
            for (Index i : objects[b].indices) in += InsideModel(m, cloud.points[i], params.margin);
            if (static_cast<float>(in) >=
                params.min_share * static_cast<float>(objects[b].indices.size())) {
                into[b] = a;
            }
        }
    }
    // Containers keep their places; contained objects join them in their own order.
    std::vector<PerceivedObject> out;
    std::vector<std::size_t> slot(n, n);
    GroupingResult result;
    for (std::size_t k = 0; k < n; ++k) {
        if (into[k] != n) continue;
        slot[k] = out.size();
        out.push_back(std::move(objects[k]));
    }
    for (std::size_t k = 0; k < n; ++k) {
        if (into[k] == n) continue;
        Absorb(out[slot[into[k]]], objects[k]);
        result.changed.push_back(slot[into[k]]);
    }
    std::sort(result.changed.begin(), result.changed.end());
    result.changed.erase(std::unique(result.changed.begin(), result.changed.end()),
                         result.changed.end());
    result.merged = n - out.size();
    if (result.merged > 0) {
        LogDebug("perceive: {} objects joined the container they lie in", result.merged);
    }
    objects = std::move(out);
    return result;
}

GroupingResult SplitStackedBoxes(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                                 const Eigen::Vector4f& plane, const ModelParams& params,
                                 std::size_t min_object_points) {
    const StackedSplitParams& s = params.stacked;
    s.Validate();
    params.box.Validate();
    const Eigen::Vector3f up = plane.head<3>();
    if (!s.enabled || objects.empty() || !(up.norm() > 0.5f)) return {};
    const float scale = 1.0f / up.norm();
    auto height = [&](Index i) { return (up.dot(cloud.points[i]) + plane.w()) * scale; };
    Regrouped out;
    for (auto& o : objects) {
        const Category c = o.category.category;
        if ((c != Category::kBox && c != Category::kFlat) || !cloud.HasNormals()) {
            out.Keep(std::move(o));
            continue;
        }
        const std::vector<float> faces = HorizontalFaceHeights(cloud, o, plane, s.min_face_points);
        if (faces.size() < 2 || faces.front() < s.min_step ||
            faces.back() - faces.front() < s.min_step) {
            out.Keep(std::move(o));
            continue;
        }
        const float cut = faces.front() + 0.5f * s.min_step;
        PerceivedObject lower, upper;
        for (Index i : o.indices) (height(i) <= cut ? lower : upper).indices.push_back(i);
        for (const auto& part : o.parts) {
            Indices a, b;
            for (Index i : part) (height(i) <= cut ? a : b).push_back(i);
            if (!a.empty()) lower.parts.push_back(std::move(a));
            if (!b.empty()) upper.parts.push_back(std::move(b));
        }
        if (lower.indices.size() < min_object_points || upper.indices.size() < min_object_points) {
            out.Keep(std::move(o));
            continue;
        }
        const float one = FitUprightBox(cloud, o.indices, plane, params.box).inlier_ratio;
        const float n_low = static_cast<float>(lower.indices.size());
        const float n_up = static_cast<float>(upper.indices.size());
        const float two =
            (FitUprightBox(cloud, lower.indices, plane, params.box).inlier_ratio * n_low +
             FitUprightBox(cloud, upper.indices, plane, params.box).inlier_ratio * n_up) /
            (n_low + n_up);
        if (two < one + s.min_gain) {
            out.Keep(std::move(o));
            continue;
        }
        out.Add(std::move(lower));
        out.Add(std::move(upper));
    }
    return Finish(out, objects, {Category::kBox, Category::kFlat}, "stacked objects");
}

GroupingResult SplitTouchingBoxes(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                                  const Eigen::Vector4f& plane, const ModelParams& params,
                                  std::size_t min_object_points) {
    const TouchingSplitParams& t = params.touching;
    t.Validate();
    params.box.Validate();
    params.part_counts.Validate();
    if (!(params.several_min_ratio >= 0.0f)) {
        throw InvalidArgument("several_min_ratio must be >= 0");
    }
    if (!t.enabled || objects.empty() || !(plane.head<3>().norm() > 0.5f) || !cloud.HasNormals()) {
        return {};
    }
    const float threshold = params.box.inlier_threshold;
    Regrouped out;
    for (auto& o : objects) {
        const Category c = o.category.category;
        const bool boxy = c == Category::kBox || c == Category::kFlat;
        const Indices sample = EvenSubset(o.indices, t.max_points);
        BoxModel one;
        if (boxy) one = FitUprightBox(cloud, sample, plane, params.box);
        const float one_ratio =
            one.found
                ? Explained(cloud, sample, threshold,
                            [&](const Eigen::Vector3f& p) { return BoxSurfaceDistance(one, p); })
                : 0.0f;
        std::vector<std::size_t> big;
        for (std::size_t k = 0; k < o.parts.size(); ++k) {
            if (o.parts[k].size() >= t.min_part_points) big.push_back(k);
        }
        const double several =
            TwoObjectsLikelihoodRatio(ObjectTypeOf(c), o.parts.size(), params.part_counts);
        if (!boxy || !one.found || one_ratio >= params.min_inlier_ratio || big.size() < 2 ||
            several < params.several_min_ratio) {
            out.Keep(std::move(o));
            continue;
        }
        std::sort(big.begin(), big.end(), [&](std::size_t a, std::size_t b) {
            return o.parts[a].size() > o.parts[b].size() ||
                   (o.parts[a].size() == o.parts[b].size() && a < b);
        });
        if (big.size() > static_cast<std::size_t>(t.max_parts)) {
            big.resize(static_cast<std::size_t>(t.max_parts));
        }
        const BoxPair boxes = BestBoxPair(cloud, o, big, sample, plane, params, one_ratio);
        if (!boxes.found) {
            out.Keep(std::move(o));
            continue;
        }
        auto [pa, pb] = AssignToBoxes(cloud, o, boxes);
        if (pa.indices.size() < min_object_points || pb.indices.size() < min_object_points) {
            out.Keep(std::move(o));
            continue;
        }
        out.Add(std::move(pa));
        out.Add(std::move(pb));
    }
    return Finish(out, objects, {Category::kBox, Category::kFlat}, "touching boxes");
}

GroupingResult SplitTouchingRound(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                                  const Eigen::Vector4f& plane, const ModelParams& params,
                                  std::size_t min_object_points) {
    const TouchingSplitParams& t = params.touching;
    t.Validate();
    params.cylinder.Validate();
    params.concentric.Validate();
    params.part_counts.Validate();
    if (!t.round_enabled || objects.empty() || !cloud.HasNormals()) return {};
    const float threshold = params.cylinder.inlier_threshold;
    // The cylinders' consensus scoring stays within the threads the objects are given.
    CylinderModelParams cylinder = params.cylinder;
    cylinder.sac.num_threads = params.num_threads;
    auto explained = [&](const CylinderModel& m, const Indices& points) {
        return Explained(cloud, points, threshold,
                         [&](const Eigen::Vector3f& p) { return CylinderSurfaceDistance(m, p); });
    };
    auto gather = [](const std::vector<Indices>& parts) {
        Indices all;
        for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
        std::sort(all.begin(), all.end());
        return all;
    };
    // Each object is judged on its own, the objects in parallel; the regrouping follows in
    // their order.
    struct Split {
        bool done = false;
        PerceivedObject a, b;
    };
    std::vector<Split> splits(objects.size());
    ParallelFor(
        objects.size(), params.num_threads,
        [&](std::size_t k) {
            const PerceivedObject& o = objects[k];
            const Category c = o.category.category;
            const bool round =
                c == Category::kSphere || c == Category::kCylinder || c == Category::kOther;
            const double several =
                TwoObjectsLikelihoodRatio(ObjectTypeOf(c), o.parts.size(), params.part_counts);
            if (!round || o.parts.size() < 2 || several < params.several_min_ratio) return;
            const CylinderModel one = FitObjectCylinder(cloud, o.indices, plane, cylinder);
            const float one_ratio = one.found ? explained(one, o.indices) : 0.0f;
            if (!one.found || one_ratio >= params.min_inlier_ratio) return;
            std::vector<Indices> pa, pb;
            for (const auto& part : o.parts) {
                (2.0f * explained(one, part) >= 1.0f ? pa : pb).push_back(part);
            }
            const Indices ga = gather(pa), gb = gather(pb);
            if (ga.size() < min_object_points || gb.size() < min_object_points) return;
            // The second group's cylinder only when the first one's explains its group.
            const CylinderModel a = FitObjectCylinder(cloud, ga, plane, cylinder);
            if (!a.found || explained(a, ga) < params.min_inlier_ratio) return;
            const CylinderModel b = FitObjectCylinder(cloud, gb, plane, cylinder);
            if (!b.found || explained(b, gb) < params.min_inlier_ratio) return;
            std::size_t n = 0;
            for (Index i : o.indices) {
                n += std::min(CylinderSurfaceDistance(a, cloud.points[i]),
                              CylinderSurfaceDistance(b, cloud.points[i])) <= threshold;
            }
            const float both = static_cast<float>(n) / static_cast<float>(o.indices.size());
            const bool concentric = CoaxialSameRadius(a, b, params.concentric);
            LogDebug("perceive: touching round {} | {}: {:.2f} (one cylinder {:.2f}){}", ga.size(),
                     gb.size(), both, one_ratio, concentric ? ", concentric" : "");
            if (concentric || both < one_ratio + t.min_gain) return;
            // Points outside the parts go to the nearer cylinder.
            Split& split = splits[k];
            split.done = true;
            split.a.parts = std::move(pa);
            split.b.parts = std::move(pb);
            for (Index i : o.indices) {
                const bool to_a = std::binary_search(ga.begin(), ga.end(), i) ||
                                  (!std::binary_search(gb.begin(), gb.end(), i) &&
                                   CylinderSurfaceDistance(a, cloud.points[i]) <=
                                       CylinderSurfaceDistance(b, cloud.points[i]));
                (to_a ? split.a : split.b).indices.push_back(i);
            }
        },
        1);
    Regrouped out;
    for (std::size_t k = 0; k < objects.size(); ++k) {
        if (!splits[k].done) {
            out.Keep(std::move(objects[k]));
            continue;
        }
        out.Add(std::move(splits[k].a));
        out.Add(std::move(splits[k].b));
    }
    return Finish(out, objects, {}, "touching round objects");
}

}  // namespace multicue
