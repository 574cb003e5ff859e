#include "multicue/surface/mls_fit.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "multicue/surface/pca.hpp"

namespace multicue::detail {
namespace {

/// Weighted mean and PCA plane of the points with inlier != 0. Returns false if degenerate.
bool WeightedPlane(const MlsScratch& s, Eigen::Vector3f& mean, Eigen::Vector3f& normal,
                   float& curvature) {
    double sw = 0.0;
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    const std::size_t n = s.offsets.size();
    std::size_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!s.inlier[i]) continue;
        sw += s.weights[i];
        m += s.weights[i] * s.offsets[i].cast<double>();
        ++count;
    }
    if (count < 3 || !(sw > 0.0)) return false;
    m /= sw;
    // Weighted covariance of the inliers about their weighted mean (section 2.3.1).
    Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
        if (!s.inlier[i]) continue;
        const Eigen::Vector3d d = s.offsets[i].cast<double>() - m;
        c.noalias() += s.weights[i] * d * d.transpose();
    }
    c /= sw;
    if (!(c.trace() > 0.0)) return false;
    const Eigen::Vector3d l = SymmetricEigenvalues(c).cwiseMax(0.0);
    const double sum = l.sum();
    if (!(sum > 0.0)) return false;
    normal = SymmetricEigenvector(c, l(0)).cast<float>();
    curvature = static_cast<float>(l(0) / sum);
    mean = m.cast<float>();
    return normal.allFinite();
}

/// Weighted RANSAC (section 2.3.1): planes through random triples, scored by the summed weights of
/// the points within the inlier band. Marks the best plane's inliers; false if no plane found.
bool WeightedRansac(MlsScratch& s, const MlsFitSettings& settings, SplitMix64& rng) {
    const auto n = static_cast<std::uint32_t>(s.offsets.size());
    const float t = settings.inlier_distance;
    double best_score = -1.0;
    Eigen::Vector3f best_n = Eigen::Vector3f::Zero();
    float best_c = 0.0f;
    std::size_t best_count = 0;
    const double log_fail = std::log(1.0 - static_cast<double>(settings.confidence));
    double needed = settings.max_iterations;
    for (int it = 0; it < settings.max_iterations && it < needed; ++it) {
        const std::uint32_t a = rng.Below(n);
        std::uint32_t b = rng.Below(n - 1);
        if (b >= a) ++b;
        std::uint32_t c = rng.Below(n - 2);
        if (c >= std::min(a, b)) ++c;
        if (c >= std::max(a, b)) ++c;
        Eigen::Vector3f normal = (s.offsets[b] - s.offsets[a]).cross(s.offsets[c] - s.offsets[a]);
        const float len = normal.norm();
        if (!(len > 1e-12f)) continue;
        normal /= len;
        const float off = normal.dot(s.offsets[a]);
        float score_f = 0.0f;
        std::size_t count = 0;
        for (std::uint32_t i = 0; i < n; ++i) {
            const bool in = std::abs(normal.dot(s.offsets[i]) - off) <= t;  // branch-free
            score_f += in ? s.weights[i] : 0.0f;
            count += in;
        }
        const double score = score_f;
        if (score > best_score) {
            best_score = score;
            best_n = normal;
            best_c = off;
            best_count = count;
            // Samples are drawn uniformly, so the stopping rule uses the inlier count fraction.
            const double frac = static_cast<double>(count) / n;
            const double p3 = frac * frac * frac;
            needed = p3 >= 1.0 ? 0.0 : log_fail / std::log(1.0 - std::max(p3, 1e-9));
            needed = std::max(needed, 8.0);
        }
    }
    if (best_count < 3) return false;
    for (std::uint32_t i = 0; i < n; ++i)
        s.inlier[i] = std::abs(best_n.dot(s.offsets[i]) - best_c) <= t ? 1 : 0;
    return true;
}

constexpr int kTerms[4] = {1, 3, 6, 10};

/// Basis of Eq. (2.3) at (u, v): 1, u, v, uv, u^2, v^2, u^2 v, u v^2, u^3, v^3.
inline void Basis(double u, double v, int terms, double* b) {
    b[0] = 1.0;
    if (terms == 1) return;
    b[1] = u;
    b[2] = v;
    if (terms == 3) return;
    b[3] = u * v;
    b[4] = u * u;
    b[5] = v * v;
    if (terms == 6) return;
    b[6] = u * u * v;
    b[7] = u * v * v;
    b[8] = u * u * u;
    b[9] = v * v * v;
}

