#include "multicue/ml/ensemble.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/dataset_tools.hpp"
#include "multicue/ml/serialization.hpp"

namespace multicue::ml {

namespace {

constexpr std::string_view kEnsembleMagic = "MCUEENSM";
const char* kRuleNames[] = {
    "max-accuracy",    "max-confidence",    "max-accuracy-confidence",    "product",
    "accuracy-voting", "confidence-voting", "accuracy-confidence-voting", "error-correlation",
    "stacking"};

void NormaliseRows(FeatureMatrix& m) {
    for (Eigen::Index r = 0; r < m.rows(); ++r) {
        auto row = m.row(r);
        row = row.cwiseMax(0.0f);
        const float s = row.sum();
        if (s > 0.0f && std::isfinite(s)) {
            row /= s;
        } else {
            row.setConstant(1.0f / static_cast<float>(m.cols()));
        }
    }
}

std::pair<int, float> Decision(const FeatureMatrix& p, Eigen::Index r) {
    Eigen::Index arg = 0;
    for (Eigen::Index c = 1; c < p.cols(); ++c) {
        if (p(r, c) > p(r, arg)) arg = c;
    }
    return {static_cast<int>(arg), p(r, arg)};
}

void CheckTables(const std::vector<FeatureMatrix>& conf) {
    if (conf.empty()) throw InvalidArgument("an ensemble needs at least one member");
    for (const auto& c : conf) {
        if (c.rows() != conf[0].rows() || c.cols() != conf[0].cols()) {
            throw InvalidArgument("member confidence tables have different shapes");
        }
    }
}

}  // namespace

std::string ToString(EnsembleRule rule) { return kRuleNames[static_cast<int>(rule)]; }

EnsembleRule ParseEnsembleRule(const std::string& name) {
    for (std::uint32_t i = 0; i < 9; ++i) {
        if (name == kRuleNames[i]) return static_cast<EnsembleRule>(i);
    }
    std::string known;
    for (const char* n : kRuleNames) {
        if (!known.empty()) known += ", ";
        known += n;
    }
    throw InvalidArgument("unknown ensemble rule '" + name + "' (" + known + ")");
}

std::vector<EnsembleRule> SimpleRules() {
    std::vector<EnsembleRule> r;
    for (std::uint32_t i = 0; i < 8; ++i) r.push_back(static_cast<EnsembleRule>(i));
    return r;
}

MemberStatistics EstimateMemberStatistics(const FeatureMatrix& confidences,
                                          const std::vector<int>& truth) {
    if (static_cast<std::size_t>(confidences.rows()) != truth.size()) {
        throw InvalidArgument("confidence rows and truth labels differ in number");
    }
    const auto k = static_cast<std::size_t>(confidences.cols());
    std::vector<double> decided(k, 0.0), right(k, 0.0);
    double n = 0.0, correct = 0.0;
    for (Eigen::Index r = 0; r < confidences.rows(); ++r) {
        const int t = truth[static_cast<std::size_t>(r)];
        if (t == kNoLabel) continue;
        const int d = Decision(confidences, r).first;
        decided[static_cast<std::size_t>(d)] += 1.0;
        n += 1.0;
        if (d == t) {
            right[static_cast<std::size_t>(d)] += 1.0;
            correct += 1.0;
        }
    }
    if (n == 0.0) throw DataError("member statistics need labelled validation rows");
    MemberStatistics s;
    s.accuracy = correct / n;
    s.class_accuracy.resize(k);
    for (std::size_t c = 0; c < k; ++c) {
        s.class_accuracy[c] = decided[c] > 0.0 ? right[c] / decided[c] : s.accuracy;
    }
    return s;
}

Eigen::VectorXd ErrorCorrelationWeights(const std::vector<FeatureMatrix>& confidences,
                                        const std::vector<int>& truth, double ridge) {
    CheckTables(confidences);
    const auto m = static_cast<Eigen::Index>(confidences.size());
    Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(m, m);
    double n = 0.0;
    for (Eigen::Index r = 0; r < confidences[0].rows(); ++r) {
        const int t = truth[static_cast<std::size_t>(r)];
        if (t == kNoLabel) continue;
        n += 1.0;
        Eigen::MatrixXd err(confidences[0].cols(), m);
        for (Eigen::Index i = 0; i < m; ++i) {
            err.col(i) = confidences[static_cast<std::size_t>(i)].row(r).transpose().cast<double>();
            err(t, i) -= 1.0;
        }
        cov += err.transpose() * err;
    }
    if (n == 0.0) throw DataError("error-correlation weights need labelled validation rows");
    cov /= n;
    const double scale = std::max(cov.diagonal().mean(), 1e-12);
    cov.diagonal().array() += ridge * scale;
    const Eigen::VectorXd ones = Eigen::VectorXd::Ones(m);
    const Eigen::VectorXd x = cov.ldlt().solve(ones);
    const double denom = ones.dot(x);
    if (!std::isfinite(denom) || std::abs(denom) < 1e-300) return ones / static_cast<double>(m);
    return x / denom;
}

FeatureMatrix CombineConfidences(EnsembleRule rule, const std::vector<FeatureMatrix>& conf,
                                 const std::vector<MemberStatistics>& stats,
                                 const Eigen::VectorXd& weights) {
    CheckTables(conf);
    const std::size_t m = conf.size();
    const Eigen::Index rows = conf[0].rows(), k = conf[0].cols();
    const bool needs_stats =
        rule == EnsembleRule::kMaxAccuracy || rule == EnsembleRule::kMaxAccuracyConfidence ||
        rule == EnsembleRule::kAccuracyVoting || rule == EnsembleRule::kAccuracyConfidenceVoting;
    if (needs_stats && stats.size() != m) {
        throw InvalidArgument("rule " + ToString(rule) + " needs statistics for every member");
    }
    for (const auto& s : stats) {
        if (needs_stats && s.class_accuracy.size() != static_cast<std::size_t>(k)) {
            throw InvalidArgument("member statistics have the wrong number of classes");
        }
    }
    if (rule == EnsembleRule::kErrorCorrelation && static_cast<std::size_t>(weights.size()) != m) {
        throw InvalidArgument("rule error-correlation needs one weight per member");
    }
    if (rule == EnsembleRule::kStacking) {
        throw InvalidArgument("stacking needs a level-1 classifier, not a combination rule");
    }
    FeatureMatrix out = FeatureMatrix::Zero(rows, k);
    for (Eigen::Index r = 0; r < rows; ++r) {
        switch (rule) {
            case EnsembleRule::kMaxAccuracy:
            case EnsembleRule::kMaxConfidence:
            case EnsembleRule::kMaxAccuracyConfidence: {
                // Section 3.3.1: the whole decision of the single best member.
                std::size_t best = 0;
                double best_score = -1.0;
                for (std::size_t i = 0; i < m; ++i) {
                    const auto [d, q] = Decision(conf[i], r);
                    double score = q;
                    if (rule == EnsembleRule::kMaxAccuracy)
                        score = stats[i].class_accuracy[static_cast<std::size_t>(d)];
                    if (rule == EnsembleRule::kMaxAccuracyConfidence)
                        score *= stats[i].class_accuracy[static_cast<std::size_t>(d)];
                    if (score > best_score) {
                        best_score = score;
                        best = i;
                    }
                }
                out.row(r) = conf[best].row(r);
                break;
            }
            case EnsembleRule::kProduct: {
                // In log space with a floor, so one zero does not veto a class outright.
                Eigen::ArrayXd logp = Eigen::ArrayXd::Zero(k);
                for (std::size_t i = 0; i < m; ++i) {
                    logp += conf[i].row(r).transpose().cast<double>().array().max(1e-12).log();
                }
                logp -= logp.maxCoeff();
                out.row(r) = logp.exp().cast<float>().matrix().transpose();
                break;
            }
            case EnsembleRule::kAccuracyVoting:
            case EnsembleRule::kConfidenceVoting:
            case EnsembleRule::kAccuracyConfidenceVoting: {
                // Section 3.3.2: each member votes for its decision with a weight.
                for (std::size_t i = 0; i < m; ++i) {
                    const auto [d, q] = Decision(conf[i], r);
                    double w = q;
                    if (rule == EnsembleRule::kAccuracyVoting) w = stats[i].accuracy;
                    if (rule == EnsembleRule::kAccuracyConfidenceVoting)
                        w = q * stats[i].class_accuracy[static_cast<std::size_t>(d)];
                    out(r, d) += static_cast<float>(w);
                }
                break;
            }
            case EnsembleRule::kErrorCorrelation:
                for (std::size_t i = 0; i < m; ++i) {
                    out.row(r) +=
                        static_cast<float>(weights(static_cast<Eigen::Index>(i))) * conf[i].row(r);
                }
                break;
            case EnsembleRule::kStacking:
                break;
        }
    }
    NormaliseRows(out);
    return out;
}

std::vector<std::vector<std::string>> FeatureSubsets(const std::vector<std::string>& blocks,
                                                     std::size_t min_size, std::size_t max_size) {
    if (min_size < 1 || min_size > max_size) {
        throw InvalidArgument("subset sizes must satisfy 1 <= min <= max, got " +
                              std::to_string(min_size) + ".." + std::to_string(max_size));
    }
    std::vector<std::vector<std::string>> out;
    const std::size_t n = blocks.size();
    for (std::size_t size = min_size; size <= std::min(max_size, n); ++size) {
        // Combinations in lexicographic order of positions.
        std::vector<std::size_t> idx(size);
        for (std::size_t i = 0; i < size; ++i) idx[i] = i;
        while (true) {
            std::vector<std::string> subset;
            for (std::size_t i : idx) subset.push_back(blocks[i]);
            out.push_back(std::move(subset));
            std::size_t i = size;
            while (i > 0 && idx[i - 1] == n - size + i - 1) --i;
            if (i == 0) break;
            ++idx[i - 1];
            for (std::size_t j = i; j < size; ++j) idx[j] = idx[j - 1] + 1;
        }
    }
    return out;
}

std::vector<FeatureMatrix> Ensemble::MemberConfidences(const Dataset& data) const {
    std::vector<FeatureMatrix> out;
    for (const auto& member : members) {
        out.push_back(member.classifier->PredictProba(SelectBlocks(data, member.blocks)));
    }
    return out;
}

Dataset Ensemble::Level1Dataset(const Dataset& data) const {
    const auto conf = MemberConfidences(data);
    Dataset out;
    for (std::size_t i = 0; i < members.size(); ++i) {
        Dataset part = ConfidencesToDataset(conf[i], class_names, data, members[i].name);
        out = i == 0 ? std::move(part) : ConcatColumns(out, part);
    }
    return out;
}

FeatureMatrix Ensemble::PredictProba(const Dataset& data) const { return PredictProba(data, rule); }

FeatureMatrix Ensemble::PredictProba(const Dataset& data, EnsembleRule with_rule) const {
    if (members.empty()) throw InvalidArgument("ensemble has no members");
    if (with_rule == EnsembleRule::kStacking) {
        if (!level1)
            throw InvalidArgument("this ensemble was trained without a level-1 classifier");
        return level1->PredictProba(Level1Dataset(data));
    }
    return CombineConfidences(with_rule, MemberConfidences(data), stats, weights);
}

std::vector<int> Ensemble::Predict(const Dataset& data) const {
    return ArgMaxRows(PredictProba(data));
}

Ensemble TrainEnsemble(const Dataset& level0_train, const Dataset& level1_train,
                       const EnsembleParams& params, Progress* progress) {
    // The split of section 3.3.4: level 1 must see only rows the members were not trained on.
    const std::unordered_set<std::int64_t> ids0(level0_train.row_ids.begin(),
                                                level0_train.row_ids.end());
    for (auto id : level1_train.row_ids) {
        if (ids0.count(id)) {
            throw DataError("level-1 training rows overlap the level-0 training rows (row id " +
                            std::to_string(id) + "); use a three-way split");
        }
    }
    if (level1_train.empty()) throw DataError("the level-1 training part is empty");
    auto subsets = params.subsets;
    if (subsets.empty()) subsets = FeatureSubsets(level0_train.BlockNames(), 1, 1);
    CreateClassifier(params.member_spec);  // spec errors before training
    if (!params.level1_spec.empty()) CreateClassifier(params.level1_spec);

    Ensemble e;
    e.rule = params.level1_spec.empty() ? EnsembleRule::kAccuracyConfidenceVoting
                                        : EnsembleRule::kStacking;
    for (const auto& subset : subsets) {
        EnsembleMember member;
        for (const auto& b : subset) {
            if (!member.name.empty()) member.name += '+';
            member.name += b;
        }
        member.blocks = subset;
        member.classifier = CreateClassifier(params.member_spec);
        member.classifier->seed = params.seed;
        member.classifier->Fit(SelectBlocks(level0_train, subset));
        if (!e.members.empty() && member.classifier->class_names() != e.class_names) {
            throw DataError("ensemble members disagree on the classes");
        }
        e.class_names = member.classifier->class_names();
        e.members.push_back(std::move(member));
        if (progress != nullptr) progress->Advance();
    }
    const auto truth = MapLabels(level1_train, e.class_names);
    const auto conf = e.MemberConfidences(level1_train);
    for (const auto& c : conf) e.stats.push_back(EstimateMemberStatistics(c, truth));
    e.weights = ErrorCorrelationWeights(conf, truth);
    e.level1_row_ids = level1_train.row_ids;
    if (!params.level1_spec.empty()) {
        e.level1 = CreateClassifier(params.level1_spec);
        e.level1->seed = params.seed;
        e.level1->Fit(e.Level1Dataset(level1_train));
    }
    if (progress != nullptr) progress->Advance();
    return e;
}

void Ensemble::Save(const std::filesystem::path& path) const {
    if (members.empty()) throw InvalidArgument("cannot save an ensemble without members");
    ByteWriter w;
    w.Put<std::uint32_t>(static_cast<std::uint32_t>(rule));
    w.PutStrings(class_names);
    w.Put<std::uint64_t>(members.size());
    for (std::size_t i = 0; i < members.size(); ++i) {
        w.PutString(members[i].name);
        w.PutStrings(members[i].blocks);
        w.PutString(members[i].classifier->Serialize());
        w.Put<double>(stats[i].accuracy);
        w.PutVector(stats[i].class_accuracy);
    }
    w.PutArray(weights.data(), static_cast<std::size_t>(weights.size()));
    w.PutVector(level1_row_ids);
    w.Put<std::uint8_t>(level1 ? 1 : 0);
    if (level1) w.PutString(level1->Serialize());
    WriteContainer(path, kEnsembleMagic, kEnsembleFormatVersion, w.bytes());
}

Ensemble Ensemble::Load(const std::filesystem::path& path) {
    const auto payload = ReadContainer(path, kEnsembleMagic, kEnsembleFormatVersion, "ensemble");
    ByteReader r(payload, path.string());
    Ensemble e;
    const auto rule = r.Get<std::uint32_t>();
    if (rule > 8) r.Fail("unknown ensemble rule");
    e.rule = static_cast<EnsembleRule>(rule);
    e.class_names = r.GetStrings();
    const auto n = r.Get<std::uint64_t>();
    if (n == 0 || n > payload.size()) r.Fail("bad member count");
    for (std::uint64_t i = 0; i < n; ++i) {
        EnsembleMember m;
        m.name = r.GetString();
        m.blocks = r.GetStrings();
        m.classifier = DeserializeClassifier(r.GetString(), path.string() + " member " + m.name);
        if (m.classifier->class_names() != e.class_names) r.Fail("member classes differ");
        MemberStatistics s;
        s.accuracy = r.Get<double>();
        s.class_accuracy = r.GetVector<double>();
        if (s.class_accuracy.size() != e.class_names.size()) r.Fail("bad member statistics");
        e.members.push_back(std::move(m));
        e.stats.push_back(std::move(s));
    }
    const auto w = r.GetVector<double>();
    if (w.size() != n) r.Fail("bad weight count");
    e.weights = Eigen::Map<const Eigen::VectorXd>(w.data(), static_cast<Eigen::Index>(w.size()));
    e.level1_row_ids = r.GetVector<std::int64_t>();
    if (r.Get<std::uint8_t>() != 0)
        e.level1 = DeserializeClassifier(r.GetString(), path.string() + " level 1");
    if (!r.AtEnd()) r.Fail("trailing bytes in payload");
    if (e.rule == EnsembleRule::kStacking && !e.level1) r.Fail("stacking without level-1 model");
    return e;
}

}  // namespace multicue::ml
