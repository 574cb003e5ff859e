#include "multicue/ml/svm.hpp"

#include <libsvm/svm.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <sstream>

#include <unistd.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/serialization.hpp"
#include "multicue/ml/svm_model_text.hpp"

namespace multicue::ml {

namespace {

void Silent(const char*) {}

// libsvm keeps global state (print function, rand()); serialise our calls into it.
std::mutex& LibsvmMutex() {
    static std::mutex m;
    return m;
}

// Dense rows as libsvm's sparse nodes (zeros skipped, index -1 terminates each row).
struct SvmProblem {
    std::vector<svm_node> nodes;
    std::vector<svm_node*> rows;
    std::vector<double> y;
    svm_problem problem{};

    SvmProblem(const FeaturesRef& x, const std::vector<int>& labels) {
        std::vector<std::size_t> starts;
        for (Eigen::Index r = 0; r < x.rows(); ++r) {
            starts.push_back(nodes.size());
            for (Eigen::Index c = 0; c < x.cols(); ++c) {
                if (x(r, c) != 0.0f) nodes.push_back({static_cast<int>(c) + 1, x(r, c)});
            }
            nodes.push_back({-1, 0.0});
        }
        for (std::size_t s : starts) rows.push_back(nodes.data() + s);
        y.assign(labels.begin(), labels.end());
        problem.l = static_cast<int>(rows.size());
        problem.y = y.data();
        problem.x = rows.data();
    }
};

std::vector<svm_node> RowNodes(const FeaturesRef& x, Eigen::Index r) {
    std::vector<svm_node> n;
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
        if (x(r, c) != 0.0f) n.push_back({static_cast<int>(c) + 1, x(r, c)});
    }
    n.push_back({-1, 0.0});
    return n;
}

std::filesystem::path TempModelPath() {
    static std::atomic<unsigned> counter{0};
    return std::filesystem::temp_directory_path() / ("multicue-svm-" + std::to_string(::getpid()) +
                                                     "-" + std::to_string(counter++) + ".model");
}

// libsvm reads and writes models only through files: go through a private temporary file.
std::string ModelToText(const svm_model* model) {
    const auto path = TempModelPath();
    errno = 0;
    const int rc = svm_save_model(path.c_str(), model);
    const int error = errno;
    std::string text;
    try {
        if (rc != 0) {
            throw IoError("libsvm could not write its model to " + path.string() + ": " +
                          (error != 0 ? std::strerror(error) : "unknown error"));
        }
        text = ReadBytes(path);
    } catch (...) {
        std::error_code ec;
        std::filesystem::remove(path, ec);
        throw;
    }
    std::error_code ec;
    std::filesystem::remove(path, ec);
    return text;
}

svm_model* ModelFromText(const std::string& text) {
    const auto path = TempModelPath();
    WriteBytesAtomically(path, text);
    svm_model* m = svm_load_model(path.c_str());
    std::error_code ec;
    std::filesystem::remove(path, ec);
    return m;
}

std::vector<double> ParseList(const std::string& s, const std::string& key) {
    std::vector<double> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ':')) {
        try {
            out.push_back(std::stod(item));
        } catch (const std::exception&) {
            throw InvalidArgument("svm spec: " + key + " must be numbers separated by ':'");
        }
        if (!(out.back() > 0.0)) throw InvalidArgument("svm spec: " + key + " values must be > 0");
    }
    if (out.empty()) throw InvalidArgument("svm spec: " + key + " is empty");
    return out;
}

std::string JoinList(const std::vector<double>& v) {
    std::ostringstream ss;
    ss.precision(17);
    for (std::size_t i = 0; i < v.size(); ++i) ss << (i ? ":" : "") << v[i];
    return ss.str();
}

}  // namespace

void SvmClassifier::ModelDeleter::operator()(svm_model* m) const { svm_free_and_destroy_model(&m); }

