#include "multicue/ml/evaluation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/dataset_tools.hpp"
#include "multicue/ml/serialization.hpp"
#include "multicue/ml/split.hpp"

namespace multicue::ml {

namespace {
double Seconds(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
double Choose2(double n) { return n * (n - 1.0) / 2.0; }
}  // namespace

double ConfusionMatrix::Accuracy() const {
    const auto n = total();
    return n == 0 ? 0.0 : static_cast<double>(counts.trace()) / static_cast<double>(n);
}

std::size_t ConfusionMatrix::TotalExcluding(int excluded) const {
    if (excluded < 0 || excluded >= counts.rows()) {
        throw InvalidArgument("excluded class " + std::to_string(excluded) + " out of range");
    }
    return total() - static_cast<std::size_t>(counts.row(excluded).sum());
}

double ConfusionMatrix::AccuracyExcluding(int excluded) const {
    const std::size_t n = TotalExcluding(excluded);
    if (n == 0) return 0.0;
    const auto correct = static_cast<std::size_t>(counts.trace() - counts(excluded, excluded));
    return static_cast<double>(correct) / static_cast<double>(n);
}

double ConfusionMatrix::ErrorRate() const { return total() == 0 ? 0.0 : 1.0 - Accuracy(); }

std::vector<double> ConfusionMatrix::PerClassAccuracy() const {
    std::vector<double> out(class_names.size());
    for (Eigen::Index c = 0; c < counts.rows(); ++c) {
        const int row = counts.row(c).sum();
        out[static_cast<std::size_t>(c)] =
            row == 0 ? std::nan("") : static_cast<double>(counts(c, c)) / row;
    }
    return out;
}

std::string ConfusionMatrix::ToText() const {
    std::ostringstream out;
    std::size_t width = 5;
    for (const auto& n : class_names) width = std::max(width, n.size());
    const auto pad = [&](const std::string& s, std::size_t w) {
        return std::string(w > s.size() ? w - s.size() : 0, ' ') + s;
    };
    out << pad("true\\pred", width + 1);
    for (std::size_t c = 0; c < class_names.size(); ++c) out << ' ' << pad(std::to_string(c), 6);
    out << "  accuracy\n";
    const auto per_class = PerClassAccuracy();
    for (std::size_t r = 0; r < class_names.size(); ++r) {
        out << pad(std::to_string(r) + ":" + class_names[r], width + 1);
        for (std::size_t c = 0; c < class_names.size(); ++c) {
            out << ' '
                << pad(std::to_string(
                           counts(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c))),
                       6);
        }
        char buf[32];
        std::snprintf(buf, sizeof(buf), "  %.4f", per_class[r]);
        out << buf << '\n';
    }
    char buf[96];
    std::snprintf(buf, sizeof(buf), "accuracy %.4f  error rate %.4f  (%zu rows)\n", Accuracy(),
                  ErrorRate(), total());
    out << buf;
    return out.str();
}

void ConfusionMatrix::WriteImage(const std::filesystem::path& path, int cell) const {
    if (cell < 1 || cell > 256) throw InvalidArgument("cell size must be in [1, 256] pixels");
    const int k = static_cast<int>(counts.rows());
    if (k == 0) throw DataError("cannot draw an empty confusion matrix");
    const int size = k * cell;
    std::string img = "P6\n" + std::to_string(size) + " " + std::to_string(size) + "\n255\n";
    const std::size_t header = img.size();
    img.resize(header + static_cast<std::size_t>(size) * size * 3);
    for (int r = 0; r < k; ++r) {
        const double row = std::max(1, counts.row(r).sum());
        for (int c = 0; c < k; ++c) {
            const double v = counts(r, c) / row;  // 0 white .. 1 dark blue
            const auto red = static_cast<unsigned char>(std::lround(255.0 * (1.0 - v)));
            const auto green = static_cast<unsigned char>(std::lround(255.0 * (1.0 - 0.8 * v)));
            const auto blue = static_cast<unsigned char>(std::lround(255.0 * (1.0 - 0.45 * v)));
            for (int y = r * cell; y < (r + 1) * cell; ++y) {
                for (int x = c * cell; x < (c + 1) * cell; ++x) {
                    const std::size_t p = header + (static_cast<std::size_t>(y) * size + x) * 3;
                    img[p] = static_cast<char>(red);
                    img[p + 1] = static_cast<char>(green);
                    img[p + 2] = static_cast<char>(blue);
                }
            }
        }
    }
    WriteBytesAtomically(path, img);
}

ConfusionMatrix Confusion(const std::vector<int>& truth, const std::vector<int>& predicted,
                          const std::vector<std::string>& class_names) {
    if (truth.size() != predicted.size()) {
        throw InvalidArgument("truth has " + std::to_string(truth.size()) +
                              " labels, predictions " + std::to_string(predicted.size()));
    }
    const int k = static_cast<int>(class_names.size());
    ConfusionMatrix m;
    m.class_names = class_names;
    m.counts = Eigen::MatrixXi::Zero(k, k);
    for (std::size_t i = 0; i < truth.size(); ++i) {
        if (truth[i] == kNoLabel) continue;
        if (truth[i] < 0 || truth[i] >= k || predicted[i] < 0 || predicted[i] >= k) {
            throw InvalidArgument("class index out of range at row " + std::to_string(i));
        }
        ++m.counts(truth[i], predicted[i]);
    }
    return m;
}

ConfusionCounter::ConfusionCounter(std::vector<std::string> class_names)
    : class_names_(std::move(class_names)), counts_(class_names_.size() * class_names_.size(), 0) {}

std::size_t ConfusionCounter::At(int truth, int predicted) const {
    const int k = static_cast<int>(class_names_.size());
    if (truth < 0 || truth >= k || predicted < 0 || predicted >= k) {
        throw InvalidArgument("class index out of range: truth " + std::to_string(truth) +
                              ", predicted " + std::to_string(predicted) + " of " +
                              std::to_string(k) + " classes");
    }
    return static_cast<std::size_t>(truth) * class_names_.size() +
           static_cast<std::size_t>(predicted);
}

void ConfusionCounter::Add(int truth, int predicted, std::size_t count) {
    if (truth == kNoLabel) return;
    counts_[At(truth, predicted)] += count;
}

void ConfusionCounter::Merge(const ConfusionCounter& other) {
    if (other.class_names_ != class_names_) {
        throw InvalidArgument("cannot merge confusion counts over different classes");
    }
    for (std::size_t i = 0; i < counts_.size(); ++i) counts_[i] += other.counts_[i];
}

void ConfusionCounter::Clear() { std::fill(counts_.begin(), counts_.end(), 0); }

std::size_t ConfusionCounter::count(int truth, int predicted) const {
    return static_cast<std::size_t>(counts_[At(truth, predicted)]);
}

std::size_t ConfusionCounter::total() const {
    std::uint64_t n = 0;
    for (const auto c : counts_) n += c;
    return static_cast<std::size_t>(n);
}

ConfusionMatrix ConfusionCounter::ToMatrix() const {
    const auto k = static_cast<Eigen::Index>(class_names_.size());
    ConfusionMatrix m;
    m.class_names = class_names_;
    m.counts = Eigen::MatrixXi::Zero(k, k);
    std::uint64_t sum = 0;
    for (Eigen::Index t = 0; t < k; ++t) {
        for (Eigen::Index p = 0; p < k; ++p) {
            const std::uint64_t c = counts_[static_cast<std::size_t>(t * k + p)];
            sum += c;
            if (sum > static_cast<std::uint64_t>(std::numeric_limits<int>::max())) {
                throw DataError("confusion counts too large for a ConfusionMatrix");
            }
            m.counts(t, p) = static_cast<int>(c);
        }
    }
    return m;
}

double Accuracy(const std::vector<int>& truth, const std::vector<int>& predicted) {
    if (truth.size() != predicted.size()) {
        throw InvalidArgument("truth and predictions have different lengths");
    }
    std::size_t n = 0, correct = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
        if (truth[i] == kNoLabel) continue;
        ++n;
        correct += truth[i] == predicted[i];
    }
    return n == 0 ? 0.0 : static_cast<double>(correct) / static_cast<double>(n);
}

