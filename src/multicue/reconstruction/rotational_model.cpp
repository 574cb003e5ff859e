#include "multicue/reconstruction/rotational_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/parallel.hpp"

namespace multicue {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Sample {
    Eigen::Vector3d p;  // relative to the centroid
    Eigen::Vector3d n;
};

struct AxisFit {
    double cost = std::numeric_limits<double>::infinity();
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d center = Eigen::Vector3d::Zero();  // relative to the centroid
};

void OrthonormalBasis(const Eigen::Vector3d& a, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
    const Eigen::Vector3d helper =
        std::abs(a.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    e1 = a.cross(helper).normalized();
    e2 = a.cross(e1);
}

/// The truncated line-to-line cost of the best axis with direction `a` (see the header).
AxisFit EvaluateDirection(const std::vector<Sample>& samples, std::size_t stride,
                          const Eigen::Vector3d& a, double t, double sin_parallel) {
    Eigen::Vector3d e1, e2;
    OrthonormalBasis(a, e1, e2);
    struct Row {
        double b, g1, g2;
    };
    std::vector<Row> rows;
    rows.reserve(samples.size() / stride + 1);
    std::size_t parallel = 0;
    for (std::size_t i = 0; i < samples.size(); i += stride) {
        const Eigen::Vector3d v = samples[i].n.cross(a);
        const double s = v.norm();
        if (s < sin_parallel) {
            ++parallel;
            continue;
        }
        const Eigen::Vector3d m = v / s;
        rows.push_back({m.dot(samples[i].p), m.dot(e1), m.dot(e2)});
    }
    AxisFit fit;
    fit.direction = a;
    if (rows.size() < 3) return fit;
    double u = 0.0, w = 0.0;
    // Least squares, then truncated reweighting with a shrinking window.
    const double windows[] = {std::numeric_limits<double>::infinity(), 4.0 * t, 2.0 * t, t};
    for (double window : windows) {
        double a11 = 0, a12 = 0, a22 = 0, r1 = 0, r2 = 0;
        for (const auto& r : rows) {
            const double residual = r.b - u * r.g1 - w * r.g2;
            if (std::abs(residual) > window) continue;
            a11 += r.g1 * r.g1;
            a12 += r.g1 * r.g2;
            a22 += r.g2 * r.g2;
            r1 += r.g1 * r.b;
            r2 += r.g2 * r.b;
        }
        const double det = a11 * a22 - a12 * a12;
        if (!(std::abs(det) > 1e-12)) break;
        u = (a22 * r1 - a12 * r2) / det;
        w = (a11 * r2 - a12 * r1) / det;
    }
    double cost = 0.25 * t * t * static_cast<double>(parallel);
    for (const auto& r : rows) {
        const double residual = r.b - u * r.g1 - w * r.g2;
        cost += std::min(residual * residual, t * t);
    }
    fit.cost = cost;
    fit.center = u * e1 + w * e2;
    return fit;
}

/// About `count` directions spread evenly over the cap within max_tilt of `pole` (a hemisphere
/// for 90 degrees): a Fibonacci spiral in height.
std::vector<Eigen::Vector3d> CapDirections(const Eigen::Vector3d& pole, double max_tilt_rad,
                                           int count) {
    Eigen::Vector3d e1, e2;
    OrthonormalBasis(pole, e1, e2);
    const double z_min = std::cos(max_tilt_rad);
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    std::vector<Eigen::Vector3d> directions;
    directions.reserve(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) {
        const double z = 1.0 - (1.0 - z_min) * (i + 0.5) / count;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = golden * i;
        directions.push_back(
            (z * pole + r * std::cos(phi) * e1 + r * std::sin(phi) * e2).normalized());
    }
    return directions;
}

void CheckParams(const RotationalFitParams& p) {
    auto bad = [](const std::string& what) { throw InvalidArgument("rotational fit: " + what); };
    if (p.max_points < 10) bad(fmt::format("max_points must be >= 10, got {}", p.max_points));
    if (!(p.line_threshold > 0.0f))
        bad(fmt::format("line_threshold must be > 0, got {}", p.line_threshold));
    if (!(p.parallel_angle_deg >= 0.0f && p.parallel_angle_deg < 80.0f)) {
        bad(fmt::format("parallel_angle_deg must be in [0, 80), got {}", p.parallel_angle_deg));
    }
    if (p.grid_directions < 100)
        bad(fmt::format("grid_directions must be >= 100, got {}", p.grid_directions));
    if (p.refine_candidates < 1)
        bad(fmt::format("refine_candidates must be >= 1, got {}", p.refine_candidates));
    if (!(p.max_tilt_deg > 0.0f && p.max_tilt_deg <= 90.0f)) {
        bad(fmt::format("max_tilt_deg must be in (0, 90], got {}", p.max_tilt_deg));
    }
    if (!(p.profile_step > 0.0f))
        bad(fmt::format("profile_step must be > 0, got {}", p.profile_step));
    if (!(p.inlier_threshold > 0.0f))
        bad(fmt::format("inlier_threshold must be > 0, got {}", p.inlier_threshold));
    if (!(p.min_radius >= 0.0f)) bad(fmt::format("min_radius must be >= 0, got {}", p.min_radius));
}

float Median(std::vector<float>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

}  // namespace

float RotationalModel::RadiusAt(float h) const {
    if (heights.empty() || h < heights.front() || h > heights.back()) return 0.0f;
    const auto it = std::upper_bound(heights.begin(), heights.end(), h);
    if (it == heights.end()) return radii.back();
    const std::size_t k = static_cast<std::size_t>(it - heights.begin());
    if (k == 0) return radii.front();
    const float span = heights[k] - heights[k - 1];
    const float f = span > 0.0f ? (h - heights[k - 1]) / span : 0.0f;
    return radii[k - 1] + f * (radii[k] - radii[k - 1]);
}

RotationalModel FitRotationalModel(const PointCloud& cloud, const Indices& indices,
                                   const Eigen::Vector3f& up, const Eigen::Vector4f& support_plane,
                                   const RotationalFitParams& params) {
    CheckParams(params);
    if (!up.allFinite() || !support_plane.allFinite()) {
        throw InvalidArgument("rotational fit: up and support plane must be finite");
    }
    RotationalModel model;
    if (indices.empty()) return model;
    if (!cloud.HasNormals()) throw DataError("rotational fit: the cloud has no normals");
    for (auto i : indices) {
        if (i >= cloud.size()) {
            throw InvalidArgument(
                fmt::format("rotational fit: index {} out of range ({} points)", i, cloud.size()));
        }
    }
    // Usable points, an even stride through the object.
    Indices usable;
    for (auto i : indices) {
        if (cloud.points[i].allFinite() && cloud.normals[i].allFinite() &&
            cloud.normals[i].squaredNorm() > 0.25f) {
            usable.push_back(i);
        }
    }
    if (usable.size() < 10) return model;
    const std::size_t stride = (usable.size() + params.max_points - 1) / params.max_points;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    std::vector<Sample> samples;
    for (std::size_t k = 0; k < usable.size(); k += stride) {
        const auto i = usable[k];
        samples.push_back(
            {cloud.points[i].cast<double>(), cloud.normals[i].cast<double>().normalized()});
        centroid += samples.back().p;
    }
    centroid /= static_cast<double>(samples.size());
    for (auto& s : samples) s.p -= centroid;

    const double t = params.line_threshold;
    const double sin_parallel = std::sin(params.parallel_angle_deg * kPi / 180.0);
    const bool has_up = up.squaredNorm() > 0.0f;
    const Eigen::Vector3d pole = has_up ? up.cast<double>().normalized() : Eigen::Vector3d::UnitZ();
    const double max_tilt = has_up ? params.max_tilt_deg * kPi / 180.0 : kPi / 2.0;

    // Coarse search on a subset, then local refinement of the best few on all samples.
    const auto directions = CapDirections(pole, max_tilt, params.grid_directions);
    const std::size_t coarse_stride = std::max<std::size_t>(1, samples.size() / 300);
    std::vector<double> costs(directions.size());
    ParallelFor(
        directions.size(), 0,
        [&](std::size_t d) {
            costs[d] =
                EvaluateDirection(samples, coarse_stride, directions[d], t, sin_parallel).cost;
        },
        64);
    std::vector<std::size_t> order(directions.size());
    for (std::size_t d = 0; d < order.size(); ++d) order[d] = d;
    const std::size_t keep =
        std::min<std::size_t>(static_cast<std::size_t>(params.refine_candidates), order.size());
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep), order.end(),
                      [&](std::size_t a, std::size_t b) {
                          return costs[a] < costs[b] || (costs[a] == costs[b] && a < b);
                      });
    const double spacing = std::sqrt(2.0 * kPi * (1.0 - std::cos(max_tilt)) / directions.size());
    AxisFit best;
    for (std::size_t c = 0; c < keep; ++c) {
        AxisFit current = EvaluateDirection(samples, 1, directions[order[c]], t, sin_parallel);
        for (double step = spacing; step > 0.0005;) {
            Eigen::Vector3d e1, e2;
            OrthonormalBasis(current.direction, e1, e2);
            AxisFit next = current;
            for (int i = -1; i <= 1; ++i) {
                for (int j = -1; j <= 1; ++j) {
                    if (i == 0 && j == 0) continue;
                    Eigen::Vector3d a = (current.direction + step * (i * e1 + j * e2)).normalized();
                    if (has_up &&
                        std::acos(std::clamp(std::abs(a.dot(pole)), 0.0, 1.0)) > max_tilt) {
                        continue;
                    }
                    const AxisFit fit = EvaluateDirection(samples, 1, a, t, sin_parallel);
                    if (fit.cost < next.cost) next = fit;
                }
            }
            if (next.cost < current.cost) {
                current = next;
            } else {
                step *= 0.5;
            }
        }
        if (current.cost < best.cost) best = current;
    }
    if (!std::isfinite(best.cost)) return model;

