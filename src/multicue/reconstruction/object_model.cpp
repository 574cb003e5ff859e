// Models of perceived objects (thesis section 5.4): the primitive of the object's category, a
// surface of revolution where that explains more, verification against the frame (section
// 4.2.4.3), triangulated meshes where the primitive fails (section 5.4.2.3), attached outlier
// surfaces and a grasp summary.

#include "multicue/reconstruction/object_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/core/task_order.hpp"
#include "multicue/reconstruction/fit_guidance.hpp"

namespace multicue {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Unit up of a support plane, or zero without one.
Eigen::Vector3f PlaneUp(const Eigen::Vector4f& plane) {
    const float n = plane.head<3>().norm();
    return n > 0.5f ? Eigen::Vector3f(plane.head<3>() / n) : Eigen::Vector3f::Zero();
}

// The scan points whose rays from the sensor can cross the box [lo, hi]. For an organized frame
// in the sensor's frame (a pinhole: x/z and y/z affine in the pixel column and row, checked on a
// sample of pixels), only the pixels inside the box's projected rectangle; otherwise none, which
// means every point (VerifyModel clips every ray to its grid and skips invalid points, so the
// caller passes the frame itself instead of a copy of it).
std::optional<PointCloud> RaysThroughBox(const PointCloud& cloud, const Eigen::Vector3f& lo,
                                         const Eigen::Vector3f& hi, float voxel_size) {
    PointCloud out;
    if (!cloud.IsOrganized()) return std::nullopt;
    const Eigen::Matrix3f to_sensor = cloud.sensor_orientation.conjugate().toRotationMatrix();
    auto local = [&](const Eigen::Vector3f& p) -> Eigen::Vector3f {
        return to_sensor * (p - cloud.sensor_origin);
    };
    // Least squares x/z = a u + b and y/z = c v + d over every 8th pixel in both directions.
    Eigen::Matrix2d su = Eigen::Matrix2d::Zero(), sv = Eigen::Matrix2d::Zero();
    Eigen::Vector2d bu = Eigen::Vector2d::Zero(), bv = Eigen::Vector2d::Zero();
    std::vector<Eigen::Vector4d> samples;  // u, v, x/z, y/z
    for (std::uint32_t v = 0; v < cloud.height; v += 8) {
        for (std::uint32_t u = 0; u < cloud.width; u += 8) {
            const Eigen::Vector3f& p = cloud.At(u, v);
            if (!p.allFinite()) continue;
            const Eigen::Vector3f q = local(p);
            if (!(q.z() > 1e-3f)) continue;
            samples.emplace_back(u, v, q.x() / q.z(), q.y() / q.z());
        }
    }
    if (samples.size() < 20) return std::nullopt;
    for (const auto& s : samples) {
        const Eigen::Vector2d xu(s[0], 1.0), xv(s[1], 1.0);
        su += xu * xu.transpose();
        sv += xv * xv.transpose();
        bu += xu * s[2];
        bv += xv * s[3];
    }
    if (std::abs(su.determinant()) < 1e-9 || std::abs(sv.determinant()) < 1e-9) return std::nullopt;
    const Eigen::Vector2d fu = su.ldlt().solve(bu), fv = sv.ldlt().solve(bv);
    if (std::abs(fu[0]) < 1e-9 || std::abs(fv[0]) < 1e-9) return std::nullopt;
    double worst = 0.0;
    for (const auto& s : samples) {
        worst = std::max(worst, std::abs((s[2] - fu[1]) / fu[0] - s[0]));
        worst = std::max(worst, std::abs((s[3] - fv[1]) / fv[0] - s[1]));
    }
    if (worst > 1.0) return std::nullopt;  // not a pinhole frame in the sensor's coordinates
    double u0 = std::numeric_limits<double>::max(), u1 = -u0, v0 = u0, v1 = -u0, far = 0.0;
    for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3f corner((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(),
                                     (k & 4) ? hi.z() : lo.z());
        const Eigen::Vector3f q = local(corner);
        if (!(q.z() > 1e-3f)) return std::nullopt;  // the box reaches behind the sensor
        far = std::max(far, static_cast<double>(q.z()));
        const double u = (q.x() / q.z() - fu[1]) / fu[0], v = (q.y() / q.z() - fv[1]) / fv[0];
        u0 = std::min(u0, u);
        u1 = std::max(u1, u);
        v0 = std::min(v0, v);
        v1 = std::max(v1, v);
    }
    const double pad = 2.0;
    const auto clamp = [](double x, std::uint32_t n) {
        return static_cast<std::int64_t>(std::clamp(x, 0.0, static_cast<double>(n) - 1.0));
    };
    if (u1 + pad < 0.0 || v1 + pad < 0.0 || u0 - pad > cloud.width - 1.0 ||
        v0 - pad > cloud.height - 1.0) {
        out.height = 1;
        return out;
    }
    const auto ub = clamp(std::floor(u0 - pad), cloud.width),
               ue = clamp(std::ceil(u1 + pad), cloud.width);
    const auto vb = clamp(std::floor(v0 - pad), cloud.height),
               ve = clamp(std::ceil(v1 + pad), cloud.height);
    // Rays at most half a cell apart at the box's farthest depth are enough to mark every cell
    // the sensor saw through, and the points they end in every occupied cell.
    const double footprint = far * std::min(std::abs(fu[0]), std::abs(fv[0]));
    const auto stride =
        static_cast<std::int64_t>(std::clamp(std::floor(0.5 * voxel_size / footprint), 1.0, 8.0));
    for (auto v = vb; v <= ve; v += stride) {
        for (auto u = ub; u <= ue; u += stride) {
            const Eigen::Vector3f& p =
                cloud.At(static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v));
            if (p.allFinite()) out.points.push_back(p);
        }
    }
    out.width = static_cast<std::uint32_t>(out.points.size());
    out.height = 1;
    return out;
}

