#include "multicue/reconstruction/rotational_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
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

/// The spread of the contour about an axis: the points' (height, radius) pairs are fitted by a
/// linear spline in height (knots about `step` apart, a light first-difference penalty bridging
/// empty stretches) with Huber weights (scale `tolerance`); points of the inner surface (normal
/// towards the axis: the inside of a bowl or pitcher) share the spline less a constant wall
/// thickness fitted with it. The cost is the mean Huber loss of the radius residuals. A true axis
/// gives a thin profile; a tilted or shifted one smears it.
class ProfileObjective {
  public:
    ProfileObjective(std::vector<Eigen::Vector3d> points, std::vector<char> inner, bool caps,
                     double step, double tolerance)
        : points_(std::move(points)),
          inner_(std::move(inner)),
          caps_(caps),
          step_(step),
          tolerance_(tolerance) {
        for (std::size_t i = 0; i < inner_.size(); ++i) {
            if (inner_[i]) inner_points_.push_back(i);
        }
    }

    std::size_t size() const { return points_.size(); }

    double operator()(const Eigen::Vector3d& a, const Eigen::Vector3d& c) const {
        const std::size_t n = points_.size();
        h_.resize(n);
        rho_.resize(n);
        double h_min = std::numeric_limits<double>::infinity(), h_max = -h_min;
        for (std::size_t i = 0; i < n; ++i) {
            const Eigen::Vector3d q = points_[i] - c;
            double h = q.dot(a);
            double rho = (q - h * a).norm();
            if (caps_) std::swap(h, rho);
            h_[i] = h;
            rho_[i] = rho;
            h_min = std::min(h_min, h);
            h_max = std::max(h_max, h);
        }
        const double extent = std::max(h_max - h_min, 1e-6);
        const std::size_t knots =
            std::max<std::size_t>(2, static_cast<std::size_t>(std::ceil(extent / step_)) + 1);
        const double spacing = extent / static_cast<double>(knots - 1);
        k_.resize(n);
        f_.resize(n);
        w_.assign(n, 1.0);
        StartSystem(knots);
        for (std::size_t i = 0; i < n; ++i) {
            const double s = (h_[i] - h_min) / spacing;  // >= 0: truncation is floor
            const std::size_t k = std::min<std::size_t>(
                knots - 2, static_cast<std::size_t>(static_cast<std::int64_t>(s)));
            k_[i] = k;
            f_[i] = std::clamp(s - static_cast<double>(k), 0.0, 1.0);
            AddPoint(i);
        }
        // Three reweighted solves; the residuals of one give the weights of the next system,
        // which is assembled in the same pass.
        double cost = 0.0;
        for (int iteration = 0; iteration < 3; ++iteration) {
            const double thickness = Solve(knots);
            const bool again = iteration < 2;
            if (again) StartSystem(knots);
            cost = 0.0;
            const double t = tolerance_;
            for (std::size_t i = 0; i < n; ++i) {
                const double model = (1.0 - f_[i]) * x_[k_[i]] + f_[i] * x_[k_[i] + 1] -
                                     (inner_[i] ? thickness : 0.0);
                const double r = std::abs(rho_[i] - model);
                // Both sides computed and one chosen: no branch on the residual.
                const bool near = r <= t;
                const double quadratic = r * r, linear = 2.0 * t * r - t * t;
                cost += near ? quadratic : linear;
                if (again) {
                    const double down = t / r;
                    w_[i] = near ? 1.0 : down;
                    AddPoint(i);
                }
            }
        }
        return cost / static_cast<double>(n);
    }

  private:
    /// The normal equations of the knot radii x_ and the wall thickness without points: the
    /// first-difference penalty, tridiagonal (diag_, off_), and a tiny thickness prior.
    void StartSystem(std::size_t knots) const {
        constexpr double kSmooth = 1e-2;
        diag_.assign(knots, 0.0);
        off_.assign(knots, 0.0);
        rhs_.assign(knots, 0.0);
        border_.assign(knots, 0.0);
        corner_ = 1e-6;
        corner_rhs_ = 0.0;
        for (std::size_t k = 0; k + 1 < knots; ++k) {
            diag_[k] += kSmooth;
            diag_[k + 1] += kSmooth;
            off_[k] -= kSmooth;
        }
    }

    /// Point i with weight w_[i] added to the normal equations (k_ and f_ set).
    void AddPoint(std::size_t i) const {
        const std::size_t k = k_[i];
        const double f = f_[i], g = 1.0 - f, w = w_[i];
        diag_[k] += w * g * g;
        diag_[k + 1] += w * f * f;
        off_[k] += w * g * f;
        rhs_[k] += w * g * rho_[i];
        rhs_[k + 1] += w * f * rho_[i];
        if (inner_[i]) {  // the model's thickness column is -1 for inner points
            border_[k] -= w * g;
            border_[k + 1] -= w * f;
            corner_ += w;
            corner_rhs_ -= w * rho_[i];
        }
    }

