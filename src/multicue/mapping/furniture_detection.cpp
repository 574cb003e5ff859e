#include "multicue/mapping/furniture_detection.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <unordered_set>
#include <utility>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/cell_key.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/filters/voxel_grid.hpp"
#include "multicue/ml/classifier.hpp"

namespace multicue {
namespace {

using Polygon = std::vector<Eigen::Vector2f>;

double MillisecondsSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

float Cross(const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return a.x() * b.y() - a.y() * b.x();
}

float Area(const Polygon& p) {
    float a = 0.0f;
    for (std::size_t i = 0; i < p.size(); ++i) a += Cross(p[i], p[(i + 1) % p.size()]);
    return 0.5f * std::abs(a);
}

// Convex hull (counter-clockwise) by Andrew's monotone chain.
Polygon Hull(std::vector<Eigen::Vector2f> pts) {
    std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) {
        return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
    });
    if (pts.size() < 3) return pts;
    Polygon h(2 * pts.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && Cross(h[k - 1] - h[k - 2], pts[i] - h[k - 2]) <= 0) --k;
        h[k++] = pts[i];
    }
    for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
        while (k >= t && Cross(h[k - 1] - h[k - 2], pts[i] - h[k - 2]) <= 0) --k;
        h[k++] = pts[i];
    }
    h.resize(k - 1);
    return h;
}

// The fitted model's footprint in the world.
Polygon Footprint(const FurnitureCad& cad, const Eigen::Affine3f& T) {
    std::vector<Eigen::Vector2f> pts;
    const std::size_t step = std::max<std::size_t>(1, cad.cloud.size() / 2000);
    for (std::size_t i = 0; i < cad.cloud.size(); i += step)
        pts.push_back((T * cad.cloud.points[i]).head<2>());
    return Hull(std::move(pts));
}

// A fitted model's surface in the world: about 2000 of its points and the cells (of the given
// size) that hold them.
struct PlacedSurface {
    std::vector<Eigen::Vector3i> cells;  // one per point
    std::unordered_set<std::uint64_t> occupied;
};

PlacedSurface PlaceSurface(const PointCloud& model, const Eigen::Affine3f& T, float cell) {
    PlacedSurface s;
    const std::size_t step = std::max<std::size_t>(1, model.size() / 2000);
    for (std::size_t i = 0; i < model.size(); i += step) {
        if (!model.points[i].allFinite()) continue;
        const Eigen::Vector3i c =
            ((T * model.points[i]) / cell).array().floor().cast<int>().matrix();
        s.cells.push_back(c);
        s.occupied.insert(detail::PackCellKey(c));
    }
    return s;
}

// The share of a's points with a point of b in their cell or a neighbouring one (within about
// one to two cells).
float SharedSurface(const PlacedSurface& a, const PlacedSurface& b) {
    if (a.cells.empty()) return 0.0f;
    std::size_t shared = 0;
    for (const Eigen::Vector3i& c : a.cells) {
        bool near = false;
        for (int dz = -1; dz <= 1 && !near; ++dz) {
            for (int dy = -1; dy <= 1 && !near; ++dy) {
                for (int dx = -1; dx <= 1 && !near; ++dx) {
                    near =
                        b.occupied.count(detail::PackCellKey(c + Eigen::Vector3i(dx, dy, dz))) > 0;
                }
            }
        }
        shared += near ? 1 : 0;
    }
    return static_cast<float>(shared) / static_cast<float>(a.cells.size());
}

// The larger of the two shares: how much the two surfaces are one.
float SharedEitherWay(const PlacedSurface& a, const PlacedSurface& b) {
    return std::max(SharedSurface(a, b), SharedSurface(b, a));
}

// The box of a CAD model's finite points in its own frame; empty without any.
Eigen::AlignedBox3f CadBox(const FurnitureCad& cad) {
    Eigen::AlignedBox3f box;
    for (const auto& p : cad.cloud.points) {
        if (p.allFinite()) box.extend(p);
    }
    return box;
}

// The points (world frame, with normals) of a hypothesis's supporting parts whose centres lie
// within `radius` of it.
PointCloud SupportPoints(const FurnitureScene& scene, const FurnitureHypothesis& h, float radius) {
    PointCloud out;
    for (const auto& [view, part] : h.parts) {
        const FurnitureParts& v = scene.views[static_cast<std::size_t>(view)];
        const FurniturePart& fp = v.parts[static_cast<std::size_t>(part)];
        if ((fp.centroid.head<2>() - h.centre).norm() > radius) continue;
        for (Index i : fp.indices) {
            out.points.push_back(v.cloud.points[i]);
            out.normals.push_back(v.cloud.normals[i]);
        }
    }
    out.width = static_cast<std::uint32_t>(out.points.size());
    return out;
}

}  // namespace

