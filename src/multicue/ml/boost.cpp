#include "multicue/ml/boost.hpp"

#include <cmath>

#include "multicue/ml/opencv_util.hpp"
#include "multicue/ml/serialization.hpp"

namespace multicue::ml {

struct BoostClassifier::Models {
    std::vector<cv::Ptr<cv::ml::Boost>> per_class;
};

namespace {
const char* kTypeNames[] = {"discrete", "real", "logit", "gentle"};
}

BoostParams BoostParams::FromSpec(SpecArgs& args) {
    BoostParams p;
    const std::string type = args.GetString("type", "real");
    bool found = false;
    for (std::uint32_t i = 0; i < 4; ++i) {
        if (type == kTypeNames[i]) {
            p.type = static_cast<BoostType>(i);
            found = true;
        }
    }
    if (!found) {
        throw InvalidArgument("boost spec: type must be real, gentle, logit or discrete, got '" +
                              type + "'");
    }
    p.weak_count = static_cast<int>(args.GetInt("weak", p.weak_count));
    p.max_depth = static_cast<int>(args.GetInt("depth", p.max_depth));
    p.weight_trim = args.GetDouble("trim", p.weight_trim);
    if (p.weak_count < 1) throw InvalidArgument("boost spec: weak must be >= 1");
    if (p.max_depth < 1) throw InvalidArgument("boost spec: depth must be >= 1");
    if (p.weight_trim < 0.0 || p.weight_trim > 1.0) {
        throw InvalidArgument("boost spec: trim must be in [0, 1]");
    }
    return p;
}

BoostClassifier::BoostClassifier(BoostParams params)
    : params_(params), models_(std::make_unique<Models>()) {}
BoostClassifier::~BoostClassifier() = default;

std::string BoostClassifier::spec() const {
    return std::string("boost:type=") + kTypeNames[static_cast<int>(params_.type)] +
           ",weak=" + std::to_string(params_.weak_count) +
           ",depth=" + std::to_string(params_.max_depth) +
           ",trim=" + std::to_string(params_.weight_trim) + ",seed=" + std::to_string(seed);
}

void BoostClassifier::FitImpl(const FeaturesRef& x, const std::vector<int>& y, int num_classes,
                              Progress* progress) {
    const cv::Mat samples = detail::ToMat(x);
    auto fresh = std::make_unique<Models>();
    try {
        for (int c = 0; c < num_classes; ++c) {
            cv::Mat responses(static_cast<int>(y.size()), 1, CV_32S);
            for (std::size_t i = 0; i < y.size(); ++i) {
                responses.at<int>(static_cast<int>(i)) = y[i] == c ? 1 : 0;
            }
            cv::theRNG().state = seed + static_cast<std::uint64_t>(c);
            auto b = cv::ml::Boost::create();
            b->setBoostType(static_cast<int>(params_.type));
            b->setWeakCount(params_.weak_count);
            b->setMaxDepth(params_.max_depth);
            b->setWeightTrimRate(params_.weight_trim);
            b->setUseSurrogates(false);
            b->setMinSampleCount(2);
            b->setCVFolds(0);
            b->train(cv::ml::TrainData::create(samples, cv::ml::ROW_SAMPLE, responses));
            fresh->per_class.push_back(b);
            if (progress != nullptr) progress->Advance();
        }
    } catch (const cv::Exception& e) {
        throw DataError("boosting failed in OpenCV: " + e.msg);
    }
    models_ = std::move(fresh);
}

FeatureMatrix BoostClassifier::RawResponses(const FeaturesRef& x) const {
    const cv::Mat samples = detail::ToMat(x);
    FeatureMatrix raw(x.rows(), static_cast<Eigen::Index>(models_->per_class.size()));
    for (std::size_t c = 0; c < models_->per_class.size(); ++c) {
        cv::Mat out;
        // PREDICT_SUM: without it OpenCV returns the class label even with RAW_OUTPUT.
        models_->per_class[c]->predict(samples, out,
                                       static_cast<int>(cv::ml::StatModel::RAW_OUTPUT) |
                                           static_cast<int>(cv::ml::DTrees::PREDICT_SUM));
        for (Eigen::Index r = 0; r < x.rows(); ++r) {
            raw(r, static_cast<Eigen::Index>(c)) = out.at<float>(static_cast<int>(r));
        }
    }
    return raw;
}

FeatureMatrix BoostClassifier::PredictImpl(const FeaturesRef& x) const {
    // Each f_c(x) estimates half the log-odds of class c against the rest (Friedman et al.,
    // 1998); the symmetric multi-class link p_c = exp(2 f_c) / sum_k exp(2 f_k) keeps classes
    // apart even where the per-class logistic saturates at 1 for several classes.
    FeatureMatrix raw = 2.0f * RawResponses(x);
    for (Eigen::Index r = 0; r < raw.rows(); ++r) {
        raw.row(r).array() = (raw.row(r).array() - raw.row(r).maxCoeff()).exp();
    }
    return raw;
}

void BoostClassifier::WriteModel(ByteWriter& w) const {
    w.Put<std::uint64_t>(models_->per_class.size());
    for (const auto& m : models_->per_class) w.PutString(detail::ModelToString(m));
}

void BoostClassifier::ReadModel(ByteReader& r) {
    const auto n = r.Get<std::uint64_t>();
    if (n != num_classes()) r.Fail("boost model count differs from the class count");
    auto fresh = std::make_unique<Models>();
    for (std::uint64_t c = 0; c < n; ++c) {
        fresh->per_class.push_back(detail::ModelFromString<cv::ml::Boost>(
            r.GetString(), r.what(), [&](const cv::FileNode& m) {
                return detail::TreesProblem(m, num_features(), num_classes());
            }));
    }
    models_ = std::move(fresh);
}

}  // namespace multicue::ml