/// Fixed-size LDLT solve of the top-left N x N normal equations (no allocation per point).
template <int N>
bool Solve(const Eigen::Matrix<double, 10, 10>& ata, const Eigen::Matrix<double, 10, 1>& atb,
           Eigen::Matrix<double, 10, 1>& coef) {
    const Eigen::LDLT<Eigen::Matrix<double, N, N>> ldlt(ata.topLeftCorner<N, N>());
    if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-10)) return false;
    coef.setZero();
    coef.head<N>() = ldlt.solve(atb.head<N>());
    return coef.allFinite();
}

}  // namespace

bool FitMls(MlsScratch& s, const MlsFitSettings& settings, SplitMix64& rng, MlsFit& fit) {
    const std::size_t n = s.offsets.size();
    if (n < static_cast<std::size_t>(std::max(3, settings.min_neighbors))) return false;
    s.weights.resize(n);
    s.inlier.assign(n, 1);
    for (std::size_t i = 0; i < n; ++i)
        s.weights[i] = std::exp(-s.offsets[i].squaredNorm() * settings.inv_h2);  // Eq. (2.2)

    if (settings.robust && !WeightedRansac(s, settings, rng)) return false;
    Eigen::Vector3f mean, normal;
    float curvature = 0.0f;
    if (!WeightedPlane(s, mean, normal, curvature)) return false;
    if (settings.robust) {
        // The PCA plane of the RANSAC inliers fits them better than the sampled triple; take the
        // inliers of that refined plane as the reduced neighbourhood.
        std::size_t count = 0;
        for (std::size_t i = 0; i < n; ++i) {
            s.inlier[i] = std::abs(normal.dot(s.offsets[i] - mean)) <= settings.inlier_distance;
            count += s.inlier[i];
        }
        if (count < 3 || !WeightedPlane(s, mean, normal, curvature)) return false;
    }
    int inliers = 0;
    for (std::size_t i = 0; i < n; ++i) inliers += s.inlier[i];

    // Local frame: origin at the query point's projection onto the plane (offset 0 is the query).
    const Eigen::Vector3f origin = normal.dot(mean) * normal;
    const Eigen::Vector3f u_axis = normal.unitOrthogonal();
    const Eigen::Vector3f v_axis = normal.cross(u_axis);

    fit.offset = origin;
    fit.normal = normal;
    fit.curvature = curvature;
    fit.inliers = inliers;
    fit.plane_only = true;

    int order = settings.order;
    while (order > 0 && inliers < kTerms[order] + 1) --order;
    if (order == 0) return true;
    const int terms = kTerms[order];

    // Weighted least squares for the height field (Eq. 2.3); u, v scaled by 1 / radius.
    const double scale = 1.0 / settings.radius;
    Eigen::Matrix<double, 10, 10> ata = Eigen::Matrix<double, 10, 10>::Zero();
    Eigen::Matrix<double, 10, 1> atb = Eigen::Matrix<double, 10, 1>::Zero();
    double b[10];
    for (std::size_t i = 0; i < n; ++i) {
        if (!s.inlier[i]) continue;
        const Eigen::Vector3f x = s.offsets[i] - origin;
        Basis(x.dot(u_axis) * scale, x.dot(v_axis) * scale, terms, b);
        const double w = s.weights[i];
        const double h = x.dot(normal) * scale;
        for (int r = 0; r < terms; ++r) {
            const double wb = w * b[r];
            for (int c = 0; c <= r; ++c) ata(r, c) += wb * b[c];
            atb(r) += wb * h;
        }
    }
    for (int r = 0; r < terms; ++r)
        for (int c = r + 1; c < terms; ++c) ata(r, c) = ata(c, r);
    Eigen::Matrix<double, 10, 1> coef;
    const bool solved = terms == 3   ? Solve<3>(ata, atb, coef)
                        : terms == 6 ? Solve<6>(ata, atb, coef)
                                     : Solve<10>(ata, atb, coef);
    if (!solved || std::abs(coef(0)) > 1.0) return true;  // > radius: not trustworthy

    // Eq. (2.4): tangents U + h_u N and V + h_v N at (0, 0); their cross product is
    // N - h_u U - h_v V (h_u, h_v in metres per metre: the 1 / radius scales cancel).
    const float hu = static_cast<float>(coef(1));
    const float hv = static_cast<float>(coef(2));
    const Eigen::Vector3f poly_normal = (normal - hu * u_axis - hv * v_axis).normalized();
    if (!poly_normal.allFinite()) return true;
    fit.offset = origin + static_cast<float>(coef(0) * settings.radius) * normal;
    fit.normal = poly_normal;
    fit.plane_only = false;
    return true;
}

}  // namespace multicue::detail
