#include "multicue/ml/opencv_models.hpp"

#include <algorithm>
#include <sstream>

#include "multicue/ml/opencv_util.hpp"
#include "multicue/ml/serialization.hpp"

namespace multicue::ml {

struct MlpClassifier::Model {
    cv::Ptr<cv::ml::ANN_MLP> net;
};
struct RTreesClassifier::Model {
    cv::Ptr<cv::ml::RTrees> forest;
};

// --- MLP ---------------------------------------------------------------------------------------

MlpParams MlpParams::FromSpec(SpecArgs& args) {
    MlpParams p;
    const std::string hidden = args.GetString("hidden", "32");
    p.hidden.clear();
    std::stringstream ss(hidden);
    std::string item;
    while (std::getline(ss, item, 'x')) {
        int n = 0;
        try {
            n = std::stoi(item);
        } catch (const std::exception&) {
            n = 0;
        }
        if (n < 1)
            throw InvalidArgument("mlp spec: hidden must be sizes >= 1 like 64x32, got '" + hidden +
                                  "'");
        p.hidden.push_back(n);
    }
    p.iterations = static_cast<int>(args.GetInt("iterations", p.iterations));
    if (p.iterations < 1) throw InvalidArgument("mlp spec: iterations must be >= 1");
    const std::string method = args.GetString("method", "rprop");
    if (method != "rprop" && method != "backprop") {
        throw InvalidArgument("mlp spec: method must be rprop or backprop, got '" + method + "'");
    }
    p.rprop = method == "rprop";
    return p;
}

MlpClassifier::MlpClassifier(MlpParams params)
    : params_(std::move(params)), model_(std::make_unique<Model>()) {}
MlpClassifier::~MlpClassifier() = default;

std::string MlpClassifier::spec() const {
    std::string hidden;
    for (std::size_t i = 0; i < params_.hidden.size(); ++i) {
        if (i > 0) hidden += 'x';
        hidden += std::to_string(params_.hidden[i]);
    }
    return "mlp:hidden=" + hidden + ",iterations=" + std::to_string(params_.iterations) +
           ",method=" + (params_.rprop ? "rprop" : "backprop") + ",seed=" + std::to_string(seed);
}

void MlpClassifier::FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                            Progress* progress) {
    const cv::Mat samples = detail::ToMat(x);
    cv::Mat targets = cv::Mat::zeros(static_cast<int>(y.size()), num_classes, CV_32F);
    for (std::size_t i = 0; i < y.size(); ++i) targets.at<float>(static_cast<int>(i), y[i]) = 1.0f;
    cv::Mat layers(static_cast<int>(params_.hidden.size()) + 2, 1, CV_32S);
    layers.at<int>(0) = static_cast<int>(x.cols());
    for (std::size_t i = 0; i < params_.hidden.size(); ++i) {
        layers.at<int>(static_cast<int>(i) + 1) = params_.hidden[i];
    }
    layers.at<int>(layers.rows - 1) = num_classes;
    try {
        cv::theRNG().state = seed;  // initial weights
        auto net = cv::ml::ANN_MLP::create();
        net->setLayerSizes(layers);
        net->setActivationFunction(cv::ml::ANN_MLP::SIGMOID_SYM, 0, 0);
        if (params_.rprop) {
            net->setTrainMethod(cv::ml::ANN_MLP::RPROP, 0.1, 0.1);
        } else {
            net->setTrainMethod(cv::ml::ANN_MLP::BACKPROP, 0.1, 0.1);
        }
        net->setTermCriteria(cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS,
                                              params_.iterations, 1e-6));
        net->train(cv::ml::TrainData::create(samples, cv::ml::ROW_SAMPLE, targets));
        model_->net = net;
    } catch (const cv::Exception& e) {
        throw DataError("MLP training failed in OpenCV: " + e.msg);
    }
    if (progress != nullptr) progress->Advance();
}

FeatureMatrix MlpClassifier::PredictImpl(const FeaturesRef& x) const {
    cv::Mat out;
    model_->net->predict(detail::ToMat(x), out);
    FeatureMatrix scores(x.rows(), out.cols);
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
        for (int c = 0; c < out.cols; ++c) {
            scores(r, c) = std::clamp(out.at<float>(static_cast<int>(r), c), 0.0f, 1.0f) + 1e-3f;
        }
    }
    return scores;
}

