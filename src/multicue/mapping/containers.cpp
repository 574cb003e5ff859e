#include "multicue/mapping/containers.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include <fmt/format.h>

#include "multicue/core/disjoint_sets.hpp"
#include "multicue/core/exceptions.hpp"

namespace multicue::mapping {
namespace {

enum Feature : std::size_t {
    kFronts,
    kDrawers,
    kSideHinged,
    kBottomHinged,
    kTopHinged,
    kHandles,
    kKnobs,
    kWidth,
    kHeight,
    kBottom,
    kTop,
    kAspect,
    kHandleLength,
    kBrightness,
    kTexture,
    kTableAbove,
    kWorktopAbove,
    kNumFeatures
};

/// How a front is hinged, from its articulation.
enum class Hinging { kNone, kDrawer, kSide, kBottom, kTop };

Hinging HingingOf(const Front& f) {
    const Articulation& a = f.articulation;
    if (a.type == JointType::kPrismatic) return Hinging::kDrawer;
    if (a.type != JointType::kRevolute) return Hinging::kNone;
    if (std::abs(a.axis.dot(f.v_axis)) > 0.7f) return Hinging::kSide;
    return (a.origin - f.center).dot(f.v_axis) < 0 ? Hinging::kBottom : Hinging::kTop;
}

}  // namespace

const std::vector<std::string>& ContainerTypeNames() {
    static const std::vector<std::string> names = {"cupboard", "drawer_unit", "oven", "dishwasher",
                                                   "fridge",   "microwave",   "table"};
    return names;
}

const std::vector<std::string>& ContainerFeatureNames() {
    static const std::vector<std::string> names = {
        "fronts",        "drawers",    "side_hinged", "bottom_hinged", "top_hinged",   "handles",
        "knobs",         "width",      "height",      "bottom",        "top",          "aspect",
        "handle_length", "brightness", "texture",     "table_above",   "worktop_above"};
    return names;
}

void ContainerParams::Validate() const {
    if (!(stack_gap >= 0.0f) || !(stack_overlap > 0.0f && stack_overlap <= 1.0f) ||
        !(pair_tolerance >= 0.0f) || !(default_depth > 0.0f) || !(knob_reach >= 0.0f)) {
        throw InvalidArgument(fmt::format(
            "containers: need stack_gap >= 0, stack_overlap in (0, 1], pair_tolerance >= 0, "
            "default_depth > 0, knob_reach >= 0 (got {}, {}, {}, {}, {})",
            stack_gap, stack_overlap, pair_tolerance, default_depth, knob_reach));
    }
}

void GroupFurniture(KitchenMap& map, const ContainerParams& p) {
    p.Validate();
    map.furniture.clear();
    map.kitchenettes.clear();
    const std::size_t n = map.fronts.size();
    detail::DisjointSets pieces(n);
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = i + 1; j < n; ++j) {
            const Front& a = map.fronts[i];
            const Front& b = map.fronts[j];
            if (a.face != b.face) continue;
            const float overlap_u = std::min(a.max.x(), b.max.x()) - std::max(a.min.x(), b.min.x());
            const float narrower = std::min(a.max.x() - a.min.x(), b.max.x() - b.min.x());
            const float gap_v = std::max(a.min.y(), b.min.y()) - std::min(a.max.y(), b.max.y());
            bool link =
                narrower > 0 && overlap_u >= p.stack_overlap * narrower && gap_v <= p.stack_gap;
            // Two doors side by side hinged at their outer edges: one double-door cupboard.
            const Hinging ha = HingingOf(a), hb = HingingOf(b);
            if (!link && ha == Hinging::kSide && hb == Hinging::kSide) {
                const Front& l = a.min.x() < b.min.x() ? a : b;
                const Front& r = a.min.x() < b.min.x() ? b : a;
                const float gap_u = r.min.x() - l.max.x();
                const bool outer = (l.articulation.origin.dot(l.u_axis) < l.center.dot(l.u_axis)) &&
                                   (r.articulation.origin.dot(r.u_axis) > r.center.dot(r.u_axis));
                link = outer && gap_u <= p.stack_gap && gap_u > -p.stack_gap &&
                       std::abs(l.min.y() - r.min.y()) <= p.pair_tolerance &&
                       std::abs(l.max.y() - r.max.y()) <= p.pair_tolerance;
            }
            if (link) pieces.Unite(static_cast<Index>(i), static_cast<Index>(j));
        }
    }
    std::vector<int> piece_of(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        const Index root = pieces.Find(static_cast<Index>(i));
        if (piece_of[root] < 0) {
            piece_of[root] = static_cast<int>(map.furniture.size());
            map.furniture.emplace_back();
        }
        const int k = piece_of[root];
        map.furniture[static_cast<std::size_t>(k)].fronts.push_back(static_cast<int>(i));
        map.fronts[i].furniture = k;
    }
    // Boxes: the fronts' extent on the face, as deep as the face stands in front of a parallel
    // wall (or the default depth).
    for (Furniture& f : map.furniture) {
        const Front& first = map.fronts[static_cast<std::size_t>(f.fronts.front())];
        f.face = first.face;
        Eigen::Vector2f lo = first.min, hi = first.max;
        for (const int i : f.fronts) {
            lo = lo.cwiseMin(map.fronts[static_cast<std::size_t>(i)].min);
            hi = hi.cwiseMax(map.fronts[static_cast<std::size_t>(i)].max);
        }
        const Eigen::Vector3f nrm = first.normal;
        const float face_offset = nrm.dot(first.center);
        float depth = p.default_depth;
        for (std::size_t c = 0; c < map.components.size(); ++c) {
            const PlanarComponent& w = map.components[c];
            if (w.label != MapClass::kWall || w.plane.head<3>().dot(nrm) < 0.95f) continue;
            const float d = face_offset + w.plane.w();  // distance in front of the wall
            if (d > 0.15f && d < 1.3f && (depth == p.default_depth || d < depth)) depth = d;
        }
        const Eigen::Vector2f c = (lo + hi) / 2;
        f.extents = Eigen::Vector3f(hi.x() - lo.x(), depth, hi.y() - lo.y());
        f.axes.col(0) = first.u_axis;
        f.axes.col(1) = nrm;
        f.axes.col(2) = first.v_axis;
        f.center = first.u_axis * c.x() + first.v_axis * c.y() + nrm * (face_offset - depth / 2);
    }
    // Kitchenettes: pieces in front of the same wall (nearest parallel wall behind the face).
    std::vector<int> wall_of(map.furniture.size(), -1);
    for (std::size_t k = 0; k < map.furniture.size(); ++k) {
        const Furniture& f = map.furniture[k];
        const Eigen::Vector3f nrm = f.axes.col(1);
        float best = std::numeric_limits<float>::infinity();
        for (std::size_t c = 0; c < map.components.size(); ++c) {
            const PlanarComponent& w = map.components[c];
            if (w.label != MapClass::kWall || w.plane.head<3>().dot(nrm) < 0.95f) continue;
            const float d = nrm.dot(f.center) + w.plane.w();
            if (d > 0 && d < best) {
                best = d;
                wall_of[k] = static_cast<int>(c);
            }
        }
    }
    for (std::size_t k = 0; k < map.furniture.size(); ++k) {
        int found = -1;
        for (std::size_t e = 0; e < map.kitchenettes.size(); ++e) {
            // Walls of one plane are one kitchenette.
            const int w = map.kitchenettes[e].wall;
            const bool same =
                w == wall_of[k] || (w >= 0 && wall_of[k] >= 0 &&
                                    (map.components[static_cast<std::size_t>(w)].plane -
                                     map.components[static_cast<std::size_t>(wall_of[k])].plane)
                                            .norm() < 0.05f);
            if (same) found = static_cast<int>(e);
        }
        if (found < 0) {
            found = static_cast<int>(map.kitchenettes.size());
            map.kitchenettes.push_back(Kitchenette{{}, wall_of[k]});
        }
        map.kitchenettes[static_cast<std::size_t>(found)].furniture.push_back(static_cast<int>(k));
        map.furniture[k].kitchenette = found;
    }
}

