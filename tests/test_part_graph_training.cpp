// Part-graph hashing trained on simulated turntable scans and tested on held-out objects.

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/recognition/part_graph_model.hpp"
#include "multicue/sim/objects.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/raycaster.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/training/part_graph_training.hpp"

namespace multicue {
namespace {

const std::vector<std::string> kCats = {"sphere", "box", "cylinder"};

// A model of a few turntable objects of kCats (no table scenes), trained to completion.
PartGraphModel TrainSmall(int objects, int views, std::uint64_t seed, int threads,
                          int stacker_scenes = 0) {
    training::PartGraphTrainingOptions o;
    o.categories = kCats;
    o.objects_per_category = objects;
    o.views = views;
    o.table_scenes = 0;
    o.stacker_scenes = stacker_scenes;
    o.stacker_views = 1;
    o.seed = seed;
    o.num_threads = threads;
    PartGraphModel m;
    EXPECT_TRUE(training::TrainPartGraphModel(m, o));
    return m;
}

PartGraphModel TinyModel(int threads) { return TrainSmall(5, 3, 11, threads); }

TEST(PartGraphTraining, RecognisesHeldOutObjects) {
    const PartGraphModel m = TinyModel(0);
    ASSERT_GT(m.num_rows(), 100u);
    int correct = 0, total = 0;
    for (const auto& cat : kCats) {
        for (int i = 0; i < 3; ++i) {
            sim::StreamRng rng(99, static_cast<std::uint64_t>(total));
            auto p = sim::MakeProceduralObject(cat, rng);
            sim::ObjectModel om;
            om.mesh = std::make_shared<const sim::PartMesh>(std::move(p.mesh));
            om.category = cat;
            const sim::TurntableParams tp;
            const auto scene = sim::MakeTurntableScene(om, tp, 5);
            const auto pose = sim::TurntableViews(scene, 5, tp)[static_cast<std::size_t>(i)];
            PointCloud scan = sim::ScanKinect(scene, pose, sim::KinectParams{}, 3);
            Indices object;
            for (std::size_t k = 0; k < scan.size(); ++k) {
                if (scan.labels[k] == 20 && scan.IsFinite(k)) object.push_back(Index(k));
            }
            const auto parts = training::DecomposeObject(scan, object);
            const auto r = RecognizeParts(m, scan, parts);
            std::vector<std::size_t> ids(parts.size());
            for (std::size_t k = 0; k < ids.size(); ++k) ids[k] = k;
            const Category got = ArgMaxCategory(MergePartProbabilities(r, parts, ids));
            correct += got == ParseCategory(cat);
            ++total;
        }
    }
    // 9 held-out objects of 3 categories (chance: 3 of 9).
    EXPECT_GE(correct, 7) << correct << " of " << total;
}

TEST(PartGraphTraining, DeterministicAcrossThreads) {
    EXPECT_EQ(TinyModel(1).Serialize(), TinyModel(2).Serialize());
}

// Table scenes segmented by perceive: labelled objects of the scenes' categories only, the same
// model whatever the thread count.
TEST(PartGraphTraining, TableScenesAddPerceivedObjects) {
    std::vector<training::TrainingObject> objects;
    auto train = [&](int threads, bool baselines) {
        training::PartGraphTrainingOptions o;
        o.categories = kCats;
        o.objects_per_category = 0;
        o.table_scenes = 2;
        o.table_views = 1;
        o.seed = 5;
        o.num_threads = threads;
        if (baselines) {
            o.objects_out = &objects;
            o.part_statistics = true;
        }
        PartGraphModel m;
        EXPECT_TRUE(training::TrainPartGraphModel(m, o));
        return m;
    };
    const PartGraphModel m = train(1, true);
    // Every labelled object is handed over with its baseline features.
    ASSERT_FALSE(objects.empty());
    for (const auto& t : objects) {
        EXPECT_NE(t.category, Category::kNone);
        EXPECT_GT(t.part_descriptors.rows(), 0);
        EXPECT_EQ(t.part_statistics.rows(), t.part_descriptors.rows());
        EXPECT_EQ(t.cluster.size(), kClusterDescriptorSize);
    }
    EXPECT_GT(m.num_rows(), 0u);
    const auto per = m.rows_per_category();
    std::size_t in_cats = 0;
    for (const auto& c : kCats) in_cats += per[static_cast<std::size_t>(ParseCategory(c))];
    EXPECT_EQ(in_cats, m.num_rows());
    EXPECT_EQ(m.Serialize(), train(2, false).Serialize());
    training::PartGraphTrainingOptions bad;
    bad.table_scenes = -1;
    PartGraphModel unused;
    EXPECT_THROW(training::TrainPartGraphModel(unused, bad), InvalidArgument);
}

// Held-out table scenes train the stacker: the same model and stacker whatever the thread count,
// and perceive's "stacked" categoriser then runs on it.
TEST(PartGraphTraining, StackerScenesTrainTheStacker) {
    auto train = [](int threads) { return TrainSmall(2, 2, 7, threads, 2); };
    const PartGraphModel m = train(1);
    ASSERT_TRUE(m.stacker.trained());
    EXPECT_GT(m.stacker.train_rows(), 2u);
    EXPECT_EQ(m.Serialize(), train(2).Serialize());
    const PartGraphModel back = PartGraphModel::Deserialize(m.Serialize(), "round trip");
    EXPECT_TRUE(back.stacker.trained());

    sim::TableSceneParams sp;
    sim::ObjectSource source(kCats);
    const auto scene = sim::MakeTableScene(sp, source, 123);
    const auto pose = sim::TableViewpoints(scene, 1, {}, 4).at(0);
    PointCloud scan = sim::ScanKinect(scene, pose, sim::KinectParams{}, 3);
    PerceiveParams pp;
    pp.category.categoriser = Categoriser::kStacked;
    PerceiveModels models{std::make_shared<const PartGraphModel>(back)};
    const PerceiveResult r = Perceive(scan, pp, models);
    ASSERT_FALSE(r.objects.empty());
    for (const auto& o : r.objects) {
        if (o.category.category == Category::kNone) continue;
        float sum = 0.0f;
        for (float p : o.category.probabilities) sum += p;
        EXPECT_NEAR(sum, 1.0f, 1e-4f);
        EXPECT_EQ(o.category.probabilities[0], 0.0f);
    }
    // A model without a stacker is refused by name.
    models.part_graph = std::make_shared<const PartGraphModel>(TinyModel(0));
    try {
        Perceive(scan, pp, models);
        ADD_FAILURE() << "stacked categoriser ran without a stacker";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("stacker"), std::string::npos) << e.what();
    }
    training::PartGraphTrainingOptions bad;
    bad.stacker_scenes = -1;
    PartGraphModel unused;
    EXPECT_THROW(training::TrainPartGraphModel(unused, bad), InvalidArgument);
}

}  // namespace
}  // namespace multicue
