// Ensemble rules on hand-computed confidence tables, error-correlation weights, stacking with a
// three-way split (section 3.3).

#include <set>

#include <gtest/gtest.h>

#include "ml_test_data.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/ml/dataset_tools.hpp"
#include "multicue/ml/ensemble.hpp"
#include "multicue/ml/evaluation.hpp"
#include "multicue/ml/serialization.hpp"
#include "multicue/ml/split.hpp"
#include "test_util.hpp"

namespace multicue::ml {
namespace {

FeatureMatrix Table(std::initializer_list<std::initializer_list<float>> rows) {
    FeatureMatrix m(static_cast<Eigen::Index>(rows.size()),
                    static_cast<Eigen::Index>(rows.begin()->size()));
    Eigen::Index r = 0;
    for (const auto& row : rows) {
        Eigen::Index c = 0;
        for (float v : row) m(r, c++) = v;
        ++r;
    }
    return m;
}

class MlEnsembleRules : public ::testing::Test {
  protected:
    // Member A: rows decide 0 (0.6) and 1 (0.8); member B: 1 (0.7) and 1 (0.55).
    std::vector<FeatureMatrix> conf = {Table({{0.6f, 0.4f}, {0.2f, 0.8f}}),
                                       Table({{0.3f, 0.7f}, {0.45f, 0.55f}})};
    std::vector<MemberStatistics> stats = {{0.9, {0.9, 0.5}}, {0.6, {0.4, 0.7}}};