    /// Weighted least squares for the knot radii x_ and the wall thickness (returned) from the
    /// assembled system: a tridiagonal system bordered by one column, solved by the Thomas
    /// algorithm for two right hand sides and the Schur complement of the thickness.
    double Solve(std::size_t knots) const {
        for (std::size_t k = 1; k < knots; ++k) {
            const double m = off_[k - 1] / diag_[k - 1];
            diag_[k] -= m * off_[k - 1];
            rhs_[k] -= m * rhs_[k - 1];
            border_[k] -= m * border_[k - 1];
        }
        x_.resize(knots);
        y_.resize(knots);
        const std::size_t last = knots - 1;
        x_[last] = rhs_[last] / diag_[last];
        y_[last] = border_[last] / diag_[last];
        for (std::size_t k = last; k-- > 0;) {
            x_[k] = (rhs_[k] - off_[k] * x_[k + 1]) / diag_[k];
            y_[k] = (border_[k] - off_[k] * y_[k + 1]) / diag_[k];
        }
        // border^T x + corner * thickness = corner_rhs, with x = x_ - thickness * y_ (the
        // border here is the original one: recompute it from the inner points).
        double bx = 0.0, by = 0.0;
        for (const std::size_t i : inner_points_) {
            const std::size_t k = k_[i];
            const double f = f_[i], g = 1.0 - f, w = w_[i];
            bx -= w * (g * x_[k] + f * x_[k + 1]);
            by -= w * (g * y_[k] + f * y_[k + 1]);
        }
        const double thickness = (corner_rhs_ - bx) / (corner_ - by);
        for (std::size_t k = 0; k < knots; ++k) x_[k] -= thickness * y_[k];
        return thickness;
    }

    std::vector<Eigen::Vector3d> points_;
    std::vector<char> inner_;
    std::vector<std::size_t> inner_points_;  // the indices of the inner points
    bool caps_;
    double step_, tolerance_;
    mutable std::vector<double> h_, rho_, f_, w_, x_, y_, diag_, off_, rhs_, border_;
    mutable double corner_ = 0.0, corner_rhs_ = 0.0;
    mutable std::vector<std::size_t> k_;
};

/// The level of an end of the object (a rim, a cap): for an axis through c with direction a, the
/// second highest point in each of `bins` sectors around the axis; on a surface of revolution
/// whose top is in view these agree. Both ends are tried (the axis has no sign here) and the
/// more level one counts: the cost is the mean Huber loss of the levels' deviation from their
/// median (0 with fewer than bins/4 sectors of at least 3 points).
class RimObjective {
  public:
    RimObjective(std::vector<Eigen::Vector3d> points, int bins, double tolerance)
        : points_(std::move(points)), bins_(bins), tolerance_(tolerance) {
        // Sector b starts at the angle 2 pi b / bins from the direction -e1 (atan2 = -pi);
        // its start as a pseudo-angle, so that no point needs a trigonometric function.
        starts_.resize(static_cast<std::size_t>(bins));
        for (int b = 0; b < bins; ++b) {
            const double angle = 2.0 * kPi * b / bins;
            starts_[static_cast<std::size_t>(b)] =
                b == 0 ? 0.0 : Pseudo(std::sin(angle), std::cos(angle));
        }
    }

    double operator()(const Eigen::Vector3d& a, const Eigen::Vector3d& c) const {
        Eigen::Vector3d e1, e2;
        OrthonormalBasis(a, e1, e2);
        const auto bins = static_cast<std::size_t>(bins_);
        const double lowest = -std::numeric_limits<double>::infinity();
        // [0..bins): highest along +a, [bins..2 bins): highest along -a.
        first_.assign(2 * bins, lowest);
        second_.assign(2 * bins, lowest);
        count_.assign(bins, 0);
        for (const auto& p : points_) {
            const Eigen::Vector3d q = p - c;
            const auto b = Sector(q.dot(e2), q.dot(e1));
            const double h = q.dot(a);
            ++count_[b];
            for (const auto& [k, v] : {std::pair{b, h}, std::pair{b + bins, -h}}) {
                if (v > first_[k]) {
                    second_[k] = first_[k];
                    first_[k] = v;
                } else if (v > second_[k]) {
                    second_[k] = v;
                }
            }
        }
        return std::min(LevelCost(0), LevelCost(bins));
    }

  private:
    /// A strictly increasing function of the angle of (x, y) from the x axis over [0, 2 pi),
    /// with values in [0, 4): the position on the unit diamond |x| + |y| = 1.
    static double Pseudo(double y, double x) {
        const double l1 = std::abs(x) + std::abs(y);
        if (l1 == 0.0) return 0.0;
        if (y >= 0.0) return x >= 0.0 ? y / l1 : 1.0 - x / l1;
        return x < 0.0 ? 2.0 - y / l1 : 3.0 + x / l1;
    }

    /// The sector of the direction (x, y) as `floor((atan2(y, x) + pi) / (2 pi) * bins)` gives
    /// it: the angle from -e1 is the angle of (-x, -y).
    std::size_t Sector(double y, double x) const {
        const double p = (x == 0.0 && y == 0.0) ? 2.0 : Pseudo(-y, -x);  // atan2(0, 0) = 0
        const auto last = static_cast<std::size_t>(bins_ - 1);
        auto b = std::min(last, static_cast<std::size_t>(p * 0.25 * bins_));
        while (b > 0 && p < starts_[b]) --b;
        while (b < last && p >= starts_[b + 1]) ++b;
        return b;
    }

