// Datasets: formats, tools, splits, transforms, k-means, bag of words (section 3.1.4).

#include <cmath>
#include <fstream>
#include <limits>
#include <set>

#include <gtest/gtest.h>

#include "ml_test_data.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/ml/dataset_tools.hpp"
#include "multicue/ml/evaluation.hpp"
#include "multicue/ml/kmeans.hpp"
#include "multicue/ml/serialization.hpp"
#include "multicue/ml/split.hpp"
#include "multicue/ml/transform.hpp"
#include "test_util.hpp"

namespace multicue::ml {
namespace {

void ExpectSame(const Dataset& a, const Dataset& b) {
    EXPECT_EQ(a.values, b.values);
    EXPECT_EQ(a.feature_names, b.feature_names);
    EXPECT_EQ(a.BlockNames(), b.BlockNames());
    EXPECT_EQ(a.class_names, b.class_names);
    EXPECT_EQ(a.labels, b.labels);
    EXPECT_EQ(a.groups, b.groups);
    EXPECT_EQ(a.views, b.views);
    EXPECT_EQ(a.row_ids, b.row_ids);
    EXPECT_EQ(a.sources, b.sources);
}

TEST(MlDataset, BinaryAndCsvRoundTrip) {
    test::TempDir dir;
    Dataset d = test::Blobs(3, 2, 2, 6, 0.5f, 1, 3);
    d.AppendRow(std::vector<float>(6, 0.25f), "", -1, -1, "with,comma \"quoted\"");
    SaveDataset(d, dir / "a.mcd");
    ExpectSame(d, LoadDataset(dir / "a.mcd"));
    SaveCsv(d, dir / "a.csv");
    ExpectSame(d, LoadCsv(dir / "a.csv"));
    ExpectSame(d, ReadDatasetFile(dir / "a.csv"));
}

TEST(MlDataset, RefusesOtherVersionCorruptAndTruncatedFiles) {
    test::TempDir dir;
    const Dataset d = test::Blobs(2, 2, 1, 4, 0.5f);
    SaveDataset(d, dir / "a.mcd");
    std::string bytes = ReadBytes(dir / "a.mcd");
    auto write = [&](const std::string& b) { WriteBytesAtomically(dir / "b.mcd", b); };
    auto message = [&] {
        try {
            LoadDataset(dir / "b.mcd");
        } catch (const FormatError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    std::string v2 = bytes;
    v2[8] = 2;
    write(v2);
    EXPECT_NE(message().find("version 2 is not supported"), std::string::npos) << message();
    std::string flipped = bytes;
    flipped[bytes.size() - 5] ^= 0x10;
    write(flipped);
    EXPECT_NE(message().find("checksum"), std::string::npos) << message();
    write(bytes.substr(0, bytes.size() - 7));
    EXPECT_NE(message().find("truncated"), std::string::npos) << message();
    write("not a dataset at all");
    EXPECT_NE(message().find("bad magic"), std::string::npos) << message();
    EXPECT_THROW(LoadDataset(dir / "missing.mcd"), IoError);
}

TEST(MlDataset, CsvErrorsNameTheLine) {
    test::TempDir dir;
    { std::ofstream(dir / "bad.csv") << "label,a,b\nx,1,2\ny,1\n"; }
    try {
        LoadCsv(dir / "bad.csv");
        FAIL();
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.csv:3"), std::string::npos) << e.what();
    }
    { std::ofstream(dir / "nan.csv") << "label,a\nx,nan\n"; }
    EXPECT_THROW(LoadCsv(dir / "nan.csv"), DataError);
}

TEST(MlDataset, AppendRowChecksAndResumeBySource) {
    Dataset d = Dataset::WithColumns(3);
    d.AppendRow(std::vector<float>{1, 2, 3}, "a/b", 0, 0, "f1.pcd");
    EXPECT_THROW(d.AppendRow(std::vector<float>{1, 2}, "a"), InvalidArgument);
    EXPECT_THROW(d.AppendRow(std::vector<float>{1, NAN, 3}, "a"), DataError);
    EXPECT_EQ(d.rows(), 1u);
    EXPECT_TRUE(d.Sources().count("f1.pcd"));
    EXPECT_EQ(LabelPathFromFile("/data", "/data/cylinder/mug/scan1.pcd"), "cylinder/mug");
    EXPECT_THROW(LabelPathFromFile("/data", "/other/x.pcd"), InvalidArgument);
    EXPECT_EQ(TruncateLabelPath("cylinder/mug/red", 1), "cylinder");
    EXPECT_EQ(TruncateLabelPath("cylinder/mug/red", 2), "cylinder/mug");
    EXPECT_EQ(TruncateLabelPath("box", 2), "box");
}

// How an extraction tool resumes: load the partial file, skip sources already present, append,
// save; the result equals an uninterrupted run.
TEST(MlDataset, ResumedAppendingEqualsOneRun) {
    test::TempDir dir;
    const std::vector<std::string> files = {"box/a.pcd", "box/b.pcd", "cylinder/mug/c.pcd",
                                            "cylinder/mug/d.pcd"};
    auto extract = [&](Dataset& d, std::size_t upto) {
        const auto done = d.Sources();
        for (std::size_t i = 0; i < upto; ++i) {
            if (done.count(files[i])) continue;
            const float v = static_cast<float>(i);
            d.AppendRow(std::vector<float>{v, 2 * v}, LabelPathFromFile("", files[i]),
                        static_cast<std::int64_t>(i / 2), static_cast<std::int64_t>(i % 2),
                        files[i]);
        }
    };
    Dataset full = Dataset::WithColumns(2);
    extract(full, files.size());
    Dataset part = Dataset::WithColumns(2);
    extract(part, 2);
    SaveDataset(part, dir / "part.mcd");
    Dataset resumed = LoadDataset(dir / "part.mcd");
    extract(resumed, files.size());
    ExpectSame(full, resumed);
    EXPECT_EQ(resumed.class_names, (std::vector<std::string>{"box", "cylinder/mug"}));
}

TEST(MlDataset, SelectDropConcatRelabel) {
    const Dataset d = test::Blobs(4, 2, 1, 6, 0.5f, 3, 2);  // blocks b0 b1 b2
    const Dataset sel = SelectBlocks(d, {"b2", "b0"});
    ASSERT_EQ(sel.cols(), 4u);
    EXPECT_EQ(sel.BlockNames(), (std::vector<std::string>{"b2", "b0"}));
    EXPECT_EQ(sel.values[0], d.values[4]);
    EXPECT_EQ(DropBlocks(d, {"b1"}).BlockNames(), (std::vector<std::string>{"b0", "b2"}));
    EXPECT_THROW(SelectBlocks(d, {"nope"}), InvalidArgument);

    // Column-wise concatenation by row id, even with rows in another order.
    std::vector<std::size_t> reversed(d.rows());
    for (std::size_t i = 0; i < reversed.size(); ++i) reversed[i] = d.rows() - 1 - i;
    const Dataset joined =
        ConcatColumns(SelectBlocks(d, {"b0"}), SelectRows(SelectBlocks(d, {"b1", "b2"}), reversed));
    EXPECT_EQ(joined.values, d.values);
    EXPECT_THROW(ConcatColumns(d, d), InvalidArgument);

    // Row-wise concatenation renumbers colliding ids.
    const Dataset both = ConcatRows(d, d);
    EXPECT_EQ(both.rows(), 2 * d.rows());
    both.Validate();
    EXPECT_THROW(ConcatRows(d, SelectBlocks(d, {"b0"})), InvalidArgument);

    const Dataset flat = FlattenLabels(d, 1);
    EXPECT_EQ(flat.class_names, (std::vector<std::string>{"shape0", "shape1"}));
    for (std::size_t r = 0; r < d.rows(); ++r) {
        EXPECT_EQ(flat.class_names[flat.labels[r]],
                  TruncateLabelPath(d.class_names[d.labels[r]], 1));
    }
    const Dataset merged = Relabel(d, {{"shape0/class0", "x"}, {"shape0/class2", "x"}});
    EXPECT_EQ(merged.num_classes(), 3u);
    EXPECT_THROW(MapLabels(d, {"shape0/class0"}), DataError);
}

bool Disjoint(const Dataset& d, const std::vector<std::size_t>& a,
              const std::vector<std::size_t>& b) {
    std::set<std::int64_t> ga;
    for (auto r : a) ga.insert(d.groups[r]);
    for (auto r : b) {
        if (ga.count(d.groups[r])) return false;
    }
    return true;
}

TEST(MlSplit, GroupsStayDisjointWherePromised) {
    const Dataset d = test::Blobs(3, 8, 3, 4, 0.5f);
    const auto g = GroupSplit(d, 0.25, 5);
    EXPECT_TRUE(Disjoint(d, g.train, g.test));
    EXPECT_EQ(g.train.size() + g.test.size(), d.rows());
    EXPECT_EQ(g.test.size(), 3u * 2u * 3u);  // 2 of 8 instances per class
    for (const auto& f : KFold(d, 4, 9, true)) {
        EXPECT_TRUE(Disjoint(d, f.train, f.test));
        EXPECT_EQ(f.train.size() + f.test.size(), d.rows());
    }
    const auto logo = LeaveOneGroupOut(d);
    EXPECT_EQ(logo.size(), 24u);
    for (const auto& f : logo) {
        EXPECT_TRUE(Disjoint(d, f.train, f.test));
        EXPECT_EQ(f.test.size(), 3u);
    }
    const auto t = SplitThreeWay(d);
    EXPECT_TRUE(Disjoint(d, t.level0_train, t.level1_train));
    EXPECT_TRUE(Disjoint(d, t.level0_train, t.test));
    EXPECT_TRUE(Disjoint(d, t.level1_train, t.test));
    EXPECT_EQ(t.level0_train.size(), d.rows() / 2);
    EXPECT_EQ(t.level1_train.size(), d.rows() / 4);
    EXPECT_EQ(t.test.size(), d.rows() / 4);
    // Random row split: every row once, deterministic for a seed.
    const auto r1 = RandomSplit(d, 0.3, 1), r2 = RandomSplit(d, 0.3, 1);
    EXPECT_EQ(r1.test, r2.test);
    EXPECT_EQ(r1.train.size() + r1.test.size(), d.rows());
    EXPECT_THROW(RandomSplit(d, 1.5, 1), InvalidArgument);
    EXPECT_THROW(KFold(d, 1, 1, false), InvalidArgument);
}

TEST(MlTransform, FittedOnTrainingDataOnlyAndSaved) {
    test::TempDir dir;
    Dataset train = Dataset::WithColumns(2);
    train.AppendRow(std::vector<float>{0, 10}, "a");
    train.AppendRow(std::vector<float>{2, 10}, "b");
    Dataset test = Dataset::WithColumns(2);
    test.AppendRow(std::vector<float>{4, 7}, "a");
    const auto mm = FitMinMax(train);
    const Dataset out = mm.Apply(test);
    EXPECT_FLOAT_EQ(out.values[0], 2.0f);  // (4 - 0) / 2, outside [0, 1] as it must be
    EXPECT_FLOAT_EQ(out.values[1], 0.0f);  // constant training column
    const auto z = FitZScore(train);
    EXPECT_FLOAT_EQ(z.Apply(test).values[0], 3.0f);  // (4 - 1) / 1
    SaveTransform(z, dir / "z.mcx");
    EXPECT_EQ(LoadTransform(dir / "z.mcx").Apply(test).values, z.Apply(test).values);
    EXPECT_THROW(mm.Apply(Dataset::WithColumns(3)), InvalidArgument);
}

TEST(MlTransform, PcaRecoversTheMainAxisAndWhitens) {
    std::mt19937 rng(3);
    std::normal_distribution<float> n(0.0f, 1.0f);
    Dataset d = Dataset::WithColumns(3);
    for (int i = 0; i < 2000; ++i) {
        const float t = 5.0f * n(rng);
        d.AppendRow(
            std::vector<float>{t * 0.6f + 0.1f * n(rng), t * 0.8f + 0.1f * n(rng), 0.1f * n(rng)},
            "a");
    }
    const auto pca = FitPca(d, {.components = 0, .variance = 0.95, .whiten = true});
    ASSERT_EQ(pca.components.rows(), 1);
    EXPECT_NEAR(std::abs(pca.components(0, 0)), 0.6f, 0.01f);
    EXPECT_NEAR(std::abs(pca.components(0, 1)), 0.8f, 0.01f);
    const Dataset y = pca.Apply(d);
    double var = 0.0;
    for (float v : y.values) var += v * v;
    EXPECT_NEAR(var / static_cast<double>(y.rows()), 1.0, 0.01);
    EXPECT_EQ(y.BlockNames(), (std::vector<std::string>{"pca"}));
}

TEST(MlKMeans, RecoversSeparatedClustersDeterministically) {
    const Dataset d = test::Blobs(4, 1, 50, 5, 0.1f, 11);
    const auto a = KMeans(d.features(), {.k = 4, .seed = 3});
    const auto b = KMeans(d.features(), {.k = 4, .seed = 3});
    EXPECT_EQ(a.assignment, b.assignment);
    EXPECT_TRUE(a.converged);
    EXPECT_NEAR(AdjustedRandIndex(a.assignment, d.labels), 1.0, 1e-9);
    EXPECT_THROW(KMeans(d.features(), {.k = 0}), InvalidArgument);
    EXPECT_THROW(KMeans(d.features(), {.k = 1000}), InvalidArgument);
}

TEST(MlKMeans, BagOfWordsHistogramsPerView) {
    Dataset local = Dataset::WithColumns(1);
    // Two views of one instance: view 0 has words {0, 0, 1}, view 1 has {1}.
    for (float v : {0.0f, 0.1f, 10.0f}) local.AppendRow(std::vector<float>{v}, "mug", 5, 0);
    local.AppendRow(std::vector<float>{9.0f}, "mug", 5, 1);
    FeatureMatrix codebook(2, 1);
    codebook << 0.0f, 10.0f;
    const Dataset bow = BagOfWords(local, codebook);
    ASSERT_EQ(bow.rows(), 2u);
    EXPECT_FLOAT_EQ(bow.values[0], 2.0f / 3.0f);
    EXPECT_FLOAT_EQ(bow.values[1], 1.0f / 3.0f);
    EXPECT_FLOAT_EQ(bow.values[3], 1.0f);
    EXPECT_EQ(bow.groups[1], 5);
    EXPECT_EQ(bow.views[1], 1);
    EXPECT_EQ(bow.class_names[bow.labels[0]], "mug");
}

TEST(MlEvaluation, AdjustedRandIndexOnKnownPartitions) {
    EXPECT_DOUBLE_EQ(AdjustedRandIndex({0, 0, 1, 1}, {5, 5, 7, 7}), 1.0);
    // Hand-computed: contingency [[1,1],[1,1]] -> index 0, expected 2*2/6, max 2 -> -0.5.
    EXPECT_DOUBLE_EQ(AdjustedRandIndex({0, 0, 1, 1}, {0, 1, 0, 1}), -0.5);
    // {0,0,0,1,1,1} vs {0,0,1,1,2,2}: index 2, sa 6, sb 3, expected 18/15, max 4.5.
    EXPECT_NEAR(AdjustedRandIndex({0, 0, 0, 1, 1, 1}, {0, 0, 1, 1, 2, 2}),
                (2.0 - 1.2) / (4.5 - 1.2), 1e-12);
    EXPECT_THROW(AdjustedRandIndex({0}, {0, 1}), InvalidArgument);
}

TEST(MlEvaluation, ConfusionMatrixTextAndImage) {
    test::TempDir dir;
    const auto m = Confusion({0, 0, 1, 1, 1}, {0, 1, 1, 1, 0}, {"a", "b"});
    EXPECT_EQ(m.counts(0, 1), 1);
    EXPECT_EQ(m.counts(1, 1), 2);
    EXPECT_DOUBLE_EQ(m.Accuracy(), 0.6);
    EXPECT_DOUBLE_EQ(m.PerClassAccuracy()[1], 2.0 / 3.0);
    EXPECT_NE(m.ToText().find("error rate 0.4000"), std::string::npos) << m.ToText();
    m.WriteImage(dir / "c.ppm", 4);
    const std::string img = ReadBytes(dir / "c.ppm");
    EXPECT_EQ(img.substr(0, 11), "P6\n8 8\n255\n");
    EXPECT_EQ(img.size(), 11u + 8 * 8 * 3);
}

TEST(MlEvaluation, AccuracyExcludingOneTrueClass) {
    // Class 0 ("none") as truth is not scored; predicting it for another class is an error.
    const auto m = Confusion({0, 0, 1, 1, 2, 2, 2}, {0, 1, 1, 0, 2, 2, 1}, {"none", "a", "b"});
    EXPECT_EQ(m.TotalExcluding(0), 5u);
    EXPECT_DOUBLE_EQ(m.AccuracyExcluding(0), 3.0 / 5.0);
    EXPECT_EQ(m.TotalExcluding(2), 4u);
    EXPECT_DOUBLE_EQ(m.AccuracyExcluding(2), 2.0 / 4.0);
    EXPECT_DOUBLE_EQ(m.Accuracy(), 4.0 / 7.0);
    const auto only_none = Confusion({0, 0}, {0, 1}, {"none", "a"});
    EXPECT_EQ(only_none.TotalExcluding(0), 0u);
    EXPECT_DOUBLE_EQ(only_none.AccuracyExcluding(0), 0.0);
    EXPECT_THROW(m.AccuracyExcluding(3), InvalidArgument);
    EXPECT_THROW(m.TotalExcluding(-1), InvalidArgument);
}

TEST(MlEvaluation, ConfusionCounterMatchesConfusion) {
    const std::vector<int> truth{0, 0, 1, 1, 1, kNoLabel, 2};
    const std::vector<int> predicted{0, 1, 1, 1, 0, 2, 2};
    const std::vector<std::string> names{"a", "b", "c"};
    ConfusionCounter counter(names);
    for (std::size_t i = 0; i < truth.size(); ++i) counter.Add(truth[i], predicted[i]);
    EXPECT_EQ(counter.total(), 6u);  // the kNoLabel row is skipped
    EXPECT_EQ(counter.count(1, 1), 2u);
    const ConfusionMatrix m = counter.ToMatrix();
    const ConfusionMatrix expected = Confusion(truth, predicted, names);
    EXPECT_EQ(m.class_names, names);
    EXPECT_EQ(m.counts, expected.counts);
    EXPECT_DOUBLE_EQ(m.Accuracy(), expected.Accuracy());

    counter.Add(2, 0, 4);  // several items at once
    EXPECT_EQ(counter.count(2, 0), 4u);
    EXPECT_EQ(counter.total(), 10u);
    EXPECT_THROW(counter.Add(3, 0), InvalidArgument);
    EXPECT_THROW(counter.Add(0, -1), InvalidArgument);
    EXPECT_THROW(counter.count(0, 3), InvalidArgument);
    counter.Clear();
    EXPECT_EQ(counter.total(), 0u);
    EXPECT_EQ(counter.ToMatrix().counts, Eigen::MatrixXi::Zero(3, 3));
    EXPECT_DOUBLE_EQ(counter.ToMatrix().Accuracy(), 0.0);
}

TEST(MlEvaluation, ConfusionCountersMerge) {
    ConfusionCounter a({"x", "y"}), b({"x", "y"});
    a.Add(0, 0);
    a.Add(1, 0);
    b.Add(1, 1, 3);
    a.Merge(b);
    EXPECT_EQ(a.count(0, 0), 1u);
    EXPECT_EQ(a.count(1, 0), 1u);
    EXPECT_EQ(a.count(1, 1), 3u);
    EXPECT_EQ(a.total(), 5u);
    EXPECT_EQ(b.total(), 3u);  // the merged-in counter is unchanged
    EXPECT_DOUBLE_EQ(a.ToMatrix().Accuracy(), 4.0 / 5.0);
    ConfusionCounter other({"x", "z"});
    EXPECT_THROW(a.Merge(other), InvalidArgument);
    EXPECT_THROW(a.Merge(ConfusionCounter({"x"})), InvalidArgument);
}

TEST(MlEvaluation, ConfusionCounterRefusesCountsBeyondTheMatrix) {
    ConfusionCounter c({"a", "b"});
    c.Add(0, 0, static_cast<std::size_t>(std::numeric_limits<int>::max()));
    EXPECT_NO_THROW(c.ToMatrix());
    c.Add(1, 0);
    EXPECT_EQ(c.total(), static_cast<std::size_t>(std::numeric_limits<int>::max()) + 1);
    EXPECT_THROW(c.ToMatrix(), DataError);
}

}  // namespace
}  // namespace multicue::ml
