#include <set>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/tabletop_scene.hpp"
#include "multicue/system/executive.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

/// A view of the scene from the default camera turned by `angle` about the table's centre.
Frame View(const sim::TableTopScene& scene, float angle, double time, std::uint32_t seed) {
    sim::ScanParams scan;
    const Eigen::Isometry3f turn(Eigen::AngleAxisf(angle, Eigen::Vector3f::UnitZ()));
    scan.T_world_camera = turn * sim::DefaultCameraPose(scene);
    scan.seed = seed;
    Frame frame;
    frame.cloud = sim::ScanTableTopScene(scene, scan);
    frame.T_world_sensor = scan.T_world_camera.cast<double>();
    frame.time = time;
    frame.name = "t" + std::to_string(static_cast<int>(time));
    return frame;
}

std::size_t CountNovel(const FrameReport& r) {
    std::size_t n = 0;
    for (const auto& h : r.hypotheses) n += h.novel ? 1 : 0;
    return n;
}

TEST(Executive, PlansTheMethodsATaskNeedsInDependencyOrder) {
    PerceptionExecutive executive(nullptr);
    Task enumerate;
    EXPECT_EQ(executive.Plan(enumerate),
              (std::vector<std::string>{"segmentation", "colour", "shape", "identification"}));
    Task model;
    model.kind = Task::Kind::kModel;
    EXPECT_EQ(executive.Plan(model), (std::vector<std::string>{"segmentation"}));
    EXPECT_THROW(ParseTaskKind("dance"), InvalidArgument);
    Task find;
    find.kind = Task::Kind::kFind;
    EXPECT_THROW(executive.Run(Frame{}, find), InvalidArgument);  // no target
}

TEST(Executive, LearnsANovelObjectAndRecognisesItLaterAndElsewhere) {
    test::TempDir dir;
    auto db = ObjectDatabase::Open(dir / "objects.db", DatabaseMode::kCreateOrWrite);
    PerceptionExecutive executive(&db);
    Task task;  // enumerate and learn

    auto scene = sim::MakeDemoScene();
    // First frame: nothing is known, every object is novel and learnt.
    const auto first = executive.Run(View(scene, 0.0f, 1.0, 1), task);
    ASSERT_EQ(first.hypotheses.size(), 5u);
    EXPECT_EQ(first.learnt_objects, 5u);
    EXPECT_EQ(db.ListObjects().size(), 5u);

    // Another viewpoint later: the same five, identified, nothing new.
    const auto second = executive.Run(View(scene, 0.35f, 2.0, 2), task);
    EXPECT_EQ(second.hypotheses.size(), 5u);
    EXPECT_EQ(CountNovel(second), 0u);
    EXPECT_EQ(second.learnt_objects, 0u);

    // An unknown object appears: novel first, then known.
    scene.cylinders.push_back({{-0.40f, -0.22f}, 0.03f, 0.16f, {240, 130, 20, 255}});
    const auto third = executive.Run(View(scene, -0.3f, 3.0, 3), task);
    EXPECT_EQ(third.hypotheses.size(), 6u);
    EXPECT_EQ(CountNovel(third), 1u);
    EXPECT_EQ(db.ListObjects().size(), 6u);
    std::int64_t unknown_id = 0;
    for (const auto& h : third.hypotheses) {
        if (h.novel) unknown_id = h.object_id;
    }
    ASSERT_GT(unknown_id, 0);
    const auto fourth = executive.Run(View(scene, 0.2f, 4.0, 4), task);
    EXPECT_EQ(CountNovel(fourth), 0u);

    // Moved to another place: position no longer tells, its learnt views do.
    scene.cylinders.back().center_xy = {0.42f, 0.25f};
    const auto fifth = executive.Run(View(scene, 0.0f, 5.0, 5), task);
    bool redetected = false;
    for (const auto& h : fifth.hypotheses) {
        if (h.object_id == unknown_id) {
            EXPECT_FALSE(h.by_position);
            redetected = true;
        }
    }
    EXPECT_TRUE(redetected);
    EXPECT_EQ(db.ListObjects().size(), 6u);
}