// Triangulated surface of the given points (at most max_points, an even stride); only vertices
// with triangles are kept.
TriangleMesh TriangulatePoints(const PointCloud& cloud, const Indices& indices,
                               const ModelParams& params) {
    const std::size_t stride =
        std::max<std::size_t>(1, (indices.size() + params.mesh_max_points - 1) /
                                     std::max<std::size_t>(1, params.mesh_max_points));
    PointCloud sub;
    const bool normals = cloud.HasNormals();
    for (std::size_t k = 0; k < indices.size(); k += stride) {
        const Index i = indices[k];
        if (!cloud.IsFinite(i)) continue;
        sub.points.push_back(cloud.points[i]);
        if (normals) sub.normals.push_back(cloud.normals[i]);
    }
    sub.width = static_cast<std::uint32_t>(sub.points.size());
    sub.height = 1;
    sub.sensor_origin = cloud.sensor_origin;
    TriangleMesh mesh;
    if (sub.points.size() < 3) return mesh;
    GreedyTriangulationParams p = params.mesh;
    p.per_label = false;
    p.num_threads = 1;
    if (!p.viewpoint) p.viewpoint = cloud.sensor_origin;
    const TriangleMesh full = GreedyProjectionTriangulation(sub, p).mesh;
    std::vector<std::uint32_t> map(full.vertices.size(), std::numeric_limits<std::uint32_t>::max());
    for (const auto& t : full.triangles) {
        Triangle nt;
        for (int c = 0; c < 3; ++c) {
            auto& m = map[t[c]];
            if (m == std::numeric_limits<std::uint32_t>::max()) {
                m = static_cast<std::uint32_t>(mesh.vertices.size());
                mesh.vertices.push_back(full.vertices[t[c]]);
            }
            nt[c] = m;
        }
        mesh.triangles.push_back(nt);
    }
    return mesh;
}

