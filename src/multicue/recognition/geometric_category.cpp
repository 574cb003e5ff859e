#include "multicue/recognition/geometric_category.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <utility>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/recognition/bounding_box.hpp"
#include "multicue/segmentation/sac_cylinder.hpp"
#include "multicue/segmentation/sac_sphere.hpp"

namespace multicue {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

template <typename... Args>
void Require(bool ok, fmt::format_string<Args...> message, Args&&... args) {
    if (!ok) throw InvalidArgument(fmt::format(message, std::forward<Args>(args)...));
}

// 0 below lo, 1 above hi, linear in between.
float Ramp(float x, float lo, float hi) {
    if (!(hi > lo)) return x >= hi ? 1.0f : 0.0f;
    return std::clamp((x - lo) / (hi - lo), 0.0f, 1.0f);
}

// 1 when `measured` is within a factor `tol` of `expected`, 0 beyond tol^2, linear in log scale.
float SizeMatch(float measured, float expected, float tol) {
    if (!(measured > 0.0f) || !(expected > 0.0f)) return 0.0f;
    const float l = std::abs(std::log(measured / expected));
    return 1.0f - Ramp(l, std::log(tol), 2.0f * std::log(tol));
}

bool UsableNormal(const PointCloud& cloud, Index i) {
    const Eigen::Vector3f& n = cloud.normals[i];
    return cloud.points[i].allFinite() && n.allFinite() && n.squaredNorm() > 0.0f;
}

// Share of the usable points of `parts` that lie in planar parts: parts whose normals deviate
// from their principal direction by less than max_angle on average.
float PlanarPartRatio(const PointCloud& cloud, const std::vector<Indices>& parts, float max_angle) {
    std::size_t total = 0, planar = 0;
    for (const Indices& part : parts) {
        Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
        std::size_t count = 0;
        for (Index i : part) {
            if (!UsableNormal(cloud, i)) continue;
            const Eigen::Vector3d n = cloud.normals[i].cast<double>().normalized();
            scatter += n * n.transpose();
            ++count;
        }
        if (count == 0) continue;
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
        const Eigen::Vector3d dir = solver.eigenvectors().col(2);
        double angle_sum = 0.0;
        for (Index i : part) {
            if (!UsableNormal(cloud, i)) continue;
            const double c = std::abs(cloud.normals[i].cast<double>().normalized().dot(dir));
            angle_sum += std::acos(std::min(1.0, c));
        }
        total += count;
        if (angle_sum / static_cast<double>(count) < double{max_angle}) planar += count;
    }
    return total > 0 ? static_cast<float>(planar) / static_cast<float>(total) : 0.0f;
}

struct Footprint {
    float fill = 1.0f;  // hull area / minimum rectangle area
    float area = 0.0f;  // hull area [m^2]
};

// The footprint across box axis k: its hull's area, and that area over the minimum rectangle's
// (how round it is).
Footprint MeasureFootprint(const PointCloud& cloud, const Indices& usable, const OrientedBox& box,
                           int k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    const float rect = box.extents[i] * box.extents[j];
    if (!(rect > 0.0f)) return {};
    std::vector<Eigen::Vector2f> proj;
    proj.reserve(usable.size());
    for (Index p : usable) {
        proj.emplace_back(cloud.points[p].dot(box.axes.col(i)),
                          cloud.points[p].dot(box.axes.col(j)));
    }
    const std::vector<Eigen::Vector2f> hull = ConvexHull2d(std::move(proj));
    // The box's rectangle across axis k may be larger than the hull's minimum-area rectangle
    // (PCA boxes); the minimum-area one is the fair reference for roundness.
    const float min_rect = MinAreaRectangle(hull).Area();
    const float ref = min_rect > 0.0f ? min_rect : rect;
    Footprint f;
    f.area = PolygonArea(hull);
    f.fill = std::clamp(f.area / ref, 0.0f, 1.0f);
    return f;
}

// Area of the grid cells (`cell` metres across box axis k) that hold points, over the hull's
// area `hull_area`, at most 1.
float FootprintCover(const PointCloud& cloud, const Indices& usable, const OrientedBox& box, int k,
                     float hull_area, float cell) {
    if (!(hull_area > 0.0f) || usable.empty()) return 1.0f;
    const Eigen::Vector3f u = box.axes.col((k + 1) % 3), v = box.axes.col((k + 2) % 3);
    const Eigen::Vector3f& origin = cloud.points[usable.front()];
    // Cell keys relative to the first point, offset so that both halves stay positive (objects
    // are far smaller than 2^20 cells).
    constexpr std::int64_t kOffset = std::int64_t{1} << 20;
    std::vector<std::uint64_t> cells;
    cells.reserve(usable.size());
    for (Index p : usable) {
        const Eigen::Vector3f d = cloud.points[p] - origin;
        const auto a = static_cast<std::int64_t>(std::floor(d.dot(u) / cell)) + kOffset;
        const auto b = static_cast<std::int64_t>(std::floor(d.dot(v) / cell)) + kOffset;
        cells.push_back((static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint64_t>(b));
    }
    std::sort(cells.begin(), cells.end());
    const auto occupied =
        static_cast<float>(std::unique(cells.begin(), cells.end()) - cells.begin());
    return std::min(occupied * cell * cell / hull_area, 1.0f);
}

// Soft share of "flat" for sorted extents e1 >= e2 >= e3: > 0.5 exactly where the data README's
// rule says flat, approaching 0 or 1 with the log-distance from the rule's boundary.
float FlatShare(const Eigen::Vector3f& e, const CategoryParams& p) {
    const float e3 = std::max(e[2], 1e-4f);
    const float x = std::log(std::max(e[1], e3) / e3);
    const float y = std::log(std::max(e[0], e3) / e3);
    const float a = std::log(p.flat_ratio), b = std::log(p.box_ratio);
    const float c = std::log(p.flat_long_ratio);
    const bool flat = x >= a || (x >= b && y > c);
    float m = 0.0f;
    if (flat) {
        // Cheapest move out of {x >= a} u {x >= b, y > c}.
        m = std::min(x - b, std::max(0.0f, x - a) + std::max(0.0f, y - c));
        m = std::max(m, 1e-3f);
    } else {
        m = std::min(std::max(0.0f, a - x), std::max(0.0f, b - x) + std::max(0.0f, c - y));
        m = -std::max(m, 1e-3f);
    }
    return 0.5f + 0.5f * std::tanh(p.boundary_softness * m);
}

struct CylinderEvidence {
    float score = 0.0f;
    float side = 0.0f;
    float cap = 0.0f;
    float side_lo = 0.0f;  // extent of the side points along the axis [m]
    float side_hi = 0.0f;
    float coverage = 0.0f;  // AxialCoverage
    float radius = 0.0f;
    Eigen::Vector3f axis = Eigen::Vector3f::Zero();
    Eigen::Vector3f point = Eigen::Vector3f::Zero();  // on the axis
};

// Side points (within `threshold` of the side, normal within the angle of radial) and cap points
// (normal within cap_angle of the axis, inside the rim, near an end of the side) of a fitted
// cylinder, as shares of the sampled points.
CylinderEvidence MeasureCylinder(const PointCloud& cloud, const Indices& sample,
                                 const CylinderFit& fit, float threshold, float cos_normal,
                                 float cap_angle) {
    CylinderEvidence ev;
    ev.radius = fit.radius;
    ev.axis = fit.axis;
    ev.point = fit.point;
    const auto n = static_cast<float>(sample.size());
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    std::size_t side = 0;
    for (Index i : sample) {
        const Eigen::Vector3f w = cloud.points[i] - fit.point;
        const float t = w.dot(fit.axis);
        const Eigen::Vector3f q = w - t * fit.axis;
        const float rho = q.norm();
        if (!(rho > 0.0f) || std::abs(rho - fit.radius) > threshold) continue;
        if (std::abs(cloud.normals[i].normalized().dot(q / rho)) < cos_normal) continue;
        ++side;
        lo = std::min(lo, t);
        hi = std::max(hi, t);
    }
    ev.side = static_cast<float>(side) / n;
    ev.side_lo = side > 0 ? lo : 0.0f;
    ev.side_hi = side > 0 ? hi : 0.0f;
    const float cos_cap = std::cos(cap_angle);
    std::size_t cap = 0;
    for (Index i : sample) {
        const Eigen::Vector3f w = cloud.points[i] - fit.point;
        const float t = w.dot(fit.axis);
        const float radial = (w - t * fit.axis).norm();
        const float c = std::abs(cloud.normals[i].normalized().dot(fit.axis));
        if (c >= cos_cap && radial <= fit.radius + threshold &&
            (t >= hi - threshold || t <= lo + threshold)) {
            ++cap;
        }
    }
    ev.cap = static_cast<float>(cap) / n;
    return ev;
}

// Share of the sampled points on a fitted sphere (same test as the cylinder's side).
float MeasureSphere(const PointCloud& cloud, const Indices& sample, const SphereFit& fit,
                    float threshold, float cos_normal) {
    std::size_t on = 0;
    for (Index i : sample) {
        const Eigen::Vector3f w = cloud.points[i] - fit.center;
        const float rho = w.norm();
        if (!(rho > 0.0f) || std::abs(rho - fit.radius) > threshold) continue;
        if (std::abs(cloud.normals[i].normalized().dot(w / rho)) >= cos_normal) ++on;
    }
    return static_cast<float>(on) / static_cast<float>(sample.size());
}

// The direction shared by the most normals (sign-free, within max_angle): each of up to 64
// evenly strided normals of the sample is a candidate, the best one is refined to the mean of
// the normals it gathers. A box's largest seen face, a can's cap, any direction for a ball.
Eigen::Vector3f DominantNormal(const PointCloud& cloud, const Indices& sample, float max_angle) {
    const float cos_max = std::cos(max_angle);
    const std::size_t candidates = std::min<std::size_t>(64, sample.size());
    Eigen::Vector3f best = Eigen::Vector3f::UnitZ();
    std::size_t best_count = 0;
    for (std::size_t c = 0; c < candidates; ++c) {
        const Eigen::Vector3f dir =
            cloud.normals[sample[c * sample.size() / candidates]].normalized();
        std::size_t count = 0;
        for (Index i : sample) {
            if (std::abs(cloud.normals[i].normalized().dot(dir)) >= cos_max) ++count;
        }
        if (count > best_count) {
            best_count = count;
            best = dir;
        }
    }
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    for (Index i : sample) {
        const Eigen::Vector3f n = cloud.normals[i].normalized();
        const float c = n.dot(best);
        if (std::abs(c) >= cos_max) sum += c < 0.0f ? Eigen::Vector3f(-n) : n;
    }
    return sum.norm() > 0.0f ? Eigen::Vector3f(sum.normalized()) : best;
}

// Share of the cylinder's extent along its axis, over the object's, that its side points cover:
// near 1 for a can, about 1/3 for the equator band of a ball that a cylinder also fits.
float AxialCoverage(const PointCloud& cloud, const Indices& sample, const CylinderFit& fit,
                    float side_lo, float side_hi) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (Index i : sample) {
        const float t = (cloud.points[i] - fit.point).dot(fit.axis);
        lo = std::min(lo, t);
        hi = std::max(hi, t);
    }
    return hi > lo ? std::clamp((side_hi - side_lo) / (hi - lo), 0.0f, 1.0f) : 0.0f;
}

CategoryResult NoneResult(std::size_t points) {
    CategoryResult r;
    r.points = points;
    r.probabilities[static_cast<std::size_t>(Category::kNone)] = 1.0f;
    r.scores[static_cast<std::size_t>(Category::kNone)] = 1.0f;
    r.confidence = 1.0f;
    return r;
}

// Throws for an index of the object or of a part outside the cloud.
void CheckIndices(const PointCloud& cloud, const Indices& object,
                  const std::vector<Indices>& parts) {
    auto check = [&](const Indices& idx) {
        for (Index i : idx) {
            Require(i < cloud.size(), "index {} out of range for a cloud of {} points", i,
                    cloud.size());
        }
    };
    check(object);
    for (const Indices& part : parts) check(part);
}

// The object's points with a finite position and a usable normal: all evidence is taken on them.
Indices UsablePoints(const PointCloud& cloud, const Indices& object) {
    Indices usable;
    usable.reserve(object.size());
    for (Index i : object) {
        if (UsableNormal(cloud, i)) usable.push_back(i);
    }
    return usable;
}

/// The object's bounding box and its thinnest axis (in the box's own order).
struct ObjectBox {
    OrientedBox box;
    int thin_axis = 0;
    float hull_area = 0.0f;  ///< of the footprint across the thin axis [m^2]
};

/// Extents: the upright box on the support plane, else an approximate minimum-volume box; sets
/// the result's height, sorted extents, thickness ratio, footprint fill and cover.
ObjectBox MeasureExtents(const PointCloud& cloud, const Indices& usable,
                         const std::optional<Eigen::Vector4f>& plane, CategoryResult& r) {
    r.upright = plane.has_value();
    ObjectBox out{plane ? UprightBoundingBox(cloud, usable, *plane)
                        : MinVolumeBoundingBox(cloud, usable)};
    const OrientedBox& box = out.box;
    if (plane) r.height = box.extents.z();
    r.extents = box.extents;
    std::sort(r.extents.data(), r.extents.data() + 3, std::greater<float>());
    box.extents.minCoeff(&out.thin_axis);
    r.thickness_ratio = r.extents[0] > 0.0f ? r.extents[2] / r.extents[0] : 1.0f;
    const Footprint footprint = MeasureFootprint(cloud, usable, box, out.thin_axis);
    r.footprint_fill = footprint.fill;
    out.hull_area = footprint.area;
    return out;
}

/// Box-likeness: the share of normals along the axes of the upright frame (or of the most
/// populated face direction without a plane), averaged with the planar parts when given.
void MeasureBoxLikeness(const PointCloud& cloud, const Indices& usable, const Indices& sample,
                        const std::vector<Indices>& parts,
                        const std::optional<Eigen::Vector4f>& plane, float axis_angle,
                        const CategoryParams& params, CategoryResult& r) {
    if (plane) {
        const FaceAlignment faces = AlignUprightAxes(cloud, usable, plane->head<3>(), axis_angle);
        r.axis_area = faces.aligned_ratio;
        if (faces.num_normals > 0) {
            r.side_face_ratio = static_cast<float>(faces.num_aligned - faces.num_vertical) /
                                static_cast<float>(faces.num_normals);
        }
    } else {
        // Without a plane the box's "up" is taken as its most populated face direction.
        const Eigen::Vector3f face = DominantNormal(cloud, sample, axis_angle);
        r.axis_area = AlignUprightAxes(cloud, usable, face, axis_angle).aligned_ratio;
    }
    r.box_score = r.axis_area;
    if (!parts.empty()) {
        r.planar_part_ratio = PlanarPartRatio(cloud, parts, params.planar_part_angle_deg * kDeg);
        r.box_score = 0.5f * (r.axis_area + r.planar_part_ratio);
    }
}

/// The consensus settings shared by the cylinder and sphere fits.
SacParams ShapeFitSac(const CategoryParams& params) {
    SacParams sac;
    sac.method = SacMethod::kMsac;
    sac.distance_threshold = params.fit_threshold;
    sac.max_iterations = params.max_iterations;
    sac.seed = params.seed;
    sac.max_refine_rounds = 3;
    sac.normal_distance_weight = params.normal_weight;
    sac.num_threads = params.num_threads;
    return sac;
}

/// The best cylinder (section 5.4.2.1): upright and lying candidates when "up" is known, any axis
/// otherwise, each scored by its side and cap shares, its axial coverage and how well its
/// diameter matches the box; sets the result's cylinder fields.
CylinderEvidence BestCylinder(const PointCloud& cloud, const Indices& sample,
                              const std::optional<Eigen::Vector4f>& plane, const OrientedBox& box,
                              const SacParams& sac, float axis_angle, float cos_inlier_normal,
                              const CategoryParams& params, CategoryResult& r) {
    CylinderFitParams cp{
        .sac = sac, .min_radius = params.min_radius, .max_radius = params.max_radius};
    CylinderEvidence best_cyl;
    auto consider = [&](const CylinderFit& fit, float plausibility, bool upright) {
        if (!fit.found) return;
        CylinderEvidence ev = MeasureCylinder(cloud, sample, fit, params.fit_threshold,
                                              cos_inlier_normal, axis_angle);
        ev.coverage = AxialCoverage(cloud, sample, fit, ev.side_lo, ev.side_hi);
        ev.score = plausibility * Ramp(ev.side, params.min_side_ratio, params.full_side_ratio) *
                   Ramp(ev.coverage, params.min_coverage, params.full_coverage) *
                   std::min(1.0f, ev.side + ev.cap);
        if (ev.score > best_cyl.score || (best_cyl.radius == 0.0f && ev.side > best_cyl.side)) {
            best_cyl = ev;
            r.cylinder_upright = upright;
        }
    };
    if (plane) {
        const Eigen::Vector3f up = plane->head<3>();
        cp.axis = up;
        cp.max_angle = params.upright_angle_deg * kDeg;
        const CylinderFit upright = FitCylinder(cloud, sample, cp);
        // Upright: the footprint's longer side is a diameter (also for a half-visible side).
        consider(upright, SizeMatch(2.0f * upright.radius, box.extents.x(), params.size_tolerance),
                 true);
        cp.axis = std::nullopt;
        const CylinderFit free = FitCylinder(cloud, sample, cp);
        if (free.found && std::abs(free.axis.dot(up)) <= std::sin(params.lying_angle_deg * kDeg)) {
            // Lying: its height above the table is a diameter.
            consider(free, SizeMatch(2.0f * free.radius, box.extents.z(), params.size_tolerance),
                     false);
        }
    } else {
        const CylinderFit free = FitCylinder(cloud, sample, cp);
        const float match =
            std::max(SizeMatch(2.0f * free.radius, r.extents[0], params.size_tolerance),
                     SizeMatch(2.0f * free.radius, r.extents[1], params.size_tolerance));
        consider(free, match, false);
    }
    r.cylinder_inlier_ratio = best_cyl.side;
    r.cylinder_cap_ratio = best_cyl.cap;
    r.cylinder_coverage = best_cyl.coverage;
    r.cylinder_radius = best_cyl.radius;
    r.cylinder_axis = best_cyl.axis;
    r.cylinder_point = best_cyl.point;
    return best_cyl;
}

/// Sphere: its share of the points, its diameter matched to the object's largest extent, and not
/// box-like; sets the result's sphere fields.
float SphereScore(const PointCloud& cloud, const Indices& sample, const SacParams& sac,
                  float cos_inlier_normal, const CategoryParams& params, CategoryResult& r) {
    // Box-like normals zero the sphere's score whatever sphere fits: then none is fitted (its
    // measurements stay 0, as when no sphere is found).
    if (r.axis_area >= params.sphere_box_axis_area_max) return 0.0f;
    SphereFitParams spp{.sac = sac,
                        .min_radius = params.min_radius,
                        .max_radius = params.max_radius,
                        .oriented_samples = true};
    const SphereFit sphere = FitSphere(cloud, sample, spp);
    float sphere_score = 0.0f;
    if (sphere.found) {
        r.sphere_inlier_ratio =
            MeasureSphere(cloud, sample, sphere, params.fit_threshold, cos_inlier_normal);
        r.sphere_radius = sphere.radius;
        sphere_score = r.sphere_inlier_ratio *
                       SizeMatch(2.0f * sphere.radius, r.extents[0], params.size_tolerance) *
                       (1.0f - Ramp(r.axis_area, params.sphere_box_axis_area,
                                    params.sphere_box_axis_area_max));
    }
    return sphere_score;
}

/// Plate: thin, no wider than the largest round object considered, and with a support plane
/// low and lying (thin axis along up, see the header); then round or dish-like, and seen as a
/// rim rather than a solid top (sets r.footprint_cover for such candidates).
float PlateScore(const PointCloud& cloud, const Indices& usable, const ObjectBox& box,
                 bool has_plane, const CategoryParams& params, CategoryResult& r) {
    if (r.extents[0] > 2.0f * params.max_radius) return 0.0f;
    if (has_plane && box.thin_axis != 2) return 0.0f;
    const float thin =
        1.0f - Ramp(r.thickness_ratio, params.plate_thin_ratio, params.plate_thick_ratio);
    const float low =
        has_plane ? 1.0f - Ramp(r.height, params.plate_low_height, params.plate_high_height) : 1.0f;
    if (!(thin * low > 0.0f)) return 0.0f;
    const float round = 1.0f - Ramp(r.footprint_fill, params.round_fill, params.square_fill);
    const float dish = 1.0f - Ramp(r.box_score, params.dish_box_score, params.slab_box_score);
    r.footprint_cover =
        FootprintCover(cloud, usable, box.box, box.thin_axis, box.hull_area, params.footprint_cell);
    const float solid = Ramp(r.footprint_cover, params.rim_cover, params.solid_cover);
    return thin * low * std::max(round, dish) * (1.0f - (1.0f - params.solid_plate) * solid);
}

/// The category scores: box-likeness shared between box and flat, a plate taking precedence over
/// both and the cylinder, and "other" as strong as the strongest category is weak.
void ScoreCategories(float sphere_score, float cylinder_score, float plate, float flat_share,
                     float min_evidence, CategoryResult& r) {
    auto& s = r.scores;
    s[static_cast<std::size_t>(Category::kSphere)] = sphere_score;
    s[static_cast<std::size_t>(Category::kBox)] =
        r.box_score * (1.0f - flat_share) * (1.0f - plate);
    s[static_cast<std::size_t>(Category::kFlat)] = r.box_score * flat_share * (1.0f - plate);
    s[static_cast<std::size_t>(Category::kCylinder)] = cylinder_score * (1.0f - plate);
    s[static_cast<std::size_t>(Category::kPlate)] = plate;
    const float strongest = *std::max_element(s.begin(), s.end());
    s[static_cast<std::size_t>(Category::kOther)] =
        std::clamp(min_evidence * (1.0f - strongest) / (1.0f - min_evidence), 0.0f, 1.0f);
}

/// Probabilities from the scores raised to `sharpness` and normalised; the category is the most
/// probable one.
void SetProbabilities(float sharpness, CategoryResult& r) {
    const auto& s = r.scores;
    double total = 0.0;
    std::array<double, kNumCategories> powered{};
    for (std::size_t c = 0; c < kNumCategories; ++c) {
        powered[c] = std::pow(double{s[c]}, double{sharpness});
        total += powered[c];
    }
    for (std::size_t c = 0; c < kNumCategories; ++c) {
        r.probabilities[c] = static_cast<float>(powered[c] / total);
    }
    const auto best = static_cast<std::size_t>(
        std::max_element(r.probabilities.begin(), r.probabilities.end()) - r.probabilities.begin());
    r.category = static_cast<Category>(best);
    r.confidence = r.probabilities[best];
}

}  // namespace