    double LevelCost(std::size_t offset) const {
        levels_.clear();
        for (std::size_t b = 0; b < count_.size(); ++b) {
            if (count_[b] >= 3) levels_.push_back(second_[offset + b]);
        }
        if (static_cast<int>(levels_.size()) < std::max(2, bins_ / 4)) return 0.0;
        sorted_ = levels_;
        const auto mid = sorted_.begin() + static_cast<std::ptrdiff_t>(sorted_.size() / 2);
        std::nth_element(sorted_.begin(), mid, sorted_.end());
        double cost = 0.0;
        for (double level : levels_) {
            const double r = std::abs(level - *mid);
            cost += r <= tolerance_ ? r * r : 2.0 * tolerance_ * r - tolerance_ * tolerance_;
        }
        return cost / static_cast<double>(levels_.size());
    }

    std::vector<Eigen::Vector3d> points_;
    int bins_;
    double tolerance_;
    std::vector<double> starts_;
    mutable std::vector<double> first_, second_, levels_, sorted_;
    mutable std::vector<int> count_;
};

/// Nelder-Mead simplex minimisation of `f` from `x0` with initial steps `scale`; stops when the
/// simplex's cost spread falls below `tolerance` or after `max_evaluations`.
template <int N, typename F>
Eigen::Matrix<double, N, 1> NelderMead(const F& f, const Eigen::Matrix<double, N, 1>& x0,
                                       const Eigen::Matrix<double, N, 1>& scale, double tolerance,
                                       int max_evaluations) {
    using Vec = Eigen::Matrix<double, N, 1>;
    std::array<Vec, N + 1> x;
    std::array<double, N + 1> y;
    x[0] = x0;
    for (int i = 0; i < N; ++i) {
        x[i + 1] = x0;
        x[i + 1][i] += scale[i];
    }
    int evaluations = 0;
    for (int i = 0; i <= N; ++i, ++evaluations) y[i] = f(x[i]);
    std::array<int, N + 1> order;
    while (evaluations < max_evaluations) {
        for (int i = 0; i <= N; ++i) order[i] = i;
        std::sort(order.begin(), order.end(), [&](int a, int b) { return y[a] < y[b]; });
        const int best = order[0], worst = order[N], second = order[N - 1];
        if (y[worst] - y[best] <= tolerance) break;
        Vec centroid = Vec::Zero();
        for (int i = 0; i < N; ++i) centroid += x[order[i]];
        centroid /= N;
        const Vec reflected = centroid + (centroid - x[worst]);
        const double y_reflected = f(reflected);
        ++evaluations;
        if (y_reflected < y[best]) {
            const Vec expanded = centroid + 2.0 * (centroid - x[worst]);
            const double y_expanded = f(expanded);
            ++evaluations;
            if (y_expanded < y_reflected) {
                x[worst] = expanded;
                y[worst] = y_expanded;
            } else {
                x[worst] = reflected;
                y[worst] = y_reflected;
            }
        } else if (y_reflected < y[second]) {
            x[worst] = reflected;
            y[worst] = y_reflected;
        } else {
            const bool outside = y_reflected < y[worst];
            const Vec contracted = outside ? Vec(centroid + 0.5 * (reflected - centroid))
                                           : Vec(centroid + 0.5 * (x[worst] - centroid));
            const double y_contracted = f(contracted);
            ++evaluations;
            if (y_contracted < std::min(y[worst], y_reflected)) {
                x[worst] = contracted;
                y[worst] = y_contracted;
            } else {
                for (int i = 1; i <= N; ++i) {
                    x[order[i]] = x[best] + 0.5 * (x[order[i]] - x[best]);
                    y[order[i]] = f(x[order[i]]);
                    ++evaluations;
                }
            }
        }
    }
    int best = 0;
    for (int i = 1; i <= N; ++i) {
        if (y[i] < y[best]) best = i;
    }
    return x[best];
}

/// The truncated line-to-line cost of the axis with direction `a` through `c`.
double LineCost(const std::vector<Sample>& samples, const Eigen::Vector3d& a,
                const Eigen::Vector3d& c, double t, double sin_parallel) {
    double cost = 0.0;
    for (const auto& sample : samples) {
        const Eigen::Vector3d v = sample.n.cross(a);
        const double s = v.norm();
        if (s < sin_parallel) {
            cost += 0.25 * t * t;
            continue;
        }
        const double d = (v / s).dot(sample.p - c);
        cost += std::min(d * d, t * t);
    }
    return cost;
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
    if (p.profile_points < 10)
        bad(fmt::format("profile_points must be >= 10, got {}", p.profile_points));
    if (!(p.rim_weight >= 0.0f && std::isfinite(p.rim_weight)))
        bad(fmt::format("rim_weight must be >= 0, got {}", p.rim_weight));
    if (!(p.cap_weight >= 0.0f && std::isfinite(p.cap_weight)))
        bad(fmt::format("cap_weight must be >= 0, got {}", p.cap_weight));
    if (!(p.profile_tolerance > 0.0f))
        bad(fmt::format("profile_tolerance must be > 0, got {}", p.profile_tolerance));
    if (!(p.min_radius >= 0.0f)) bad(fmt::format("min_radius must be >= 0, got {}", p.min_radius));
    if (p.num_threads < 0) bad(fmt::format("num_threads must be >= 0, got {}", p.num_threads));
}

