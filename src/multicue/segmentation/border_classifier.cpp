#include "multicue/segmentation/border_classifier.hpp"

#include <cmath>

#include <fmt/format.h>
#include <Eigen/Dense>

#include "multicue/core/exceptions.hpp"

namespace multicue {

void BorderClassifierParams::Validate() const {
    if (!(threshold > 0.0f && threshold < 1.0f)) {
        throw InvalidArgument(fmt::format("threshold must be in (0, 1), got {}", threshold));
    }
    if (!std::isfinite(bias))
        throw InvalidArgument(fmt::format("bias must be finite, got {}", bias));
    for (std::size_t k = 0; k < kBorderFeatureCount; ++k) {
        if (!std::isfinite(weights[k])) {
            throw InvalidArgument(fmt::format("weights.{} must be finite, got {}",
                                              kBorderFeatureNames[k], weights[k]));
        }
    }
}

float JoinProbability(const BorderFeatures& f, const BorderClassifierParams& params) {
    double z = params.bias;
    for (std::size_t k = 0; k < kBorderFeatureCount; ++k) z += params.weights[k] * f[k];
    return static_cast<float>(1.0 / (1.0 + std::exp(-z)));
}

BorderClassifierParams FitBorderClassifier(const std::vector<BorderExample>& rows, double l2,
                                           BorderClassifierParams start) {
    if (!(l2 >= 0.0 && std::isfinite(l2))) {
        throw InvalidArgument(fmt::format("l2 must be finite and >= 0, got {}", l2));
    }
    constexpr auto d = static_cast<Eigen::Index>(kBorderFeatureCount);
    const auto n = static_cast<Eigen::Index>(rows.size());
    Eigen::MatrixXd x(n, d + 1);
    Eigen::VectorXd y(n);
    Eigen::VectorXd weight(n);
    double same = 0.0;
    double apart = 0.0;
    for (Eigen::Index r = 0; r < n; ++r) {
        const BorderExample& row = rows[static_cast<std::size_t>(r)];
        if (!(row.weight >= 0.0 && std::isfinite(row.weight))) {
            throw InvalidArgument(
                fmt::format("row {}: weight must be finite and >= 0, got {}", r, row.weight));
        }
        for (Eigen::Index k = 0; k < d; ++k) {
            const float v = row.features[static_cast<std::size_t>(k)];
            if (!std::isfinite(v)) {
                throw InvalidArgument(
                    fmt::format("row {}: feature {} is not finite", r,
                                kBorderFeatureNames[static_cast<std::size_t>(k)]));
            }
            x(r, k) = v;
        }
        x(r, d) = 1.0;
        y(r) = row.same ? 1.0 : 0.0;
        weight(r) = row.weight;
        (row.same ? same : apart) += row.weight;
    }
    if (!(same > 0.0 && apart > 0.0)) {
        throw InvalidArgument(fmt::format(
            "need rows of both kinds with positive weight, got {} same-object and {} two-object",
            same, apart));
    }
    const double total = same + apart;
    Eigen::VectorXd mean = (x.transpose() * weight) / total;
    Eigen::VectorXd scale = Eigen::VectorXd::Ones(d + 1);
    for (Eigen::Index k = 0; k < d; ++k) {
        const double sd =
            std::sqrt(((x.col(k).array() - mean(k)).square() * weight.array()).sum() / total);
        if (sd > 1e-9) scale(k) = sd;
        x.col(k) = (x.col(k).array() - mean(k)) / scale(k);
    }
    mean(d) = 0.0;
    Eigen::VectorXd penalty = Eigen::VectorXd::Constant(d + 1, l2);
    penalty(d) = 0.0;
    Eigen::VectorXd beta = Eigen::VectorXd::Zero(d + 1);
    constexpr int kMaxSteps = 50;
    for (int it = 0; it < kMaxSteps; ++it) {
        const Eigen::VectorXd p =
            (-(x * beta)).array().exp().unaryExpr([](double e) { return 1.0 / (1.0 + e); });
        const Eigen::VectorXd grad =
            x.transpose() * (weight.array() * (p - y).array()).matrix() / total +
            penalty.cwiseProduct(beta);
        const Eigen::VectorXd w = weight.array() * p.array() * (1.0 - p.array());
        Eigen::MatrixXd hess = x.transpose() * w.asDiagonal() * x / total;
        hess.diagonal() += penalty;
        hess.diagonal().array() += 1e-12;  // a constant feature without penalty stays solvable
        const Eigen::VectorXd step = hess.ldlt().solve(grad);
        if (!step.allFinite()) break;
        beta -= step;
        if (step.norm() < 1e-10) break;
    }
    double bias = beta(d);
    for (Eigen::Index k = 0; k < d; ++k) {
        start.weights[static_cast<std::size_t>(k)] = static_cast<float>(beta(k) / scale(k));
        bias -= beta(k) * mean(k) / scale(k);
    }
    start.bias = static_cast<float>(bias);
    return start;
}

}  // namespace multicue