// Distance of p to the surface of a surface of revolution (side or caps).
float RotationalSurfaceDistance(const RotationalModel& m, const Eigen::Vector3f& point) {
    const Eigen::Vector3f p = point - m.origin;
    const float h = p.dot(m.axis);
    const float r = (p - h * m.axis).norm();
    const float h0 = m.heights.front(), h1 = m.heights.back();
    const float hc = std::clamp(h, h0, h1);
    const float side = std::hypot(r - m.RadiusAt(hc), h - hc);
    const float below = std::max(0.0f, r - m.RadiusAt(h0)),
                above = std::max(0.0f, r - m.RadiusAt(h1));
    const float cap = std::min(std::hypot(h - h0, below), std::hypot(h - h1, above));
    return std::min(side, cap);
}

// Width of the points projected onto the plane, minimised over directions (2 degree steps).
float SmallestHorizontalWidth(const std::vector<Eigen::Vector3f>& points,
                              const Eigen::Vector3f& up) {
    Eigen::Vector3f e1 = up.unitOrthogonal();
    const Eigen::Vector3f e2 = up.cross(e1);
    std::vector<Eigen::Vector2f> flat;
    flat.reserve(points.size());
    for (const auto& p : points) flat.emplace_back(p.dot(e1), p.dot(e2));
    float best = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 90; ++a) {
        const float t = static_cast<float>(a) * static_cast<float>(M_PI) / 90.0f;
        const Eigen::Vector2f d(std::cos(t), std::sin(t));
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        for (const auto& q : flat) {
            const float s = q.dot(d);
            lo = std::min(lo, s);
            hi = std::max(hi, s);
        }
        best = std::min(best, hi - lo);
    }
    return std::isfinite(best) ? best : 0.0f;
}

GraspSummary Grasp(const PointCloud& cloud, const Indices& indices, const ObjectModel& m,
                   const Eigen::Vector4f& plane, const ModelParams& params) {
    GraspSummary g;
    const Eigen::Vector3f up = PlaneUp(plane);
    if (m.box) {
        g.dimensions = {{"length", m.box->extents.x()},
                        {"width", m.box->extents.y()},
                        {"height", m.box->extents.z()}};
    } else if (m.cylinder) {
        g.dimensions = {{"diameter", 2.0f * m.cylinder->radius}, {"height", m.cylinder->height}};
        g.axis = m.cylinder->axis;
    } else if (m.rotational) {
        const auto& r = *m.rotational;
        const float max_r =
            r.radii.empty() ? 0.0f : *std::max_element(r.radii.begin(), r.radii.end());
        g.dimensions = {
            {"max_diameter", 2.0f * max_r},
            {"height", r.heights.empty() ? 0.0f : r.heights.back() - r.heights.front()}};
        g.axis = r.axis;
    } else {
        BoxFitParams bp = params.box;
        bp.use_normals = false;
        const BoxModel b = up.isZero() ? FitOrientedBoundingBox(cloud, indices, bp)
                                       : FitUprightBox(cloud, indices, plane, bp);
        g.dimensions = {
            {"length", b.extents.x()}, {"width", b.extents.y()}, {"height", b.extents.z()}};
    }
    if (m.mesh.vertices.empty()) return g;
    if (!up.isZero()) {
        g.graspable_width = SmallestHorizontalWidth(m.mesh.vertices, up);
    } else {
        PointCloud v;
        v.points = m.mesh.vertices;
        v.width = static_cast<std::uint32_t>(v.points.size());
        v.height = 1;
        Indices all(v.points.size());
        for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<Index>(i);
        const BoxModel b = FitOrientedBoundingBox(v, all, params.box);
        g.graspable_width = b.found ? b.extents.minCoeff() : 0.0f;
    }
    return g;
}