float MedianInPlace(std::vector<float>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

/// Throws InvalidArgument for an index outside the cloud.
void CheckRotationalIndices(const PointCloud& cloud, const Indices& indices) {
    for (auto i : indices) {
        if (i >= cloud.size()) {
            throw InvalidArgument(
                fmt::format("rotational fit: index {} out of range ({} points)", i, cloud.size()));
        }
    }
}

/// Points with a finite position and a finite, not vanishing normal: only they carry a normal line.
Indices UsablePoints(const PointCloud& cloud, const Indices& indices) {
    Indices usable;
    for (auto i : indices) {
        if (cloud.points[i].allFinite() && cloud.normals[i].allFinite() &&
            cloud.normals[i].squaredNorm() > 0.25f) {
            usable.push_back(i);
        }
    }
    return usable;
}

/// At most max_points usable points, an even stride through the object, relative to their centroid
/// (returned in `centroid`) and with unit normals: more points slow the axis search without making
/// it more accurate.
std::vector<Sample> StridedSamples(const PointCloud& cloud, const Indices& usable,
                                   std::size_t max_points, Eigen::Vector3d& centroid) {
    const std::size_t stride = (usable.size() + max_points - 1) / max_points;
    centroid = Eigen::Vector3d::Zero();
    std::vector<Sample> samples;
    for (std::size_t k = 0; k < usable.size(); k += stride) {
        const auto i = usable[k];
        samples.push_back(
            {cloud.points[i].cast<double>(), cloud.normals[i].cast<double>().normalized()});
        centroid += samples.back().p;
    }
    centroid /= static_cast<double>(samples.size());
    for (auto& s : samples) s.p -= centroid;
    return samples;
}

/// What every axis cost needs of the parameters and of `up` (section 5.4.2.2): the line threshold
/// t, the sine below which a normal counts as parallel to the axis, and the bound on the tilt.
struct AxisSearch {
    double t = 0.0;
    double sin_parallel = 0.0;
    bool has_up = false;
    Eigen::Vector3d pole = Eigen::Vector3d::UnitZ();
    double max_tilt = 0.0;

    /// Whether direction `a` leans more than max_tilt from up (never without an up direction).
    bool TooTilted(const Eigen::Vector3d& a) const {
        return has_up && std::acos(std::clamp(std::abs(a.dot(pole)), 0.0, 1.0)) > max_tilt;
    }
};

AxisSearch MakeAxisSearch(const Eigen::Vector3f& up, const RotationalFitParams& params) {
    AxisSearch search;
    search.t = params.line_threshold;
    search.sin_parallel = std::sin(params.parallel_angle_deg * kPi / 180.0);
    search.has_up = up.squaredNorm() > 0.0f;
    search.pole = search.has_up ? up.cast<double>().normalized() : Eigen::Vector3d::UnitZ();
    search.max_tilt = search.has_up ? params.max_tilt_deg * kPi / 180.0 : kPi / 2.0;
    return search;
}

/// The coarse search: every direction scored on a subset of about 300 samples (cheap, and enough
/// to rank them); the indices of the best `refine_candidates`, ties broken by index.
std::vector<std::size_t> BestCoarseDirections(const std::vector<Sample>& samples,
                                              const std::vector<Eigen::Vector3d>& directions,
                                              const AxisSearch& search, int refine_candidates,
                                              int num_threads) {
    const std::size_t coarse_stride = std::max<std::size_t>(1, samples.size() / 300);
    std::vector<double> costs(directions.size());
    ParallelFor(
        directions.size(), num_threads,
        [&](std::size_t d) {
            costs[d] = EvaluateDirection(samples, coarse_stride, directions[d], search.t,
                                         search.sin_parallel)
                           .cost;
        },
        64);
    std::vector<std::size_t> order(directions.size());
    for (std::size_t d = 0; d < order.size(); ++d) order[d] = d;
    const std::size_t keep =
        std::min<std::size_t>(static_cast<std::size_t>(refine_candidates), order.size());
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep), order.end(),
                      [&](std::size_t a, std::size_t b) {
                          return costs[a] < costs[b] || (costs[a] == costs[b] && a < b);
                      });
    order.resize(keep);
    return order;
}

/// Local refinement of a direction on every `stride`-th sample: the best of its 8 neighbours
/// `step` away is taken while it lowers the cost, else the step halves, from `spacing` down to
/// `min_step`.
AxisFit DescendLocalGrid(const std::vector<Sample>& samples, std::size_t stride,
                         const Eigen::Vector3d& start, double spacing, double min_step,
                         const AxisSearch& search) {
    AxisFit current = EvaluateDirection(samples, stride, start, search.t, search.sin_parallel);
    for (double step = spacing; step > min_step;) {
        Eigen::Vector3d e1, e2;
        OrthonormalBasis(current.direction, e1, e2);
        AxisFit next = current;
        for (int i = -1; i <= 1; ++i) {
            for (int j = -1; j <= 1; ++j) {
                if (i == 0 && j == 0) continue;
                Eigen::Vector3d a = (current.direction + step * (i * e1 + j * e2)).normalized();
                if (search.TooTilted(a)) continue;
                const AxisFit fit =
                    EvaluateDirection(samples, stride, a, search.t, search.sin_parallel);
                if (fit.cost < next.cost) next = fit;
            }
        }
        if (next.cost < current.cost) {
            current = next;
        } else {
            step *= 0.5;
        }
    }
    return current;
}