SvmParams SvmParams::FromSpec(SpecArgs& args) {
    SvmParams p;
    const std::string kernel = args.GetString("kernel", "rbf");
    if (kernel == "rbf") {
        p.kernel = SvmKernel::kRbf;
    } else if (kernel == "linear") {
        p.kernel = SvmKernel::kLinear;
    } else {
        throw InvalidArgument("svm spec: kernel must be linear or rbf, got '" + kernel + "'");
    }
    p.c = args.GetDouble("C", p.c);
    if (!(p.c > 0.0)) throw InvalidArgument("svm spec: C must be > 0");
    p.gamma = args.GetDouble("gamma", p.gamma);
    if (p.gamma < 0.0) throw InvalidArgument("svm spec: gamma must be >= 0");
    p.probability = args.GetInt("probability", 1) != 0;
    p.grid_search = args.GetInt("grid", 0) != 0;
    const std::string gc = args.GetString("grid_C", "");
    if (!gc.empty()) p.grid_c = ParseList(gc, "grid_C");
    const std::string gg = args.GetString("grid_gamma", "");
    if (!gg.empty()) p.grid_gamma = ParseList(gg, "grid_gamma");
    p.folds = static_cast<int>(args.GetInt("folds", 5));
    if (p.folds < 2) throw InvalidArgument("svm spec: folds must be >= 2");
    p.cache_mb = args.GetDouble("cache", p.cache_mb);
    p.epsilon = args.GetDouble("eps", p.epsilon);
    if (!(p.cache_mb > 0.0) || !(p.epsilon > 0.0)) {
        throw InvalidArgument("svm spec: cache and eps must be > 0");
    }
    return p;
}

SvmClassifier::SvmClassifier(SvmParams params) : params_(std::move(params)) {}
SvmClassifier::~SvmClassifier() = default;

std::string SvmClassifier::spec() const {
    std::ostringstream ss;
    ss.precision(17);
    ss << "svm:kernel=" << (params_.kernel == SvmKernel::kRbf ? "rbf" : "linear")
       << ",C=" << params_.c << ",gamma=" << params_.gamma
       << ",probability=" << (params_.probability ? 1 : 0)
       << ",grid=" << (params_.grid_search ? 1 : 0) << ",grid_C=" << JoinList(params_.grid_c)
       << ",grid_gamma=" << JoinList(params_.grid_gamma) << ",folds=" << params_.folds
       << ",cache=" << params_.cache_mb << ",eps=" << params_.epsilon << ",seed=" << seed;
    return ss.str();
}

void SvmClassifier::FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                            Progress* progress) {
    SvmProblem prob(x, y);
    svm_parameter param{};
    param.svm_type = C_SVC;
    param.kernel_type = params_.kernel == SvmKernel::kRbf ? RBF : LINEAR;
    param.cache_size = params_.cache_mb;
    param.eps = params_.epsilon;
    param.shrinking = 1;
    param.probability = params_.probability ? 1 : 0;
    param.C = params_.c;
    param.gamma = params_.gamma > 0.0 ? params_.gamma : 1.0 / static_cast<double>(x.cols());

    std::lock_guard<std::mutex> lock(LibsvmMutex());
    svm_set_print_string_function(&Silent);
    grid_.clear();
    if (params_.grid_search) {
        const std::vector<double> gammas = params_.kernel == SvmKernel::kRbf
                                               ? params_.grid_gamma
                                               : std::vector<double>{param.gamma};
        std::vector<double> target(y.size());
        double best = -1.0;
        double best_c = param.C, best_gamma = param.gamma;
        svm_parameter cv = param;
        cv.probability = 0;
        for (double c : params_.grid_c) {
            for (double g : gammas) {
                cv.C = c;
                cv.gamma = g;
                std::srand(seed);  // libsvm shuffles the folds with rand()
                svm_cross_validation(&prob.problem, &cv, params_.folds, target.data());
                std::size_t correct = 0;
                for (std::size_t i = 0; i < y.size(); ++i)
                    correct += static_cast<int>(target[i]) == y[i];
                const double acc = static_cast<double>(correct) / static_cast<double>(y.size());
                grid_.push_back({c, g, acc});
                if (acc > best) {
                    best = acc;
                    best_c = c;
                    best_gamma = g;
                }
                if (progress != nullptr) progress->Advance();
            }
        }
        param.C = best_c;
        param.gamma = best_gamma;
    }
    if (const char* err = svm_check_parameter(&prob.problem, &param)) {
        throw InvalidArgument(std::string("libsvm: ") + err);
    }
    std::srand(seed);  // probability estimates use an internal cross-validation
    svm_model* trained = svm_train(&prob.problem, &param);
    // A trained model points into `prob`; keep an independent copy through libsvm's text form.
    std::string text;
    try {
        text = ModelToText(trained);
    } catch (...) {
        svm_free_and_destroy_model(&trained);
        throw;
    }
    svm_free_and_destroy_model(&trained);
    svm_model* loaded = ModelFromText(text);
    if (loaded == nullptr) throw DataError("libsvm could not reload the model it trained");
    model_.reset(loaded);
    model_text_ = std::move(text);
    c_ = param.C;
    gamma_ = param.gamma;
    num_classes_ = num_classes;
    if (progress != nullptr) progress->Advance();
}

