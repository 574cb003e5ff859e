#pragma once
// Scoring of furniture detections (thesis section 4.2.5.1): a detection is a true positive when
// its class is right and its centre lies closer than half the object's width to the true centre;
// each true object is matched once (strongest detections first). Recall vs 1 - precision curves
// come from sweeping a cut on the detections' normalised scores, and are drawn as SVG.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Core>

namespace multicue::eval {

struct TruthItem {
    int cls = 0;
    Eigen::Vector2f centre = Eigen::Vector2f::Zero();
    float width = 0.0f;  ///< smaller footprint side [m]
    float yaw = 0.0f;    ///< [rad]
};

struct DetectionItem {
    int cls = 0;
    Eigen::Vector2f centre = Eigen::Vector2f::Zero();
    float score = 0.0f;  ///< normalised score (1 = the class threshold)
    bool fitted = false;
    float yaw = 0.0f;
};

/// One scored unit: a room seen from one view or from all views merged.
struct EvalFrame {
    std::vector<TruthItem> truth;  ///< the objects visible in the view(s)
    std::vector<DetectionItem> detections;
    std::string group;  ///< room type
};

struct MatchCounts {
    std::size_t tp = 0, fp = 0, fn = 0;
    std::vector<float> yaw_errors;  ///< [deg], true positives with a fitted model
    double Precision() const { return tp + fp > 0 ? static_cast<double>(tp) / (tp + fp) : 1.0; }
    double Recall() const { return tp + fn > 0 ? static_cast<double>(tp) / (tp + fn) : 1.0; }
    void Add(const MatchCounts& o) {
        tp += o.tp, fp += o.fp, fn += o.fn;
        yaw_errors.insert(yaw_errors.end(), o.yaw_errors.begin(), o.yaw_errors.end());
    }
};

/// Yaw difference [deg] in [0, 180]; modulo 180 degrees for classes symmetric under a half turn.
inline float YawError(float a, float b, bool half_turn) {
    const float pi = std::numbers::pi_v<float>;
    float d = std::abs(std::remainder(a - b, 2 * pi));
    if (half_turn) d = std::min(d, pi - d);
    return d * 180.0f / pi;
}

/// Matches the detections with score >= cut (class `only_cls` when >= 0) against the truth.
inline MatchCounts MatchFrame(const EvalFrame& f, float cut, int only_cls = -1,
                              int half_turn_cls = -1) {
    MatchCounts m;
    std::vector<const DetectionItem*> dets;
    for (const auto& d : f.detections) {
        if (d.score >= cut && (only_cls < 0 || d.cls == only_cls)) dets.push_back(&d);
    }
    std::stable_sort(dets.begin(), dets.end(),
                     [](auto* a, auto* b) { return a->score > b->score; });
    std::vector<bool> used(f.truth.size(), false);
    for (const auto* d : dets) {
        int best = -1;
        float best_d = 1e9f;
        for (std::size_t t = 0; t < f.truth.size(); ++t) {
            const auto& g = f.truth[t];
            if (used[t] || g.cls != d->cls) continue;
            const float dist = (g.centre - d->centre).norm();
            if (dist < g.width / 2 && dist < best_d) best = static_cast<int>(t), best_d = dist;
        }
        if (best < 0) {
            ++m.fp;
            continue;
        }
        used[static_cast<std::size_t>(best)] = true;
        ++m.tp;
        if (d->fitted) {
            const auto& g = f.truth[static_cast<std::size_t>(best)];
            m.yaw_errors.push_back(YawError(d->yaw, g.yaw, g.cls == half_turn_cls));
        }
    }
    for (std::size_t t = 0; t < f.truth.size(); ++t) {
        if (!used[t] && (only_cls < 0 || f.truth[t].cls == only_cls)) ++m.fn;
    }
    return m;
}

/// Every detection of class `cls` in a frame, strongest first, with whether it matched a true
/// object (greedy in score order, so the marks do not depend on any cut); `truth` receives the
/// frame's true objects of the class.
inline std::vector<std::pair<float, bool>> MarkDetections(const EvalFrame& f, int cls,
                                                          std::size_t& truth) {
    std::vector<const DetectionItem*> dets;
    for (const auto& d : f.detections) {
        if (d.cls == cls) dets.push_back(&d);
    }
    std::stable_sort(dets.begin(), dets.end(),
                     [](auto* a, auto* b) { return a->score > b->score; });
    std::vector<bool> used(f.truth.size(), false);
    truth = 0;
    for (const auto& g : f.truth) truth += g.cls == cls ? 1 : 0;
    std::vector<std::pair<float, bool>> out;
    for (const auto* d : dets) {
        int best = -1;
        float best_d = 1e9f;
        for (std::size_t t = 0; t < f.truth.size(); ++t) {
            const auto& g = f.truth[t];
            if (used[t] || g.cls != cls) continue;
            const float dist = (g.centre - d->centre).norm();
            if (dist < g.width / 2 && dist < best_d) best = static_cast<int>(t), best_d = dist;
        }
        if (best >= 0) used[static_cast<std::size_t>(best)] = true;
        out.push_back({d->score, best >= 0});
    }
    return out;
}

/// Average precision of class `cls` over the frames (area under the precision-recall curve,
/// precision made monotone), and the score cut with the best F1 (`best_cut`, `best_f1`).
inline double AveragePrecision(const std::vector<EvalFrame>& frames, int cls,
                               float* best_cut = nullptr, double* best_f1 = nullptr) {
    std::vector<std::pair<float, bool>> all;
    std::size_t n_truth = 0;
    for (const auto& f : frames) {
        std::size_t t = 0;
        const auto marks = MarkDetections(f, cls, t);
        all.insert(all.end(), marks.begin(), marks.end());
        n_truth += t;
    }
    std::stable_sort(all.begin(), all.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    std::vector<double> prec, rec;
    std::size_t tp = 0;
    double f1_max = 0.0;
    float cut = all.empty() ? 1.0f : all.front().first + 1.0f;
    for (std::size_t i = 0; i < all.size(); ++i) {
        tp += all[i].second ? 1 : 0;
        const double p = static_cast<double>(tp) / static_cast<double>(i + 1);
        const double r = n_truth ? static_cast<double>(tp) / static_cast<double>(n_truth) : 0.0;
        prec.push_back(p);
        rec.push_back(r);
        const bool last_of_score = i + 1 == all.size() || all[i + 1].first < all[i].first;
        const double f1 = p + r > 0 ? 2 * p * r / (p + r) : 0.0;
        if (last_of_score && f1 > f1_max) f1_max = f1, cut = all[i].first;
    }
    if (best_cut) *best_cut = cut;
    if (best_f1) *best_f1 = f1_max;
    if (n_truth == 0) return 0.0;
    for (std::size_t i = prec.size(); i-- > 1;) prec[i - 1] = std::max(prec[i - 1], prec[i]);
    double ap = 0.0, last_r = 0.0;
    for (std::size_t i = 0; i < prec.size(); ++i) {
        ap += (rec[i] - last_r) * prec[i];
        last_r = rec[i];
    }
    return ap;
}

struct CurvePoint {
    float cut = 0.0f;
    double precision = 1.0, recall = 0.0;
};

inline std::vector<CurvePoint> Curve(const std::vector<EvalFrame>& frames, float lo, float hi,
                                     int steps, int half_turn_cls) {
    std::vector<CurvePoint> c;
    for (int k = 0; k <= steps; ++k) {
        const float cut = lo * std::pow(hi / lo, static_cast<float>(k) / steps);
        MatchCounts m;
        for (const auto& f : frames) m.Add(MatchFrame(f, cut, -1, half_turn_cls));
        c.push_back({cut, m.Precision(), m.Recall()});
    }
    return c;
}

/// The curve with a cut at every distinct detection score (scores of any scale).
inline std::vector<CurvePoint> ExactCurve(const std::vector<EvalFrame>& frames, int half_turn_cls) {
    std::vector<float> cuts;
    for (const auto& f : frames) {
        for (const auto& d : f.detections) cuts.push_back(d.score);
    }
    std::sort(cuts.begin(), cuts.end());
    cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
    std::vector<CurvePoint> c;
    for (const float cut : cuts) {
        MatchCounts m;
        for (const auto& f : frames) m.Add(MatchFrame(f, cut, -1, half_turn_cls));
        c.push_back({cut, m.Precision(), m.Recall()});
    }
    return c;
}

/// Highest recall at precision >= p_min over the curve (0 if never).
inline double RecallAtPrecision(const std::vector<CurvePoint>& c, double p_min) {
    double r = 0.0;
    for (const auto& p : c) {
        if (p.precision >= p_min) r = std::max(r, p.recall);
    }
    return r;
}

inline float Percentile(std::vector<float> v, float q) {
    if (v.empty()) return std::nanf("");
    std::sort(v.begin(), v.end());
    const auto i = static_cast<std::size_t>(std::lround(q * static_cast<float>(v.size() - 1)));
    return v[i];
}

/// Recall against 1 - precision, one polyline per curve, as a small SVG plot.
inline void WriteCurvesSvg(
    const std::string& path, const std::string& title,
    const std::vector<std::pair<std::string, std::vector<CurvePoint>>>& curves) {
    const int W = 640, H = 480, L = 70, R = 190, T = 40, B = 60;
    const int pw = W - L - R, ph = H - T - B;
    static const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                    "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};
    std::string s = fmt::format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" "
        "font-family=\"sans-serif\" "
        "font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
        W, H);
    s += fmt::format("<text x=\"{}\" y=\"22\" font-size=\"14\">{}</text>\n", L, title);
    for (int k = 0; k <= 10; ++k) {
        const double v = k / 10.0;
        const double x = L + v * pw, y = T + ph - v * ph;
        s += fmt::format("<line x1=\"{0}\" y1=\"{1}\" x2=\"{0}\" y2=\"{2}\" stroke=\"#ddd\"/>\n", x,
                         T, T + ph);
        s += fmt::format("<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"#ddd\"/>\n", L,
                         y, L + pw);
        s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{:.1f}</text>\n", x,
                         T + ph + 16, v);
        s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{:.1f}</text>\n", L - 6,
                         y + 4, v);
    }
    s += fmt::format(
        "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>\n", L,
        T, pw, ph);
    s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">1 - precision</text>\n",
                     L + pw / 2, H - 18);
    s += fmt::format(
        "<text x=\"18\" y=\"{}\" transform=\"rotate(-90 18 {})\" "
        "text-anchor=\"middle\">recall</text>\n",
        T + ph / 2, T + ph / 2);
    for (std::size_t c = 0; c < curves.size(); ++c) {
        const char* col = colours[c % 8];
        std::string pts;
        auto sorted = curves[c].second;
        std::sort(sorted.begin(), sorted.end(),
                  [](const auto& a, const auto& b) { return a.cut > b.cut; });
        for (const auto& p : sorted) {
            pts +=
                fmt::format("{:.1f},{:.1f} ", L + (1.0 - p.precision) * pw, T + ph - p.recall * ph);
        }
        s += fmt::format(
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\"/>\n", pts, col);
        // The operating point (cut 1: the class thresholds).
        const CurvePoint* op = nullptr;
        for (const auto& p : curves[c].second) {
            if (!op || std::abs(std::log(p.cut)) < std::abs(std::log(op->cut))) op = &p;
        }
        if (op) {
            s += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"4\" fill=\"{}\"/>\n",
                             L + (1.0 - op->precision) * pw, T + ph - op->recall * ph, col);
        }
        const int ly = T + 16 + 18 * static_cast<int>(c);
        s += fmt::format(
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\" stroke-width=\"2\"/>\n",
            L + pw + 10, ly - 4, L + pw + 30, ly - 4, col);
        s += fmt::format("<text x=\"{}\" y=\"{}\">{}</text>\n", L + pw + 35, ly, curves[c].first);
    }
    s += "</svg>\n";
    std::ofstream(path) << s;
}

}  // namespace multicue::eval