double AdjustedRandIndex(const std::vector<int>& a, const std::vector<int>& b) {
    if (a.size() != b.size()) throw InvalidArgument("partitions have different lengths");
    const double n = static_cast<double>(a.size());
    if (a.size() < 2) return 1.0;
    std::map<std::pair<int, int>, double> joint;
    std::map<int, double> ca, cb;
    for (std::size_t i = 0; i < a.size(); ++i) {
        joint[{a[i], b[i]}] += 1.0;
        ca[a[i]] += 1.0;
        cb[b[i]] += 1.0;
    }
    double index = 0.0, sa = 0.0, sb = 0.0;
    for (const auto& [key, v] : joint) index += Choose2(v);
    for (const auto& [key, v] : ca) sa += Choose2(v);
    for (const auto& [key, v] : cb) sb += Choose2(v);
    const double expected = sa * sb / Choose2(n);
    const double max_index = 0.5 * (sa + sb);
    if (max_index == expected) return 1.0;  // both partitions trivial in the same way
    return (index - expected) / (max_index - expected);
}

EvaluationResult Evaluate(const Classifier& classifier, const Dataset& test) {
    if (test.empty()) throw DataError("test set is empty");
    const auto truth = MapLabels(test, classifier.class_names());
    const auto t0 = std::chrono::steady_clock::now();
    const auto predicted = classifier.Predict(test);
    EvaluationResult res;
    res.predict_seconds = Seconds(t0);
    res.predict_ms_per_row = 1e3 * res.predict_seconds / static_cast<double>(test.rows());
    res.confusion = Confusion(truth, predicted, classifier.class_names());
    res.accuracy = res.confusion.Accuracy();
    return res;
}