std::string_view CategoryName(Category category) {
    const auto i = static_cast<std::size_t>(category);
    if (i >= kNumCategories) {
        throw InvalidArgument(
            fmt::format("category value must be < {}, got {}", kNumCategories, i));
    }
    return kCategoryNames[i];
}

Category ParseCategory(std::string_view name) {
    for (std::size_t i = 0; i < kNumCategories; ++i) {
        if (kCategoryNames[i] == name) return static_cast<Category>(i);
    }
    throw InvalidArgument(fmt::format(
        "unknown category '{}', expected one of none, sphere, box, flat, cylinder, plate, other",
        name));
}

void CategoryParams::Validate() const {
    const CategoryParams& p = *this;
    Require(p.min_points >= 1, "min_points must be >= 1, got {}", p.min_points);
    Require(p.max_points >= p.min_points, "max_points must be >= min_points ({}), got {}",
            p.min_points, p.max_points);
    Require(p.axis_angle_deg > 0.0f && p.axis_angle_deg <= 45.0f,
            "axis_angle_deg must be in (0, 45], got {}", p.axis_angle_deg);
    Require(p.planar_part_angle_deg > 0.0f && p.planar_part_angle_deg <= 90.0f,
            "planar_part_angle_deg must be in (0, 90], got {}", p.planar_part_angle_deg);
    Require(p.fit_threshold > 0.0f && std::isfinite(p.fit_threshold),
            "fit_threshold must be > 0 and finite, got {}", p.fit_threshold);
    Require(p.normal_weight >= 0.0f && p.normal_weight <= 1.0f,
            "normal_weight must be in [0, 1], got {}", p.normal_weight);
    Require(p.inlier_normal_angle_deg > 0.0f && p.inlier_normal_angle_deg <= 90.0f,
            "inlier_normal_angle_deg must be in (0, 90], got {}", p.inlier_normal_angle_deg);
    Require(p.min_radius >= 0.0f && p.max_radius >= p.min_radius,
            "radii must satisfy 0 <= min_radius <= max_radius, got {} and {}", p.min_radius,
            p.max_radius);
    Require(p.upright_angle_deg >= 0.0f && p.upright_angle_deg <= 90.0f,
            "upright_angle_deg must be in [0, 90], got {}", p.upright_angle_deg);
    Require(p.lying_angle_deg >= 0.0f && p.lying_angle_deg <= 90.0f,
            "lying_angle_deg must be in [0, 90], got {}", p.lying_angle_deg);
    Require(p.max_iterations >= 1, "max_iterations must be >= 1, got {}", p.max_iterations);
    Require(p.min_side_ratio >= 0.0f && p.full_side_ratio > p.min_side_ratio &&
                p.full_side_ratio <= 1.0f,
            "side ratios must satisfy 0 <= min_side_ratio < full_side_ratio <= 1, got {} and {}",
            p.min_side_ratio, p.full_side_ratio);
    Require(p.min_coverage >= 0.0f && p.full_coverage > p.min_coverage && p.full_coverage <= 1.0f,
            "coverages must satisfy 0 <= min_coverage < full_coverage <= 1, got {} and {}",
            p.min_coverage, p.full_coverage);
    Require(p.size_tolerance > 1.0f && std::isfinite(p.size_tolerance),
            "size_tolerance must be > 1 and finite, got {}", p.size_tolerance);
    Require(p.box_ratio >= 1.0f && p.flat_ratio >= p.box_ratio && p.flat_long_ratio >= 1.0f &&
                std::isfinite(p.flat_ratio) && std::isfinite(p.flat_long_ratio),
            "box/flat ratios must satisfy 1 <= box_ratio <= flat_ratio and flat_long_ratio >= 1, "
            "got {}, {} and {}",
            p.box_ratio, p.flat_ratio, p.flat_long_ratio);
    Require(p.boundary_softness > 0.0f && std::isfinite(p.boundary_softness),
            "boundary_softness must be > 0 and finite, got {}", p.boundary_softness);
    Require(p.plate_thin_ratio >= 0.0f && p.plate_thick_ratio > p.plate_thin_ratio &&
                p.plate_thick_ratio <= 1.0f,
            "plate ratios must satisfy 0 <= plate_thin_ratio < plate_thick_ratio <= 1, got {} and "
            "{}",
            p.plate_thin_ratio, p.plate_thick_ratio);
    Require(p.plate_low_height >= 0.0f && p.plate_high_height > p.plate_low_height &&
                std::isfinite(p.plate_high_height),
            "plate heights must satisfy 0 <= plate_low_height < plate_high_height, got {} and {}",
            p.plate_low_height, p.plate_high_height);
    Require(p.sphere_box_axis_area >= 0.0f && p.sphere_box_axis_area_max > p.sphere_box_axis_area &&
                p.sphere_box_axis_area_max <= 1.0f,
            "sphere axis areas must satisfy 0 <= sphere_box_axis_area < sphere_box_axis_area_max "
            "<= 1, got {} and {}",
            p.sphere_box_axis_area, p.sphere_box_axis_area_max);
    Require(p.footprint_cell > 0.0f && std::isfinite(p.footprint_cell),
            "footprint_cell must be positive and finite, got {}", p.footprint_cell);
    Require(
        p.dish_box_score >= 0.0f && p.slab_box_score > p.dish_box_score && p.slab_box_score <= 1.0f,
        "box scores must satisfy 0 <= dish_box_score < slab_box_score <= 1, got {} and {}",
        p.dish_box_score, p.slab_box_score);
    Require(p.rim_cover >= 0.0f && p.solid_cover > p.rim_cover && p.solid_cover <= 1.0f,
            "covers must satisfy 0 <= rim_cover < solid_cover <= 1, got {} and {}", p.rim_cover,
            p.solid_cover);
    Require(p.solid_plate >= 0.0f && p.solid_plate <= 1.0f,
            "solid_plate must lie in [0, 1], got {}", p.solid_plate);
    Require(p.round_fill > 0.0f && p.square_fill > p.round_fill && p.square_fill <= 1.0f,
            "fills must satisfy 0 < round_fill < square_fill <= 1, got {} and {}", p.round_fill,
            p.square_fill);
    Require(p.min_evidence > 0.0f && p.min_evidence < 1.0f,
            "min_evidence must be in (0, 1), got {}", p.min_evidence);
    Require(p.sharpness > 0.0f && std::isfinite(p.sharpness),
            "sharpness must be > 0 and finite, got {}", p.sharpness);
    Require(p.num_threads >= 0, "num_threads must be >= 0, got {}", p.num_threads);
}

