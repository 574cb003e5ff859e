// bench_ml: per-query k-NN times on 20-d features with 50,000 training rows for every metric
// (Table 2.3 reports 1-6 ms per instance for GRSD- [20d]), k-d tree against the brute-force scan,
// and SVM / boosting / random forest prediction times per row.
//
// Data: 51 classes (as the RGB-D object dataset), Gaussian clusters in [0, 1]^20 with a few
// instances per class, non-negative so that every histogram metric applies. BM_KnnQueryFar asks
// for points of other clusters: the k-d tree's worst case.

#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "multicue/ml/classifier.hpp"
#include "multicue/ml/knn.hpp"

namespace {

using namespace multicue::ml;

// The cluster centres are the same for every call (fixed seed); `seed` draws the noise, so
// queries come from the objects the training rows describe, as new scans of known instances do.
Dataset Features(std::size_t rows, int dims, int classes, std::uint32_t seed) {
    std::mt19937 centres_rng(1);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> centre(0.0f, 1.0f);
    std::normal_distribution<float> noise(0.0f, 0.05f);
    Dataset d = Dataset::WithColumns(static_cast<std::size_t>(dims), "grsd");
    constexpr int kInstances = 6;
    std::vector<std::vector<float>> centres(static_cast<std::size_t>(classes * kInstances));
    for (auto& c : centres) {
        c.resize(static_cast<std::size_t>(dims));
        for (auto& v : c) v = centre(centres_rng);
    }
    std::vector<float> row(static_cast<std::size_t>(dims));
    for (std::size_t r = 0; r < rows; ++r) {
        const std::size_t inst = r % centres.size();
        for (int j = 0; j < dims; ++j) {
            row[static_cast<std::size_t>(j)] =
                std::max(0.0f, centres[inst][static_cast<std::size_t>(j)] + noise(rng));
        }
        d.AppendRow(row, IndexedName("c", inst / kInstances), static_cast<std::int64_t>(inst));
    }
    return d;
}

const Dataset& Train() {
    static const Dataset d = Features(50000, 20, 51, 1);
    return d;
}
const Dataset& Queries() {
    static const Dataset d = Features(1000, 20, 51, 2);
    return d;
}
const Dataset& FarQueries() {
    static const Dataset d = [] {
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        Dataset q = Dataset::WithColumns(20, "grsd");
        std::vector<float> row(20);
        for (int r = 0; r < 1000; ++r) {
            for (auto& v : row) v = u(rng);
            q.AppendRow(row, "c0");
        }
        return q;
    }();
    return d;
}

void BM_KnnQuery(benchmark::State& state) {
    const auto metric = static_cast<KnnMetric>(state.range(0));
    const auto index = static_cast<KnnIndex>(state.range(1));
    KnnClassifier knn({.k = 5, .metric = metric, .index = index, .num_threads = 1});
    knn.Fit(Train());
    const auto q = (state.range(2) != 0 ? FarQueries() : Queries()).features();
    Eigen::Index i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(knn.PredictProba(q.row(i)));
        i = (i + 1) % q.rows();
    }
    state.SetLabel(ToString(metric) + (index == KnnIndex::kBrute ? " scan" : " k-d tree") +
                   (state.range(2) != 0 ? ", far queries" : ""));
}
BENCHMARK(BM_KnnQuery)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {static_cast<long>(KnnIndex::kBrute)}, {0}})
    ->ArgsProduct({{1, 2}, {static_cast<long>(KnnIndex::kKdTree)}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

void BM_PredictPerRow(benchmark::State& state, const std::string& spec, std::size_t train_rows) {
    const Dataset train = Features(train_rows, 20, 51, 3);
    auto c = CreateClassifier(spec);
    c->Fit(train);
    const auto q = Queries().features();
    for (auto _ : state) benchmark::DoNotOptimize(c->PredictProba(q));
    state.SetItemsProcessed(state.iterations() * q.rows());
    state.counters["us_per_row"] = benchmark::Counter(
        static_cast<double>(q.rows()),
        benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK_CAPTURE(BM_PredictPerRow, svm_rbf_prob, std::string("svm:kernel=rbf,C=10"), 3000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PredictPerRow, svm_linear_prob, std::string("svm:kernel=linear,C=10"), 3000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PredictPerRow, boost_real_100, std::string("boost:type=real,weak=100"), 3000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PredictPerRow, rtrees_100, std::string("rtrees:trees=100"), 3000)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