// The guidance of the box and cylinder fits (sections 5.4.1, 5.4.2.1): RSD r_min of the object's
// points and, with part probabilities, each point's probability of the fitted shape.
struct ShapeGuidance {
    std::vector<float> rsd, box_prior, round_prior;
    FitGuidance Box() const { return {.rsd_min_radius = rsd, .shape_prior = box_prior}; }
    FitGuidance Round() const { return {.rsd_min_radius = rsd, .shape_prior = round_prior}; }
};

ShapeGuidance GuideFits(const PointCloud& cloud, const PerceivedObject& object,
                        const ModelParams& params) {
    ShapeGuidance g;
    if (!params.guided_fits || !cloud.HasNormals()) return g;
    RsdParams rp = params.guided_rsd;
    rp.num_threads = params.num_threads;  // nested in the loop over objects: its threads help
    g.rsd = RsdMinRadii(cloud, object.indices, rp);
    if (object.part_probabilities.size() != object.parts.size() || object.parts.empty()) return g;
    g.box_prior.assign(cloud.size(), 0.0f);
    g.round_prior.assign(cloud.size(), 0.0f);
    for (std::size_t k = 0; k < object.parts.size(); ++k) {
        const auto& q = object.part_probabilities[k];
        const auto at = [&](Category x) { return q[static_cast<std::size_t>(x)]; };
        for (Index i : object.parts[k]) {
            g.box_prior[i] = std::clamp(at(Category::kBox) + at(Category::kFlat), 0.0f, 1.0f);
            g.round_prior[i] = std::clamp(
                at(Category::kCylinder) + at(Category::kSphere) + at(Category::kPlate), 0.0f, 1.0f);
        }
    }
    // Points outside every part keep a neutral prior.
    std::vector<char> in_part(cloud.size(), 0);
    for (const auto& part : object.parts) {
        for (Index i : part) in_part[i] = 1;
    }
    for (Index i : object.indices) {
        if (!in_part[i]) g.box_prior[i] = g.round_prior[i] = 0.5f;
    }
    return g;
}

// The primitive of the object's category into `model` (a cylinder for cylinders and plates, else
// a box, upright on the table for boxes and flat objects), replaced by a surface of revolution
// for round and other objects when that explains more than a poor primitive (section 5.4.2.2).
// Returns the inlier ratio of the model kept (0 without one).
float FitPrimitive(const PointCloud& cloud, const PerceivedObject& object,
                   const Eigen::Vector4f& plane, const ModelParams& params,
                   const ShapeGuidance& guidance, ObjectModel& model) {
    const Category c = object.category.category;
    const Eigen::Vector3f up = PlaneUp(plane);
    const bool upright_possible = !up.isZero();
    float inlier_ratio = 0.0f;
    if (c == Category::kCylinder || c == Category::kPlate) {
        CylinderModelParams p = params.cylinder;
        p.sac.num_threads = params.num_threads;
        // The categoriser's cylinder (when it fitted one) starts the refinement.
        std::optional<CylinderStart> start;
        const CategoryResult& r = object.category;
        if (r.cylinder_radius > 0.0f) {
            start = CylinderStart{r.cylinder_point, r.cylinder_axis, r.cylinder_radius};
        }
        CylinderModel cyl =
            FitObjectCylinder(cloud, object.indices, plane, p, guidance.Round(), start);
        if (cyl.found) {
            model.mesh = CylinderMesh(cyl);
            model.cylinder = cyl;
            inlier_ratio = cyl.inlier_ratio;
        }
    }
    if (!model.cylinder) {
        BoxModel box = (c == Category::kBox || c == Category::kFlat) && upright_possible
                           ? FitUprightBox(cloud, object.indices, plane, params.box, guidance.Box())
                           : FitOrientedBoundingBox(cloud, object.indices, params.box);
        if (!box.found) box = FitOrientedBoundingBox(cloud, object.indices, params.box);
        if (box.found) {
            model.mesh = BoxMesh(box);
            model.box = box;
            inlier_ratio = box.inlier_ratio;
        }
    }
    if (params.rotational.enabled && upright_possible && cloud.HasNormals() &&
        (c == Category::kCylinder || c == Category::kOther || c == Category::kSphere) &&
        inlier_ratio < params.min_inlier_ratio) {
        RotationalFitParams rp = params.rotational;
        rp.num_threads = params.num_threads;
        RotationalModel rot = FitRotationalModel(cloud, object.indices, up, plane, rp);
        if (rot.found && rot.inlier_ratio > inlier_ratio) {
            model.box.reset();
            model.cylinder.reset();
            model.mesh = RotationalMesh(rot);
            inlier_ratio = rot.inlier_ratio;
            model.rotational = std::move(rot);
        }
    }
    return inlier_ratio;
}