CategoryResult CategorizeObject(const PointCloud& cloud, const Indices& object,
                                const std::vector<Indices>& parts,
                                const Eigen::Vector4f& support_plane,
                                const CategoryParams& params) {
    params.Validate();
    const std::optional<Eigen::Vector4f> plane = NormalizeSupportPlane(support_plane);
    CheckIndices(cloud, object, parts);
    if (object.empty()) return NoneResult(0);
    if (cloud.normals.size() != cloud.size()) {
        throw DataError(fmt::format("categorisation needs one normal per point, got {} for {}",
                                    cloud.normals.size(), cloud.size()));
    }
    const Indices usable = UsablePoints(cloud, object);
    if (usable.size() < params.min_points) return NoneResult(usable.size());

    CategoryResult r;
    r.points = usable.size();
    // An even subset bounds the fits' cost while the shares they measure stay representative.
    const Indices sample = EvenSubset(usable, params.max_points);
    r.sampled = sample.size();
    const float axis_angle = params.axis_angle_deg * kDeg;
    const float cos_inlier_normal = std::cos(params.inlier_normal_angle_deg * kDeg);

    // The geometric evidence (section 5.1.3), then the scores and probabilities.
    // The cylinder runs beside the box and sphere evidence: they set different fields of r, and
    // only the sphere reads one the box sets.
    const ObjectBox box = MeasureExtents(cloud, usable, plane, r);
    const SacParams sac = ShapeFitSac(params);
    CylinderEvidence best_cyl;
    float sphere_score = 0.0f;
    ParallelInvoke(
        params.num_threads,
        [&] {
            best_cyl = BestCylinder(cloud, sample, plane, box.box, sac, axis_angle,
                                    cos_inlier_normal, params, r);
        },
        [&] {
            MeasureBoxLikeness(cloud, usable, sample, parts, plane, axis_angle, params, r);
            sphere_score = SphereScore(cloud, sample, sac, cos_inlier_normal, params, r);
        });
    const float plate = PlateScore(cloud, usable, box, plane.has_value(), params, r);
    const float flat_share = FlatShare(r.extents, params);
    ScoreCategories(sphere_score, best_cyl.score, plate, flat_share, params.min_evidence, r);
    SetProbabilities(params.sharpness, r);
    LogDebug(
        "category: {} points, extents {:.3f} {:.3f} {:.3f}, box {:.2f} (axis {:.2f}, side {:.2f}, "
        "planar parts {:.2f}), cylinder {:.2f} (r {:.3f}), sphere {:.2f}, thin {:.2f}, "
        "fill {:.2f}, cover {:.2f} -> {}",
        r.points, r.extents[0], r.extents[1], r.extents[2], r.box_score, r.axis_area,
        r.side_face_ratio, r.planar_part_ratio, best_cyl.score, r.cylinder_radius, sphere_score,
        r.thickness_ratio, r.footprint_fill, r.footprint_cover, CategoryName(r.category));
    return r;
}

}  // namespace multicue