TEST(Executive, ActiveSearchFindsTheSoughtObjectWithFewerMethods) {
    test::TempDir dir;
    auto db = ObjectDatabase::Open(dir / "objects.db", DatabaseMode::kCreateOrWrite);
    PerceptionExecutive executive(&db);
    const auto scene = sim::MakeDemoScene();
    const auto learnt = executive.Run(View(scene, 0.0f, 1.0, 1), Task{});
    ASSERT_EQ(learnt.hypotheses.size(), 5u);
    // Name the magenta cylinder and look for it from elsewhere.
    ObjectRecord mug;
    for (const auto& h : learnt.hypotheses) {
        const auto o = db.GetObject(h.object_id);
        ASSERT_TRUE(o);
        if (h.extents.x() > 0.19f && h.Category() == "cylinder") mug = *o;
    }
    ASSERT_GT(mug.id, 0);
    mug.name = "tall mug";
    db.UpdateObject(mug);

    Task find;
    find.kind = Task::Kind::kFind;
    find.target = "tall mug";
    const auto plan = executive.Plan(find);
    EXPECT_LT(plan.size(), 4u);  // one descriptor singles it out
    const auto report = executive.Run(View(scene, 0.4f, 2.0, 7), find);
    ASSERT_TRUE(report.found.has_value());
    EXPECT_EQ(report.hypotheses[*report.found].object_id, mug.id);
    EXPECT_EQ(db.ListObjects().size(), 5u);  // a search learns no strangers
}

TEST(Executive, WithoutADatabaseEverythingIsNovelAndNothingIsStored) {
    PerceptionExecutive executive(nullptr);
    const auto report = executive.Run(View(sim::MakeDemoScene(), 0.0f, 1.0, 1), Task{});
    EXPECT_EQ(report.hypotheses.size(), 5u);
    EXPECT_EQ(CountNovel(report), 5u);
    EXPECT_EQ(report.learnt_objects, 0u);
}

TEST(Executive, HierarchicFilteringAgreesOnDistinctObjects) {
    test::TempDir dir;
    auto db = ObjectDatabase::Open(dir / "objects.db", DatabaseMode::kCreateOrWrite);
    ExecutiveParams params;
    params.parallel_merge = false;
    params.same_place_radius = 0.0;  // identity from the descriptors alone
    PerceptionExecutive executive(&db, params);
    const auto scene = sim::MakeDemoScene();
    ASSERT_EQ(executive.Run(View(scene, 0.0f, 1.0, 1), Task{}).learnt_objects, 5u);
    Task look;
    look.learn = false;
    const auto report = executive.Run(View(scene, 0.3f, 2.0, 2), look);
    ASSERT_EQ(report.hypotheses.size(), 5u);
    std::set<std::int64_t> ids;
    for (const auto& h : report.hypotheses) {
        EXPECT_FALSE(h.novel);
        EXPECT_FALSE(h.by_position);
        ids.insert(h.object_id);
    }
    EXPECT_EQ(ids.size(), 5u);  // five different objects
}

TEST(Executive, DescriptorDistancesAreBoundedAndRefuseMismatchedSizes) {
    EXPECT_DOUBLE_EQ(DescriptorDistance("colour", {0.5f, 0.5f}, {0.5f, 0.5f}), 0.0);
    EXPECT_DOUBLE_EQ(DescriptorDistance("colour", {1.0f, 0.0f}, {0.0f, 1.0f}), 1.0);
    EXPECT_NEAR(DescriptorDistance("shape", {0.2f, 0.1f, 0.1f, 1, 0}, {0.2f, 0.1f, 0.1f, 0, 1}),
                0.5, 1e-9);
    EXPECT_THROW(DescriptorDistance("colour", {1.0f}, {0.5f, 0.5f}), InvalidArgument);
}

}  // namespace
}  // namespace multicue