std::vector<float> ContainerFeatures(const KitchenMap& map, std::size_t index,
                                     const ContainerParams& p) {
    const Furniture& f = map.furniture.at(index);
    std::vector<float> x(kNumFeatures, 0.0f);
    const float base = std::isnan(map.floor_height) ? 0.0f : map.floor_height;
    const Eigen::Vector3f up = map.frame.Up();
    float brightness = 0.0f, texture = 0.0f, aspect = 0.0f, handle_length = 0.0f;
    for (const int i : f.fronts) {
        const Front& fr = map.fronts[static_cast<std::size_t>(i)];
        x[kFronts] += 1;
        switch (HingingOf(fr)) {
            case Hinging::kDrawer:
                x[kDrawers] += 1;
                break;
            case Hinging::kSide:
                x[kSideHinged] += 1;
                break;
            case Hinging::kBottom:
                x[kBottomHinged] += 1;
                break;
            case Hinging::kTop:
                x[kTopHinged] += 1;
                break;
            case Hinging::kNone:
                break;
        }
        for (const int fx : fr.fixtures) {
            const Fixture& fix = map.fixtures[static_cast<std::size_t>(fx)];
            if (fix.type == FixtureType::kHandle) {
                x[kHandles] += 1;
                handle_length = std::max(handle_length, fix.length);
            }
        }
        brightness += fr.appearance_median;
        texture += fr.appearance_mad;
        const float w = fr.max.x() - fr.min.x(), h = fr.max.y() - fr.min.y();
        aspect += w > 0 ? h / w : 0.0f;
    }
    const float k = std::max(1.0f, x[kFronts]);
    x[kBrightness] = brightness / k;
    x[kTexture] = texture / k;
    x[kAspect] = aspect / k;
    x[kHandleLength] = handle_length;
    x[kWidth] = f.extents.x();
    x[kHeight] = f.extents.z();
    const float mid = f.center.dot(up);
    x[kBottom] = mid - f.extents.z() / 2 - base;
    x[kTop] = mid + f.extents.z() / 2 - base;
    // Knobs on the same face within reach of the piece (oven and microwave panels).
    const Eigen::Vector3f u = f.axes.col(0);
    for (const Fixture& fix : map.fixtures) {
        if (fix.type != FixtureType::kKnob || fix.face != f.face) continue;
        const Eigen::Vector3f d = fix.center - f.center;
        if (std::abs(d.dot(u)) <= f.extents.x() / 2 + p.knob_reach &&
            std::abs(d.dot(up)) <= f.extents.z() / 2 + p.knob_reach) {
            x[kKnobs] += 1;
        }
    }
    // A table or worktop right above the piece.
    for (const PlanarComponent& c : map.components) {
        if (c.label != MapClass::kTable && c.label != MapClass::kWorktop) continue;
        const float h = -c.plane.w() - base;
        if (h < x[kTop] - 0.05f || h > x[kTop] + 0.3f) continue;
        const Eigen::Vector3f top = f.center + up * (f.extents.z() / 2);
        const float cu = top.dot(map.frame.axes.col(0)), cv = top.dot(map.frame.axes.col(1));
        if (cu >= c.min.x() - 0.1f && cu <= c.max.x() + 0.1f && cv >= c.min.y() - 0.1f &&
            cv <= c.max.y() + 0.1f) {
            (c.label == MapClass::kTable ? x[kTableAbove] : x[kWorktopAbove]) = 1.0f;
        }
    }
    return x;
}