    Eigen::Vector3d a = best.direction;
    Eigen::Index largest = 0;
    a.cwiseAbs().maxCoeff(&largest);
    if (has_up ? a.dot(pole) < 0.0 : a[largest] < 0.0) a = -a;
    const Eigen::Vector3d origin = centroid + best.center;

    // Contour from the points consistent with the axis.
    std::vector<float> all_heights;
    std::vector<std::pair<float, float>> profile_points;  // (height, radius)
    for (auto i : usable) {
        const Eigen::Vector3d p = cloud.points[i].cast<double>() - origin;
        const double h = p.dot(a);
        all_heights.push_back(static_cast<float>(h));
        const Eigen::Vector3d n = cloud.normals[i].cast<double>().normalized();
        const Eigen::Vector3d v = n.cross(a);
        if (v.norm() < sin_parallel) continue;
        if (std::abs(v.normalized().dot(p)) > t) continue;
        profile_points.emplace_back(static_cast<float>(h), static_cast<float>((p - h * a).norm()));
    }
    if (profile_points.size() < 5) return model;
    std::sort(all_heights.begin(), all_heights.end());
    float h_min = all_heights[all_heights.size() / 100];
    const float h_max = all_heights[all_heights.size() - 1 - all_heights.size() / 100];
    if (support_plane.head<3>().squaredNorm() > 0.0f) {
        const Eigen::Vector3d n = support_plane.head<3>().cast<double>().normalized();
        const double d = support_plane[3] / support_plane.head<3>().norm();
        const double along = n.dot(a);
        if (std::abs(along) > 0.5) {
            const double h_plane = -(n.dot(origin) + d) / along;
            if (h_plane < h_min && h_plane > h_min - 0.1) h_min = static_cast<float>(h_plane);
        }
    }
    const float step = params.profile_step;
    const int bins = std::max(1, static_cast<int>(std::ceil((h_max - h_min) / step)));
    std::vector<std::vector<float>> binned(static_cast<std::size_t>(bins));
    for (const auto& [h, r] : profile_points) {
        const int b = static_cast<int>((h - h_min) / step);
        if (b >= 0 && b < bins) binned[static_cast<std::size_t>(b)].push_back(r);
    }
    std::vector<float> radius(static_cast<std::size_t>(bins),
                              std::numeric_limits<float>::quiet_NaN());
    for (int b = 0; b < bins; ++b) {
        auto& v = binned[static_cast<std::size_t>(b)];
        if (v.size() >= 2) radius[static_cast<std::size_t>(b)] = Median(v);
    }
    // Fill gaps by interpolation, ends by the nearest known radius.
    int first = -1, last = -1;
    for (int b = 0; b < bins; ++b) {
        if (std::isnan(radius[static_cast<std::size_t>(b)])) continue;
        if (first < 0) first = b;
        if (last >= 0 && b - last > 1) {
            for (int k = last + 1; k < b; ++k) {
                const float f = static_cast<float>(k - last) / static_cast<float>(b - last);
                radius[static_cast<std::size_t>(k)] = radius[static_cast<std::size_t>(last)] +
                                                      f * (radius[static_cast<std::size_t>(b)] -
                                                           radius[static_cast<std::size_t>(last)]);
            }
        }
        last = b;
    }
    if (first < 0) return model;
    for (int b = 0; b < first; ++b)
        radius[static_cast<std::size_t>(b)] = radius[static_cast<std::size_t>(first)];
    for (int b = last + 1; b < bins; ++b)
        radius[static_cast<std::size_t>(b)] = radius[static_cast<std::size_t>(last)];
    // 3-bin median smoothing.
    std::vector<float> smooth = radius;
    for (int b = 1; b + 1 < bins; ++b) {
        float w[3] = {radius[static_cast<std::size_t>(b - 1)], radius[static_cast<std::size_t>(b)],
                      radius[static_cast<std::size_t>(b + 1)]};
        std::sort(w, w + 3);
        smooth[static_cast<std::size_t>(b)] = w[1];
    }
    model.heights.clear();
    model.radii.clear();
    model.heights.push_back(h_min);
    model.radii.push_back(std::max(params.min_radius, smooth.front()));
    for (int b = 0; b < bins; ++b) {
        model.heights.push_back(std::min(h_max, h_min + (static_cast<float>(b) + 0.5f) * step));
        model.radii.push_back(std::max(params.min_radius, smooth[static_cast<std::size_t>(b)]));
    }
    model.heights.push_back(h_max);
    model.radii.push_back(std::max(params.min_radius, smooth.back()));
    for (std::size_t k = 1; k < model.heights.size(); ++k) {
        model.heights[k] = std::max(model.heights[k], model.heights[k - 1]);
    }
    model.origin = origin.cast<float>();
    model.axis = a.cast<float>();
    model.found = true;
    model.axis_cost = static_cast<float>(best.cost / (static_cast<double>(samples.size()) * t * t));

