#include "multicue/mapping/fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/mapping/fronts.hpp"
#include "multicue/segmentation/euclidean_clustering.hpp"
#include "multicue/segmentation/sac_circle.hpp"
#include "multicue/segmentation/sac_line.hpp"

namespace multicue::mapping {

void FixtureParams::Validate() const {
    auto positive = [](const char* name, float v) {
        if (!(v > 0.0f) || !std::isfinite(v)) {
            throw InvalidArgument(fmt::format("fixtures: {} must be > 0, got {}", name, v));
        }
    };
    positive("max_height", max_height);
    positive("cluster_tolerance", cluster_tolerance);
    positive("max_diameter", max_diameter);
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("fixtures: num_threads must be >= 0, got {}", num_threads));
    }
    positive("max_protrusion_extent", max_protrusion_extent);
    positive("min_protrusion", min_protrusion);
    positive("footprint_reach", footprint_reach);
    if (!(min_contrast >= 0.0f) || !std::isfinite(min_contrast) ||
        !(contrast_min_residual >= 0.0f) || !std::isfinite(contrast_min_residual)) {
        throw InvalidArgument(fmt::format(
            "fixtures: min_contrast and contrast_min_residual must be >= 0, got {} and {}",
            min_contrast, contrast_min_residual));
    }
    if (!(range_noise >= 0.0f) || !std::isfinite(range_noise)) {
        throw InvalidArgument(
            fmt::format("fixtures: range_noise must be >= 0, got {}", range_noise));
    }
    positive("noise_floor", noise_floor);
    positive("background_cell", background_cell);
    positive("residual_cell", residual_cell);
    positive("min_residual", min_residual);
    positive("point_sigmas", point_sigmas);
    positive("surround_outer", surround_outer);
    positive("background_tolerance", background_tolerance);
    if (!(residual_sigmas >= 0.0f) || background_radius < 0 || background_radius > 20 ||
        background_passes < 1 || background_passes > 5 ||
        !(surround_inner >= 0.0f && surround_inner < surround_outer) ||
        !(min_confidence >= 0.0f && min_confidence <= 1.0f) || min_sides < 0 || min_sides > 4) {
        throw InvalidArgument(fmt::format(
            "fixtures: need residual_sigmas >= 0, background_radius in [0, 20], background_passes "
            "in [1, 5], 0 <= surround_inner < surround_outer, min_confidence in [0, 1], min_sides "
            "in [0, 4] (got {}, {}, {}, {} and {}, {}, {})",
            residual_sigmas, background_radius, background_passes, surround_inner, surround_outer,
            min_confidence, min_sides));
    }
    if (!(lone_min_confidence >= 0.0f && lone_min_confidence <= 1.0f) ||
        !(lone_clearance >= 0.0f) || !std::isfinite(lone_clearance)) {
        throw InvalidArgument(fmt::format(
            "fixtures: need lone_min_confidence in [0, 1] and lone_clearance >= 0 (got {} and {})",
            lone_min_confidence, lone_clearance));
    }
    positive("attach_cell", attach_cell);
    positive("min_blocking_area", min_blocking_area);
    if (!(max_attached_share >= 0.0f && max_attached_share <= 1.0f)) {
        throw InvalidArgument(fmt::format("fixtures: max_attached_share must be in [0, 1], got {}",
                                          max_attached_share));
    }
    if (!(merge_gap >= 0.0f)) {
        throw InvalidArgument(fmt::format("fixtures: merge_gap must be >= 0, got {}", merge_gap));
    }
    positive("min_handle_length", min_handle_length);
    positive("min_elongation", min_elongation);
    positive("max_knob_size", max_knob_size);
    if (!(min_knob_size >= 0.0f) || !(min_knob_roundness >= 0.0f && min_knob_roundness <= 1.0f) ||
        border_px < 0) {
        throw InvalidArgument(fmt::format(
            "fixtures: need min_knob_size >= 0, min_knob_roundness in [0, 1], border_px >= 0 (got "
            "{}, {}, {})",
            min_knob_size, min_knob_roundness, border_px));
    }
    positive("line_threshold", line_threshold);
    positive("circle_threshold", circle_threshold);
    if (!(min_height >= 0.0f && min_height < max_height)) {
        throw InvalidArgument(fmt::format(
            "fixtures: need 0 <= min_height < max_height, got {} and {}", min_height, max_height));
    }
    if (!(face_margin >= 0.0f)) {
        throw InvalidArgument(
            fmt::format("fixtures: face_margin must be >= 0, got {}", face_margin));
    }
    if (min_points < 3) {
        throw InvalidArgument(fmt::format("fixtures: min_points must be >= 3, got {}", min_points));
    }
}

