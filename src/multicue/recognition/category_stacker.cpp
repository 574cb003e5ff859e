#include "multicue/recognition/category_stacker.hpp"

#include <algorithm>
#include <cmath>
#include <span>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue {

namespace {

constexpr float kFloor = 0.01f;

float Finite(float v) { return std::isfinite(v) ? v : 0.0f; }

// Softmax in place: exp(s - max s), normalised to sum 1.
void Softmax(std::span<double> s) {
    const double top = *std::max_element(s.begin(), s.end());
    double sum = 0.0;
    for (double& v : s) sum += (v = std::exp(v - top));
    for (double& v : s) v /= sum;
}

}  // namespace

std::array<float, kStackerInputSize> StackerInputs(const CategoryResult& rules,
                                                   const CategoryDistribution& part_graph,
                                                   const CategoryDistribution& cluster) {
    std::array<float, kStackerInputSize> x{};
    std::size_t n = 0;
    for (const CategoryDistribution* p : {&rules.probabilities, &part_graph, &cluster}) {
        for (std::size_t c = 1; c < kNumCategories; ++c) {
            x[n++] = std::log(std::max((*p)[c], 0.0f) + kFloor);
        }
    }
    const float e1 = rules.extents.x() + 1e-3f, e2 = rules.extents.y() + 1e-3f,
                e3 = rules.extents.z() + 1e-3f;
    for (float v : {std::log(e1), std::log(e2), std::log(e3), std::log(e2 / e3), std::log(e1 / e3),
                    rules.height, rules.box_score, rules.axis_area, rules.planar_part_ratio,
                    rules.cylinder_inlier_ratio, rules.cylinder_cap_ratio, rules.cylinder_coverage,
                    rules.cylinder_radius, rules.sphere_inlier_ratio, rules.sphere_radius,
                    rules.footprint_fill, rules.side_face_ratio, rules.upright ? 1.0f : 0.0f}) {
        x[n++] = v;
    }
    for (float& v : x) v = Finite(v);
    return x;
}

void CategoryStacker::Fit(const std::vector<std::array<float, kStackerInputSize>>& inputs,
                          const std::vector<Category>& truth, const CategoryStackerParams& params) {
    if (inputs.empty()) throw InvalidArgument("stacker: no training rows");
    if (inputs.size() != truth.size()) {
        throw InvalidArgument(
            fmt::format("stacker: {} input rows but {} categories", inputs.size(), truth.size()));
    }
    if (!(params.l2 >= 0.0f) || !std::isfinite(params.l2) || params.iterations == 0 ||
        !(params.step > 0.0f) || !std::isfinite(params.step)) {
        throw InvalidArgument("stacker: l2 must be >= 0, iterations >= 1 and step > 0");
    }
    for (Category c : truth) {
        if (c == Category::kNone || static_cast<std::size_t>(c) >= kNumCategories) {
            throw InvalidArgument("stacker: every training row needs a category other than none");
        }
    }
    constexpr std::size_t d = kStackerInputSize, k = kClasses;
    const std::size_t rows = inputs.size();
    // Standardise each input over the training rows (constant inputs get scale 1).
    std::vector<double> mean(d, 0.0), var(d, 0.0);
    for (const auto& x : inputs)
        for (std::size_t j = 0; j < d; ++j) mean[j] += x[j];
    for (double& m : mean) m /= double(rows);
    for (const auto& x : inputs)
        for (std::size_t j = 0; j < d; ++j) var[j] += (x[j] - mean[j]) * (x[j] - mean[j]);
    mean_.assign(d, 0.0f);
    scale_.assign(d, 1.0f);
    for (std::size_t j = 0; j < d; ++j) {
        mean_[j] = float(mean[j]);
        const double sd = std::sqrt(var[j] / double(rows));
        scale_[j] = sd > 1e-6 ? float(1.0 / sd) : 1.0f;
    }
    std::vector<double> z(rows * d);
    for (std::size_t i = 0; i < rows; ++i)
        for (std::size_t j = 0; j < d; ++j)
            z[i * d + j] = (double(inputs[i][j]) - mean_[j]) * scale_[j];
    // Softmax regression: minimise mean cross-entropy + l2/2 |W|^2 by gradient descent.
    std::vector<double> w(d * k, 0.0), b(k, 0.0), gw(d * k), gb(k), p(k);
    for (std::size_t it = 0; it < params.iterations; ++it) {
        std::fill(gw.begin(), gw.end(), 0.0);
        std::fill(gb.begin(), gb.end(), 0.0);
        for (std::size_t i = 0; i < rows; ++i) {
            const double* zi = &z[i * d];
            for (std::size_t c = 0; c < k; ++c) {
                p[c] = b[c];
                for (std::size_t j = 0; j < d; ++j) p[c] += zi[j] * w[j * k + c];
            }
            Softmax(p);
            const std::size_t t = static_cast<std::size_t>(truth[i]) - 1;
            for (std::size_t c = 0; c < k; ++c) {
                const double g = (p[c] - (c == t ? 1.0 : 0.0)) / double(rows);
                gb[c] += g;
                for (std::size_t j = 0; j < d; ++j) gw[j * k + c] += g * zi[j];
            }
        }
        for (std::size_t q = 0; q < w.size(); ++q) w[q] -= params.step * (gw[q] + params.l2 * w[q]);
        for (std::size_t c = 0; c < k; ++c) b[c] -= params.step * gb[c];
    }
    weights_.assign(w.begin(), w.end());
    bias_.assign(b.begin(), b.end());
    train_rows_ = rows;
}