FeatureMatrix SvmClassifier::PredictImpl(const FeaturesRef& x) const {
    FeatureMatrix scores = FeatureMatrix::Zero(x.rows(), num_classes_);
    const int k = svm_get_nr_class(model_.get());
    std::vector<int> labels(static_cast<std::size_t>(k));
    svm_get_labels(model_.get(), labels.data());
    const bool prob = svm_check_probability_model(model_.get()) != 0;
    std::vector<double> out(static_cast<std::size_t>(k * (k - 1) / 2 + k));
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
        const auto nodes = RowNodes(x, r);
        if (prob) {
            svm_predict_probability(model_.get(), nodes.data(), out.data());
            for (int i = 0; i < k; ++i)
                scores(r, labels[static_cast<std::size_t>(i)]) =
                    static_cast<float>(out[static_cast<std::size_t>(i)]);
        } else {
            // One-against-one votes (libsvm's pair order: (0,1), (0,2), ..., (1,2), ...).
            svm_predict_values(model_.get(), nodes.data(), out.data());
            std::size_t p = 0;
            for (int i = 0; i < k; ++i) {
                for (int j = i + 1; j < k; ++j, ++p) {
                    const int winner = out[p] > 0 ? labels[static_cast<std::size_t>(i)]
                                                  : labels[static_cast<std::size_t>(j)];
                    scores(r, winner) += 1.0f;
                }
            }
        }
    }
    return scores;
}

void SvmClassifier::WriteModel(ByteWriter& w) const {
    w.Put<double>(c_);
    w.Put<double>(gamma_);
    w.Put<std::int32_t>(num_classes_);
    w.PutString(model_text_);
}

void SvmClassifier::ReadModel(ByteReader& r) {
    c_ = r.Get<double>();
    gamma_ = r.Get<double>();
    num_classes_ = r.Get<std::int32_t>();
    model_text_ = r.GetString();
    if (num_classes_ != static_cast<int>(num_classes())) r.Fail("bad SVM class count");
    if (const std::string problem = SvmModelTextProblem(model_text_, num_features(), num_classes());
        !problem.empty()) {
        r.Fail("bad embedded libsvm model: " + problem);
    }
    std::lock_guard<std::mutex> lock(LibsvmMutex());
    svm_model* m = ModelFromText(model_text_);
    if (m == nullptr) r.Fail("libsvm cannot read the embedded model");
    model_.reset(m);
    const int k = svm_get_nr_class(m);
    std::vector<int> labels(static_cast<std::size_t>(std::max(k, 0)));
    if (k > 0) svm_get_labels(m, labels.data());
    for (int l : labels) {
        if (l < 0 || l >= num_classes_) r.Fail("bad SVM class label");
    }
}

}  // namespace multicue::ml
