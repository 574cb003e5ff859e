#include "multicue/ml/transform.hpp"

#include <Eigen/Eigenvalues>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/serialization.hpp"

namespace multicue::ml {

namespace {

constexpr std::string_view kTransformMagic = "MCUEXFRM";

void CheckTrain(const Dataset& train) {
    if (train.empty() || train.cols() == 0)
        throw DataError("cannot fit a transform on an empty dataset");
    train.CheckFinite("training set");
}

void PutVectorXf(ByteWriter& w, const Eigen::VectorXf& v) { w.PutArray(v.data(), v.size()); }
Eigen::VectorXf GetVectorXf(ByteReader& r) {
    const auto v = r.GetVector<float>();
    return Eigen::Map<const Eigen::VectorXf>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace

FeatureMatrix FeatureTransform::Apply(const FeaturesRef& features) const {
    if (static_cast<std::size_t>(features.cols()) != input_dims()) {
        throw InvalidArgument("transform was fitted on " + std::to_string(input_dims()) +
                              " columns, got " + std::to_string(features.cols()));
    }
    if (!features.allFinite()) throw DataError("non-finite feature value given to a transform");
    FeatureMatrix centred = features.rowwise() - offset.transpose();
    if (kind != TransformKind::kPca) return centred.array().rowwise() * scale.transpose().array();
    FeatureMatrix projected = centred * components.transpose();
    if (whiten) {
        const Eigen::VectorXf inv = variances.array().max(1e-12f).rsqrt();
        projected.array().rowwise() *= inv.transpose().array();
    }
    return projected;
}

Dataset FeatureTransform::Apply(const Dataset& data) const {
    if (data.feature_names != input_names) {
        if (data.cols() != input_dims()) Apply(data.features());  // throws with the counts
        throw InvalidArgument("dataset columns differ from those the transform was fitted on");
    }
    Dataset out = data;
    const FeatureMatrix y = Apply(data.features());
    if (kind == TransformKind::kPca) {
        std::vector<std::string> names(static_cast<std::size_t>(y.cols()));
        for (std::size_t i = 0; i < names.size(); ++i) names[i] = IndexedName("pc", i);
        Dataset shape = Dataset::WithBlocks({{"pca", names}});
        out.num_cols = shape.num_cols;
        out.feature_names = shape.feature_names;
        out.blocks = shape.blocks;
    }
    out.values.assign(y.data(), y.data() + y.size());
    return out;
}

FeatureTransform FitMinMax(const Dataset& train) {
    CheckTrain(train);
    const auto x = train.features();
    FeatureTransform t;
    t.kind = TransformKind::kMinMax;
    t.input_names = train.feature_names;
    t.offset = x.colwise().minCoeff().transpose();
    const Eigen::VectorXf range = x.colwise().maxCoeff().transpose() - t.offset;
    t.scale = (range.array() > 0.0f).select(range.array().inverse(), 0.0f);
    return t;
}

FeatureTransform FitZScore(const Dataset& train) {
    CheckTrain(train);
    const Eigen::MatrixXd x = train.features().cast<double>();
    FeatureTransform t;
    t.kind = TransformKind::kZScore;
    t.input_names = train.feature_names;
    const Eigen::VectorXd mean = x.colwise().mean().transpose();
    const Eigen::VectorXd var =
        (x.rowwise() - mean.transpose()).array().square().colwise().mean().transpose();
    t.offset = mean.cast<float>();
    t.scale = (var.array() > 1e-24).select(var.array().rsqrt(), 0.0).cast<float>();
    return t;
}

FeatureTransform FitPca(const Dataset& train, const PcaParams& params) {
    CheckTrain(train);
    if (!(params.variance > 0.0 && params.variance <= 1.0)) {
        throw InvalidArgument("PCA variance fraction must be in (0, 1], got " +
                              std::to_string(params.variance));
    }
    if (params.components > train.cols()) {
        throw InvalidArgument("PCA components must be <= " + std::to_string(train.cols()) +
                              ", got " + std::to_string(params.components));
    }
    const Eigen::MatrixXd x = train.features().cast<double>();
    const Eigen::VectorXd mean = x.colwise().mean().transpose();
    const Eigen::MatrixXd centred = x.rowwise() - mean.transpose();
    const Eigen::MatrixXd cov = centred.transpose() * centred / std::max<double>(1, x.rows() - 1);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(cov);
    // Eigen sorts eigenvalues ascending; take them from the back.
    const Eigen::VectorXd ev = solver.eigenvalues().cwiseMax(0.0);
    const double total = ev.sum();
    const auto d = static_cast<std::size_t>(ev.size());
    std::size_t k = params.components;
    if (k == 0) {
        double acc = 0.0;
        k = d;
        for (std::size_t i = 0; i < d; ++i) {
            acc += ev(static_cast<Eigen::Index>(d - 1 - i));
            if (total <= 0.0 || acc >= params.variance * total - 1e-12) {
                k = i + 1;
                break;
            }
        }
    }
    FeatureTransform t;
    t.kind = TransformKind::kPca;
    t.whiten = params.whiten;
    t.input_names = train.feature_names;
    t.offset = mean.cast<float>();
    t.components.resize(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(d));
    t.variances.resize(static_cast<Eigen::Index>(k));
    for (std::size_t i = 0; i < k; ++i) {
        const auto src = static_cast<Eigen::Index>(d - 1 - i);
        Eigen::VectorXd axis = solver.eigenvectors().col(src);
        // Sign convention: largest-magnitude entry positive, so results do not flip between runs.
        Eigen::Index arg;
        axis.cwiseAbs().maxCoeff(&arg);
        if (axis(arg) < 0) axis = -axis;
        t.components.row(static_cast<Eigen::Index>(i)) = axis.cast<float>().transpose();
        t.variances(static_cast<Eigen::Index>(i)) = static_cast<float>(ev(src));
    }
    return t;
}

void SaveTransform(const FeatureTransform& t, const std::filesystem::path& path) {
    ByteWriter w;
    w.Put<std::uint32_t>(static_cast<std::uint32_t>(t.kind));
    w.PutStrings(t.input_names);
    PutVectorXf(w, t.offset);
    PutVectorXf(w, t.scale);
    w.Put<std::uint64_t>(static_cast<std::uint64_t>(t.components.rows()));
    w.PutArray(t.components.data(), static_cast<std::size_t>(t.components.size()));
    PutVectorXf(w, t.variances);
    w.Put<std::uint8_t>(t.whiten ? 1 : 0);
    WriteContainer(path, kTransformMagic, kTransformFormatVersion, w.bytes());
}

FeatureTransform LoadTransform(const std::filesystem::path& path) {
    const auto payload = ReadContainer(path, kTransformMagic, kTransformFormatVersion, "transform");
    ByteReader r(payload, path.string());
    FeatureTransform t;
    const auto kind = r.Get<std::uint32_t>();
    if (kind > 2) r.Fail("unknown transform kind " + std::to_string(kind));
    t.kind = static_cast<TransformKind>(kind);
    t.input_names = r.GetStrings();
    t.offset = GetVectorXf(r);
    t.scale = GetVectorXf(r);
    const auto rows = r.Get<std::uint64_t>();
    const auto comp = r.GetVector<float>();
    const auto d = static_cast<std::uint64_t>(t.offset.size());
    // rows * d could wrap around (or be 0 with any rows when d is 0): compare by division.
    if (d == 0 ? rows != 0 || !comp.empty() : comp.size() % d != 0 || rows != comp.size() / d) {
        r.Fail("bad PCA component matrix size");
    }
    t.components = Eigen::Map<const Eigen::MatrixXf>(comp.data(), static_cast<Eigen::Index>(rows),
                                                     static_cast<Eigen::Index>(d));
    t.variances = GetVectorXf(r);
    t.whiten = r.Get<std::uint8_t>() != 0;
    if (!r.AtEnd()) r.Fail("trailing bytes in payload");
    if (t.input_names.size() != d) r.Fail("column names do not match the transform size");
    if (t.kind != TransformKind::kPca && static_cast<std::uint64_t>(t.scale.size()) != d) {
        r.Fail("scale vector does not match the transform size");
    }
    if (t.kind == TransformKind::kPca &&
        (rows == 0 || static_cast<std::uint64_t>(t.variances.size()) != rows)) {
        r.Fail("PCA components and variances do not match");
    }
    return t;
}

}  // namespace multicue::ml