CategoryDistribution CategoryStacker::Predict(
    const std::array<float, kStackerInputSize>& input) const {
    if (!trained()) throw InvalidArgument("stacker: not trained");
    constexpr std::size_t d = kStackerInputSize, k = kClasses;
    std::array<double, k> s{};
    for (std::size_t c = 0; c < k; ++c) s[c] = bias_[c];
    for (std::size_t j = 0; j < d; ++j) {
        const double zj = (double(Finite(input[j])) - mean_[j]) * scale_[j];
        for (std::size_t c = 0; c < k; ++c) s[c] += zj * weights_[j * k + c];
    }
    Softmax(s);
    CategoryDistribution out{};
    for (std::size_t c = 0; c < k; ++c) out[c + 1] = float(s[c]);
    return out;
}

std::vector<float> CategoryStacker::Parameters() const {
    std::vector<float> v;
    if (!trained()) return v;
    v.push_back(float(train_rows_));
    v.insert(v.end(), mean_.begin(), mean_.end());
    v.insert(v.end(), scale_.begin(), scale_.end());
    v.insert(v.end(), weights_.begin(), weights_.end());
    v.insert(v.end(), bias_.begin(), bias_.end());
    return v;
}

CategoryStacker CategoryStacker::FromParameters(const std::vector<float>& values,
                                                const std::string& what) {
    CategoryStacker s;
    if (values.empty()) return s;
    constexpr std::size_t d = kStackerInputSize, k = kClasses;
    if (values.size() != 1 + 2 * d + d * k + k) {
        throw FormatError(fmt::format("{}: bad stacker ({} values)", what, values.size()));
    }
    for (float v : values) {
        if (!std::isfinite(v)) throw FormatError(fmt::format("{}: bad stacker value", what));
    }
    auto at = values.begin();
    // A count of rows: whole, not negative, and below 2^24 (exact in a float).
    if (*at < 0.0f || *at > 16777216.0f || *at != std::floor(*at)) {
        throw FormatError(fmt::format("{}: bad stacker row count {}", what, *at));
    }
    s.train_rows_ = static_cast<std::size_t>(*at++);
    s.mean_.assign(at, at + d);
    at += d;
    s.scale_.assign(at, at + d);
    at += d;
    s.weights_.assign(at, at + d * k);
    at += d * k;
    s.bias_.assign(at, at + k);
    return s;
}

}  // namespace multicue