/// Where the descents on the coarse subset stop and where those on all samples stop [rad].
constexpr double kCoarseDescentStep = 0.004;
constexpr double kFineDescentStep = 0.0005;

/// The best normal-line axis (section 5.4.2.2): a coarse grid of directions over the cap around
/// up, the best few refined by successively finer local grids.
AxisFit SearchNormalLineAxis(const std::vector<Sample>& samples, const AxisSearch& search,
                             const RotationalFitParams& params) {
    // grid_directions cover the hemisphere; a cap around up gets the same density (its share of
    // the hemisphere's area, 1 - cos(max_tilt)), at least 100 directions.
    const double share = 1.0 - std::cos(search.max_tilt);
    const int count =
        std::max(std::min(100, params.grid_directions),
                 static_cast<int>(std::ceil(share * static_cast<double>(params.grid_directions))));
    const auto directions = CapDirections(search.pole, search.max_tilt, count);
    const std::vector<std::size_t> candidates = BestCoarseDirections(
        samples, directions, search, params.refine_candidates, params.num_threads);
    const double spacing =
        std::sqrt(2.0 * kPi * (1.0 - std::cos(search.max_tilt)) / directions.size());
    // The candidates descend in parallel to half a milliradian, the first of the lowest cost wins.
    // With many samples they descend on the coarse subset to a few milliradians, and only the
    // best of them (on all samples) goes on with all samples.
    const std::size_t coarse_stride = std::max<std::size_t>(1, samples.size() / 300);
    const bool two_stage = coarse_stride > 1;
    std::vector<AxisFit> ends(candidates.size());
    ParallelFor(
        candidates.size(), params.num_threads,
        [&](std::size_t k) {
            const Eigen::Vector3d& start = directions[candidates[k]];
            if (!two_stage) {
                ends[k] = DescendLocalGrid(samples, 1, start, spacing, kFineDescentStep, search);
                return;
            }
            const AxisFit coarse = DescendLocalGrid(samples, coarse_stride, start, spacing,
                                                    kCoarseDescentStep, search);
            ends[k] =
                EvaluateDirection(samples, 1, coarse.direction, search.t, search.sin_parallel);
        },
        1);
    AxisFit best;
    for (const AxisFit& end : ends) {
        if (end.cost < best.cost) best = end;
    }
    if (!two_stage || !std::isfinite(best.cost)) return best;
    return DescendLocalGrid(samples, 1, best.direction, 2.0 * kCoarseDescentStep, kFineDescentStep,
                            search);
}

/// The point sets of the contour refinement, fixed by the normal-line axis so that the cost of
/// every candidate axis is taken over the same points: side points whose normal line passes within
/// 2 t of it (a looser window; `inner`: normal towards the axis), cap points (normal parallel to
/// it; `down`: facing against it) and all points, for the level of the ends.
struct ContourSets {
    std::vector<Eigen::Vector3d> side, cap, all;
    std::vector<char> inner, down;
};

ContourSets SelectContourSets(const std::vector<Sample>& samples, const Eigen::Vector3d& a0,
                              const Eigen::Vector3d& c0, std::size_t profile_points,
                              const AxisSearch& search) {
    ContourSets sets;
    const std::size_t refine_stride = (samples.size() + profile_points - 1) / profile_points;
    for (std::size_t k = 0; k < samples.size(); k += refine_stride) {
        const Sample& sample = samples[k];
        sets.all.push_back(sample.p);
        const Eigen::Vector3d v = sample.n.cross(a0);
        const double s = v.norm();
        const Eigen::Vector3d q = sample.p - c0;
        if (s < search.sin_parallel) {
            sets.cap.push_back(sample.p);
            sets.down.push_back(sample.n.dot(a0) < 0.0 ? 1 : 0);
            continue;
        }
        if (std::abs((v / s).dot(q)) > 2.0 * search.t) continue;
        sets.side.push_back(sample.p);
        sets.inner.push_back(sample.n.dot(q - q.dot(a0) * a0) < 0.0 ? 1 : 0);
    }
    return sets;
}

/// Every second point of each set (the flags kept with their points).
ContourSets EveryOther(const ContourSets& sets) {
    ContourSets thin;
    for (std::size_t k = 0; k < sets.side.size(); k += 2) {
        thin.side.push_back(sets.side[k]);
        thin.inner.push_back(sets.inner[k]);
    }
    for (std::size_t k = 0; k < sets.cap.size(); k += 2) {
        thin.cap.push_back(sets.cap[k]);
        thin.down.push_back(sets.down[k]);
    }
    for (std::size_t k = 0; k < sets.all.size(); k += 2) thin.all.push_back(sets.all[k]);
    return thin;
}

/// The refinement's parameters of an axis: two offsets of the direction and two of the position
/// from the normal-line axis (a0 through c0), along the basis e1, e2 perpendicular to a0.
struct AxisOffsets {
    Eigen::Vector3d a0, c0, e1, e2;