CrossValidationResult CrossValidate(const std::string& spec, const Dataset& data, std::size_t k,
                                    std::uint32_t seed, bool by_group, Progress* progress) {
    CreateClassifier(spec);  // parameter errors before any work
    const auto folds = KFold(data, k, seed, by_group);
    CrossValidationResult res;
    res.confusion.class_names = data.class_names;
    res.confusion.counts = Eigen::MatrixXi::Zero(static_cast<Eigen::Index>(data.num_classes()),
                                                 static_cast<Eigen::Index>(data.num_classes()));
    for (const auto& fold : folds) {
        const Dataset train = SelectRows(data, fold.train);
        const Dataset test = SelectRows(data, fold.test);
        auto c = CreateClassifier(spec);
        const auto t0 = std::chrono::steady_clock::now();
        c->Fit(train);
        res.train_seconds += Seconds(t0);
        // A class present only in the test fold cannot be predicted: count it as an error row.
        const auto t1 = std::chrono::steady_clock::now();
        const auto predicted = c->Predict(test);
        res.predict_seconds += Seconds(t1);
        std::size_t correct = 0;
        for (std::size_t i = 0; i < test.rows(); ++i) {
            const int truth = test.labels[i];
            const int pred =
                data.FindClass(c->class_names()[static_cast<std::size_t>(predicted[i])]);
            if (truth == kNoLabel) continue;
            ++res.confusion.counts(truth, pred);
            correct += truth == pred;
        }
        res.fold_accuracy.push_back(static_cast<double>(correct) /
                                    std::max<std::size_t>(1, test.rows()));
        if (progress != nullptr) progress->Advance();
    }
    double sum = 0.0, sq = 0.0;
    for (double a : res.fold_accuracy) sum += a;
    res.mean_accuracy = sum / static_cast<double>(res.fold_accuracy.size());
    for (double a : res.fold_accuracy) sq += (a - res.mean_accuracy) * (a - res.mean_accuracy);
    res.stddev_accuracy = std::sqrt(sq / static_cast<double>(res.fold_accuracy.size()));
    return res;
}

}  // namespace multicue::ml