// The walls among a view's parts: upright planes reaching above max_top, long enough. A part
// counts as a wall when nearly all its points (kWallInliers) lie within kWallSpread of one upright
// plane: region growing lets a wall's part take in a few points around a corner or of an object
// touching it, and a single such point must not cost the room its wall.
std::vector<FurnitureWall> FindFurnitureWalls(const FurnitureParts& v, float max_top,
                                              float min_length) {
    if (!std::isfinite(max_top) || !(min_length > 0.0f) || !std::isfinite(min_length)) {
        throw InvalidArgument(
            fmt::format("furniture walls: max_top must be finite and min_length > 0, got {} and {}",
                        max_top, min_length));
    }
    constexpr double kWallSpread = 0.1, kWallInliers = 0.95;
    std::vector<FurnitureWall> walls;
    std::vector<Eigen::Vector2d> pts, in;
    for (const auto& part : v.parts) {
        if (part.top <= max_top || part.indices.size() < 20) continue;
        pts.clear();
        for (Index i : part.indices) pts.push_back(v.cloud.points[i].head<2>().cast<double>());
        // The line through points by their mean and principal direction; n its normal.
        Eigen::Vector2d mean, n;
        auto fit = [&](const std::vector<Eigen::Vector2d>& p) {
            mean.setZero();
            for (const auto& q : p) mean += q;
            mean /= static_cast<double>(p.size());
            Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
            for (const auto& q : p) cov += (q - mean) * (q - mean).transpose();
            n = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvectors().col(0);
        };
        auto inliers = [&](std::vector<Eigen::Vector2d>& out) {
            out.clear();
            for (const auto& q : pts) {
                if (std::abs((q - mean).dot(n)) <= kWallSpread) out.push_back(q);
            }
        };
        fit(pts);
        inliers(in);
        if (in.size() < 20) continue;
        fit(in);  // again without the stray points
        inliers(in);
        if (static_cast<double>(in.size()) < kWallInliers * static_cast<double>(pts.size()))
            continue;  // not one upright plane
        if (n.dot(v.sensor_origin.head<2>().cast<double>() - mean) < 0.0) n = -n;
        const Eigen::Vector2d dir(-n.y(), n.x());
        double lo = 1e9, hi = -1e9;
        for (const auto& q : in) {
            lo = std::min(lo, (q - mean).dot(dir));
            hi = std::max(hi, (q - mean).dot(dir));
        }
        if (hi - lo < min_length) continue;
        FurnitureWall w;
        w.point = mean.cast<float>();
        w.normal = n.cast<float>();
        w.lo = static_cast<float>(lo);
        w.hi = static_cast<float>(hi);
        walls.push_back(w);
    }
    return walls;
}

float ConvexIntersectionArea(const Polygon& a, const Polygon& b) {
    if (a.size() < 3 || b.size() < 3) return 0.0f;
    // Sutherland-Hodgman: clip a by every edge of b.
    Polygon out = a;
    for (std::size_t i = 0; i < b.size() && !out.empty(); ++i) {
        const Eigen::Vector2f p = b[i], q = b[(i + 1) % b.size()];
        auto inside = [&](const Eigen::Vector2f& x) { return Cross(q - p, x - p) >= 0.0f; };
        Polygon in = std::move(out);
        out.clear();
        for (std::size_t k = 0; k < in.size(); ++k) {
            const Eigen::Vector2f c = in[k], n = in[(k + 1) % in.size()];
            const bool ci = inside(c), ni = inside(n);
            if (ci) out.push_back(c);
            if (ci != ni) {
                const float t = Cross(q - p, c - p) / (Cross(q - p, c - p) - Cross(q - p, n - p));
                out.push_back(c + t * (n - c));
            }
        }
    }
    return out.size() < 3 ? 0.0f : Area(out);
}

void FurnitureDetectionParams::Validate() const {
    voting.Validate();
    selection.Validate();
    fit.Validate();
    piece.Validate();
    if (!(min_wall_length > 0.0f) || !std::isfinite(min_wall_length)) {
        throw InvalidArgument(fmt::format(
            "furniture detection: min_wall_length must be > 0, got {}", min_wall_length));
    }
    if (!(max_overlap > 0.0f && max_overlap <= 1.0f)) {
        throw InvalidArgument(
            fmt::format("furniture detection: max_overlap must be in (0, 1], got {}", max_overlap));
    }
    if (!(surface_overlap_distance > 0.0f) || !std::isfinite(surface_overlap_distance)) {
        throw InvalidArgument(
            fmt::format("furniture detection: surface_overlap_distance must be > 0, got {}",
                        surface_overlap_distance));
    }
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("furniture detection: num_threads must be >= 0, got {}", num_threads));
    }
    if (fit_models < 1) {
        throw InvalidArgument(
            fmt::format("furniture detection: fit_models must be >= 1, got {}", fit_models));
    }
    for (const auto& [name, v] : {std::pair{"min_confidence", min_confidence},
                                  {"min_confidence_single", min_confidence_single}}) {
        if (!(v >= 0.0f && v <= 1.0f)) {
            throw InvalidArgument(
                fmt::format("furniture detection: {} must be in [0, 1], got {}", name, v));
        }
    }
}