    void Axis(const Eigen::Vector4d& x, Eigen::Vector3d& a, Eigen::Vector3d& c) const {
        a = (a0 + x[0] * e1 + x[1] * e2).normalized();
        c = c0 + x[2] * e1 + x[3] * e2;
    }
};

/// The refinement's cost of the axis with offsets x (section 5.4.2.2, see the header): the side
/// contour's spread, the caps' weighted in, plus the weighted level of the ends; infinite beyond
/// the tilt bound.
class ContourCost {
  public:
    ContourCost(ContourSets sets, const Eigen::Vector3d& a0, const Eigen::Vector3d& c0,
                const AxisSearch& search, const RotationalFitParams& params)
        : side_(std::move(sets.side), std::move(sets.inner), false, params.profile_step,
                params.profile_tolerance),
          cap_(std::move(sets.cap), std::move(sets.down), true, params.profile_step,
               params.profile_tolerance),
          rim_(std::move(sets.all), 24, params.profile_tolerance),
          rim_weight_(params.rim_weight),
          cap_weight_(params.cap_weight),
          search_(search) {
        offsets_.a0 = a0;
        offsets_.c0 = c0;
        OrthonormalBasis(a0, offsets_.e1, offsets_.e2);
    }

    const AxisOffsets& offsets() const { return offsets_; }

    /// The polish ignores the level of the ends: it is biased on small tops such as a bottle's
    /// cap, where a millimetre is degrees.
    void DropEndLevel() { rim_weight_ = 0.0; }

    double operator()(const Eigen::Vector4d& x) const {
        Eigen::Vector3d a, c;
        offsets_.Axis(x, a, c);
        if (search_.TooTilted(a)) return std::numeric_limits<double>::infinity();
        return Objective(a, c);
    }

  private:
    double Objective(const Eigen::Vector3d& a, const Eigen::Vector3d& c) const {
        double sum = side_(a, c) * static_cast<double>(side_.size());
        std::size_t count = side_.size();
        if (cap_weight_ > 0.0f && cap_.size() >= 10) {
            sum += cap_weight_ * cap_(a, c) * static_cast<double>(cap_.size());
            count += cap_.size();
        }
        sum /= static_cast<double>(count);
        if (rim_weight_ > 0.0) sum += rim_weight_ * rim_(a, c);
        return sum;
    }

    ProfileObjective side_, cap_;
    RimObjective rim_;
    double rim_weight_;
    float cap_weight_;
    AxisSearch search_;
    AxisOffsets offsets_;
};

using ScoredStart = std::pair<double, Eigen::Vector4d>;

/// Starts of the simplex searches, the best `refined` (at most 3) first: the normal-line axis and
/// about 150 directions within 30 degrees of it, each with the normal-line position for it (the
/// contour cost has local minima; the normal lines place each direction well). The directions are
/// scored in parallel, each block on its own copy of the cost, and kept in their order.
std::vector<ScoredStart> RefinementStarts(const std::vector<Sample>& samples,
                                          const ContourCost& cost, const AxisSearch& search,
                                          int num_threads, std::size_t& refined) {
    const AxisOffsets& o = cost.offsets();
    const std::vector<Eigen::Vector3d> directions = CapDirections(o.a0, 30.0 * kPi / 180.0, 150);
    std::vector<std::optional<ScoredStart>> scored(directions.size());
    ParallelForChunks(
        directions.size(), num_threads,
        [&](std::size_t begin, std::size_t end) {
            const ContourCost own = cost;
            for (std::size_t k = begin; k < end; ++k) {
                const Eigen::Vector3d& d = directions[k];
                if (d.dot(o.a0) < 0.5 || search.TooTilted(d)) continue;
                const AxisFit fit = EvaluateDirection(samples, 1, d, search.t, search.sin_parallel);
                const Eigen::Vector4d x(d.dot(o.e1) / d.dot(o.a0), d.dot(o.e2) / d.dot(o.a0),
                                        (fit.center - o.c0).dot(o.e1),
                                        (fit.center - o.c0).dot(o.e2));
                scored[k] = ScoredStart(own(x), x);
            }
        },
        16);
    std::vector<ScoredStart> starts;
    starts.emplace_back(cost(Eigen::Vector4d::Zero()), Eigen::Vector4d::Zero());
    for (const auto& s : scored) {
        if (s) starts.push_back(*s);
    }
    refined = std::min<std::size_t>(3, starts.size());
    std::partial_sort(starts.begin(), starts.begin() + static_cast<std::ptrdiff_t>(refined),
                      starts.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
    return starts;
}

/// Nelder-Mead from each of the first `refined` starts; the end of lowest cost (the first of equal
/// ones). The starts run in parallel, each on its own copy of the cost (it keeps scratch
/// buffers); the result does not depend on the thread count.
Eigen::Vector4d BestOfStarts(const ContourCost& cost, const std::vector<ScoredStart>& starts,
                             std::size_t refined, const Eigen::Vector4d& scale, double tolerance,
                             int num_threads) {
    std::vector<Eigen::Vector4d> ends(refined);
    std::vector<double> end_costs(refined);
    ParallelFor(
        refined, num_threads,
        [&](std::size_t k) {
            const ContourCost own = cost;
            ends[k] = NelderMead<4>(own, starts[k].second, scale, tolerance, 400);
            end_costs[k] = own(ends[k]);
        },
        1);
    Eigen::Vector4d x = starts.front().second;
    double x_cost = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < refined; ++k) {
        if (end_costs[k] < x_cost) {
            x = ends[k];
            x_cost = end_costs[k];
        }
    }
    return x;
}

