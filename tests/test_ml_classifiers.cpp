// Classifiers behind one interface: accuracy on separable data, save/load, determinism, bad input.

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "ml_test_data.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/dataset_tools.hpp"
#include "multicue/ml/evaluation.hpp"
#include "multicue/ml/knn.hpp"
#include "multicue/ml/serialization.hpp"
#include "multicue/ml/split.hpp"
#include "multicue/ml/svm.hpp"
#include "test_util.hpp"

namespace multicue::ml {
namespace {

struct Case {
    const char* spec;
    double min_accuracy;
};

class MlClassifier : public ::testing::TestWithParam<Case> {};

TEST_P(MlClassifier, LearnsBlobsAndRoundTripsSaveLoad) {
    test::TempDir dir;
    const Dataset d = test::Blobs(4, 8, 4, 8, 0.4f, 21);
    const auto split = GroupSplit(d, 0.25, 2);
    const Dataset train = SelectRows(d, split.train), test = SelectRows(d, split.test);
    auto c = CreateClassifier(GetParam().spec);
    c->Fit(train);
    const auto eval = Evaluate(*c, test);
    EXPECT_GE(eval.accuracy, GetParam().min_accuracy) << GetParam().spec << "\n"
                                                      << eval.confusion.ToText();
    const FeatureMatrix p = c->PredictProba(test);
    ASSERT_EQ(p.rows(), static_cast<Eigen::Index>(test.rows()));
    ASSERT_EQ(p.cols(), 4);
    for (Eigen::Index r = 0; r < p.rows(); ++r) {
        EXPECT_NEAR(p.row(r).sum(), 1.0f, 1e-5f);
        EXPECT_GE(p.row(r).minCoeff(), 0.0f);
    }
    c->Save(dir / "m.mcm");
    const auto loaded = LoadClassifier(dir / "m.mcm");
    EXPECT_EQ(loaded->type(), c->type());
    EXPECT_EQ(loaded->class_names(), c->class_names());
    const FeatureMatrix q = loaded->PredictProba(test);
    EXPECT_TRUE(p.isApprox(q, 1e-6f) || p == q) << GetParam().spec;
    EXPECT_EQ(loaded->Predict(test), c->Predict(test));

    // Same seed, same model.
    auto again = CreateClassifier(GetParam().spec);
    again->Fit(train);
    EXPECT_EQ(again->PredictProba(test), p) << GetParam().spec;
}

INSTANTIATE_TEST_SUITE_P(
    AllTypes, MlClassifier,
    ::testing::Values(Case{"knn:k=5,metric=l1", 0.95}, Case{"knn:k=5,metric=l2", 0.95},
                      Case{"knn:k=5,metric=hellinger", 0.95}, Case{"knn:k=5,metric=chi2", 0.95},
                      Case{"knn:k=5,metric=jm,weighted=1", 0.9},
                      Case{"svm:kernel=linear,C=1", 0.95}, Case{"svm:kernel=rbf", 0.95},
                      Case{"svm:kernel=rbf,grid=1,grid_C=1:10,grid_gamma=0.01:0.1,folds=3", 0.95},
                      Case{"svm:kernel=rbf,probability=0", 0.95},
                      Case{"boost:type=real,weak=50", 0.9}, Case{"boost:type=gentle,weak=50", 0.9},
                      Case{"boost:type=logit,weak=50", 0.9},
                      Case{"boost:type=discrete,weak=50", 0.9},
                      Case{"mlp:hidden=16,iterations=200", 0.9}, Case{"rtrees:trees=50", 0.9}),
    [](const auto& param_info) {
        std::string n = param_info.param.spec;
        for (auto& ch : n) {
            if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
        }
        return n;
    });

// Oracle: every metric's neighbours equal a direct computation of its formula, for the k-d tree
// and the brute-force scan alike.
// Two informative columns in metres and one of noise in millimetres (values 1000 times larger):
// the classifiers whose result depends on units learn it only with their inputs scaled, which
// `auto` does inside the model; the scaling survives save and load, and version 1 files (no
// scaling) are still read.
TEST(MlScaling, UnitDependentClassifiersScaleTheirInputsInsideTheModel) {
    std::mt19937 rng(3);
    std::normal_distribution<float> n(0.0f, 1.0f);
    auto make = [&](int rows) {
        Dataset d = Dataset::WithBlocks({{"f", {"a", "b", "noise_mm"}}});
        for (int r = 0; r < rows; ++r) {
            const int c = r % 2;
            const std::vector<float> row{(c == 0 ? -0.3f : 0.3f) + 0.1f * n(rng), 0.1f * n(rng),
                                         1000.0f * n(rng)};
            d.AppendRow(row, c == 0 ? "left" : "right");
        }
        return d;
    };
    const Dataset train = make(100), test = make(100);
    auto accuracy = [&](const Classifier& c) {
        const auto pred = c.Predict(test);
        int ok = 0;
        for (std::size_t r = 0; r < pred.size(); ++r) ok += pred[r] == test.labels[r] ? 1 : 0;
        return static_cast<double>(ok) / static_cast<double>(pred.size());
    };
    for (const char* spec : {"svm:kernel=rbf,probability=0", "knn:k=5"}) {
        auto scaled = CreateClassifier(spec);
        scaled->Fit(train);
        EXPECT_TRUE(scaled->scales_input()) << spec;
        EXPECT_GT(accuracy(*scaled), 0.9) << spec;
        if (std::string(spec).starts_with("knn")) {  // (an unscaled SVM takes long to fail)
            auto raw = CreateClassifier(std::string(spec) + ",scale=none");
            raw->Fit(train);
            EXPECT_FALSE(raw->scales_input());
            EXPECT_LT(accuracy(*raw), 0.8) << spec << " learns the units without scaling";
        }
        const auto loaded = DeserializeClassifier(scaled->Serialize(), "model");
        EXPECT_TRUE(loaded->scales_input());
        EXPECT_EQ(loaded->PredictProba(test), scaled->PredictProba(test)) << spec;
    }
    // A version 1 file (before scaling: no scaling block after the columns) reads as unscaled.
    auto raw = CreateClassifier("knn:k=5,scale=none");
    raw->Fit(train);
    const std::string v2 = UnwrapContainer(raw->Serialize(), "MCUEMODL", kModelFormatVersion,
                                           "classifier model", "v2");
    ByteWriter head;
    head.PutString(raw->type());
    head.PutString(raw->spec());
    head.Put<std::uint32_t>(raw->seed);
    head.PutStrings(raw->class_names());
    head.PutStrings(raw->feature_names());
    const std::size_t at = head.bytes().size();
    const std::size_t block = 1 + 8 + 8;  // mode, two empty arrays
    const std::string v1 = WrapContainer("MCUEMODL", 1, v2.substr(0, at) + v2.substr(at + block));
    EXPECT_EQ(ContainerVersion(v1), 1u);
    const auto old = DeserializeClassifier(v1, "v1");
    EXPECT_FALSE(old->scales_input());
    EXPECT_EQ(old->PredictProba(test), raw->PredictProba(test));
    // Unit-free classifiers are left alone unless asked.
    auto trees = CreateClassifier("rtrees:trees=10");
    trees->Fit(train);
    EXPECT_FALSE(trees->scales_input());
    EXPECT_FALSE(CreateClassifier("svm:kernel=linear")->scaling != InputScaling::kAuto);
    auto asked = CreateClassifier("rtrees:trees=10,scale=zscore");
    asked->Fit(train);
    EXPECT_TRUE(asked->scales_input());
    EXPECT_THROW(CreateClassifier("knn:scale=minmax"), InvalidArgument);
}

TEST(MlKnn, NeighboursMatchDirectFormulas) {
    const Dataset d = test::Blobs(3, 20, 10, 6, 1.0f, 5);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.0f, 5.0f);
    for (auto metric : {KnnMetric::kL1, KnnMetric::kL2, KnnMetric::kHellinger, KnnMetric::kChi2,
                        KnnMetric::kJm}) {
        for (auto index : {KnnIndex::kAuto, KnnIndex::kKdTree, KnnIndex::kBrute}) {
            if (index == KnnIndex::kKdTree && metric != KnnMetric::kL2 &&
                metric != KnnMetric::kHellinger) {
                continue;
            }
            KnnClassifier knn({.k = 7, .metric = metric, .index = index, .leaf_size = 4});
            knn.Fit(d);
            for (int trial = 0; trial < 20; ++trial) {
                std::vector<float> q(6);
                for (auto& v : q) v = u(rng);
                std::vector<std::pair<double, std::uint32_t>> all;
                double sq = 0.0;
                for (float v : q) sq += v;
                for (std::size_t r = 0; r < d.rows(); ++r) {
                    const auto row = d.row(r);
                    double s = 0.0, sr = 0.0;
                    for (float v : row) sr += v;
                    for (std::size_t j = 0; j < 6; ++j) {
                        const double a = row[j], b = q[j];
                        switch (metric) {
                            case KnnMetric::kL1:
                                s += std::abs(a - b);
                                break;
                            case KnnMetric::kL2:
                                s += (a - b) * (a - b);
                                break;
                            case KnnMetric::kHellinger:
                                s += std::pow(std::sqrt(a) - std::sqrt(b), 2);
                                break;
                            case KnnMetric::kChi2:
                                s += a + b > 0 ? (a - b) * (a - b) / (a + b) : 0.0;
                                break;
                            case KnnMetric::kJm:
                                s += std::sqrt(a / sr * b / sq);
                                break;
                        }
                    }
                    if (metric == KnnMetric::kL2 || metric == KnnMetric::kHellinger)
                        s = std::sqrt(s);
                    if (metric == KnnMetric::kJm) s = std::sqrt(std::max(0.0, 2.0 * (1.0 - s)));
                    all.push_back({s, static_cast<std::uint32_t>(r)});
                }
                std::sort(all.begin(), all.end());
                const auto nb = knn.Neighbours(q);
                ASSERT_EQ(nb.size(), 7u);
                for (std::size_t i = 0; i < nb.size(); ++i) {
                    EXPECT_NEAR(nb[i].distance, all[i].first, 1e-3 * (1.0 + all[i].first))
                        << ToString(metric) << " neighbour " << i;
                }
            }
        }
    }
}

TEST(MlKnn, ParallelAndSerialPredictionsAgree) {
    const Dataset d = test::Blobs(3, 10, 20, 6, 1.0f, 8);
    const Dataset q = test::Blobs(3, 4, 20, 6, 1.0f, 9);
    KnnClassifier serial({.k = 4, .metric = KnnMetric::kChi2, .num_threads = 1});
    KnnClassifier parallel({.k = 4, .metric = KnnMetric::kChi2, .num_threads = 2});
    serial.Fit(d);
    parallel.Fit(d);
    EXPECT_EQ(serial.PredictProba(q), parallel.PredictProba(q));
}

TEST(MlKnn, HistogramMetricsRefuseNegativeFeatures) {
    Dataset d = Dataset::WithColumns(2);
    d.AppendRow(std::vector<float>{-1, 0}, "a");
    d.AppendRow(std::vector<float>{1, 0}, "b");
    EXPECT_THROW(CreateClassifier("knn:metric=chi2")->Fit(d), DataError);
    EXPECT_NO_THROW(CreateClassifier("knn:metric=l1,k=1")->Fit(d));
}

TEST(MlClassifierContract, BadInputGivesClearErrors) {
    test::TempDir dir;
    const Dataset d = test::Blobs(3, 4, 2, 4, 0.3f);
    auto c = CreateClassifier("knn:k=3");
    EXPECT_THROW(c->PredictProba(d), InvalidArgument);  // not trained
    EXPECT_THROW(c->Save(dir / "x.mcm"), InvalidArgument);
    c->Fit(d);
    EXPECT_THROW(c->PredictProba(FeatureMatrix::Zero(2, 5)), InvalidArgument);
    FeatureMatrix bad = FeatureMatrix::Ones(2, 4);
    bad(1, 2) = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(c->PredictProba(bad), DataError);
    bad(1, 2) = std::numeric_limits<float>::infinity();
    EXPECT_THROW(c->PredictProba(bad), DataError);
    // Same column count, other names: refused for datasets.
    Dataset renamed = d;
    renamed.feature_names[0] = "other";
    EXPECT_THROW(c->PredictProba(renamed), InvalidArgument);
    // A label the classifier never saw.
    Dataset unseen = d;
    unseen.class_names[0] = "never/seen";
    EXPECT_THROW(Evaluate(*c, unseen), DataError);
    // Training input.
    Dataset one_class = SelectRows(d, {0, 1});
    one_class.labels = {0, 0};
    EXPECT_THROW(CreateClassifier("knn")->Fit(one_class), DataError);
    EXPECT_THROW(CreateClassifier("knn")->Fit(Dataset::WithColumns(2)), DataError);
    Dataset unlabelled = d;
    unlabelled.labels[0] = kNoLabel;
    EXPECT_THROW(CreateClassifier("knn")->Fit(unlabelled), DataError);
    // Specs.
    EXPECT_THROW(CreateClassifier("tree"), InvalidArgument);
    EXPECT_THROW(CreateClassifier("knn:k=0"), InvalidArgument);
    EXPECT_THROW(CreateClassifier("knn:metric=cosine"), InvalidArgument);
    EXPECT_THROW(CreateClassifier("svm:C=-1"), InvalidArgument);
    EXPECT_THROW(CreateClassifier("boost:kind=real"), InvalidArgument);
    EXPECT_THROW(CreateClassifier("knn:index=kdtree,metric=l1"), InvalidArgument);

    // Model files: another version and corruption are refused.
    c->Save(dir / "m.mcm");
    std::string bytes = ReadBytes(dir / "m.mcm");
    std::string v9 = bytes;
    v9[8] = 9;
    WriteBytesAtomically(dir / "v9.mcm", v9);
    try {
        LoadClassifier(dir / "v9.mcm");
        FAIL();
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("version 9"), std::string::npos) << e.what();
    }
    std::string corrupt = bytes;
    corrupt[corrupt.size() / 2] ^= 0x55;
    WriteBytesAtomically(dir / "bad.mcm", corrupt);
    EXPECT_THROW(LoadClassifier(dir / "bad.mcm"), FormatError);
    EXPECT_THROW(LoadClassifier(dir / "none.mcm"), IoError);
}

TEST(MlCrossValidation, KFoldAccuracyAndPooledConfusion) {
    const Dataset d = test::Blobs(3, 6, 3, 5, 0.3f, 4);
    const auto cv = CrossValidate("knn:k=3", d, 3, 1, true);
    ASSERT_EQ(cv.fold_accuracy.size(), 3u);
    EXPECT_GE(cv.mean_accuracy, 0.95);
    EXPECT_EQ(cv.confusion.total(), d.rows());
}

TEST(MlSvm, GridSearchReportsEveryPoint) {
    const Dataset d = test::Blobs(3, 6, 3, 5, 0.3f, 4);
    SvmParams p;
    p.grid_search = true;
    p.grid_c = {0.1, 10};
    p.grid_gamma = {0.01, 1};
    p.folds = 3;
    SvmClassifier svm(p);
    svm.Fit(d);
    EXPECT_EQ(svm.grid().size(), 4u);
    const auto best = std::max_element(svm.grid().begin(), svm.grid().end(),
                                       [](auto& a, auto& b) { return a.accuracy < b.accuracy; });
    EXPECT_EQ(svm.trained_c(), best->c);
}

}  // namespace
}  // namespace multicue::ml