void FurniturePieceParams::Validate() const {
    for (const auto& [name, v] :
         {std::pair{"member_share", member_share}, {"free_share", free_share}}) {
        if (!(v > 0.0f && v <= 1.0f))
            throw InvalidArgument(
                fmt::format("furniture piece: {} must be in (0, 1], got {}", name, v));
    }
    if (!(slice > 0.0f) || !std::isfinite(slice))
        throw InvalidArgument(fmt::format("furniture piece: slice must be > 0, got {}", slice));
    for (const auto& [name, v] :
         {std::pair{"margin", margin}, {"min_growth", min_growth}, {"max_growth", max_growth}}) {
        if (!(v >= 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(
                fmt::format("furniture piece: {} must be finite and >= 0, got {}", name, v));
        }
    }
}

namespace {

// The fitted model's box in the frame of fit.T_world_model: the CAD model's box stretched by
// fit.scale (T_world_model holds the pose as reported, turned or not). Empty without a fit.
Eigen::AlignedBox3f FittedModelBox(const FurnitureCad& cad, const FurnitureFit& fit) {
    if (fit.cad < 0 || !fit.T_world_model.matrix().allFinite() || !fit.scale.allFinite()) return {};
    const Eigen::AlignedBox3f box = CadBox(cad);
    if (box.isEmpty()) return box;
    const Eigen::Vector3f a = box.min().cwiseProduct(fit.scale);
    const Eigen::Vector3f b = box.max().cwiseProduct(fit.scale);
    return {a.cwiseMin(b), a.cwiseMax(b)};
}

bool Taken(const std::vector<FurnitureTakenSpace>& taken, const Eigen::Vector2f& xy) {
    for (const auto& t : taken) {
        if (t.Contains(xy)) return true;
    }
    return false;
}

Eigen::AlignedBox3f PieceBox(const std::vector<const FurnitureParts*>& views,
                             const Eigen::AlignedBox3f& box, const FurnitureFit& fit,
                             const FurniturePieceParams& params,
                             const std::vector<const FurnitureFreeSpace*>& free,
                             const std::vector<FurnitureTakenSpace>& taken) {
    if (box.isEmpty() || !params.grow) return box;
    const Eigen::Isometry3f to_model = fit.T_world_model.inverse();
    const Eigen::Vector3f size = box.sizes();
    const float m = params.margin;
    const float reach = 0.5f * size.head<2>().norm() + m + 1.0f;  // parts' centroids within
    auto inside = [&](const Eigen::Vector3f& q) {
        return q.x() >= box.min().x() - m && q.x() <= box.max().x() + m &&
               q.y() >= box.min().y() - m && q.y() <= box.max().y() + m &&
               q.z() <= box.max().z() + m;
    };
    std::vector<float> xs, ys, zs;
    std::vector<Eigen::Vector3f> q;
    for (const FurnitureParts* v : views) {
        if (v == nullptr) continue;
        for (const FurniturePart& part : v->parts) {
            if (part.indices.empty() || !part.centroid.allFinite() ||
                (part.centroid.head<2>() - fit.T_world_model.translation().head<2>()).norm() >
                    reach)
                continue;
            q.clear();
            std::size_t in = 0, elsewhere = 0;
            for (Index i : part.indices) {
                const Eigen::Vector3f& p = v->cloud.points[i];
                if (!p.allFinite()) continue;
                q.push_back(to_model * p);
                in += inside(q.back()) ? 1 : 0;
                elsewhere += !taken.empty() && Taken(taken, p.head<2>()) ? 1 : 0;
            }
            const float n = static_cast<float>(q.size());
            if (q.empty() || static_cast<float>(in) < params.member_share * n ||
                static_cast<float>(elsewhere) >= params.member_share * n)
                continue;
            for (const auto& r : q) {
                xs.push_back(r.x());
                ys.push_back(r.y());
                zs.push_back(r.z());
            }
        }
    }
    if (xs.empty()) return box;
    auto quantile = [](std::vector<float>& v, double f) {
        const auto k = static_cast<std::size_t>(f * static_cast<double>(v.size() - 1));
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
        return v[k];
    };
    // The parts' extent (2-98 %, against stray points) where it goes beyond the box.
    Eigen::AlignedBox3f grown = box;
    Eigen::Vector2f lo, hi;
    for (int a = 0; a < 2; ++a) {
        std::vector<float>& v = a == 0 ? xs : ys;
        lo[a] = quantile(v, 0.02), hi[a] = quantile(v, 0.98);
        const float most = params.max_growth * size[a];
        if (box.min()[a] - lo[a] > params.min_growth)
            grown.min()[a] = std::max(lo[a], box.min()[a] - most);
        if (hi[a] - box.max()[a] > params.min_growth)
            grown.max()[a] = std::min(hi[a], box.max()[a] + most);
    }
    if (!params.shrink || (free.empty() && taken.empty())) return grown;
    // Where the box reaches beyond the parts: slices cut off from the outside in while the scans
    // saw them free or another piece takes them, at three heights up to the parts' top (a taller
    // model's upper part is free above any piece), never inside the parts' extent.
    const float top = std::min(box.max().z(), quantile(zs, 0.98));
    std::vector<float> heights;
    for (float z : {0.3f * top, 0.6f * top, top - 0.05f}) {
        if (z > 0.05f) heights.push_back(z);
    }
    if (heights.empty()) return grown;
    const Eigen::AlignedBox3f outer = grown;
    // Whether the slice centred at `at` across axis a is free.
    auto slice_free = [&](int a, float at) {
        const int b = 1 - a;
        std::size_t n = 0, in_free = 0;
        for (float t = outer.min()[b] + 0.025f; t <= outer.max()[b]; t += 0.05f) {
            for (float z : heights) {
                Eigen::Vector3f p;
                p[a] = at, p[b] = t, p.z() = z;
                const Eigen::Vector3f w = fit.T_world_model * p;
                ++n;
                if (!taken.empty() && Taken(taken, w.head<2>())) {
                    ++in_free;
                    continue;
                }
                for (const auto* f : free) {
                    if (f != nullptr && f->IsFree(w)) {
                        ++in_free;
                        break;
                    }
                }
            }
        }
        return n > 0 && static_cast<float>(in_free) >= params.free_share * static_cast<float>(n);
    };
    for (int a = 0; a < 2; ++a) {
        const float s = params.slice;
        while (grown.max()[a] - s >= hi[a] && slice_free(a, grown.max()[a] - s / 2))
            grown.max()[a] -= s;
        while (grown.min()[a] + s <= lo[a] && slice_free(a, grown.min()[a] + s / 2))
            grown.min()[a] += s;
    }
    return grown;
}

}  // namespace

FurnitureTakenSpace FurnitureWallBand(const FurnitureWall& wall, float half_width) {
    if (!(half_width > 0.0f) || !std::isfinite(half_width)) {
        throw InvalidArgument(
            fmt::format("furniture wall band: half_width must be > 0, got {}", half_width));
    }
    FurnitureTakenSpace band;
    band.T_world_box =
        Eigen::Translation3f(wall.point.x(), wall.point.y(), 0.0f) *
        Eigen::AngleAxisf(std::atan2(wall.normal.y(), wall.normal.x()), Eigen::Vector3f::UnitZ());
    band.box = Eigen::AlignedBox3f(Eigen::Vector3f(-half_width, wall.lo, 0.0f),
                                   Eigen::Vector3f(half_width, wall.hi, 0.0f));
    return band;
}

bool FurnitureTakenSpace::Contains(const Eigen::Vector2f& xy) const {
    if (box.isEmpty()) return false;
    const Eigen::Vector3f q = T_world_box.inverse() * Eigen::Vector3f(xy.x(), xy.y(), 0.0f);
    return q.x() >= box.min().x() && q.x() <= box.max().x() && q.y() >= box.min().y() &&
           q.y() <= box.max().y();
}

Eigen::AlignedBox3f MeasureFurniturePiece(const std::vector<const FurnitureParts*>& views,
                                          const FurnitureCad& cad, const FurnitureFit& fit,
                                          const FurniturePieceParams& params,
                                          const std::vector<const FurnitureFreeSpace*>& free,
                                          const std::vector<FurnitureTakenSpace>& taken) {
    params.Validate();
    return PieceBox(views, FittedModelBox(cad, fit), fit, params, free, taken);
}

Eigen::Vector2f FurniturePieceCentre(const std::vector<const FurnitureParts*>& views,
                                     const FurnitureCad& cad, const FurnitureFit& fit,
                                     const FurniturePieceParams& params, Eigen::AlignedBox3f& box,
                                     const std::vector<const FurnitureFreeSpace*>& free,
                                     const std::vector<FurnitureTakenSpace>& taken) {
    params.Validate();
    const Eigen::AlignedBox3f model_box = FittedModelBox(cad, fit);
    box = PieceBox(views, model_box, fit, params, free, taken);
    if (box.isEmpty()) return fit.T_world_model.translation().head<2>();
    const Eigen::Vector3f shift = box.center() - model_box.center();
    return (fit.T_world_model * Eigen::Vector3f(shift.x(), shift.y(), 0.0f)).head<2>();
}

FurnitureShapeEvidence MeasureFurnitureShape(const PointCloud& points, const FurnitureCad& cad,
                                             const Eigen::Affine3f& T) {
    FurnitureShapeEvidence e;
    if (points.empty() || cad.cloud.empty() || !T.matrix().allFinite()) return e;
    // The model's box in its own frame.
    const Eigen::AlignedBox3f cad_box = CadBox(cad);
    if (cad_box.isEmpty()) return e;
    const Eigen::Vector3f lo = cad_box.min(), hi = cad_box.max();
    if (!(hi.array() > lo.array()).all()) return e;
    const Eigen::Vector3f size = hi - lo;
    const Eigen::Affine3f to_model = T.inverse();
    constexpr float kInside = 0.1f, kBeyond = 0.3f;  // [m]
    // How far outside the box's footprint a point lies (0 inside).
    auto outside = [&](const Eigen::Vector3f& q) {
        const float dx = std::max({lo.x() - q.x(), q.x() - hi.x(), 0.0f});
        const float dy = std::max({lo.y() - q.y(), q.y() - hi.y(), 0.0f});
        return std::max(dx, dy);
    };
    std::vector<float> xs, ys, zs;
    std::size_t beyond = 0, low = 0, finite = 0;
    const float floor_z = lo.z();
    for (const auto& p : points.points) {
        if (!p.allFinite()) continue;
        ++finite;
        const Eigen::Vector3f q = to_model * p;
        const float d = outside(q);
        if (d <= kInside) {
            xs.push_back(q.x());
            ys.push_back(q.y());
            zs.push_back(q.z() - floor_z);
            if (q.z() - floor_z < 0.25f * size.z()) ++low;
        } else if (d <= kBeyond) {
            ++beyond;
        }
    }
    if (finite == 0 || zs.empty()) return e;
    auto quantile = [](std::vector<float>& v, double q) {
        const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
        return v[k];
    };
    auto spread = [&](std::vector<float>& v) { return quantile(v, 0.95) - quantile(v, 0.05); };
    const auto inside = static_cast<float>(zs.size());
    e.inside_share = inside / static_cast<float>(finite);
    e.top = quantile(zs, 0.95);
    e.top_ratio = e.top / size.z();
    e.span_x = spread(xs) / size.x();
    e.span_y = spread(ys) / size.y();
    e.low_share = static_cast<float>(low) / inside;
    e.beyond = static_cast<float>(beyond) / inside;
    return e;
}

std::vector<std::string> FurnitureVerifierFeatureNames(const FurnitureModel& model) {
    std::vector<std::string> names = {"log_votes",    "log_parts", "coverage",   "free_share",
                                      "behind_share", "explained", "log_points", "refined",
                                      "shift",        "inside",    "top",        "top_ratio",
                                      "span_x",       "span_y",    "low",        "beyond"};
    for (const auto& c : model.classes()) names.push_back("class_" + c.name);
    return names;
}

namespace {

// Where each of `names` (a verifier's features) lies in FurnitureVerifierFeatures' row. Throws
// InvalidArgument for a name this version does not compute.
std::vector<std::size_t> VerifierColumns(const FurnitureModel& model,
                                         const std::vector<std::string>& names) {
    const std::vector<std::string> all = FurnitureVerifierFeatureNames(model);
    std::vector<std::size_t> columns;
    columns.reserve(names.size());
    for (const auto& n : names) {
        const auto it = std::find(all.begin(), all.end(), n);
        if (it == all.end()) {
            throw InvalidArgument(fmt::format(
                "furniture detection: the verifier needs the feature '{}', which this version "
                "does not compute; train the model again",
                n));
        }
        columns.push_back(static_cast<std::size_t>(it - all.begin()));
    }
    return columns;
}

}  // namespace

std::vector<float> FurnitureVerifierFeatures(const FurnitureDetection& d,
                                             const FurnitureModel& model) {
    const auto& classes = model.classes();
    if (d.cls < 0 || d.cls >= static_cast<int>(classes.size())) {
        throw InvalidArgument(fmt::format("furniture verifier: no class {}", d.cls));
    }
    const FurnitureClass& cls = classes[static_cast<std::size_t>(d.cls)];
    const float shift = (d.centre - d.hypothesis.centre).norm() / cls.width;
    std::vector<float> f = {std::log1p(std::max(0.0f, std::min(d.hypothesis.normalized, 1e6f))),
                            std::log1p(static_cast<float>(d.hypothesis.parts.size())),
                            d.fit.coverage,
                            d.fit.free_share,
                            d.fit.behind_share,
                            d.explained,
                            std::log1p(static_cast<float>(d.fit.scan_points)),
                            d.fit.refined ? 1.0f : 0.0f,
                            std::isfinite(shift) ? shift : 0.0f,
                            d.shape.inside_share,
                            d.shape.top,
                            d.shape.top_ratio,
                            d.shape.span_x,
                            d.shape.span_y,
                            d.shape.low_share,
                            d.shape.beyond};
    for (std::size_t c = 0; c < classes.size(); ++c)
        f.push_back(static_cast<int>(c) == d.cls ? 1.0f : 0.0f);
    return f;
}

std::vector<float> FurnitureVerifierFeatures(const FurnitureDetection& d,
                                             const FurnitureModel& model,
                                             const std::vector<std::string>& names) {
    const std::vector<float> row = FurnitureVerifierFeatures(d, model);
    std::vector<float> out;
    out.reserve(names.size());
    for (std::size_t c : VerifierColumns(model, names)) out.push_back(row[c]);
    return out;
}

float SharedSurfaceShare(const PointCloud& a, const Eigen::Isometry3f& T_a, const PointCloud& b,
                         const Eigen::Isometry3f& T_b, float distance) {
    if (!(distance > 0.0f) || !std::isfinite(distance)) {
        throw InvalidArgument(
            fmt::format("shared surface: distance must be > 0 [m], got {}", distance));
    }
    if (!T_a.matrix().allFinite() || !T_b.matrix().allFinite()) {
        throw InvalidArgument("shared surface: the poses must be finite");
    }
    const PlacedSurface sa = PlaceSurface(a, T_a, distance), sb = PlaceSurface(b, T_b, distance);
    return SharedEitherWay(sa, sb);
}

FurnitureScene PrepareFurnitureScene(const std::vector<FurnitureView>& views,
                                     const FurnitureModel& model,
                                     const FurnitureDetectionParams& params) {
    params.Validate();
    if (!model.trained()) throw InvalidArgument("furniture detection: the model is not trained");
    for (const auto& v : views) {
        if (v.scan == nullptr) throw InvalidArgument("furniture detection: a view without a scan");
        if (!v.T_world_sensor.matrix().allFinite()) {
            throw InvalidArgument("furniture detection: a view pose is not finite");
        }
    }
    FurnitureScene scene;
    FurniturePartParams pp = model.part_params();
    pp.num_threads = params.num_threads;
    for (std::size_t v = 0; v < views.size(); ++v) {
        auto t = std::chrono::steady_clock::now();
        scene.views.push_back(ExtractFurnitureParts(*views[v].scan, views[v].T_world_sensor, pp));
        scene.parts_ms += MillisecondsSince(t);
        t = std::chrono::steady_clock::now();
        scene.votes.push_back(
            CastFurnitureVotes(scene.views.back(), model, static_cast<int>(v), params.voting));
        scene.votes_ms += MillisecondsSince(t);
        scene.walls.push_back(params.walls ? FindFurnitureWalls(scene.views.back(),
                                                                model.max_object_height() +
                                                                    params.voting.height_margin,
                                                                params.min_wall_length)
                                           : std::vector<FurnitureWall>{});
        if (!params.verify || !params.free_space) continue;
        // Occupancy from the whole scan (the floor too: rays to it free the space above it),
        // thinned to the map's resolution.
        t = std::chrono::steady_clock::now();
        PointCloud world;
        const float floor = scene.views.back().floor_height;
        for (const auto& p : views[v].scan->points) {
            if (p.allFinite())
                world.points.push_back(views[v].T_world_sensor * p - Eigen::Vector3f(0, 0, floor));
        }
        world.width = static_cast<std::uint32_t>(world.points.size());
        const auto res = static_cast<float>(params.fit.occupancy_resolution);
        const PointCloud thin =
            VoxelGrid(world, {.leaf_size = res / 2, .num_threads = params.num_threads});
        FurnitureFreeSpace fs(params.fit.occupancy_resolution);
        fs.AddView(thin, scene.views.back().sensor_origin);
        scene.free_space.push_back(std::move(fs));
        scene.occupancy_ms += MillisecondsSince(t);
    }
    return scene;
}

FurnitureDetectionResult DetectFurniture(const FurnitureScene& scene,
                                         const std::vector<int>& subset,
                                         const FurnitureModel& model,
                                         const FurnitureFitContext* context,
                                         const FurnitureDetectionParams& params) {
    params.Validate();
    if (params.verify && context == nullptr) {
        throw InvalidArgument("furniture detection: verification needs a fit context");
    }
    if (params.verify && &context->model() != &model) {
        throw InvalidArgument("furniture detection: the fit context belongs to another model");
    }
    std::vector<int> views = subset;
    if (views.empty()) {
        for (std::size_t v = 0; v < scene.views.size(); ++v) views.push_back(static_cast<int>(v));
    }
    for (int v : views) {
        if (v < 0 || v >= static_cast<int>(scene.views.size())) {
            throw InvalidArgument(fmt::format("furniture detection: no view {}", v));
        }
    }
    FurnitureDetectionResult result;
    if (views.empty()) return result;
    auto t = std::chrono::steady_clock::now();
    std::vector<FurnitureVote> votes;
    for (int v : views) {
        const auto& vv = scene.votes[static_cast<std::size_t>(v)];
        votes.insert(votes.end(), vv.begin(), vv.end());
    }
    result.votes = votes.size();
    FurnitureSelectionParams selection = params.selection;
    selection.other_classes = selection.other_classes || (params.verify && params.other_classes);
    const auto hyps =
        SelectFurnitureHypotheses(votes, static_cast<int>(views.size()), model, selection);
    result.selection_ms = MillisecondsSince(t);
    std::vector<const FurnitureWall*> walls;
    for (int v : views) {
        if (static_cast<std::size_t>(v) >= scene.walls.size()) continue;
        for (const auto& w : scene.walls[static_cast<std::size_t>(v)]) walls.push_back(&w);
    }
    std::vector<FurnitureDetection> all(hyps.size());
    for (std::size_t i = 0; i < hyps.size(); ++i) {
        all[i].cls = hyps[i].cls;
        all[i].category = model.classes()[static_cast<std::size_t>(hyps[i].cls)].name;
        all[i].hypothesis = hyps[i];
        all[i].centre = hyps[i].centre;
        all[i].score = hyps[i].found;  // a proposed hypothesis: the votes that found the place
        all[i].accepted = !BehindWalls(walls, hyps[i].centre, params.fit.wall_margin);
        if (!all[i].accepted) all[i].rejection = "behind_wall";
    }
    const ml::Classifier* verifier = params.verify && params.learned ? model.verifier() : nullptr;
    // The verifier's columns, checked before any fitting.
    const std::vector<std::size_t> columns = verifier != nullptr
                                                 ? VerifierColumns(model, verifier->feature_names())
                                                 : std::vector<std::size_t>{};
    if (params.verify) {
        t = std::chrono::steady_clock::now();
        // What the chosen views say about the space: their free space and walls.
        FurnitureSpace space;
        space.walls = walls;
        for (int v : views) {
            if (static_cast<std::size_t>(v) < scene.free_space.size())
                space.free.push_back(&scene.free_space[static_cast<std::size_t>(v)]);
        }
        // Each hypothesis's fits: the best model's in place, the other models' (fit_models)
        // appended after the hypotheses as detections of their own.
        std::vector<std::vector<FurnitureDetection>> others(all.size());
        ParallelFor(
            all.size(), params.num_threads,
            [&](std::size_t i) {
                if (!all[i].accepted) return;  // behind a wall
                const FurnitureClass& cls = model.classes()[static_cast<std::size_t>(all[i].cls)];
                const PointCloud pts =
                    SupportPoints(scene, all[i].hypothesis, cls.length / 2 + params.support_margin);
                std::vector<FurnitureFit> fits = FitFurnitureModels(
                    pts, all[i].cls, all[i].hypothesis.centre, *context, space, params.fit_models);
                auto finish = [&](FurnitureDetection& d, FurnitureFit&& fit) {
                    d.fit = std::move(fit);
                    d.fitted = d.fit.cad >= 0;
                    if (d.fitted) {
                        d.centre = d.fit.T_world_model.translation().head<2>();
                        d.score *= std::max(
                            0.0f, 0.5f + d.fit.coverage - d.fit.free_share - d.fit.behind_share);
                        const FurnitureCad& cad = model.cads()[static_cast<std::size_t>(d.fit.cad)];
                        d.explained =
                            SharedSurface(PlaceSurface(cad.cloud, d.fit.FittedModelToWorld(),
                                                       params.surface_overlap_distance),
                                          PlaceSurface(pts, Eigen::Isometry3f::Identity(),
                                                       params.surface_overlap_distance));
                        d.shape = MeasureFurnitureShape(pts, cad, d.fit.FittedModelToWorld());
                    }
                    d.accepted = d.fit.accepted;
                    d.rejection = d.fit.rejection;
                };
                for (std::size_t k = 1; k < fits.size(); ++k) {
                    others[i].push_back(all[i]);
                    finish(others[i].back(), std::move(fits[k]));
                }
                finish(all[i], std::move(fits.front()));
            },
            1);
        for (const auto& d : all) result.fitted_hypotheses += d.fitted ? 1 : 0;
        for (auto& list : others) {
            for (auto& d : list) all.push_back(std::move(d));
        }
        if (verifier != nullptr) {
            // The verifier's probability of a right fit for every fit that passed the tests
            // and, with learned_tests, every fit they rejected: the verifier decides.
            const auto& names = verifier->class_names();
            const auto right = static_cast<Eigen::Index>(
                std::find(names.begin(), names.end(), "right") - names.begin());
            std::vector<std::size_t> rows;
            for (std::size_t i = 0; i < all.size(); ++i) {
                const std::string& why = all[i].rejection;
                const bool tested =
                    why == "coverage" || why == "free_space" || why == "behind_wall";
                if (all[i].fitted && (all[i].accepted || (params.learned_tests && tested)))
                    rows.push_back(i);
            }
            if (!rows.empty()) {
                const std::size_t nf = columns.size();
                ml::FeatureMatrix x(static_cast<Eigen::Index>(rows.size()),
                                    static_cast<Eigen::Index>(nf));
                for (std::size_t r = 0; r < rows.size(); ++r) {
                    const auto f = FurnitureVerifierFeatures(all[rows[r]], model);
                    for (std::size_t c = 0; c < nf; ++c) {
                        x(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) =
                            f[columns[c]];
                    }
                }
                const ml::FeatureMatrix p = verifier->PredictProba(x);
                const float cut =
                    views.size() == 1 ? params.min_confidence_single : params.min_confidence;
                for (std::size_t r = 0; r < rows.size(); ++r) {
                    FurnitureDetection& d = all[rows[r]];
                    d.confidence = p(static_cast<Eigen::Index>(r), right);
                    d.score = d.confidence;
                    const bool confident = d.confidence >= cut;
                    if (d.accepted && !confident) {
                        d.accepted = false;
                        d.rejection = "confidence";
                    } else if (!d.accepted && confident) {  // a test's rejection overruled
                        d.accepted = true;
                        d.rejection.clear();
                    }
                }
            }
        }
        // Fitted footprints that overlap are one piece. Strongest first, each detection gathers
        // the accepted ones overlapping it; with the verifier the most likely stays, else with
        // class_by_fit the one whose model explains the scan best (coverage minus free space and
        // space behind walls) stays, with the group's best vote score, else the strongest stays.
        std::vector<Polygon> feet(all.size());
        std::vector<PlacedSurface> surfaces(all.size());
        std::vector<float> areas(all.size(), 0.0f), vote(all.size(), 0.0f);
        for (std::size_t i = 0; i < all.size(); ++i) {
            vote[i] = all[i].hypothesis.found;
            if (!all[i].accepted) continue;
            const FurnitureCad& cad = model.cads()[static_cast<std::size_t>(all[i].fit.cad)];
            feet[i] = Footprint(cad, all[i].fit.FittedModelToWorld());
            areas[i] = Area(feet[i]);
            if (params.cross_class && params.cross_class_surfaces) {
                surfaces[i] = PlaceSurface(cad.cloud, all[i].fit.FittedModelToWorld(),
                                           params.surface_overlap_distance);
            }
        }
        auto overlaps = [&](std::size_t i, std::size_t k) {
            if (all[i].cls != all[k].cls) {
                if (!params.cross_class) return false;
                if (params.cross_class_surfaces) {
                    return SharedEitherWay(surfaces[i], surfaces[k]) > params.max_overlap;
                }
            }
            return ConvexIntersectionArea(feet[i], feet[k]) >
                   params.max_overlap * std::min(areas[i], areas[k]);
        };
        auto quality = [&](const FurnitureDetection& d) {
            return d.fit.coverage - d.fit.free_share - d.fit.behind_share;
        };
        std::vector<std::size_t> order(all.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::stable_sort(order.begin(), order.end(),
                         [&](std::size_t a, std::size_t b) { return all[a].score > all[b].score; });
        std::vector<bool> done(all.size(), false);
        std::vector<std::size_t> kept;
        for (std::size_t i : order) {
            if (!all[i].accepted || done[i]) continue;
            bool clash = false;
            for (std::size_t k : kept) clash = clash || overlaps(i, k);
            if (clash) {
                all[i].accepted = false;
                all[i].rejection = "overlap";
                continue;
            }
            std::vector<std::size_t> group = {i};
            for (std::size_t k : order) {
                if (k != i && all[k].accepted && !done[k] && overlaps(i, k)) group.push_back(k);
            }
            // A hypothesis proposed by another class's votes names the piece only when no fit
            // of a voted-for class does.
            auto proposed = [&](std::size_t k) { return all[k].hypothesis.proposed_by >= 0; };
            std::size_t winner = i;
            for (std::size_t k : group) {
                if (proposed(winner) && !proposed(k)) winner = k;
            }
            if (verifier != nullptr) {
                for (std::size_t k : group) {
                    if (proposed(k) == proposed(winner) &&
                        all[k].confidence > all[winner].confidence)
                        winner = k;
                }
            } else if (params.class_by_fit) {
                for (std::size_t k : group) {
                    if (proposed(k) == proposed(winner) && quality(all[k]) > quality(all[winner]))
                        winner = k;
                }
                float best_vote = 0.0f;
                for (std::size_t k : group) best_vote = std::max(best_vote, vote[k]);
                all[winner].score = best_vote * std::max(0.0f, 0.5f + quality(all[winner]));
            }
            for (std::size_t k : group) {
                done[k] = true;
                if (k == winner) continue;
                all[k].accepted = false;
                all[k].rejection = "overlap";
            }
            kept.push_back(winner);
        }
        // The accepted pieces' boxes grown or shrunk to their parts, and their centres with them;
        // the fitted models of the more likely accepted pieces take their space.
        std::vector<const FurnitureParts*> parts;
        for (int v : views) parts.push_back(&scene.views[static_cast<std::size_t>(v)]);
        // The views' walls take a band of 5 cm on either side of their planes: a part of a wall
        // next to a piece, say the wall seen below a table's top, is no part of the piece.
        std::vector<FurnitureTakenSpace> wall_bands;
        if (params.piece.walls) {
            for (const FurnitureWall* w : walls) wall_bands.push_back(FurnitureWallBand(*w, 0.05f));
        }
        std::vector<FurnitureTakenSpace> taken;
        for (std::size_t i = 0; i < all.size(); ++i) {
            FurnitureDetection& d = all[i];
            if (!d.fitted) continue;
            FurniturePieceParams piece = params.piece;
            piece.grow = piece.grow && d.accepted;
            taken.clear();
            if (d.accepted) taken = wall_bands;
            if (d.accepted && params.piece.taken) {
                for (std::size_t k = 0; k < all.size(); ++k) {
                    const FurnitureDetection& o = all[k];
                    if (k == i || !o.accepted ||
                        !(o.score > d.score || (o.score == d.score && k < i)))
                        continue;
                    taken.push_back(
                        {o.fit.T_world_model,
                         FittedModelBox(model.cads()[static_cast<std::size_t>(o.fit.cad)], o.fit)});
                }
            }
            d.centre =
                FurniturePieceCentre(parts, model.cads()[static_cast<std::size_t>(d.fit.cad)],
                                     d.fit, piece, d.box, space.free, taken);
        }
        result.fit_ms = MillisecondsSince(t);
    }
    for (auto& d : all) (d.accepted ? result.detections : result.rejected).push_back(std::move(d));
    auto by_score = [](const FurnitureDetection& a, const FurnitureDetection& b) {
        return a.score > b.score;
    };
    std::stable_sort(result.detections.begin(), result.detections.end(), by_score);
    std::stable_sort(result.rejected.begin(), result.rejected.end(), by_score);
    return result;
}

FurnitureDetectionResult DetectFurniture(const std::vector<FurnitureView>& views,
                                         const FurnitureModel& model,
                                         const FurnitureFitContext* context,
                                         const FurnitureDetectionParams& params) {
    const FurnitureScene scene = PrepareFurnitureScene(views, model, params);
    return DetectFurniture(scene, {}, model, context, params);
}

}  // namespace multicue