/// Second criterion, the thinnest contour (section 5.4.2.2, see the header): where the normals
/// barely constrain the direction (a shallow bowl) the normal-line axis can be far off. Replaces
/// `best` by the refined axis and sets `profile_spread`; leaves both with fewer than 20 side
/// points.
void RefineAxisByContour(const std::vector<Sample>& samples, const AxisSearch& search,
                         const RotationalFitParams& params, AxisFit& best, float& profile_spread) {
    ContourSets sets =
        SelectContourSets(samples, best.direction, best.center, params.profile_points, search);
    if (sets.side.size() < 20) return;
    // The starts are scored and descended on every second point; the best end is restarted on
    // all of them.
    const ContourCost coarse(EveryOther(sets), best.direction, best.center, search, params);
    ContourCost cost(std::move(sets), best.direction, best.center, search, params);
    const Eigen::Vector4d scale(0.05, 0.05, 0.005, 0.005);
    const double tolerance = 1e-4 * params.profile_tolerance * params.profile_tolerance;
    std::size_t refined = 0;
    const std::vector<ScoredStart> starts =
        RefinementStarts(samples, coarse, search, params.num_threads, refined);
    Eigen::Vector4d x = BestOfStarts(coarse, starts, refined, scale, tolerance, params.num_threads);
    x = NelderMead<4>(cost, x, Eigen::Vector4d(0.25 * scale), tolerance, 400);
    // One polish on the contour alone (a second one changed the axes by hundredths of a degree on
    // simulated bottles, bowls and pitchers).
    cost.DropEndLevel();
    x = NelderMead<4>(cost, x, Eigen::Vector4d(0.25 * scale), tolerance, 400);
    profile_spread = static_cast<float>(std::sqrt(cost(x)));
    cost.offsets().Axis(x, best.direction, best.center);
    best.cost = LineCost(samples, best.direction, best.center, search.t, search.sin_parallel);
}

/// The axis sign: away from the support (along up when given, else its largest component
/// positive), so that heights grow from the bottom.
Eigen::Vector3d AwayFromSupport(const Eigen::Vector3d& direction, const AxisSearch& search) {
    Eigen::Vector3d a = direction;
    Eigen::Index largest = 0;
    a.cwiseAbs().maxCoeff(&largest);
    if (search.has_up ? a.dot(search.pole) < 0.0 : a[largest] < 0.0) a = -a;
    return a;
}

/// The heights along the axis (a through origin) of all usable points, and (height, radius) of
/// those whose normal line passes within t of it: the points consistent with the axis.
struct ContourPoints {
    std::vector<float> heights;
    std::vector<std::pair<float, float>> profile;  // (height, radius)
};

ContourPoints CollectContourPoints(const PointCloud& cloud, const Indices& usable,
                                   const Eigen::Vector3d& origin, const Eigen::Vector3d& a,
                                   const AxisSearch& search) {
    ContourPoints contour;
    for (auto i : usable) {
        const Eigen::Vector3d p = cloud.points[i].cast<double>() - origin;
        const double h = p.dot(a);
        contour.heights.push_back(static_cast<float>(h));
        const Eigen::Vector3d n = cloud.normals[i].cast<double>().normalized();
        const Eigen::Vector3d v = n.cross(a);
        if (v.norm() < search.sin_parallel) continue;
        if (std::abs(v.normalized().dot(p)) > search.t) continue;
        contour.profile.emplace_back(static_cast<float>(h), static_cast<float>((p - h * a).norm()));
    }
    return contour;
}

/// The contour's height range: the 1st to 99th percentile of `heights` (sorted here; stray points
/// do not stretch it), its bottom lowered to a support plane at most 10 cm below (the contact
/// side is hidden).
std::pair<float, float> ContourHeightRange(std::vector<float>& heights,
                                           const Eigen::Vector4f& support_plane,
                                           const Eigen::Vector3d& origin,
                                           const Eigen::Vector3d& a) {
    std::sort(heights.begin(), heights.end());
    float h_min = heights[heights.size() / 100];
    const float h_max = heights[heights.size() - 1 - heights.size() / 100];
    if (support_plane.head<3>().squaredNorm() > 0.0f) {
        const Eigen::Vector3d n = support_plane.head<3>().cast<double>().normalized();
        const double d = support_plane[3] / support_plane.head<3>().norm();
        const double along = n.dot(a);
        if (std::abs(along) > 0.5) {
            const double h_plane = -(n.dot(origin) + d) / along;
            if (h_plane < h_min && h_plane > h_min - 0.1) h_min = static_cast<float>(h_plane);
        }
    }
    return {h_min, h_max};
}