// Bounding box of a mesh's vertices (empty for a mesh without vertices).
Eigen::AlignedBox3f MeshBounds(const TriangleMesh& mesh) {
    Eigen::AlignedBox3f box;
    for (const auto& v : mesh.vertices) box.extend(v);
    return box;
}

// Verification of the model's mesh against the frame (section 4.2.4.3), none when it is off or
// the model is too large for the grid (a whole room without a table). Surface inside the table
// is as impossible as surface in free space, but hidden from the sensor: samples more than two
// cells below the plane count as invalid.
std::optional<ModelVerificationSummary> VerifyInFrame(const PointCloud& cloud,
                                                      const TriangleMesh& mesh,
                                                      const Eigen::Vector4f& plane,
                                                      const ModelParams& params) {
    if (!params.verification.enabled) return std::nullopt;
    VerificationParams vp = params.verification;
    vp.num_threads = params.num_threads;  // nested in the loop over objects: its threads help
    const Eigen::AlignedBox3f bounds = MeshBounds(mesh);
    Eigen::Vector3f lo = bounds.min(), hi = bounds.max();
    const Eigen::Vector3d cells =
        ((hi - lo).array() + 2.0f * vp.margin).cast<double>() / vp.voxel_size + 1.0;
    if (cells.prod() > 0.9 * static_cast<double>(vp.max_cells)) return std::nullopt;
    lo.array() -= vp.margin;
    hi.array() += vp.margin;
    const std::optional<PointCloud> rays = RaysThroughBox(cloud, lo, hi, vp.voxel_size);
    VerificationResult v = VerifyModel(mesh, rays ? *rays : cloud, cloud.sensor_origin, vp);
    if (!PlaneUp(plane).isZero() && !v.samples.empty()) {
        const float n = plane.head<3>().norm();
        const float depth = 2.0f * vp.voxel_size;
        std::size_t counts[3] = {0, 0, 0};
        for (std::size_t i = 0; i < v.samples.size(); ++i) {
            if ((plane.head<3>().dot(v.samples[i]) + plane.w()) / n < -depth) {
                v.states[i] = SurfaceState::kInvalid;
            }
            ++counts[static_cast<int>(v.states[i])];
        }
        const float total = static_cast<float>(v.samples.size());
        v.verified_ratio = static_cast<float>(counts[0]) / total;
        v.occluded_ratio = static_cast<float>(counts[1]) / total;
        v.invalid_ratio = static_cast<float>(counts[2]) / total;
        v.accepted = v.invalid_ratio <= vp.max_invalid_ratio;
    }
    return ModelVerificationSummary{v.verified_ratio, v.occluded_ratio, v.invalid_ratio,
                                    v.accepted};
}

// Whether the model's mesh has the size of the object's points (ModelParams::max_size_ratio).
bool FitsPointSize(const PointCloud& cloud, const Indices& indices, const TriangleMesh& mesh,
                   const ModelParams& params) {
    Eigen::AlignedBox3f points;
    for (Index i : indices) {
        if (cloud.IsFinite(i)) points.extend(cloud.points[i]);
    }
    if (mesh.vertices.empty() || points.isEmpty()) return true;
    return MeshBounds(mesh).diagonal().norm() <=
           params.max_size_ratio * points.diagonal().norm() + params.size_margin;
}