bool ClassifyFixture(const PointCloud& cloud, const Indices& cluster, const PlanarComponent& face,
                     const RoomFrame& frame, const FixtureParams& p, Fixture& out) {
    if (cluster.size() < 3) return false;
    return MeasureFixture(cloud, cluster, face, frame, p, out) &&
           out.protrusion >= p.min_protrusion && out.depth_extent <= p.max_protrusion_extent;
}

bool MeasureFixture(const PointCloud& cloud, const Indices& cluster, const PlanarComponent& face,
                    const RoomFrame& frame, const FixtureParams& p, Fixture& out) {
    if (cluster.size() < 3) return false;
    const Eigen::Vector3f n = face.plane.head<3>();
    const Eigen::Vector3f u = PlaneU(face, frame), v = PlaneV(face, frame);
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    for (const Index i : cluster) centroid += cloud.points[i];
    centroid /= static_cast<float>(cluster.size());
    // The footprint on the face: principal axes of the projected points.
    Eigen::Matrix2f cov = Eigen::Matrix2f::Zero();
    float protrusion = 0.0f, dmin = std::numeric_limits<float>::infinity(), dmax = -dmin;
    for (const Index i : cluster) {
        const Eigen::Vector3f d = cloud.points[i] - centroid;
        const Eigen::Vector2f q(d.dot(u), d.dot(v));
        cov += q * q.transpose();
        const float h = n.dot(cloud.points[i]) + face.plane.w();
        protrusion = std::max(protrusion, h);
        dmin = std::min(dmin, h);
        dmax = std::max(dmax, h);
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2f> eig(cov);
    const Eigen::Vector2f e1 = eig.eigenvectors().col(1);  // largest eigenvalue last
    const Eigen::Vector2f e2 = eig.eigenvectors().col(0);
    float a0 = std::numeric_limits<float>::infinity(), a1 = -a0, b0 = a0, b1 = -a0;
    for (const Index i : cluster) {
        const Eigen::Vector3f d = cloud.points[i] - centroid;
        const Eigen::Vector2f q(d.dot(u), d.dot(v));
        a0 = std::min(a0, q.dot(e1));
        a1 = std::max(a1, q.dot(e1));
        b0 = std::min(b0, q.dot(e2));
        b1 = std::max(b1, q.dot(e2));
    }
    const float length = a1 - a0, width = std::max(b1 - b0, 0.004f);
    out.depth_extent = dmax - dmin;
    // RANSAC line and circle on the cluster: the handle's bar, the knob's rim.
    LineFitParams lp;
    lp.sac.distance_threshold = p.line_threshold;
    lp.sac.seed = p.seed;
    lp.sac.num_threads = 1;
    lp.sac.max_iterations = 200;
    const LineFit line = FitLine(cloud, cluster, lp);
    Circle3dFitParams cp;
    cp.sac.distance_threshold = p.circle_threshold;
    cp.sac.seed = p.seed;
    cp.sac.num_threads = 1;
    cp.sac.max_iterations = 200;
    cp.max_radius = p.max_knob_size / 2;
    cp.viewpoint = centroid + n;
    const Circle3dFit circle = FitCircle3d(cloud, cluster, cp);
    const auto count = static_cast<float>(cluster.size());
    out.line_inlier_ratio = line.found ? static_cast<float>(line.inliers.size()) / count : 0.0f;
    out.circle_inlier_ratio =
        circle.found ? static_cast<float>(circle.inliers.size()) / count : 0.0f;
    out.center = centroid;
    out.length = length;
    out.width = width;
    out.protrusion = protrusion;
    out.indices = cluster;
    const Eigen::Vector3f dir = (e1.x() * u + e1.y() * v).normalized();
    out.direction = dir;
    if (length >= p.min_handle_length && length / width >= p.min_elongation) {
        out.type = FixtureType::kHandle;
        // The bar's direction: the line's, once it lies along the footprint (a line fitted to
        // the stand-offs of a short handle can point away from the face).
        Eigen::Vector3f d = dir;
        if (line.found) {
            Eigen::Vector3f l = line.direction - line.direction.dot(n) * n;
            if (l.norm() > 0.5f && std::abs(l.normalized().dot(dir)) > 0.9f) d = l.normalized();
        }
        // A fixed sign: handles point along +u or +v.
        if (d.dot(u) + d.dot(v) * 1e-3f < 0) d = -d;
        out.direction = d;
        return true;
    }
    if (std::max(length, width) <= p.max_knob_size && width >= p.min_knob_size &&
        width >= p.min_knob_roundness * length) {
        out.type = FixtureType::kKnob;
        out.direction = n;
        return true;
    }
    return false;
}

void CheckFixtureClassifier(const ml::Classifier& c) {
    ml::CheckClassifierFor(c, FixtureFeatureNames(), FixtureClassNames(), "fixtures", "fixture");
    bool none = false, fixture = false;
    for (const auto& name : c.class_names()) {
        none = none || name == "none";
        fixture = fixture || name != "none";
    }
    if (!none || !fixture) {
        throw InvalidArgument("fixtures: the classifier must predict none and handle or knob");
    }
}

const char* FixtureByRules(const FixtureEvidence& e, bool shape_ok, const FixtureParams& p) {
    if (e.border > 0.0f) return "image border";
    if (e.local_protrusion < p.min_protrusion || e.depth_extent > p.max_protrusion_extent) {
        return "low";
    }
    if (!shape_ok) return "shape";
    if (e.sides < static_cast<float>(p.min_sides)) return "not in front of the face";
    if (e.attached_share > p.max_attached_share) return "attached to another plane";
    return "";
}

namespace {

/// Pieces of one fixture (a handle's bar and its posts, split by a shadow) whose boxes nearly
/// touch become one cluster.
std::vector<Indices> MergeClose(const PointCloud& cloud, std::vector<Indices> merged, float gap) {
    for (bool changed = true; changed;) {
        changed = false;
        for (std::size_t a = 0; a < merged.size() && !changed; ++a) {
            Eigen::AlignedBox3f ba;
            for (const Index i : merged[a]) ba.extend(cloud.points[i]);
            for (std::size_t b = a + 1; b < merged.size(); ++b) {
                Eigen::AlignedBox3f bb;
                for (const Index i : merged[b]) bb.extend(cloud.points[i]);
                const Eigen::Vector3f d =
                    (ba.min() - bb.max()).cwiseMax(bb.min() - ba.max()).cwiseMax(0.0f);
                if (d.norm() <= gap) {
                    merged[a].insert(merged[a].end(), merged[b].begin(), merged[b].end());
                    std::sort(merged[a].begin(), merged[a].end());
                    merged.erase(merged.begin() + static_cast<long>(b));
                    changed = true;
                    break;
                }
            }
        }
    }
    return merged;
}

/// Cells of the planes large enough to block, with the axes present (bit k for axis k): a
/// cluster next to a plane of another orientation is an edge (a worktop's, a side panel's).
class PlaneCells {
  public:
    PlaneCells(const PointCloud& cloud, const RoomFrame& frame, const RoomStructure& s,
               const FixtureParams& p)
        : cloud_(cloud), frame_(frame), cell_(p.attach_cell) {
        for (const PlanarComponent& c : s.components) {
            if (c.area < p.min_blocking_area) continue;
            for (const Index i : c.indices) cells_[Key(cloud.points[i])] |= 1u << c.axis;
        }
    }
    float AttachedShare(const Indices& cluster, int axis) const {
        std::size_t attached = 0;
        const auto others = static_cast<std::uint8_t>(7u & ~(1u << axis));
        for (const Index i : cluster) {
            const Eigen::Vector3f q = frame_.axes.transpose() * cloud_.points[i] / cell_;
            bool found = false;
            for (int dx = -1; dx <= 1 && !found; ++dx) {
                for (int dy = -1; dy <= 1 && !found; ++dy) {
                    for (int dz = -1; dz <= 1 && !found; ++dz) {
                        const Eigen::Vector3f x =
                            frame_.axes * ((q + Eigen::Vector3f(dx, dy, dz)) * cell_);
                        const auto it = cells_.find(Key(x));
                        found = it != cells_.end() && (it->second & others) != 0;
                    }
                }
            }
            attached += found;
        }
        return static_cast<float>(attached) /
               static_cast<float>(std::max<std::size_t>(1, cluster.size()));
    }

  private:
    std::uint64_t Key(const Eigen::Vector3f& x) const {
        const Eigen::Vector3f q = frame_.axes.transpose() * x / cell_;
        auto c = [](float v) {
            return static_cast<std::uint64_t>(std::floor(v) + (1 << 20)) & 0x1fffff;
        };
        return (c(q.x()) << 42) | (c(q.y()) << 21) | c(q.z());
    }
    const PointCloud& cloud_;
    const RoomFrame& frame_;
    float cell_;
    std::unordered_map<std::uint64_t, std::uint8_t> cells_;
};

/// Closest distance between the axes of two fixtures: a handle's segment along its direction, a
/// knob's centre.
float FixtureAxisDistance(const Fixture& a, const Fixture& b) {
    auto half = [](const Fixture& f) {
        return f.type == FixtureType::kHandle ? 0.5f * f.length * f.direction
                                              : Eigen::Vector3f::Zero().eval();
    };
    const Eigen::Vector3f p0 = a.center - half(a), d0 = 2.0f * half(a);
    const Eigen::Vector3f p1 = b.center - half(b), d1 = 2.0f * half(b);
    // Closest points of segments p0 + s d0 and p1 + t d1, s and t in [0, 1].
    const Eigen::Vector3f r = p0 - p1;
    const float a00 = d0.squaredNorm(), a11 = d1.squaredNorm(), a01 = d0.dot(d1);
    const float b0 = d0.dot(r), b1 = d1.dot(r);
    constexpr float kTiny = 1e-12f;
    float s = 0.0f, t = 0.0f;
    if (a00 <= kTiny && a11 <= kTiny) return r.norm();
    if (a00 <= kTiny) {
        t = std::clamp(b1 / a11, 0.0f, 1.0f);
    } else if (a11 <= kTiny) {
        s = std::clamp(-b0 / a00, 0.0f, 1.0f);
    } else {
        const float det = a00 * a11 - a01 * a01;
        s = det > kTiny ? std::clamp((a01 * b1 - a11 * b0) / det, 0.0f, 1.0f) : 0.0f;
        t = (a01 * s + b1) / a11;
        if (t < 0.0f) {
            t = 0.0f;
            s = std::clamp(-b0 / a00, 0.0f, 1.0f);
        } else if (t > 1.0f) {
            t = 1.0f;
            s = std::clamp((a01 - b0) / a00, 0.0f, 1.0f);
        }
    }
    return (p0 + s * d0 - p1 - t * d1).norm();
}

}  // namespace

void AcceptLoneCandidates(const std::vector<FixtureCandidate*>& candidates,
                          const FixtureParams& p) {
    p.Validate();
    std::vector<const Fixture*> accepted;
    std::vector<FixtureCandidate*> low;
    for (FixtureCandidate* c : candidates) {
        if (c->accepted) {
            accepted.push_back(&c->fixture);
        } else if (c->confidence >= p.lone_min_confidence) {
            low.push_back(c);
        }
    }
    std::stable_sort(low.begin(), low.end(),
                     [](const FixtureCandidate* a, const FixtureCandidate* b) {
                         return a->confidence > b->confidence;
                     });
    for (FixtureCandidate* c : low) {
        if (std::any_of(accepted.begin(), accepted.end(), [&](const Fixture* f) {
                return FixtureAxisDistance(*f, c->fixture) < p.lone_clearance;
            })) {
            continue;
        }
        c->accepted = true;
        c->reason = "";
        accepted.push_back(&c->fixture);
    }
}

FixtureResult DetectFixtures(const PointCloud& cloud, const RoomFrame& frame,
                             const RoomStructure& s, const FixtureParams& p,
                             const std::vector<float>& ranges, const ml::Classifier* classifier) {
    p.Validate();
    if (classifier != nullptr) CheckFixtureClassifier(*classifier);
    FixtureResult result;
    if (cloud.empty()) return result;
    if (!ranges.empty() && ranges.size() != cloud.size()) {
        throw InvalidArgument(
            fmt::format("fixtures: {} ranges for {} points", ranges.size(), cloud.size()));
    }
    result.point_face.assign(cloud.size(), -1);
    result.point_residual.assign(cloud.size(), std::numeric_limits<float>::quiet_NaN());
    std::vector<int> faces, face_slot(s.components.size(), -1);
    for (std::size_t c = 0; c < s.components.size(); ++c) {
        // Faces too small to block are no doors (a handle's bar can be one): their points are
        // looked for in front of the larger faces.
        if (s.components[c].label != MapClass::kFace ||
            s.components[c].area < p.min_blocking_area) {
            continue;
        }
        face_slot[c] = static_cast<int>(faces.size());
        faces.push_back(static_cast<int>(c));
    }
    if (faces.empty()) return result;
    const std::vector<float> look =
        cloud.HasColors() || cloud.HasIntensity()
            ? AppearanceValues(cloud, AppearanceCue::kAuto, 255.0f)
            : std::vector<float>(cloud.size(), std::numeric_limits<float>::quiet_NaN());
    // Every point on a face or in front of one is a sample of that face.
    // The face of every point in parallel, then the samples in point order.
    std::vector<std::int32_t> face_of(cloud.size(), -1);
    ParallelFor(cloud.size(), p.num_threads, [&](std::size_t i) {
        if (!cloud.IsFinite(i)) return;
        const Eigen::Vector3f& x = cloud.points[i];
        const int comp = i < s.point_component.size() ? s.point_component[i] : -1;
        int best = comp >= 0 ? face_slot[static_cast<std::size_t>(comp)] : -1;
        if (best < 0) {
            // The orientation of the plane the point lies on; only planes of some size block (a
            // flat handle's sides are planes too, but small ones).
            int axis = i < s.plane_axis.size() ? s.plane_axis[i] : -1;
            const bool blocking = comp >= 0 && s.components[static_cast<std::size_t>(comp)].area >=
                                                   p.min_blocking_area;
            if (!blocking && axis >= 0 && comp >= 0) axis = -1;
            float best_h = std::numeric_limits<float>::infinity();
            for (std::size_t k = 0; k < faces.size(); ++k) {
                const PlanarComponent& c = s.components[static_cast<std::size_t>(faces[k])];
                // Points on planes of other orientations (a worktop, a side panel) are no fixtures.
                if (blocking && axis != c.axis) continue;
                const float h = c.plane.head<3>().dot(x) + c.plane.w();
                if (h > p.max_height || h < -p.min_height || h >= best_h) continue;
                const Eigen::Vector2f q = PlaneCoordinates(c, frame, x);
                if ((q.array() < c.min.array() - p.face_margin).any() ||
                    (q.array() > c.max.array() + p.face_margin).any()) {
                    continue;
                }
                best = static_cast<int>(k);
                best_h = h;
                // On a large face's surface: that face's (the edge of a door standing in front of
                // the frame, where normals bend).
                if (h < p.min_height && c.area >= p.min_blocking_area) break;
            }
        }
        face_of[i] = best;
    });
    std::vector<FaceSamples> samples(faces.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const int best = face_of[i];
        if (best < 0) continue;
        const Eigen::Vector3f& x = cloud.points[i];
        const PlanarComponent& c = s.components[static_cast<std::size_t>(faces[best])];
        FaceSamples& fs = samples[static_cast<std::size_t>(best)];
        const float r = ranges.empty() ? (x - cloud.sensor_origin).norm() : ranges[i];
        fs.points.push_back(static_cast<Index>(i));
        fs.q.push_back(PlaneCoordinates(c, frame, x));
        fs.height.push_back(c.plane.head<3>().dot(x) + c.plane.w());
        fs.appearance.push_back(look[i]);
        if (cloud.HasColors()) {
            // Colour beside the grey level: two opponent channels (FaceSamples::chroma).
            const Color& rgb = cloud.colors[i];
            const float red = rgb.r, green = rgb.g, blue = rgb.b;
            fs.chroma.push_back(
                std::isnan(look[i])
                    ? Eigen::Vector2f::Constant(look[i])
                    : Eigen::Vector2f((red - green) / std::sqrt(2.0f),
                                      (red + green - 2.0f * blue) / std::sqrt(6.0f)));
        }
        fs.sigma.push_back(std::max(p.noise_floor, p.range_noise * r * r));
        fs.range.push_back(r);
    }
    const PlaneCells plane_cells(cloud, frame, s, p);
    std::vector<std::int32_t> sample_of(cloud.size(), -1);
    // The faces in parallel (each point is a sample of one face only, so the per-point arrays
    // are written in disjoint places); their clusters are then classified and joined in face
    // order, so the result does not depend on the thread count.
    struct Measured {
        FixtureCandidate candidate;
        bool shape_ok = false;
        bool too_large = false;
        Eigen::Vector3f center = Eigen::Vector3f::Zero();
        std::size_t points = 0;
    };
    std::vector<Indices> face_candidates(faces.size());
    std::vector<std::vector<Measured>> measured(faces.size());
    ParallelFor(
        faces.size(), p.num_threads,
        [&](std::size_t k) {
            FaceSamples& fs = samples[k];
            if (fs.size() < p.min_points) return;
            const PlanarComponent& face = s.components[static_cast<std::size_t>(faces[k])];
            ComputeFaceResiduals(fs, p.background_cell, p.background_radius, p.background_passes,
                                 p.min_residual);
            // Heights above the background averaged per small cell: a handle one depth step out of
            // its door stands out of the noise once a few of its points are averaged.
            struct Cell {
                float sum = 0.0f, sigma = 0.0f;
                std::uint32_t n = 0;
            };
            std::unordered_map<std::uint64_t, Cell> cells;
            auto key = [&](const Eigen::Vector2f& q) {
                const auto a = static_cast<std::int64_t>(std::floor(q.x() / p.residual_cell));
                const auto b = static_cast<std::int64_t>(std::floor(q.y() / p.residual_cell));
                return (static_cast<std::uint64_t>(a + (1 << 30)) << 32) ^
                       static_cast<std::uint64_t>(b + (1 << 30));
            };
            for (std::size_t j = 0; j < fs.size(); ++j) {
                Cell& c = cells[key(fs.q[j])];
                c.sum += fs.residual[j];
                c.sigma += fs.sigma[j];
                ++c.n;
            }
            // Appearance residuals: the distance of a point's grey level and colour from their
            // local background, the same cells' median of medians (one pass: a handle may be
            // darker or brighter than its front, or of its grey level and another hue).
            std::vector<float> contrast;
            if (p.min_contrast > 0.0f && std::all_of(fs.appearance.begin(), fs.appearance.end(),
                                                     [](float a) { return std::isfinite(a); })) {
                contrast = AppearanceContrast(fs, p.background_radius);
            }
            Indices candidates, by_contrast;
            for (std::size_t j = 0; j < fs.size(); ++j) {
                const bool contrasting = !contrast.empty() &&
                                         fs.residual[j] >= p.contrast_min_residual &&
                                         contrast[j] >= p.min_contrast;
                if (contrasting) by_contrast.push_back(fs.points[j]);
                if (fs.residual[j] <= 0.0f) continue;
                const Cell& c = cells[key(fs.q[j])];
                const float n = static_cast<float>(c.n);
                const float threshold =
                    std::max(p.min_residual, p.residual_sigmas * c.sigma / n / std::sqrt(n));
                // Its cell stands out on average, or the point itself clearly does (sparse scans).
                if (c.sum / n >= threshold ||
                    fs.residual[j] >= std::max(p.min_residual, p.point_sigmas * fs.sigma[j])) {
                    candidates.push_back(fs.points[j]);
                }
            }
            for (std::size_t j = 0; j < fs.size(); ++j) {
                sample_of[fs.points[j]] = static_cast<std::int32_t>(j);
            }
            face_candidates[k] = candidates;
            auto cluster_points = [&](Indices subset) {
                if (subset.size() < p.min_points) return std::vector<Indices>{};
                EuclideanClusteringParams cp;
                cp.tolerance = p.cluster_tolerance;
                cp.min_cluster_size = p.min_points;
                cp.subset = std::move(subset);
                return MergeClose(cloud, EuclideanClusteringGrid(cloud, cp).clusters, p.merge_gap);
            };
            std::vector<Indices> clusters = cluster_points(candidates);
            if (!by_contrast.empty()) {
                // Clusters of the depth candidates stay as they are; clusters of the depth and
                // appearance candidates together are added where they hold none of them (a thin
                // handle whose depth hardly leaves the noise, but whose colour does).
                // Marked per sample of this face (sample_of), not per cloud point.
                std::vector<bool> taken(fs.size(), false);
                for (const auto& c : clusters) {
                    for (const Index i : c) taken[static_cast<std::size_t>(sample_of[i])] = true;
                }
                Indices all = candidates;
                all.insert(all.end(), by_contrast.begin(), by_contrast.end());
                std::sort(all.begin(), all.end());
                all.erase(std::unique(all.begin(), all.end()), all.end());
                for (auto& c : cluster_points(std::move(all))) {
                    if (std::none_of(c.begin(), c.end(), [&](Index i) {
                            return taken[static_cast<std::size_t>(sample_of[i])];
                        })) {
                        face_candidates[k].insert(face_candidates[k].end(), c.begin(), c.end());
                        clusters.push_back(std::move(c));
                    }
                }
                // A depth candidate left out of the depth clusters may be in an added one.
                std::sort(face_candidates[k].begin(), face_candidates[k].end());
                face_candidates[k].erase(
                    std::unique(face_candidates[k].begin(), face_candidates[k].end()),
                    face_candidates[k].end());
            }
            for (const Indices& cluster : clusters) {
                Eigen::AlignedBox3f box;
                for (const Index i : cluster) box.extend(cloud.points[i]);
                Measured m;
                m.center = box.center();
                m.points = cluster.size();
                if (box.sizes().norm() > p.max_diameter) {
                    m.too_large = true;
                    measured[k].push_back(std::move(m));
                    continue;
                }
                FixtureCandidate& cand = m.candidate;
                cand.fixture.face = faces[k];
                m.shape_ok = MeasureFixture(cloud, cluster, face, frame, p, cand.fixture);
                std::vector<std::uint32_t> members;
                for (const Index i : cluster) {
                    members.push_back(static_cast<std::uint32_t>(sample_of[i]));
                }
                cand.evidence = MeasureFixtureEvidence(fs, members, cand.fixture, face, frame,
                                                       s.floor_height, p);
                if (cloud.IsOrganized() && p.border_px > 0) {
                    const auto b = static_cast<std::uint32_t>(p.border_px);
                    for (const Index i : cluster) {
                        const std::uint32_t u = i % cloud.width, v = i / cloud.width;
                        if (u < b || v < b || u + b >= cloud.width || v + b >= cloud.height) {
                            cand.evidence.border = 1.0f;
                        }
                    }
                }
                cand.evidence.attached_share = plane_cells.AttachedShare(cluster, face.axis);
                measured[k].push_back(std::move(m));
            }
            for (std::size_t j = 0; j < fs.size(); ++j) {
                result.point_face[fs.points[j]] = faces[k];
                result.point_residual[fs.points[j]] = fs.residual[j];
            }
        },
        1);
    for (std::size_t k = 0; k < faces.size(); ++k) {
        result.candidate_points.insert(result.candidate_points.end(), face_candidates[k].begin(),
                                       face_candidates[k].end());
        const PlanarComponent& face = s.components[static_cast<std::size_t>(faces[k])];
        for (Measured& m : measured[k]) {
            if (m.too_large) continue;
            FixtureCandidate& cand = m.candidate;
            if (classifier != nullptr) {
                const std::vector<float> row = FixtureFeatureRow(cand.evidence);
                const ml::FeatureMatrix x = Eigen::Map<const ml::FeatureMatrix>(
                    row.data(), 1, static_cast<Eigen::Index>(row.size()));
                const ml::FeatureMatrix proba = classifier->PredictProba(x);
                float handle = 0.0f, knob = 0.0f;
                for (std::size_t c = 0; c < classifier->num_classes(); ++c) {
                    const auto& name = classifier->class_names()[c];
                    (name == "handle" ? handle
                     : name == "knob" ? knob
                                      : cand.confidence) += proba(0, static_cast<Eigen::Index>(c));
                }
                cand.confidence = handle + knob;
                cand.accepted = cand.confidence >= p.min_confidence;
                cand.fixture.type = handle >= knob ? FixtureType::kHandle : FixtureType::kKnob;
                if (cand.fixture.type == FixtureType::kKnob) {
                    cand.fixture.direction = face.plane.head<3>();
                }
                cand.reason = cand.accepted ? "" : "classifier";
            } else {
                cand.reason = FixtureByRules(cand.evidence, m.shape_ok, p);
                cand.accepted = cand.reason[0] == '\0';
                cand.confidence = cand.accepted ? 1.0f : 0.0f;
            }
        }
    }
    // Lone candidates are judged against the fixtures of every face (a handle near a face's
    // edge may stand beside one on the next face), then all are joined in face order.
    if (classifier != nullptr && p.lone_min_confidence < p.min_confidence) {
        std::vector<FixtureCandidate*> all;
        for (auto& face_measured : measured) {
            for (Measured& m : face_measured) {
                if (!m.too_large) all.push_back(&m.candidate);
            }
        }
        AcceptLoneCandidates(all, p);
    }
    for (std::size_t k = 0; k < faces.size(); ++k) {
        for (Measured& m : measured[k]) {
            if (m.too_large) {
                ++result.too_large;
                result.rejected.push_back({m.center, m.points, "too large"});
                continue;
            }
            FixtureCandidate& cand = m.candidate;
            if (cand.accepted) {
                result.fixtures.push_back(cand.fixture);
            } else {
                ++result.unclassified;
                result.rejected.push_back({m.center, m.points, cand.reason});
            }
            result.candidates.push_back(std::move(cand));
        }
    }
    return result;
}

}  // namespace multicue::mapping
