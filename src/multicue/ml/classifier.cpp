#include "multicue/ml/classifier.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/boost.hpp"
#include "multicue/ml/knn.hpp"
#include "multicue/ml/opencv_models.hpp"
#include "multicue/ml/serialization.hpp"
#include "multicue/ml/svm.hpp"

namespace multicue::ml {

namespace {
constexpr std::string_view kModelMagic = "MCUEMODL";
}  // namespace

void Classifier::Fit(const Dataset& train, Progress* progress) {
    if (train.empty()) throw DataError("cannot train a classifier on an empty dataset");
    if (train.cols() == 0) throw DataError("cannot train a classifier without feature columns");
    train.CheckFinite("training set");
    std::vector<int> remap(train.num_classes(), kNoLabel);
    std::vector<std::string> classes;
    for (std::size_t r = 0; r < train.rows(); ++r) {
        const int l = train.labels[r];
        if (l == kNoLabel) throw DataError("training row " + std::to_string(r) + " has no label");
        if (remap[l] == kNoLabel) remap[l] = 0;
    }
    for (std::size_t c = 0; c < remap.size(); ++c) {
        if (remap[c] != kNoLabel) {
            remap[c] = static_cast<int>(classes.size());
            classes.push_back(train.class_names[c]);
        }
    }
    if (classes.size() < 2) {
        throw DataError("training set has " + std::to_string(classes.size()) +
                        " class; a classifier needs at least 2");
    }
    std::vector<int> y(train.rows());
    for (std::size_t r = 0; r < y.size(); ++r) y[r] = remap[train.labels[r]];
    const bool scale =
        scaling == InputScaling::kZScore || (scaling == InputScaling::kAuto && NeedsScaledInput());
    scale_mean_.resize(0);
    scale_inv_std_.resize(0);
    if (scale) {
        const FeaturesRef x = train.features();
        const Eigen::RowVectorXd mean = x.cast<double>().colwise().mean();
        const Eigen::RowVectorXd var =
            (x.cast<double>().rowwise() - mean).array().square().colwise().mean();
        scale_mean_ = mean.cast<float>();
        scale_inv_std_ =
            var.unaryExpr([](double v) { return v > 1e-24 ? 1.0 / std::sqrt(v) : 1.0; })
                .cast<float>();
        feature_names_ = train.feature_names;  // Scaled() checks the column count
        FitImpl(Scaled(x), y, static_cast<int>(classes.size()), progress);
    } else {
        FitImpl(train.features(), y, static_cast<int>(classes.size()), progress);
    }
    class_names_ = std::move(classes);
    feature_names_ = train.feature_names;
}

FeatureMatrix Classifier::Scaled(const FeaturesRef& features) const {
    FeatureMatrix out = features;
    out.array().rowwise() -= scale_mean_.array();
    out.array().rowwise() *= scale_inv_std_.array();
    return out;
}

void Classifier::ScaleRow(float* row) const {
    for (Eigen::Index c = 0; c < scale_mean_.size(); ++c)
        row[c] = (row[c] - scale_mean_[c]) * scale_inv_std_[c];
}

void Classifier::CheckInput(const FeaturesRef& features) const {
    if (!fitted()) throw InvalidArgument(type() + " classifier is used before it was trained");
    if (static_cast<std::size_t>(features.cols()) != num_features()) {
        throw InvalidArgument(type() + " classifier was trained on " +
                              std::to_string(num_features()) + " features, got " +
                              std::to_string(features.cols()));
    }
    for (Eigen::Index r = 0; r < features.rows(); ++r) {
        if (!features.row(r).allFinite()) {
            throw DataError("non-finite feature value in row " + std::to_string(r));
        }
    }
}

FeatureMatrix Classifier::PredictProba(const FeaturesRef& features) const {
    CheckInput(features);
    if (features.rows() == 0) {
        return FeatureMatrix(0, static_cast<Eigen::Index>(num_classes()));
    }
    FeatureMatrix p = scales_input() ? PredictImpl(Scaled(features)) : PredictImpl(features);
    for (Eigen::Index r = 0; r < p.rows(); ++r) {
        auto row = p.row(r);
        row = row.cwiseMax(0.0f);
        const float s = row.sum();
        if (s > 0.0f && std::isfinite(s)) {
            row /= s;
        } else {
            row.setConstant(1.0f / static_cast<float>(p.cols()));
        }
    }
    return p;
}

FeatureMatrix Classifier::PredictProba(const Dataset& data) const {
    if (fitted() && data.feature_names != feature_names_ && data.cols() == num_features()) {
        throw InvalidArgument("dataset columns differ from those the " + type() +
                              " classifier was trained on (same count, other names or order)");
    }
    return PredictProba(data.features());
}

std::vector<int> Classifier::Predict(const FeaturesRef& features) const {
    return ArgMaxRows(PredictProba(features));
}

std::vector<int> Classifier::Predict(const Dataset& data) const {
    return ArgMaxRows(PredictProba(data));
}

std::string Classifier::Serialize() const {
    if (!fitted()) throw InvalidArgument("cannot save an untrained " + type() + " classifier");
    ByteWriter w;
    w.PutString(type());
    w.PutString(spec());
    w.Put<std::uint32_t>(seed);
    w.PutStrings(class_names_);
    w.PutStrings(feature_names_);
    w.Put<std::uint8_t>(static_cast<std::uint8_t>(scaling));
    w.PutArray(scale_mean_.data(), static_cast<std::size_t>(scale_mean_.size()));
    w.PutArray(scale_inv_std_.data(), static_cast<std::size_t>(scale_inv_std_.size()));
    WriteModel(w);
    return WrapContainer(kModelMagic, kModelFormatVersion, w.bytes());
}

void Classifier::Save(const std::filesystem::path& path) const {
    WriteBytesAtomically(path, Serialize());
}

std::unique_ptr<Classifier> DeserializeClassifier(const std::string& bytes,
                                                  const std::string& what) {
    // Version 1 (no input scaling) is still read.
    const std::uint32_t version = ContainerVersion(bytes) == 1 ? 1 : kModelFormatVersion;
    const std::string payload =
        UnwrapContainer(bytes, kModelMagic, version, "classifier model", what);
    ByteReader r(payload, what);
    const std::string type = r.GetString();
    const std::string spec = r.GetString();
    std::unique_ptr<Classifier> c;
    try {
        c = CreateClassifier(spec);
    } catch (const InvalidArgument& e) {
        r.Fail(std::string("bad classifier spec: ") + e.what());
    }
    if (c->type() != type) r.Fail("classifier type mismatch");
    c->seed = r.Get<std::uint32_t>();
    c->class_names_ = r.GetStrings();
    c->feature_names_ = r.GetStrings();
    if (c->class_names_.size() < 2) r.Fail("model has fewer than 2 classes");
    if (version >= 2) {
        const auto mode = r.Get<std::uint8_t>();
        if (mode > static_cast<std::uint8_t>(InputScaling::kZScore)) r.Fail("bad input scaling");
        c->scaling = static_cast<InputScaling>(mode);
        const std::vector<float> mean = r.GetVector<float>();
        const std::vector<float> inv = r.GetVector<float>();
        if (mean.size() != inv.size() ||
            (!mean.empty() && mean.size() != c->feature_names_.size())) {
            r.Fail("input scaling does not match the feature columns");
        }
        c->scale_mean_ = Eigen::Map<const Eigen::RowVectorXf>(
            mean.data(), static_cast<Eigen::Index>(mean.size()));
        c->scale_inv_std_ =
            Eigen::Map<const Eigen::RowVectorXf>(inv.data(), static_cast<Eigen::Index>(inv.size()));
    }
    c->ReadModel(r);
    if (!r.AtEnd()) r.Fail("trailing bytes in payload");
    return c;
}

std::unique_ptr<Classifier> LoadClassifier(const std::filesystem::path& path) {
    return DeserializeClassifier(ReadBytes(path), path.string());
}

std::unique_ptr<Classifier> CreateClassifier(const std::string& spec) {
    const auto colon = spec.find(':');
    const std::string type = spec.substr(0, colon);
    SpecArgs args(type, colon == std::string::npos ? "" : spec.substr(colon + 1));
    std::unique_ptr<Classifier> c;
    if (type == "knn") {
        c = std::make_unique<KnnClassifier>(KnnParams::FromSpec(args));
    } else if (type == "svm") {
        c = std::make_unique<SvmClassifier>(SvmParams::FromSpec(args));
    } else if (type == "boost") {
        c = std::make_unique<BoostClassifier>(BoostParams::FromSpec(args));
    } else if (type == "mlp") {
        c = std::make_unique<MlpClassifier>(MlpParams::FromSpec(args));
    } else if (type == "rtrees") {
        c = std::make_unique<RTreesClassifier>(RTreesParams::FromSpec(args));
    } else {
        throw InvalidArgument("unknown classifier type '" + type +
                              "' (knn, svm, boost, mlp, rtrees)");
    }
    c->seed = static_cast<std::uint32_t>(args.GetInt("seed", 1));
    const std::string scale = args.GetString("scale", "auto");
    if (scale == "auto") {
        c->scaling = InputScaling::kAuto;
    } else if (scale == "zscore") {
        c->scaling = InputScaling::kZScore;
    } else if (scale == "none") {
        c->scaling = InputScaling::kNone;
    } else {
        throw InvalidArgument("scale must be auto, zscore or none, got '" + scale + "'");
    }
    args.CheckAllUsed();
    return c;
}

SpecArgs::SpecArgs(const std::string& type, const std::string& args) : type_(type) {
    std::size_t pos = 0;
    while (pos < args.size()) {
        auto end = args.find(',', pos);
        if (end == std::string::npos) end = args.size();
        const std::string item = args.substr(pos, end - pos);
        const auto eq = item.find('=');
        if (eq == std::string::npos || eq == 0) {
            throw InvalidArgument(type + " spec: expected key=value, got '" + item + "'");
        }
        values_[item.substr(0, eq)] = item.substr(eq + 1);
        pos = end + 1;
    }
}

std::string SpecArgs::GetString(const std::string& key, const std::string& fallback) {
    used_[key] = true;
    const auto it = values_.find(key);
    return it == values_.end() ? fallback : it->second;
}

double SpecArgs::GetDouble(const std::string& key, double fallback) {
    const std::string s = GetString(key, "");
    if (s.empty()) return fallback;
    try {
        std::size_t n = 0;
        const double v = std::stod(s, &n);
        if (n == s.size() && std::isfinite(v)) return v;
    } catch (const std::exception&) {
    }
    throw InvalidArgument(type_ + " spec: " + key + " must be a number, got '" + s + "'");
}

long SpecArgs::GetInt(const std::string& key, long fallback) {
    const std::string s = GetString(key, "");
    if (s.empty()) return fallback;
    try {
        std::size_t n = 0;
        const long v = std::stol(s, &n);
        if (n == s.size()) return v;
    } catch (const std::exception&) {
    }
    throw InvalidArgument(type_ + " spec: " + key + " must be an integer, got '" + s + "'");
}

void SpecArgs::CheckAllUsed() const {
    for (const auto& [key, value] : values_) {
        if (!used_.count(key)) throw InvalidArgument(type_ + " spec: unknown key '" + key + "'");
    }
}

std::vector<int> ArgMaxRows(const FeatureMatrix& scores) {
    std::vector<int> out(static_cast<std::size_t>(scores.rows()));
    for (Eigen::Index r = 0; r < scores.rows(); ++r) {
        Eigen::Index arg = 0;
        for (Eigen::Index c = 1; c < scores.cols(); ++c) {
            if (scores(r, c) > scores(r, arg)) arg = c;
        }
        out[static_cast<std::size_t>(r)] = static_cast<int>(arg);
    }
    return out;
}

void CheckClassifierFor(const Classifier& c, const std::vector<std::string>& features,
                        const std::vector<std::string>& classes, const std::string& what,
                        const std::string& kind) {
    if (!c.fitted()) {
        throw InvalidArgument(fmt::format("{}: the {} classifier is not trained", what, kind));
    }
    if (c.feature_names() != features) {
        throw InvalidArgument(fmt::format(
            "{}: the classifier was trained on {} columns (first '{}'), not on the {} {} features "
            "(first '{}')",
            what, c.num_features(), c.feature_names().empty() ? "" : c.feature_names().front(),
            features.size(), kind, features.empty() ? "" : features.front()));
    }
    for (const auto& name : c.class_names()) {
        if (std::find(classes.begin(), classes.end(), name) == classes.end()) {
            throw InvalidArgument(fmt::format("{}: the classifier predicts '{}', not one of {}",
                                              what, name, fmt::join(classes, ", ")));
        }
    }
}

}  // namespace multicue::ml