/// The median radius of each height bin of `step` from h_min (NaN where a bin has fewer than 2
/// points): robust to the points of handles and spouts.
std::vector<float> BinMedianRadii(const std::vector<std::pair<float, float>>& profile, float h_min,
                                  float h_max, float step) {
    const int bins = std::max(1, static_cast<int>(std::ceil((h_max - h_min) / step)));
    std::vector<std::vector<float>> binned(static_cast<std::size_t>(bins));
    for (const auto& [h, r] : profile) {
        const int b = static_cast<int>((h - h_min) / step);
        if (b >= 0 && b < bins) binned[static_cast<std::size_t>(b)].push_back(r);
    }
    std::vector<float> radius(static_cast<std::size_t>(bins),
                              std::numeric_limits<float>::quiet_NaN());
    for (int b = 0; b < bins; ++b) {
        auto& v = binned[static_cast<std::size_t>(b)];
        if (v.size() >= 2) radius[static_cast<std::size_t>(b)] = MedianInPlace(v);
    }
    return radius;
}

/// Fills empty bins by interpolation between known ones and the ends by the nearest known radius;
/// false (and `radius` left with gaps) when no bin is known.
bool FillGaps(std::vector<float>& radius) {
    const int bins = static_cast<int>(radius.size());
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
    if (first < 0) return false;
    for (int b = 0; b < first; ++b)
        radius[static_cast<std::size_t>(b)] = radius[static_cast<std::size_t>(first)];
    for (int b = last + 1; b < bins; ++b)
        radius[static_cast<std::size_t>(b)] = radius[static_cast<std::size_t>(last)];
    return true;
}

/// A 3-bin median of the radii: single-bin outliers go, steps (a bottle's shoulder) stay.
std::vector<float> MedianSmoothed(const std::vector<float>& radius) {
    const int bins = static_cast<int>(radius.size());
    std::vector<float> smooth = radius;
    for (int b = 1; b + 1 < bins; ++b) {
        float w[3] = {radius[static_cast<std::size_t>(b - 1)], radius[static_cast<std::size_t>(b)],
                      radius[static_cast<std::size_t>(b + 1)]};
        std::sort(w, w + 3);
        smooth[static_cast<std::size_t>(b)] = w[1];
    }
    return smooth;
}

/// The model's contour from the smoothed bin radii: one sample per bin centre plus the two ends,
/// radii at least min_radius, heights non-decreasing.
void SetContour(const std::vector<float>& smooth, float h_min, float h_max,
                const RotationalFitParams& params, RotationalModel& model) {
    const float step = params.profile_step;
    const int bins = static_cast<int>(smooth.size());
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
}

/// The share of usable points on the completed surface: within the threshold of the side, or on
/// a cap inside the contour (section 5.4.2.3 meshes objects whose model explains too few).
float InlierRatio(const PointCloud& cloud, const Indices& usable, const RotationalModel& model,
                  float inlier_threshold) {
    std::size_t inliers = 0;
    for (auto i : usable) {
        const Eigen::Vector3f p = cloud.points[i] - model.origin;
        const float h = p.dot(model.axis);
        if (h < model.heights.front() - inlier_threshold ||
            h > model.heights.back() + inlier_threshold) {
            continue;
        }
        const float r = (p - h * model.axis).norm();
        const float hc = std::clamp(h, model.heights.front(), model.heights.back());
        const bool on_side = std::abs(r - model.RadiusAt(hc)) < inlier_threshold;
        const bool on_cap = (h - model.heights.front() < inlier_threshold ||
                             model.heights.back() - h < inlier_threshold) &&
                            r <= model.RadiusAt(hc) + inlier_threshold;
        if (on_side || on_cap) ++inliers;
    }
    return static_cast<float>(inliers) / static_cast<float>(usable.size());
}

}  // namespace

void RotationalFitParams::Validate() const { CheckParams(*this); }

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
    CheckRotationalIndices(cloud, indices);
    const Indices usable = UsablePoints(cloud, indices);
    if (usable.size() < 10) return model;
    Eigen::Vector3d centroid;
    const std::vector<Sample> samples = StridedSamples(cloud, usable, params.max_points, centroid);
    const AxisSearch search = MakeAxisSearch(up, params);

    // The axis: the normal lines, then the thinnest contour.
    AxisFit best = SearchNormalLineAxis(samples, search, params);
    if (!std::isfinite(best.cost)) return model;
    if (params.profile_refinement) {
        RefineAxisByContour(samples, search, params, best, model.profile_spread);
    }
    const Eigen::Vector3d a = AwayFromSupport(best.direction, search);
    const Eigen::Vector3d origin = centroid + best.center;

    // The contour from the points consistent with the axis.
    ContourPoints contour = CollectContourPoints(cloud, usable, origin, a, search);
    if (contour.profile.size() < 5) return model;
    const auto [h_min, h_max] = ContourHeightRange(contour.heights, support_plane, origin, a);
    std::vector<float> radius = BinMedianRadii(contour.profile, h_min, h_max, params.profile_step);
    if (!FillGaps(radius)) return model;
    SetContour(MedianSmoothed(radius), h_min, h_max, params, model);
    model.origin = origin.cast<float>();
    model.axis = a.cast<float>();
    model.found = true;
    model.axis_cost =
        static_cast<float>(best.cost / (static_cast<double>(samples.size()) * search.t * search.t));
    model.inlier_ratio = InlierRatio(cloud, usable, model, params.inlier_threshold);
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