void MlpClassifier::WriteModel(ByteWriter& w) const {
    w.PutString(detail::ModelToString(model_->net));
}

void MlpClassifier::ReadModel(ByteReader& r) {
    model_->net = detail::ModelFromString<cv::ml::ANN_MLP>(
        r.GetString(), r.what(), [&](const cv::FileNode& m) {
            return detail::MlpProblem(m, num_features(), num_classes());
        });
    const cv::Mat layers = model_->net->getLayerSizes();
    if (layers.total() < 2 || layers.at<int>(0) != static_cast<int>(num_features()) ||
        layers.at<int>(static_cast<int>(layers.total()) - 1) != static_cast<int>(num_classes())) {
        r.Fail("MLP layer sizes do not match the model's features and classes");
    }
}

// --- random forest -----------------------------------------------------------------------------

RTreesParams RTreesParams::FromSpec(SpecArgs& args) {
    RTreesParams p;
    p.trees = static_cast<int>(args.GetInt("trees", p.trees));
    p.max_depth = static_cast<int>(args.GetInt("depth", p.max_depth));
    p.min_samples = static_cast<int>(args.GetInt("min_samples", p.min_samples));
    p.active_vars = static_cast<int>(args.GetInt("vars", p.active_vars));
    if (p.trees < 1 || p.max_depth < 1 || p.min_samples < 1 || p.active_vars < 0) {
        throw InvalidArgument("rtrees spec: trees, depth, min_samples must be >= 1, vars >= 0");
    }
    return p;
}

RTreesClassifier::RTreesClassifier(RTreesParams params)
    : params_(params), model_(std::make_unique<Model>()) {}
RTreesClassifier::~RTreesClassifier() = default;

std::string RTreesClassifier::spec() const {
    return "rtrees:trees=" + std::to_string(params_.trees) +
           ",depth=" + std::to_string(params_.max_depth) +
           ",min_samples=" + std::to_string(params_.min_samples) +
           ",vars=" + std::to_string(params_.active_vars) + ",seed=" + std::to_string(seed);
}

void RTreesClassifier::FitImpl(const FeaturesRef& x, const std::vector<int>& y, int,
                               Progress* progress) {
    cv::Mat responses(static_cast<int>(y.size()), 1, CV_32S);
    for (std::size_t i = 0; i < y.size(); ++i) responses.at<int>(static_cast<int>(i)) = y[i];
    try {
        cv::theRNG().state = seed;
        auto f = cv::ml::RTrees::create();
        f->setMaxDepth(params_.max_depth);
        f->setMinSampleCount(params_.min_samples);
        f->setActiveVarCount(params_.active_vars);
        f->setUseSurrogates(false);
        f->setCalculateVarImportance(false);
        f->setTermCriteria(cv::TermCriteria(cv::TermCriteria::MAX_ITER, params_.trees, 0.0));
        f->train(cv::ml::TrainData::create(detail::ToMat(x), cv::ml::ROW_SAMPLE, responses));
        model_->forest = f;
    } catch (const cv::Exception& e) {
        throw DataError("random forest training failed in OpenCV: " + e.msg);
    }
    if (progress != nullptr) progress->Advance();
}

FeatureMatrix RTreesClassifier::PredictImpl(const FeaturesRef& x) const {
    cv::Mat votes;
    model_->forest->getVotes(detail::ToMat(x), votes, 0);
    FeatureMatrix scores = FeatureMatrix::Zero(x.rows(), static_cast<Eigen::Index>(num_classes()));
    // First row: the class label of each column.
    for (int c = 0; c < votes.cols; ++c) {
        const int label = votes.at<int>(0, c);
        if (label < 0 || label >= static_cast<int>(num_classes())) continue;
        for (Eigen::Index r = 0; r < x.rows(); ++r) {
            scores(r, label) = static_cast<float>(votes.at<int>(static_cast<int>(r) + 1, c));
        }
    }
    return scores;
}

void RTreesClassifier::WriteModel(ByteWriter& w) const {
    w.PutString(detail::ModelToString(model_->forest));
}

void RTreesClassifier::ReadModel(ByteReader& r) {
    model_->forest = detail::ModelFromString<cv::ml::RTrees>(
        r.GetString(), r.what(), [&](const cv::FileNode& m) {
            return detail::TreesProblem(m, num_features(), num_classes());
        });
}

}  // namespace multicue::ml