    void Expect(EnsembleRule rule, const FeatureMatrix& expected,
                const Eigen::VectorXd& weights = {}) {
        const FeatureMatrix got = CombineConfidences(rule, conf, stats, weights);
        EXPECT_TRUE(got.isApprox(expected, 1e-5f)) << ToString(rule) << "\n" << got;
    }
};

TEST_F(MlEnsembleRules, MaxRules) {
    // Row 0: a_A(0) = 0.9 > a_B(1) = 0.7 -> A; row 1: a_A(1) = 0.5 < a_B(1) = 0.7 -> B.
    Expect(EnsembleRule::kMaxAccuracy, Table({{0.6f, 0.4f}, {0.45f, 0.55f}}));
    // Row 0: 0.7 > 0.6 -> B; row 1: 0.8 > 0.55 -> A.
    Expect(EnsembleRule::kMaxConfidence, Table({{0.3f, 0.7f}, {0.2f, 0.8f}}));
    // Row 0: 0.54 vs 0.49 -> A; row 1: 0.40 vs 0.385 -> A.
    Expect(EnsembleRule::kMaxAccuracyConfidence, Table({{0.6f, 0.4f}, {0.2f, 0.8f}}));
}

TEST_F(MlEnsembleRules, ProductRule) {
    // Row 0: (0.18, 0.28) / 0.46; row 1: (0.09, 0.44) / 0.53.
    Expect(EnsembleRule::kProduct,
           Table({{0.18f / 0.46f, 0.28f / 0.46f}, {0.09f / 0.53f, 0.44f / 0.53f}}));
}

TEST_F(MlEnsembleRules, WeightedVoting) {
    // Accuracy: row 0 -> (0.9, 0.6) / 1.5; row 1 -> both vote 1.
    Expect(EnsembleRule::kAccuracyVoting, Table({{0.6f, 0.4f}, {0.0f, 1.0f}}));
    // Confidence: row 0 -> (0.6, 0.7) / 1.3.
    Expect(EnsembleRule::kConfidenceVoting, Table({{0.6f / 1.3f, 0.7f / 1.3f}, {0.0f, 1.0f}}));
    // Class-conditional accuracy x confidence: row 0 -> (0.54, 0.49) / 1.03.
    Expect(EnsembleRule::kAccuracyConfidenceVoting,
           Table({{0.54f / 1.03f, 0.49f / 1.03f}, {0.0f, 1.0f}}));
}

TEST_F(MlEnsembleRules, ErrorCorrelationCombination) {
    Eigen::VectorXd w(2);
    w << 0.25, 0.75;
    Expect(EnsembleRule::kErrorCorrelation, Table({{0.375f, 0.625f}, {0.3875f, 0.6125f}}), w);
    EXPECT_THROW(CombineConfidences(EnsembleRule::kErrorCorrelation, conf, stats), InvalidArgument);
    EXPECT_THROW(CombineConfidences(EnsembleRule::kMaxAccuracy, conf, {}), InvalidArgument);
    EXPECT_THROW(CombineConfidences(EnsembleRule::kProduct, {conf[0], Table({{1.0f, 0.0f}})}, {}),
                 InvalidArgument);
}

TEST(MlEnsemble, MemberStatisticsAreClassConditional) {
    const auto s = EstimateMemberStatistics(
        Table({{0.9f, 0.1f}, {0.8f, 0.2f}, {0.1f, 0.9f}, {0.3f, 0.7f}, {0.4f, 0.6f}}),
        {0, 1, 1, 1, 0});
    EXPECT_DOUBLE_EQ(s.accuracy, 0.6);
    EXPECT_DOUBLE_EQ(s.class_accuracy[0], 0.5);
    EXPECT_DOUBLE_EQ(s.class_accuracy[1], 2.0 / 3.0);
}

TEST(MlEnsemble, ErrorCorrelationWeightsMatchTheClosedForm) {
    // Truth (0, 1, 0). Errors e = p - onehot; C_ij = mean over rows of e_i . e_j.
    const std::vector<int> truth = {0, 1, 0};
    const std::vector<FeatureMatrix> conf = {Table({{0.8f, 0.2f}, {0.4f, 0.6f}, {0.9f, 0.1f}}),
                                             Table({{0.5f, 0.5f}, {0.1f, 0.9f}, {0.3f, 0.7f}})};
    Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
    for (int r = 0; r < 3; ++r) {
        Eigen::Vector2d ea, eb;
        ea << conf[0](r, 0) - (truth[r] == 0), conf[0](r, 1) - (truth[r] == 1);
        eb << conf[1](r, 0) - (truth[r] == 0), conf[1](r, 1) - (truth[r] == 1);
        c(0, 0) += ea.dot(ea) / 3;
        c(0, 1) += ea.dot(eb) / 3;
        c(1, 1) += eb.dot(eb) / 3;
    }
    c(1, 0) = c(0, 1);
    const Eigen::Vector2d x = c.inverse() * Eigen::Vector2d::Ones();
    const Eigen::Vector2d expected = x / x.sum();
    const Eigen::VectorXd w = ErrorCorrelationWeights(conf, truth, 0.0);
    EXPECT_NEAR(w(0), expected(0), 1e-5);
    EXPECT_NEAR(w(1), expected(1), 1e-5);
    EXPECT_NEAR(w.sum(), 1.0, 1e-9);
}

TEST(MlEnsemble, SinglesDoublesTriples) {
    const auto s = FeatureSubsets({"a", "b", "c"}, 1, 3);
    const std::vector<std::vector<std::string>> expected = {
        {"a"}, {"b"}, {"c"}, {"a", "b"}, {"a", "c"}, {"b", "c"}, {"a", "b", "c"}};
    EXPECT_EQ(s, expected);
    EXPECT_EQ(FeatureSubsets({"a", "b", "c", "d"}, 2, 2).size(), 6u);
    EXPECT_THROW(FeatureSubsets({"a"}, 0, 1), InvalidArgument);
}

TEST(MlEnsemble, StackingNeverTrainsLevelOneOnLevelZeroRows) {
    const Dataset d = test::Blobs(3, 8, 2, 6, 0.8f, 13, 2);
    const auto split = SplitThreeWay(d);
    const Dataset l0 = SelectRows(d, split.level0_train), l1 = SelectRows(d, split.level1_train);
    EnsembleParams p{.member_spec = "knn:k=3", .subsets = {}, .level1_spec = "knn:k=3"};
    // Overlapping parts are refused.
    EXPECT_THROW(TrainEnsemble(l0, d, p), DataError);
    EXPECT_THROW(TrainEnsemble(l0, l0, p), DataError);
    const Ensemble e = TrainEnsemble(l0, l1, p);
    EXPECT_EQ(e.level1_row_ids, l1.row_ids);
    const std::set<std::int64_t> ids0(l0.row_ids.begin(), l0.row_ids.end());
    for (auto id : e.level1_row_ids) EXPECT_FALSE(ids0.count(id));
    EXPECT_EQ(e.members.size(), 3u);
}

TEST(MlEnsemble, TrainsEvaluatesAndRoundTripsEveryRule) {
    test::TempDir dir;
    const Dataset d = test::Blobs(4, 8, 2, 6, 0.5f, 17, 2);
    const auto split = SplitThreeWay(d);
    const Dataset l0 = SelectRows(d, split.level0_train), l1 = SelectRows(d, split.level1_train),
                  test = SelectRows(d, split.test);
    // Blobs spread alike in every column: nothing for input scaling to correct.
    EnsembleParams p{.member_spec = "knn:k=5,scale=none",
                     .subsets = FeatureSubsets(d.BlockNames(), 1, 2),
                     .level1_spec = "svm:kernel=linear"};
    const Ensemble e = TrainEnsemble(l0, l1, p);
    EXPECT_EQ(e.members.size(), 6u);
    e.Save(dir / "e.mce");
    const Ensemble loaded = Ensemble::Load(dir / "e.mce");
    const auto truth = MapLabels(test, e.class_names);
    auto rules = SimpleRules();
    rules.push_back(EnsembleRule::kStacking);
    for (auto rule : rules) {
        const FeatureMatrix p1 = e.PredictProba(test, rule);
        EXPECT_EQ(p1, loaded.PredictProba(test, rule)) << ToString(rule);
        EXPECT_GE(Accuracy(truth, ArgMaxRows(p1)), 0.85) << ToString(rule);
    }
    // Another version or a corrupt file is refused.
    std::string bytes = ReadBytes(dir / "e.mce");
    bytes[bytes.size() / 3] ^= 1;
    WriteBytesAtomically(dir / "bad.mce", bytes);
    EXPECT_THROW(Ensemble::Load(dir / "bad.mce"), FormatError);
    EXPECT_THROW(e.PredictProba(SelectBlocks(test, {"b0"})), InvalidArgument);
}

}  // namespace
}  // namespace multicue::ml