// A rejected primitive becomes a triangulated mesh of the object's points (section 5.4.2.3);
// `reason` says why (inlier_ratio, size or verification).
void ReplaceByMesh(const PointCloud& cloud, const Indices& indices, float inlier_ratio,
                   const char* reason, const ModelParams& params, ObjectModel& model) {
    TriangleMesh mesh = TriangulatePoints(cloud, indices, params);
    if (mesh.triangles.empty()) return;
    model.replaced = model.box ? "box" : model.cylinder ? "cylinder" : "rotational";
    model.replace_reason = reason;
    model.replaced_inlier_ratio = inlier_ratio;
    model.box.reset();
    model.cylinder.reset();
    model.rotational.reset();
    model.mesh = std::move(mesh);
}

// The outliers of a good primitive (a handle, a spout), triangulated and attached to its mesh.
void AttachOutliers(const PointCloud& cloud, const Indices& indices, const ModelParams& params,
                    ObjectModel& model) {
    float threshold = params.box.inlier_threshold;
    if (model.cylinder) threshold = params.cylinder.inlier_threshold;
    if (model.rotational) threshold = params.rotational.inlier_threshold;
    Indices outliers;
    for (Index i : indices) {
        if (!cloud.IsFinite(i)) continue;
        const Eigen::Vector3f& p = cloud.points[i];
        const float d = model.box        ? BoxSurfaceDistance(*model.box, p)
                        : model.cylinder ? CylinderSurfaceDistance(*model.cylinder, p)
                                         : RotationalSurfaceDistance(*model.rotational, p);
        if (d > threshold) outliers.push_back(i);
    }
    if (outliers.size() < params.min_attached_points) return;
    const TriangleMesh extra = TriangulatePoints(cloud, outliers, params);
    if (extra.triangles.empty()) return;
    model.attached_points = extra.vertices.size();
    model.attached_triangles = extra.triangles.size();
    TriangleMesh base = std::move(model.mesh);
    base.vertex_normals.clear();
    base.vertex_colors.clear();
    base.vertex_labels.clear();
    base.Append(extra);
    model.mesh = std::move(base);
}

// InvalidArgument "name must be <what>, got value" unless `ok`.
void RequireParam(bool ok, const char* name, const char* what, double value) {
    if (!ok) throw InvalidArgument(fmt::format("{} must be {}, got {}", name, what, value));
}

// ModelObject with the parameters checked already.
ObjectModel ModelChecked(const PointCloud& cloud, const PerceivedObject& object,
                         const Eigen::Vector4f& plane, const ModelParams& params) {
    ObjectModel model;
    const ShapeGuidance guidance = GuideFits(cloud, object, params);
    const float inlier_ratio = FitPrimitive(cloud, object, plane, params, guidance, model);
    if (!model.box && !model.cylinder && !model.rotational) {
        model.accepted = false;
        model.grasp = Grasp(cloud, object.indices, model, plane, params);
        return model;
    }
    const bool fits_size = FitsPointSize(cloud, object.indices, model.mesh, params);
    // A model of the wrong size is not verified: its surface says nothing about the object.
    if (fits_size) model.verification = VerifyInFrame(cloud, model.mesh, plane, params);
    model.accepted = fits_size && inlier_ratio >= params.min_inlier_ratio &&
                     (!model.verification || model.verification->accepted);
    const char* reason = !fits_size                               ? "size"
                         : inlier_ratio < params.min_inlier_ratio ? "inlier_ratio"
                                                                  : "verification";
    if (!model.accepted && params.mesh_fallback) {
        ReplaceByMesh(cloud, object.indices, inlier_ratio, reason, params, model);
    } else if (model.accepted && params.min_attached_points > 0) {
        AttachOutliers(cloud, object.indices, params, model);
    }
    model.grasp = Grasp(cloud, object.indices, model, plane, params);
    return model;
}

}  // namespace