std::string TypeByRules(const std::vector<float>& x) {
    if (x.size() != kNumFeatures) {
        throw InvalidArgument(fmt::format("container rules: {} features, expected {}", x.size(),
                                          static_cast<std::size_t>(kNumFeatures)));
    }
    if (x[kTableAbove] > 0.5f) return "table";
    if (x[kBottomHinged] > 0.5f) return x[kKnobs] > 0.5f ? "oven" : "dishwasher";
    if (x[kBottom] > 0.6f && x[kTop] < 1.4f && x[kHeight] < 0.5f && x[kSideHinged] > 0.5f) {
        return "microwave";
    }
    if (x[kDrawers] > 0.5f && x[kDrawers] == x[kFronts]) return "drawer_unit";
    if (x[kSideHinged] > 0.5f && x[kHeight] > 1.3f && x[kHandleLength] > 0.25f) return "fridge";
    return "cupboard";
}

void CheckContainerClassifier(const ml::Classifier& c) {
    ml::CheckClassifierFor(c, ContainerFeatureNames(), ContainerTypeNames(), "containers",
                           "container");
}

void TypeContainers(KitchenMap& map, const ml::Classifier* classifier, const ContainerParams& p) {
    p.Validate();
    if (classifier != nullptr) CheckContainerClassifier(*classifier);
    for (std::size_t k = 0; k < map.furniture.size(); ++k) {
        const std::vector<float> x = ContainerFeatures(map, k, p);
        Furniture& f = map.furniture[k];
        if (classifier == nullptr) {
            f.type = TypeByRules(x);
            f.confidence = 1.0f;
            continue;
        }
        const ml::FeatureMatrix row =
            Eigen::Map<const ml::FeatureMatrix>(x.data(), 1, static_cast<Eigen::Index>(x.size()));
        const ml::FeatureMatrix proba = classifier->PredictProba(row);
        Eigen::Index best = 0;
        f.confidence = proba.row(0).maxCoeff(&best);
        f.type = classifier->class_names()[static_cast<std::size_t>(best)];
    }
}

}  // namespace multicue::mapping