    std::size_t inliers = 0;
    for (auto i : usable) {
        const Eigen::Vector3f p = cloud.points[i] - model.origin;
        const float h = p.dot(model.axis);
        if (h < model.heights.front() - params.inlier_threshold ||
            h > model.heights.back() + params.inlier_threshold) {
            continue;
        }
        const float r = (p - h * model.axis).norm();
        const float hc = std::clamp(h, model.heights.front(), model.heights.back());
        const bool on_side = std::abs(r - model.RadiusAt(hc)) < params.inlier_threshold;
        const bool on_cap = (h - model.heights.front() < params.inlier_threshold ||
                             model.heights.back() - h < params.inlier_threshold) &&
                            r <= model.RadiusAt(hc) + params.inlier_threshold;
        if (on_side || on_cap) ++inliers;
    }
    model.inlier_ratio = static_cast<float>(inliers) / static_cast<float>(usable.size());
    return model;
}

TriangleMesh RotationalMesh(const RotationalModel& model, int segments) {
    if (segments < 3) throw InvalidArgument(fmt::format("segments must be >= 3, got {}", segments));
    TriangleMesh mesh;
    if (!model.found || model.heights.size() < 2) return mesh;
    Eigen::Vector3d e1, e2;
    OrthonormalBasis(model.axis.cast<double>(), e1, e2);
    const Eigen::Vector3f u = e1.cast<float>(), v = e2.cast<float>();
    const auto rings = static_cast<std::uint32_t>(model.heights.size());
    const auto n = static_cast<std::uint32_t>(segments);
    for (std::uint32_t k = 0; k < rings; ++k) {
        const Eigen::Vector3f center = model.origin + model.heights[k] * model.axis;
        for (std::uint32_t j = 0; j < n; ++j) {
            const float theta = static_cast<float>(2.0 * kPi * j / n);
            mesh.vertices.push_back(center +
                                    model.radii[k] * (std::cos(theta) * u + std::sin(theta) * v));
        }
    }
    auto at = [&](std::uint32_t k, std::uint32_t j) { return k * n + j % n; };
    for (std::uint32_t k = 0; k + 1 < rings; ++k) {
        for (std::uint32_t j = 0; j < n; ++j) {
            mesh.triangles.emplace_back(at(k, j), at(k, j + 1), at(k + 1, j + 1));
            mesh.triangles.emplace_back(at(k, j), at(k + 1, j + 1), at(k + 1, j));
        }
    }
    const auto bottom = static_cast<std::uint32_t>(mesh.vertices.size());
    mesh.vertices.push_back(model.origin + model.heights.front() * model.axis);
    const auto top = bottom + 1;
    mesh.vertices.push_back(model.origin + model.heights.back() * model.axis);
    for (std::uint32_t j = 0; j < n; ++j) {
        mesh.triangles.emplace_back(bottom, at(0, j + 1), at(0, j));
        mesh.triangles.emplace_back(top, at(rings - 1, j), at(rings - 1, j + 1));
    }
    return mesh;
}

}  // namespace multicue