void ConcentricMergeParams::Validate() const {
    RequireParam(angle_deg >= 0.0f, "angle_deg", ">= 0", angle_deg);
    RequireParam(distance >= 0.0f, "distance", ">= 0", distance);
    RequireParam(radius_ratio >= 0.0f, "radius_ratio", ">= 0", radius_ratio);
}

void ContainedMergeParams::Validate() const {
    RequireParam(margin >= 0.0f, "margin", ">= 0", margin);
    RequireParam(min_share > 0.0f && min_share <= 1.0f, "min_share", "in (0, 1]", min_share);
}

void StackedSplitParams::Validate() const {
    RequireParam(min_step > 0.0f, "min_step", "> 0", min_step);
    RequireParam(min_gain >= 0.0f, "min_gain", ">= 0", min_gain);
}

void TouchingSplitParams::Validate() const {
    RequireParam(min_gain >= 0.0f, "min_gain", ">= 0", min_gain);
    RequireParam(max_overlap >= 0.0f, "max_overlap", ">= 0", max_overlap);
    RequireParam(max_parts >= 2 && max_parts <= 12, "max_parts", "in [2, 12]", max_parts);
}

void ModelParams::Validate() const {
    RequireParam(min_inlier_ratio >= 0.0f && min_inlier_ratio <= 1.0f, "min_inlier_ratio",
                 "in [0, 1]", min_inlier_ratio);
    RequireParam(max_size_ratio >= 1.0f && std::isfinite(max_size_ratio), "max_size_ratio", ">= 1",
                 max_size_ratio);
    RequireParam(size_margin >= 0.0f && std::isfinite(size_margin), "size_margin", ">= 0",
                 size_margin);
    RequireParam(mesh_max_points >= 3, "mesh_max_points", ">= 3",
                 static_cast<double>(mesh_max_points));
    RequireParam(several_min_ratio >= 0.0f, "several_min_ratio", ">= 0", several_min_ratio);
    ResolveThreadCount(num_threads);
    ValidateNode("mesh", [&] { mesh.Validate(); });
    ValidateNode("guided_rsd", [&] { guided_rsd.Validate(); });
    ValidateNode("box", [&] { box.Validate(); });
    ValidateNode("cylinder", [&] { cylinder.Validate(); });
    ValidateNode("rotational", [&] { rotational.Validate(); });
    ValidateNode("verification", [&] { verification.Validate(); });
    ValidateNode("concentric", [&] { concentric.Validate(); });
    ValidateNode("contained", [&] { contained.Validate(); });
    ValidateNode("stacked", [&] { stacked.Validate(); });
    ValidateNode("touching", [&] { touching.Validate(); });
    ValidateNode("part_counts", [&] { part_counts.Validate(); });
}

ObjectModel ModelObject(const PointCloud& cloud, const PerceivedObject& object,
                        const Eigen::Vector4f& plane, const ModelParams& params) {
    params.Validate();
    return ModelChecked(cloud, object, plane, params);
}

void ModelObjects(const PointCloud& cloud, std::vector<PerceivedObject>& objects,
                  const Eigen::Vector4f& plane, const ModelParams& params,
                  std::span<const std::size_t> which) {
    params.Validate();
    const std::size_t n = which.empty() ? objects.size() : which.size();
    for (std::size_t k : which) {
        if (k >= objects.size()) {
            throw InvalidArgument(fmt::format("object {} of {} to model", k, objects.size()));
        }
    }
    // The largest objects first: a large one started last would keep one thread busy alone.
    const auto target = [&](std::size_t r) { return which.empty() ? r : which[r]; };
    const std::vector<std::size_t> order =
        LargestFirst(n, [&](std::size_t r) { return objects[target(r)].indices.size(); });
    ParallelFor(
        n, params.num_threads,
        [&](std::size_t q) {
            PerceivedObject& o = objects[target(order[q])];
            o.model = ModelChecked(cloud, o, plane, params);
        },
        1);
}

}  // namespace multicue
