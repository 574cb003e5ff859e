// Furniture detection by part configurations on small simulated scenes: a CAD model fitted to a
// noisy scan of its piece at a known pose (and rejected where a scan saw only floor) and
// stretched to a piece of another size, a planted chair found by the votes (the same for any
// thread count), merged views dropping a place only one view votes for, free space against a
// closed-form case, walls among the parts, the shape evidence of a fit, the learned verifier (and
// one of an older model that knows fewer features), the model file round trip, bad parameters and
// empty input.

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/point_cloud_io.hpp"
#include "multicue/mapping/furniture_detection.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/serialization.hpp"
#include "multicue/sim/furniture_scenes.hpp"
#include "multicue/sim/raycaster.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/training/furniture_training.hpp"
#include "test_paths.hpp"

namespace multicue {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

/// Training options of a small model: procedural pieces only, few views.
training::FurnitureTrainingOptions SmallTraining() {
    training::FurnitureTrainingOptions to;
    to.furniture.clear();
    to.kitchen.clear();
    to.procedural_per_class = 3;
    to.views.views = 8;
    to.num_threads = 2;
    to.seed = 5;
    to.verifier_rooms = 0;  // FurnitureVerifier trains one
    return to;
}

FurnitureModel TrainSmallModel(std::vector<sim::FurniturePiece>* pieces_out = nullptr) {
    const auto to = SmallTraining();
    auto pieces = training::FurnitureTrainingPieces(to);
    FurnitureModel model;
    EXPECT_TRUE(training::TrainFurnitureModel(pieces, to, model));
    if (pieces_out != nullptr) *pieces_out = std::move(pieces);
    return model;
}

/// `piece` turned by `yaw` at the origin, scanned by the laser from `heads` positions around it.
struct PieceScans {
    std::vector<PointCloud> scans;
    std::vector<Eigen::Isometry3f> poses;
};
PieceScans ScanPiece(const sim::FurniturePiece& piece, float yaw, int heads, std::uint64_t seed) {
    const sim::Scene scene = sim::MakeFurnitureViewScene(piece, yaw);
    const sim::RayCaster caster(scene);
    sim::FurnitureViewParams vp;
    vp.views = heads;
    const auto to = SmallTraining();
    PieceScans out;
    for (const auto& head : sim::FurnitureViewHeads(vp, seed)) {
        Eigen::Isometry3f T;
        out.scans.push_back(training::ScanFurniture(caster, head, Eigen::Vector3f(0, 0, 0.4f), to,
                                                    seed + out.scans.size(), T));
        out.poses.push_back(T);
    }
    return out;
}

/// Moves every view by `shift` in the world (the piece then stands at `shift`).
std::vector<FurnitureView> Views(const PieceScans& s, const Eigen::Vector3f& shift) {
    std::vector<FurnitureView> views;
    for (std::size_t i = 0; i < s.scans.size(); ++i) {
        views.push_back({&s.scans[i], Eigen::Translation3f(shift) * s.poses[i]});
    }
    return views;
}

float AngleDiff(float a, float b) {
    float d = std::fmod(std::abs(a - b), 2.0f * kPi);
    return std::min(d, 2.0f * kPi - d);
}

TEST(FurnitureFit, RecoversTheKnownPoseOfATrainingPieceAndRejectsItInFreeSpace) {
    std::vector<sim::FurniturePiece> pieces;
    const FurnitureModel model = TrainSmallModel(&pieces);
    // The first procedural chair: asymmetric (back), so its yaw is unique.
    const sim::FurniturePiece* chair = nullptr;
    for (const auto& p : pieces) {
        if (p.category == "chair") chair = &p;
        if (chair != nullptr) break;
    }
    ASSERT_NE(chair, nullptr);
    const float yaw = 0.7f;
    const Eigen::Vector3f shift(0.6f, -0.4f, 0.0f);
    const PieceScans s = ScanPiece(*chair, yaw, 3, 77);
    PointCloud points;
    FurniturePartParams pp = model.part_params();
    for (const auto& v : Views(s, shift)) {
        const FurnitureParts parts = ExtractFurnitureParts(*v.scan, v.T_world_sensor, pp);
        points.points.insert(points.points.end(), parts.cloud.points.begin(),
                             parts.cloud.points.end());
        points.normals.insert(points.normals.end(), parts.cloud.normals.begin(),
                              parts.cloud.normals.end());
    }
    points.width = static_cast<std::uint32_t>(points.points.size());
    ASSERT_GT(points.size(), 200u);
    FurnitureFitParams fp;
    const FurnitureFitContext context(model, fp);
    const int cls = model.ClassIndex("chair");
    // The search starts 15 cm off the true centre.
    const FurnitureFit fit =
        FitFurniture(points, cls, shift.head<2>() + Eigen::Vector2f(0.1f, 0.1f), context);
    ASSERT_GE(fit.cad, 0);
    EXPECT_TRUE(fit.accepted) << fit.rejection;
    EXPECT_GT(fit.coverage, 0.7f);
    EXPECT_EQ(model.cads()[static_cast<std::size_t>(fit.cad)].id, chair->id);
    EXPECT_LT((fit.T_world_model.translation().head<2>() - shift.head<2>()).norm(), 0.05f);
    EXPECT_LT(AngleDiff(fit.yaw, yaw), 5.0f * kPi / 180.0f) << "yaw " << fit.yaw;
    // Upright: the model's z stays the world's z.
    EXPECT_GT(fit.T_world_model.linear()(2, 2), 0.999f);

    // The best poses of several models: the first is the fit above, the others are other
    // chairs' models, each finished and tested on its own.
    const std::vector<FurnitureFit> fits = FitFurnitureModels(
        points, cls, shift.head<2>() + Eigen::Vector2f(0.1f, 0.1f), context, {}, 3);
    ASSERT_EQ(fits.size(), 3u);  // three procedural chairs, three models
    EXPECT_EQ(fits[0].cad, fit.cad);
    EXPECT_TRUE(fits[0].T_world_model.isApprox(fit.T_world_model));
    EXPECT_EQ(fits[0].coverage, fit.coverage);
    for (std::size_t k = 1; k < fits.size(); ++k) {
        EXPECT_GE(fits[k].cad, 0);
        EXPECT_EQ(model.cads()[static_cast<std::size_t>(fits[k].cad)].cls, cls);
        for (std::size_t j = 0; j < k; ++j) EXPECT_NE(fits[k].cad, fits[j].cad);
        // Another chair explains this chair's points less well than its own model does.
        EXPECT_LE(fits[k].coverage, fit.coverage + 0.02f);
    }
    EXPECT_EQ(FitFurnitureModels(points, cls, shift.head<2>(), context, {}, 1).size(), 1u);
    EXPECT_THROW(FitFurnitureModels(points, cls, shift.head<2>(), context, {}, 0), InvalidArgument);

    // The same points where a scan saw only the floor: the model stands in free space.
    PointCloud floor;
    for (float x = -1.5f; x <= 1.5f; x += 0.02f) {
        for (float y = -1.5f; y <= 1.5f; y += 0.02f)
            floor.points.emplace_back(shift.x() + x, shift.y() + y, 0.0f);
    }
    floor.width = static_cast<std::uint32_t>(floor.points.size());
    FurnitureFreeSpace empty_room(fp.occupancy_resolution);
    empty_room.AddView(floor, shift + Eigen::Vector3f(2.0f, 0.3f, 1.5f));
    FurnitureSpace space;
    space.free.push_back(&empty_room);
    const FurnitureFit in_free =
        FitFurniture(points, cls, shift.head<2>() + Eigen::Vector2f(0.1f, 0.1f), context, space);
    EXPECT_FALSE(in_free.accepted);
    EXPECT_GT(in_free.free_share, fp.max_free_share);
}

/// A model of one procedural cabinet and the parts' points and free space of 3 laser scans of
/// `piece` standing at `shift`, turned by `yaw`.
struct OneCabinet {
    sim::FurniturePiece cabinet;
    FurnitureModel model;
    PointCloud points;
    std::vector<FurnitureFreeSpace> free;
    FurnitureSpace space;
};
std::unique_ptr<OneCabinet> ScanForOneCabinetModel(const Eigen::Vector3f& stretch, float yaw,
                                                   const Eigen::Vector3f& shift) {
    auto out = std::make_unique<OneCabinet>();
    sim::StreamRng rng(sim::SubSeed(31, 2));
    out->cabinet = sim::MakeProceduralFurniture("cabinet", rng);
    EXPECT_TRUE(training::TrainFurnitureModel({out->cabinet}, SmallTraining(), out->model));
    auto mesh = std::make_shared<sim::PartMesh>(*out->cabinet.mesh);
    for (auto& v : mesh->mesh.vertices) v = v.cwiseProduct(stretch);
    sim::FurniturePiece scanned = out->cabinet;
    scanned.mesh = mesh;
    const PieceScans s = ScanPiece(scanned, yaw, 3, 21);
    const auto views = Views(s, shift);
    out->free.resize(views.size());
    for (std::size_t v = 0; v < views.size(); ++v) {
        const FurnitureParts parts = ExtractFurnitureParts(*views[v].scan, views[v].T_world_sensor,
                                                           out->model.part_params());
        out->points.points.insert(out->points.points.end(), parts.cloud.points.begin(),
                                  parts.cloud.points.end());
        out->points.normals.insert(out->points.normals.end(), parts.cloud.normals.begin(),
                                   parts.cloud.normals.end());
        PointCloud world;
        for (const auto& p : views[v].scan->points) {
            if (p.allFinite()) world.points.push_back(views[v].T_world_sensor * p);
        }
        world.width = static_cast<std::uint32_t>(world.points.size());
        out->free[v].AddView(world, views[v].T_world_sensor.translation());
    }
    for (const auto& f : out->free) out->space.free.push_back(&f);
    out->points.width = static_cast<std::uint32_t>(out->points.points.size());
    return out;
}

TEST(FurnitureFit, StretchesTheModelToAPieceOfAnotherSize) {
    // A model of one cabinet; the scanned cabinet is the same design, 20 % wider along its x
    // axis.
    const Eigen::Vector3f stretch(1.2f, 1.0f, 1.0f);
    const float yaw = 0.4f;
    const Eigen::Vector3f shift(0.3f, 0.2f, 0.0f);
    const auto one = ScanForOneCabinetModel(stretch, yaw, shift);
    const sim::FurniturePiece& cabinet = one->cabinet;
    const FurnitureModel& model = one->model;
    const PointCloud& points = one->points;
    const FurnitureSpace& space = one->space;
    ASSERT_EQ(model.cads().size(), 1u);
    ASSERT_GT(points.size(), 200u);
    const Eigen::Vector3f truth = cabinet.mesh->Bounds().sizes().cwiseProduct(stretch);
    const Eigen::Vector3f cad = model.cads()[0].extent;
    // Fitted size along the model's axes against the truth; x and y swap when the fit turned by
    // 90 degrees.
    auto size_error = [&](const FurnitureFit& fit) {
        const Eigen::Vector3f fitted = cad.cwiseProduct(fit.scale);
        const float turned = std::abs(std::sin(fit.yaw - yaw));
        const Eigen::Vector3f t =
            turned > 0.7f ? Eigen::Vector3f(truth.y(), truth.x(), truth.z()) : truth;
        return (fitted - t).cwiseAbs().maxCoeff();
    };
    FurnitureFitParams fixed;
    fixed.max_scale = 0.0f;  // the models keep their size
    const FurnitureFitContext fixed_context(model, fixed);
    const FurnitureFit plain = FitFurniture(points, 0, shift.head<2>(), fixed_context, space);
    ASSERT_GE(plain.cad, 0);
    EXPECT_EQ(plain.scale, Eigen::Vector3f::Ones());
    FurnitureFitParams adaptive;
    adaptive.max_scale = 0.3f;
    adaptive.scale_steps = 6;
    const FurnitureFitContext context(model, adaptive);
    const FurnitureFit fit = FitFurniture(points, 0, shift.head<2>(), context, space);
    ASSERT_GE(fit.cad, 0);
    EXPECT_TRUE(fit.accepted) << fit.rejection;
    EXPECT_GT(fit.coverage, plain.coverage + 0.05f);
    EXPECT_LT(size_error(fit), 0.06f) << "scale " << fit.scale.transpose();
    EXPECT_GT(size_error(plain), 0.08f);
    EXPECT_LT((fit.T_world_model.translation().head<2>() - shift.head<2>()).norm(), 0.06f);
    // The same fit again: deterministic.
    const FurnitureFit again = FitFurniture(points, 0, shift.head<2>(), context, space);
    EXPECT_EQ(again.scale, fit.scale);
    EXPECT_EQ(again.covered, fit.covered);
    // A stretch of half the size or more is refused.
    adaptive.max_scale = 0.5f;
    EXPECT_THROW(adaptive.Validate(), InvalidArgument);
    adaptive.max_scale = 0.2f;
    adaptive.scale_steps = 0;
    EXPECT_THROW(adaptive.Validate(), InvalidArgument);
}

TEST(FurnitureFit, AFitFacingAWallItStandsAgainstIsTurnedToFaceTheRoom) {
    const float yaw = -0.9f;
    const Eigen::Vector3f shift(-0.2f, 0.4f, 0.0f);
    const auto one = ScanForOneCabinetModel(Eigen::Vector3f::Ones(), yaw, shift);
    ASSERT_GT(one->points.size(), 200u);
    const float depth = one->model.cads()[0].extent.x();
    const Eigen::Vector2f front(std::cos(yaw), std::sin(yaw)), c = shift.head<2>();
    // A wall 5 cm behind the cabinet, facing it; and one 5 cm before its front.
    FurnitureWall behind, ahead;
    behind.point = c - front * (depth / 2 + 0.05f);
    behind.normal = front;
    ahead.point = c + front * (depth / 2 + 0.05f);
    ahead.normal = -front;
    for (auto* w : {&behind, &ahead}) w->lo = -2.0f, w->hi = 2.0f;
    FurnitureSpace space = one->space;
    FurnitureFitParams fp;
    const FurnitureFitContext context(one->model, fp);
    space.walls = {&behind};
    const FurnitureFit right = FitFurniture(one->points, 0, c, context, space);
    ASSERT_GE(right.cad, 0);
    EXPECT_LT(AngleDiff(right.yaw, yaw), 10.0f * kPi / 180.0f) << "yaw " << right.yaw;
    // With the wall before its front, the fit turns to face away from it.
    space.walls = {&ahead};
    const FurnitureFit away = FitFurniture(one->points, 0, c, context, space);
    ASSERT_GE(away.cad, 0);
    EXPECT_LT(AngleDiff(away.yaw, yaw + kPi), 10.0f * kPi / 180.0f) << "yaw " << away.yaw;
    EXPECT_LT((away.T_world_model.translation().head<2>() - c).norm(), 0.06f);
    // Without the rule nothing is turned, and the scans alone leave front and back open: the
    // fit faces either way. The turn changes the reported orientation only: the verification's
    // numbers stay those of the pose the search found.
    fp.back_to_wall = false;
    const FurnitureFitContext plain(one->model, fp);
    EXPECT_TRUE(right.turned || away.turned);
    for (const auto* w : {&behind, &ahead}) {
        space.walls = {w};
        const FurnitureFit either = FitFurniture(one->points, 0, c, plain, space);
        const FurnitureFit& ruled = w == &behind ? right : away;
        EXPECT_FALSE(either.turned);
        EXPECT_LT(std::min(AngleDiff(either.yaw, yaw), AngleDiff(either.yaw, yaw + kPi)),
                  10.0f * kPi / 180.0f);
        EXPECT_EQ(ruled.coverage, either.coverage);
        EXPECT_EQ(ruled.free_share, either.free_share);
        EXPECT_LT(AngleDiff(ruled.yaw, either.yaw + (ruled.turned ? kPi : 0.0f)), 1e-3f);
    }
    fp.flip_tolerance = -0.1f;
    EXPECT_THROW(fp.Validate(), InvalidArgument);
}

TEST(FurnitureDetection, VotesFindAPlantedChairForAnyThreadCount) {
    std::vector<sim::FurniturePiece> pieces;
    const FurnitureModel model = TrainSmallModel(&pieces);
    sim::StreamRng rng(sim::SubSeed(99, 1));
    const sim::FurniturePiece chair = sim::MakeProceduralFurniture("chair", rng);  // not trained
    const Eigen::Vector3f shift(1.0f, -0.5f, 0.0f);
    const PieceScans s = ScanPiece(chair, -1.1f, 3, 11);
    FurnitureDetectionParams dp;
    dp.verify = false;
    dp.num_threads = 1;
    const auto serial = DetectFurniture(Views(s, shift), model, nullptr, dp);
    ASSERT_FALSE(serial.detections.empty());
    const FurnitureDetection& best = serial.detections.front();
    EXPECT_EQ(best.category, "chair");
    EXPECT_LT((best.centre - shift.head<2>()).norm(), 0.25f);
    dp.num_threads = 2;
    const auto parallel = DetectFurniture(Views(s, shift), model, nullptr, dp);
    ASSERT_EQ(parallel.detections.size(), serial.detections.size());
    for (std::size_t i = 0; i < serial.detections.size(); ++i) {
        EXPECT_EQ(parallel.detections[i].category, serial.detections[i].category);
        EXPECT_EQ(parallel.detections[i].centre, serial.detections[i].centre);
        EXPECT_EQ(parallel.detections[i].score, serial.detections[i].score);
    }
    // Verified, with a chair whose CAD model the model holds: the fitted chair stays, its model
    // where the chair stands (a chair of other proportions may claim free space and go).
    const sim::FurniturePiece* known = nullptr;
    for (const auto& p : pieces) {
        if (known == nullptr && p.category == "chair") known = &p;
    }
    ASSERT_NE(known, nullptr);
    const PieceScans ks = ScanPiece(*known, -1.1f, 3, 12);
    dp.verify = true;
    dp.fit_models = 1;  // the best model's fit alone
    const FurnitureFitContext context(model, dp.fit);
    const auto verified = DetectFurniture(Views(ks, shift), model, &context, dp);
    ASSERT_FALSE(verified.detections.empty());
    EXPECT_EQ(verified.detections.front().category, "chair");
    EXPECT_LT((verified.detections.front().centre - shift.head<2>()).norm(), 0.15f);
    // With the best poses of three chair models per hypothesis: still one chair, there; the
    // other models' fits of it are overlapping fits of the same piece.
    dp.fit_models = 3;
    const auto several = DetectFurniture(Views(ks, shift), model, &context, dp);
    ASSERT_FALSE(several.detections.empty());
    std::size_t chairs_near = 0;
    for (const auto& d : several.detections)
        chairs_near += d.category == "chair" && (d.centre - shift.head<2>()).norm() < 0.3f;
    EXPECT_EQ(chairs_near, 1u);
    EXPECT_EQ(several.detections.front().category, "chair");
    EXPECT_LT((several.detections.front().centre - shift.head<2>()).norm(), 0.15f);
    EXPECT_GT(several.rejected.size(), verified.rejected.size());

    // The model file: written and read back, the same votes; a truncated file is refused.
    const auto path = std::filesystem::temp_directory_path() / "multicue_test_furniture.mcfm";
    model.Save(path);
    const FurnitureModel loaded = FurnitureModel::Load(path);
    dp.verify = false;
    const auto again = DetectFurniture(Views(s, shift), loaded, nullptr, dp);
    ASSERT_EQ(again.detections.size(), serial.detections.size());
    EXPECT_EQ(again.detections.front().score, serial.detections.front().score);
    std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
    EXPECT_THROW(FurnitureModel::Load(path), FormatError);
    std::filesystem::remove(path);
}

// Merging views (section 4.2.5.3): a place only one view votes for (clutter seen once) is a
// hypothesis of that view alone, but not of the merged views, whose vote weights are divided by
// their number; a piece every view votes for stays in both.
TEST(FurnitureDetection, MergingViewsRemovesAFalsePositiveOfOneView) {
    const FurnitureModel model = TrainSmallModel();
    const int chair = model.ClassIndex("chair");
    ASSERT_GE(chair, 0);
    const float t = model.classes()[static_cast<std::size_t>(chair)].threshold;
    ASSERT_GT(t, 0.0f);
    const Eigen::Vector2f piece(0.0f, 0.0f), clutter(3.0f, 0.0f);
    std::vector<FurnitureVote> votes, first_view;
    for (int v = 0; v < 3; ++v)
        votes.push_back({{piece.x(), piece.y(), 0.4f}, 1.5f * t, chair, 0, v});
    votes.push_back({{clutter.x(), clutter.y(), 0.4f}, 1.5f * t, chair, 1, 0});
    for (const auto& vote : votes) {
        if (vote.view == 0) first_view.push_back(vote);
    }
    auto at = [](const std::vector<FurnitureHypothesis>& hs, const Eigen::Vector2f& x) {
        int n = 0;
        for (const auto& h : hs) n += (h.centre - x).norm() < 0.1f ? 1 : 0;
        return n;
    };
    const FurnitureSelectionParams sp;  // at the class thresholds
    const auto single = SelectFurnitureHypotheses(first_view, 1, model, sp);
    EXPECT_EQ(at(single, piece), 1);
    EXPECT_EQ(at(single, clutter), 1);  // the single view's false positive
    const auto merged = SelectFurnitureHypotheses(votes, 3, model, sp);
    EXPECT_EQ(at(merged, piece), 1);
    EXPECT_EQ(at(merged, clutter), 0);
}

// Every class where another class's votes are strong: a place voted for only as a chair gets a
// hypothesis of each other class with that class's votes (none) as its score and the chair's
// parts; a weak place proposes nothing; a class already voted for nearby is not proposed again.
TEST(FurnitureSelection, AStrongHypothesisProposesEveryOtherClassWhereNoneIsNear) {
    const FurnitureModel model = TrainSmallModel();
    const int chair = model.ClassIndex("chair"), table = model.ClassIndex("table");
    ASSERT_GE(chair, 0);
    ASSERT_GE(table, 0);
    const int n_classes = static_cast<int>(model.classes().size());
    const float tc = model.classes()[static_cast<std::size_t>(chair)].threshold;
    const float tt = model.classes()[static_cast<std::size_t>(table)].threshold;
    const Eigen::Vector2f strong(0.0f, 0.0f), weak(4.0f, 0.0f), shared(-4.0f, 0.0f);
    std::vector<FurnitureVote> votes = {
        {{strong.x(), strong.y(), 0.4f}, 2.0f * tc, chair, 0, 0},
        {{weak.x(), weak.y(), 0.4f}, 0.5f * tc, chair, 1, 0},
        {{shared.x(), shared.y(), 0.4f}, 2.0f * tc, chair, 2, 0},
        {{shared.x() + 0.05f, shared.y(), 0.4f}, 0.5f * tt, table, 3, 0}};
    FurnitureSelectionParams sp;
    sp.threshold_scale = 0.3f;
    auto at = [](const std::vector<FurnitureHypothesis>& hs, const Eigen::Vector2f& x, int cls) {
        std::vector<const FurnitureHypothesis*> found;
        for (const auto& h : hs) {
            if (h.cls == cls && (h.centre - x).norm() < 0.1f) found.push_back(&h);
        }
        return found;
    };
    const auto plain = SelectFurnitureHypotheses(votes, 1, model, sp);
    EXPECT_TRUE(at(plain, strong, table).empty());
    sp.other_classes = true;
    const auto all = SelectFurnitureHypotheses(votes, 1, model, sp);
    for (int c = 0; c < n_classes; ++c) {
        const auto here = at(all, strong, c);
        ASSERT_EQ(here.size(), 1u) << model.classes()[static_cast<std::size_t>(c)].name;
        ASSERT_EQ(here.front()->parts.size(), 1u);
        EXPECT_EQ(here.front()->proposed_by, c == chair ? -1 : chair);
        // The votes that found the place: its own, or the proposing chair's (2 thresholds).
        EXPECT_FLOAT_EQ(here.front()->found, c == chair ? here.front()->normalized : 2.0f);
        EXPECT_EQ(here.front()->parts.front(), std::make_pair(0, 0));
        if (c != chair) {
            EXPECT_EQ(here.front()->score, 0.0f);
            EXPECT_TRUE(at(all, weak, c).empty());
        }
    }
    EXPECT_EQ(at(all, weak, chair).size(), 1u);
    // At the shared place the table keeps its own hypothesis (its votes, its part) only.
    const auto tables = at(all, shared, table);
    ASSERT_EQ(tables.size(), 1u);
    EXPECT_GT(tables.front()->score, 0.0f);
    EXPECT_EQ(tables.front()->parts.front(), std::make_pair(0, 3));
    sp.other_classes_from = -1.0f;
    EXPECT_THROW(SelectFurnitureHypotheses(votes, 1, model, sp), InvalidArgument);
}

// The votes find the piece, the fits name it: a sideboard whose votes all went to the table
// class is found as a sideboard when every class is fitted where one class's votes are strong,
// and not found as one when only the voted class is.
TEST(FurnitureDetection, APieceVotedForAsAnotherClassIsNamedByItsFittedModel) {
    std::vector<sim::FurniturePiece> pieces;
    const FurnitureModel model = TrainSmallModel(&pieces);
    const sim::FurniturePiece* sideboard = nullptr;
    for (const auto& p : pieces) {
        if (sideboard == nullptr && p.category == "sideboard") sideboard = &p;
    }
    ASSERT_NE(sideboard, nullptr);
    const int table = model.ClassIndex("table"), cls = model.ClassIndex("sideboard");
    ASSERT_GE(table, 0);
    const Eigen::Vector3f shift(0.5f, 0.8f, 0.0f);
    const PieceScans s = ScanPiece(*sideboard, 0.4f, 3, 21);
    FurnitureDetectionParams dp;
    dp.num_threads = 2;
    // Models of their own size: without a verifier (this model has none) a table model stretched
    // to the sideboard explains it about as well as the sideboard's own.
    dp.fit.max_scale = 0.0f;
    FurnitureScene scene = PrepareFurnitureScene(Views(s, shift), model, dp);
    // Every vote near the piece becomes a strong table vote; the rest goes.
    const float tt = model.classes()[static_cast<std::size_t>(table)].threshold;
    for (auto& view : scene.votes) {
        std::vector<FurnitureVote> kept;
        for (auto v : view) {
            if ((v.x.head<2>() - shift.head<2>()).norm() > 0.3f) continue;
            v.cls = table;
            v.weight = 6.0f * tt / static_cast<float>(view.size());
            kept.push_back(v);
        }
        view = std::move(kept);
    }
    const FurnitureFitContext context(model, dp.fit);
    auto found = [&](const FurnitureDetectionResult& r) {
        for (const auto& d : r.detections) {
            if (d.cls == cls && (d.centre - shift.head<2>()).norm() < 0.15f) return true;
        }
        return false;
    };
    dp.other_classes = false;
    EXPECT_FALSE(found(DetectFurniture(scene, {}, model, &context, dp)));
    dp.other_classes = true;
    const auto named = DetectFurniture(scene, {}, model, &context, dp);
    EXPECT_TRUE(found(named));
    for (const auto& d : named.detections) {  // ranked by the votes that found it
        if (d.cls == cls) {
            EXPECT_GT(d.score, 0.0f);
        }
    }
    for (const auto& d : named.detections) {  // and the table it was voted for does not stay
        EXPECT_FALSE(d.cls == table && (d.centre - shift.head<2>()).norm() < 0.3f);
    }
}

TEST(FurnitureFreeSpace, PointsBetweenTheSensorAndTheFloorAreFreeAndBelowItAreNot) {
    // A floor patch seen from 1.5 m above its centre.
    PointCloud floor;
    for (float x = -1.0f; x <= 1.0f; x += 0.02f) {
        for (float y = -1.0f; y <= 1.0f; y += 0.02f) floor.points.emplace_back(x, y, 0.0f);
    }
    floor.width = static_cast<std::uint32_t>(floor.points.size());
    FurnitureFreeSpace fs(0.05);
    EXPECT_EQ(fs.FreeShare({Eigen::Vector3f(0, 0, 0.5f)}), 0.0f);  // no views: nothing free
    fs.AddView(floor, Eigen::Vector3f(0, 0, 1.5f));
    std::vector<Eigen::Vector3f> above, below;
    for (float x = -0.4f; x <= 0.4f; x += 0.1f) {
        above.emplace_back(x, 0.2f, 0.6f);
        below.emplace_back(x, 0.2f, -0.4f);
    }
    EXPECT_GT(fs.FreeShare(above), 0.9f);
    EXPECT_EQ(fs.FreeShare(below), 0.0f);
}

// Points every 1 cm on the faces of the axis-aligned box [lo, hi].
void AddBoxSurface(PointCloud& cloud, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
    const float step = 0.01f;
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (float side : {lo[axis], hi[axis]}) {
            for (float a = lo[u]; a <= hi[u] + 1e-6f; a += step) {
                for (float b = lo[v]; b <= hi[v] + 1e-6f; b += step) {
                    Eigen::Vector3f p;
                    p[axis] = side;
                    p[u] = a;
                    p[v] = b;
                    cloud.points.push_back(p);
                }
            }
            if (hi[axis] == lo[axis]) break;
        }
    }
    cloud.width = static_cast<std::uint32_t>(cloud.points.size());
    cloud.height = 1;
}

TEST(FurnitureDetection, ASurfaceSharedAcrossClassesIsOnePieceAChairUnderATableIsNot) {
    // A table (1.2 x 0.8 m top at 0.72-0.75 m, four legs) and, in model frames centred on their
    // footprints, a chair (0.45 m seat at 0.45 m, legs, a back to 0.9 m) and a cabinet of the
    // table's size.
    PointCloud table, chair, cabinet;
    AddBoxSurface(table, {-0.6f, -0.4f, 0.72f}, {0.6f, 0.4f, 0.75f});
    for (float x : {-0.55f, 0.55f}) {
        for (float y : {-0.35f, 0.35f}) {
            AddBoxSurface(table, {x - 0.02f, y - 0.02f, 0.0f}, {x + 0.02f, y + 0.02f, 0.72f});
        }
    }
    AddBoxSurface(chair, {-0.225f, -0.225f, 0.43f}, {0.225f, 0.225f, 0.45f});
    for (float x : {-0.2f, 0.2f}) {
        for (float y : {-0.2f, 0.2f}) {
            AddBoxSurface(chair, {x - 0.015f, y - 0.015f, 0.0f}, {x + 0.015f, y + 0.015f, 0.43f});
        }
    }
    AddBoxSurface(chair, {0.2f, -0.225f, 0.45f}, {0.225f, 0.225f, 0.9f});
    AddBoxSurface(cabinet, {-0.6f, -0.4f, 0.0f}, {0.6f, 0.4f, 0.75f});
    const Eigen::Isometry3f at_table(Eigen::Translation3f(2.0f, 1.0f, 0.0f));
    // The chair pushed two thirds under the table's long side, its back outside the edge.
    const Eigen::Isometry3f under(Eigen::Translation3f(2.0f + 0.5f, 1.0f, 0.0f));
    const float with_chair = SharedSurfaceShare(table, at_table, chair, under, 0.05f);
    EXPECT_LT(with_chair, 0.15f);
    EXPECT_LT(SharedSurfaceShare(chair, under, table, at_table, 0.05f), 0.15f);
    // A cabinet model fitted where a table model was: one piece.
    EXPECT_GT(SharedSurfaceShare(table, at_table, cabinet, at_table, 0.05f), 0.6f);
    EXPECT_GT(SharedSurfaceShare(cabinet, at_table, table, at_table, 0.05f), 0.6f);
    // Moved apart, nothing is shared; a model shares all of its surface with itself.
    const Eigen::Isometry3f far(Eigen::Translation3f(6.0f, 1.0f, 0.0f));
    EXPECT_EQ(SharedSurfaceShare(table, at_table, cabinet, far, 0.05f), 0.0f);
    EXPECT_EQ(SharedSurfaceShare(chair, under, chair, under, 0.05f), 1.0f);
    // Bad input.
    EXPECT_EQ(SharedSurfaceShare(table, at_table, PointCloud{}, at_table, 0.05f), 0.0f);
    EXPECT_THROW(SharedSurfaceShare(table, at_table, chair, under, 0.0f), InvalidArgument);
    Eigen::Isometry3f bad = at_table;
    bad.translation().x() = std::nanf("");
    EXPECT_THROW(SharedSurfaceShare(table, bad, chair, under, 0.05f), InvalidArgument);
    FurnitureDetectionParams dp;
    dp.surface_overlap_distance = 0.0f;
    EXPECT_THROW(dp.Validate(), InvalidArgument);
}

TEST(FurnitureDetection, BadParametersAndInputAreRefused) {
    FurnitureDetectionParams dp;
    dp.max_overlap = 0.0f;
    EXPECT_THROW(dp.Validate(), InvalidArgument);
    dp = {};
    dp.num_threads = -1;
    EXPECT_THROW(dp.Validate(), InvalidArgument);
    dp = {};
    dp.fit_models = 0;
    EXPECT_THROW(dp.Validate(), InvalidArgument);
    dp = {};
    dp.fit.min_coverage = 1.5f;
    EXPECT_THROW(dp.Validate(), InvalidArgument);
    dp = {};
    dp.fit.checked_share = 0.0f;
    EXPECT_THROW(dp.Validate(), InvalidArgument);
    {
        auto to = SmallTraining();
        to.procedural_per_class = -1;
        EXPECT_THROW(to.Validate(), InvalidArgument);
    }
    // An untrained model, a view without a scan, a pose that is not finite.
    const FurnitureModel untrained;
    PointCloud scan;
    EXPECT_THROW(DetectFurniture({{&scan, Eigen::Isometry3f::Identity()}}, untrained, nullptr, {}),
                 InvalidArgument);
}

TEST(FurnitureDetection, EmptyScansGiveNoDetections) {
    const FurnitureModel model = TrainSmallModel();
    FurnitureDetectionParams dp;
    dp.verify = false;
    EXPECT_THROW(DetectFurniture({{nullptr, Eigen::Isometry3f::Identity()}}, model, nullptr, dp),
                 InvalidArgument);
    Eigen::Isometry3f bad = Eigen::Isometry3f::Identity();
    bad.translation().x() = std::nanf("");
    PointCloud empty;
    EXPECT_THROW(DetectFurniture({{&empty, bad}}, model, nullptr, dp), InvalidArgument);
    EXPECT_TRUE(
        DetectFurniture(std::vector<FurnitureView>{}, model, nullptr, dp).detections.empty());
    const auto r = DetectFurniture({{&empty, Eigen::Isometry3f::Identity()}}, model, nullptr, dp);
    EXPECT_TRUE(r.detections.empty());
    dp.verify = true;
    const FurnitureFitContext context(model, dp.fit);
    EXPECT_TRUE(DetectFurniture({{&empty, Eigen::Isometry3f::Identity()}}, model, &context, dp)
                    .detections.empty());
}

/// Points on the surface of an upright box [x0, x1] x [y0, y1] x [0, h] (no bottom), about
/// `step` apart, turned by `yaw` and moved to `at`.
PointCloud BoxSurface(float x0, float x1, float y0, float y1, float h, float step, float yaw,
                      const Eigen::Vector2f& at) {
    PointCloud c;
    const Eigen::Affine3f T = Eigen::Translation3f(at.x(), at.y(), 0.0f) *
                              Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ());
    for (float x = x0; x <= x1 + 1e-4f; x += step) {
        for (float y = y0; y <= y1 + 1e-4f; y += step) {
            for (float z = 0.0f; z <= h + 1e-4f; z += step) {
                const bool side = x < x0 + step / 2 || x > x1 - step / 2 || y < y0 + step / 2 ||
                                  y > y1 - step / 2;
                if (side || z > h - step / 2) c.points.push_back(T * Eigen::Vector3f(x, y, z));
            }
        }
    }
    c.width = static_cast<std::uint32_t>(c.points.size());
    return c;
}

// The shape evidence of the learned verifier: scan points of the piece the model was fitted to
// lie inside its footprint, up to its height and across its size; a piece twice as wide puts
// points beyond it; a table's legs and top leave its lower part nearly empty; no points give
// zeros whatever the model.
TEST(FurnitureShape, MeasuresThePieceAgainstTheFittedModel) {
    FurnitureCad cad;
    cad.cloud = BoxSurface(-0.25f, 0.25f, -0.4f, 0.4f, 0.8f, 0.02f, 0.0f, {0, 0});
    cad.extent = Eigen::Vector3f(0.5f, 0.8f, 0.8f);
    const float yaw = 0.7f;
    const Eigen::Vector2f at(2.0f, -1.0f);
    const Eigen::Affine3f T = Eigen::Translation3f(at.x(), at.y(), 0.0f) *
                              Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ());
    const PointCloud same = BoxSurface(-0.25f, 0.25f, -0.4f, 0.4f, 0.8f, 0.03f, yaw, at);
    const FurnitureShapeEvidence a = MeasureFurnitureShape(same, cad, T);
    EXPECT_FLOAT_EQ(a.inside_share, 1.0f);
    EXPECT_NEAR(a.top, 0.78f, 0.04f);  // the top's points lie at 0.78 m (3 cm rows)
    EXPECT_NEAR(a.top_ratio, 0.97f, 0.05f);
    EXPECT_NEAR(a.span_x, 0.9f, 0.1f);
    EXPECT_NEAR(a.span_y, 0.9f, 0.1f);
    EXPECT_NEAR(a.low_share, 0.25f * 0.8f * (2 * 0.5f + 2 * 0.8f) / (0.8f * 2.6f + 0.4f), 0.05f);
    EXPECT_EQ(a.beyond, 0.0f);

    // Twice as wide along the model's y: the points 10-30 cm beyond the footprint count.
    const PointCloud wide = BoxSurface(-0.25f, 0.25f, -1.2f, 0.4f, 0.8f, 0.03f, yaw, at);
    const FurnitureShapeEvidence b = MeasureFurnitureShape(wide, cad, T);
    EXPECT_LT(b.inside_share, 0.8f);
    EXPECT_GT(b.beyond, 0.1f);
    EXPECT_GT(b.span_y, 1.0f);

    // A table: a top at 0.75 m and four legs; nothing else below.
    PointCloud table = BoxSurface(-0.25f, 0.25f, -0.4f, 0.4f, 0.0f, 0.03f, 0.0f, {0, 0});
    for (auto& p : table.points) p.z() = 0.75f;
    for (float x : {-0.22f, 0.22f}) {
        for (float y : {-0.37f, 0.37f}) {
            for (float z = 0.0f; z < 0.75f; z += 0.03f) table.points.emplace_back(x, y, z);
        }
    }
    for (auto& p : table.points) p = T * p;
    table.width = static_cast<std::uint32_t>(table.points.size());
    const FurnitureShapeEvidence c = MeasureFurnitureShape(table, cad, T);
    EXPECT_LT(c.low_share, 0.1f);
    EXPECT_NEAR(c.top, 0.75f, 0.01f);

    // No points, or a non-finite pose: zeros; NaN points are skipped.
    const FurnitureShapeEvidence none = MeasureFurnitureShape(PointCloud{}, cad, T);
    EXPECT_EQ(none.inside_share, 0.0f);
    EXPECT_EQ(none.top, 0.0f);
    Eigen::Affine3f bad = T;
    bad(0, 3) = std::nanf("");
    EXPECT_EQ(MeasureFurnitureShape(same, cad, bad).inside_share, 0.0f);
    PointCloud with_nan = same;
    with_nan.points.push_back(Eigen::Vector3f::Constant(std::nanf("")));
    EXPECT_FLOAT_EQ(MeasureFurnitureShape(with_nan, cad, T).inside_share, 1.0f);
}

// Appends `pts` (world frame) to the view's cloud as one part, normals up.
void AddPart(FurnitureParts& view, const std::vector<Eigen::Vector3f>& pts) {
    FurniturePart part;
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    for (const auto& p : pts) {
        part.indices.push_back(static_cast<Index>(view.cloud.points.size()));
        view.cloud.points.push_back(p);
        view.cloud.normals.emplace_back(0.0f, 0.0f, 1.0f);
        sum += p;
    }
    part.centroid = sum / static_cast<float>(pts.size());
    view.parts.push_back(part);
}

// The piece's box: a table model 1.2 m long fitted to one end of a 1.8 m table grows to the table
// (its top and far legs are parts mostly within the model's footprint), its centre moves to the
// table's; a chair beside it (a part mostly outside) and a wall part do not count; a part reaching
// far beyond is cut at max_growth; without growth, and for a piece the model covers, the box is
// the model's; bad parameters are refused.
TEST(FurniturePiece, TheBoxGrowsToTheScannedPartsOfThePieceAndNotToItsNeighbours) {
    FurnitureCad cad;
    cad.cloud = BoxSurface(-0.6f, 0.6f, -0.4f, 0.4f, 0.75f, 0.03f, 0.0f, {0, 0});
    cad.extent = Eigen::Vector3f(1.2f, 0.8f, 0.75f);
    const float yaw = 0.4f;
    const Eigen::Vector2f at(1.0f, 2.0f);
    FurnitureFit fit;
    fit.cad = 0;
    fit.yaw = yaw;
    fit.T_world_model = Eigen::Translation3f(at.x(), at.y(), 0.0f) *
                        Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ());
    // The scan in the model's frame: a table from x = -0.6 to 1.2 (its top one part, each leg
    // one part), a chair part at x 1.3-1.7 beyond its end, and a wall part behind it.
    FurnitureParts view;
    auto add_part = [&](std::vector<Eigen::Vector3f> pts) {
        for (auto& p : pts) p = fit.T_world_model * p;
        AddPart(view, pts);
    };
    std::vector<Eigen::Vector3f> top, wall, chair;
    for (float x = -0.6f; x <= 1.2f + 1e-4f; x += 0.03f) {
        for (float y = -0.4f; y <= 0.4f + 1e-4f; y += 0.03f) top.emplace_back(x, y, 0.75f);
    }
    add_part(top);
    for (float x : {-0.57f, 1.17f}) {
        for (float y : {-0.37f, 0.37f}) {
            std::vector<Eigen::Vector3f> leg;
            for (float z = 0.0f; z < 0.72f; z += 0.03f) leg.emplace_back(x, y, z);
            add_part(leg);
        }
    }
    for (float x = 1.3f; x <= 1.7f; x += 0.03f) {
        for (float y = -0.2f; y <= 0.2f; y += 0.03f) chair.emplace_back(x, y, 0.45f);
    }
    add_part(chair);
    for (float x = -2.0f; x <= 3.0f; x += 0.05f) {
        for (float z = 0.0f; z <= 2.0f; z += 0.05f) wall.emplace_back(x, -0.45f, z);
    }
    add_part(wall);
    view.cloud.width = static_cast<std::uint32_t>(view.cloud.points.size());

    const FurniturePieceParams params;
    const Eigen::AlignedBox3f box = MeasureFurniturePiece({&view}, cad, fit, params);
    ASSERT_FALSE(box.isEmpty());
    EXPECT_NEAR(box.min().x(), -0.6f, 0.02f);
    EXPECT_NEAR(box.max().x(), 1.2f, 0.05f);   // grown to the table, not to the chair at 1.7
    EXPECT_NEAR(box.min().y(), -0.4f, 0.03f);  // the wall behind does not count
    EXPECT_NEAR(box.max().y(), 0.4f, 0.03f);
    EXPECT_NEAR(box.max().z(), 0.75f, 0.02f);
    const Eigen::Vector3f centre = fit.T_world_model * box.center();
    const Eigen::Vector3f table_centre = fit.T_world_model * Eigen::Vector3f(0.3f, 0.0f, 0.0f);
    EXPECT_LT((centre - table_centre).head<2>().norm(), 0.04f);
    // The centre it gives: moved with the box from the model's centre; without growth, the
    // model's centre.
    Eigen::AlignedBox3f piece_box;
    const Eigen::Vector2f piece_centre = FurniturePieceCentre({&view}, cad, fit, params, piece_box);
    EXPECT_TRUE(piece_box.isApprox(box));
    EXPECT_LT((piece_centre - table_centre.head<2>()).norm(), 0.04f);
    FurniturePieceParams no_growth;
    no_growth.grow = false;
    EXPECT_LT((FurniturePieceCentre({&view}, cad, fit, no_growth, piece_box) - at).norm(), 1e-5f);

    // At most max_growth of the model's length on a side.
    FurniturePieceParams tight;
    tight.max_growth = 0.25f;
    EXPECT_NEAR(MeasureFurniturePiece({&view}, cad, fit, tight).max().x(), 0.9f, 1e-4f);
    // Without growth, or with nothing beyond the model, the box is the model's.
    FurniturePieceParams off;
    off.grow = false;
    const Eigen::AlignedBox3f model_box = MeasureFurniturePiece({&view}, cad, fit, off);
    EXPECT_NEAR(model_box.max().x(), 0.6f, 0.01f);
    FurnitureFit covering = fit;
    covering.T_world_model = fit.T_world_model * Eigen::Translation3f(0.3f, 0.0f, 0.0f);
    cad.cloud = BoxSurface(-0.9f, 0.9f, -0.4f, 0.4f, 0.75f, 0.03f, 0.0f, {0, 0});
    const Eigen::AlignedBox3f same = MeasureFurniturePiece({&view}, cad, covering, params);
    EXPECT_NEAR(same.min().x(), -0.9f, 0.01f);
    EXPECT_NEAR(same.max().x(), 0.9f, 0.01f);
    // Deterministic; no views, no fit: the model's box or nothing.
    EXPECT_TRUE(MeasureFurniturePiece({&view}, cad, covering, params).isApprox(same));
    EXPECT_NEAR(MeasureFurniturePiece({}, cad, fit, params).max().x(), 0.9f, 0.01f);
    FurnitureFit none;
    EXPECT_TRUE(MeasureFurniturePiece({&view}, cad, none, params).isEmpty());
    FurniturePieceParams bad;
    bad.member_share = 0.0f;
    EXPECT_THROW(MeasureFurniturePiece({&view}, cad, fit, bad), InvalidArgument);
    bad = {};
    bad.max_growth = std::nanf("");
    EXPECT_THROW(MeasureFurniturePiece({&view}, cad, fit, bad), InvalidArgument);
}

// A box table model `length` long (x), 0.8 m deep and 0.75 m high, fitted unturned at `at`.
std::pair<FurnitureCad, FurnitureFit> TableModelFit(float length, const Eigen::Vector2f& at) {
    FurnitureCad cad;
    cad.cloud = BoxSurface(-length / 2, length / 2, -0.4f, 0.4f, 0.75f, 0.03f, 0.0f, {0, 0});
    cad.extent = Eigen::Vector3f(length, 0.8f, 0.75f);
    FurnitureFit fit;
    fit.cad = 0;
    fit.T_world_model = Eigen::Translation3f(at.x(), at.y(), 0.0f) * Eigen::Isometry3f::Identity();
    return {cad, fit};
}

// The piece's box shrinks: a table model 1.2 m long fitted over a 0.8 m table so that it reaches
// 0.4 m beyond its +x end. Where a sensor saw the floor beyond the table, the box shrinks to the
// table; without free space, or with a view that saw nothing beyond it, it stays the model's;
// it never shrinks inside the table's parts.
TEST(FurniturePiece, TheBoxShrinksToThePieceWhereTheScansSawFreeSpaceOnly) {
    const auto [cad, fit] = TableModelFit(1.2f, Eigen::Vector2f(0.2f, 0.0f));
    // The table, x from -0.4 to 0.4, y from -0.3 to 0.3: its top one part.
    FurnitureParts view;
    FurniturePart top;
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    for (float x = -0.4f; x <= 0.4f + 1e-4f; x += 0.03f) {
        for (float y = -0.3f; y <= 0.3f + 1e-4f; y += 0.03f) {
            top.indices.push_back(static_cast<Index>(view.cloud.points.size()));
            view.cloud.points.emplace_back(x, y, 0.75f);
            view.cloud.normals.emplace_back(0.0f, 0.0f, 1.0f);
            sum += view.cloud.points.back();
        }
    }
    top.centroid = sum / static_cast<float>(top.indices.size());
    view.parts.push_back(top);
    view.cloud.width = static_cast<std::uint32_t>(view.cloud.points.size());
    // A sensor 2.5 m in front of it at 1.5 m: the table top and the floor it does not hide.
    const Eigen::Vector3f sensor(0.0f, -2.5f, 1.5f);
    PointCloud seen = view.cloud;
    for (float x = -2.0f; x <= 2.0f; x += 0.02f) {
        for (float y = -2.0f; y <= 2.5f; y += 0.02f) {
            const Eigen::Vector3f at_top = sensor + 0.5f * (Eigen::Vector3f(x, y, 0.0f) - sensor);
            if (std::abs(at_top.x()) <= 0.4f && std::abs(at_top.y()) <= 0.3f) continue;
            seen.points.emplace_back(x, y, 0.0f);
        }
    }
    seen.width = static_cast<std::uint32_t>(seen.points.size());
    FurnitureFreeSpace free(0.05);
    free.AddView(seen, sensor);
    FurnitureFreeSpace top_only(0.05);  // a view of the table top alone: nothing beyond it seen
    top_only.AddView(view.cloud, sensor);

    const FurniturePieceParams params;
    const Eigen::AlignedBox3f model_box = MeasureFurniturePiece({&view}, cad, fit, params);
    EXPECT_NEAR(model_box.max().x(), 0.6f, 0.01f);  // without free space: the model's box
    const Eigen::AlignedBox3f box = MeasureFurniturePiece({&view}, cad, fit, params, {&free});
    EXPECT_NEAR(box.max().x() + 0.2f, 0.4f, 0.06f);  // in the world: the table's +x end
    EXPECT_GE(box.max().x() + 0.2f, 0.37f);          // not inside its top (98 % of its points)
    EXPECT_NEAR(box.min().x(), -0.6f, 0.01f);        // the -x end fits already
    EXPECT_GE(box.max().y(), 0.28f);                 // the y sides: not inside the top either
    EXPECT_LE(box.min().y(), -0.28f);
    Eigen::AlignedBox3f piece_box;
    const Eigen::Vector2f centre =
        FurniturePieceCentre({&view}, cad, fit, params, piece_box, {&free});
    EXPECT_TRUE(piece_box.isApprox(box));
    EXPECT_LT(std::abs(centre.x()), 0.04f);  // the table's centre, not the model's at 0.2
    EXPECT_TRUE(MeasureFurniturePiece({&view}, cad, fit, params, {&top_only}).isApprox(model_box));
    FurniturePieceParams no_shrink;
    no_shrink.shrink = false;
    EXPECT_TRUE(MeasureFurniturePiece({&view}, cad, fit, no_shrink, {&free}).isApprox(model_box));
    EXPECT_TRUE(MeasureFurniturePiece({&view}, cad, fit, params, {&free}).isApprox(box));
    FurniturePieceParams bad;
    bad.free_share = 0.0f;
    EXPECT_THROW(MeasureFurniturePiece({&view}, cad, fit, bad, {&free}), InvalidArgument);
    bad = {};
    bad.slice = -1.0f;
    EXPECT_THROW(MeasureFurniturePiece({&view}, cad, fit, bad), InvalidArgument);
}

TEST(FurniturePiece, TheBoxKeepsOutOfTheSpaceAMoreLikelyPieceTakes) {
    // A table model 1.8 m long fitted over a table 0.8 m long (x -0.9 to -0.1) and the top of a
    // cabinet beside it (x 0.3 to 0.9), which another detection explains.
    const auto [cad, fit] = TableModelFit(1.8f, Eigen::Vector2f(1.0f, -0.5f));
    FurnitureParts view;
    auto add_part = [&](float x0, float x1, float z) {
        std::vector<Eigen::Vector3f> pts;
        for (float x = x0; x <= x1 + 1e-4f; x += 0.03f) {
            for (float y = -0.35f; y <= 0.35f + 1e-4f; y += 0.03f)
                pts.push_back(fit.T_world_model * Eigen::Vector3f(x, y, z));
        }
        AddPart(view, pts);
    };
    add_part(-0.9f, -0.1f, 0.75f);  // the table's top
    add_part(0.3f, 0.9f, 0.8f);     // the cabinet's top
    view.cloud.width = static_cast<std::uint32_t>(view.cloud.points.size());
    const FurniturePieceParams params;
    // Without the cabinet's space the box keeps the model's length: the cabinet's top is a part
    // within the model's footprint, and no scan saw the floor between them free.
    const Eigen::AlignedBox3f alone = MeasureFurniturePiece({&view}, cad, fit, params);
    EXPECT_GE(alone.max().x(), 0.85f);
    FurnitureTakenSpace cabinet;
    cabinet.T_world_box = fit.T_world_model * Eigen::Translation3f(0.6f, 0.0f, 0.0f);
    cabinet.box = Eigen::AlignedBox3f(Eigen::Vector3f(-0.35f, -0.4f, 0.0f),
                                      Eigen::Vector3f(0.35f, 0.4f, 0.8f));
    EXPECT_TRUE(
        cabinet.Contains((fit.T_world_model * Eigen::Vector3f(0.5f, 0.2f, 0.0f)).head<2>()));
    EXPECT_FALSE(
        cabinet.Contains((fit.T_world_model * Eigen::Vector3f(0.1f, 0.0f, 0.0f)).head<2>()));
    // With it the cabinet's top is no part of the table, and the box shrinks through the
    // cabinet's space up to the gap, where nothing says the space is free.
    const Eigen::AlignedBox3f box = MeasureFurniturePiece({&view}, cad, fit, params, {}, {cabinet});
    EXPECT_LE(box.max().x(), 0.3f);
    EXPECT_GE(box.max().x(), 0.2f);
    EXPECT_NEAR(box.min().x(), -0.9f, 0.01f);
    Eigen::AlignedBox3f piece_box;
    const Eigen::Vector2f centre =
        FurniturePieceCentre({&view}, cad, fit, params, piece_box, {}, {cabinet});
    EXPECT_TRUE(piece_box.isApprox(box));
    EXPECT_LT(centre.x(), 1.0f - 0.3f);  // towards the table, away from the model's centre
    // A piece elsewhere, or growth turned off, changes nothing.
    FurnitureTakenSpace far = cabinet;
    far.T_world_box = Eigen::Translation3f(5.0f, 5.0f, 0.0f) * Eigen::Isometry3f::Identity();
    EXPECT_TRUE(MeasureFurniturePiece({&view}, cad, fit, params, {}, {far}).isApprox(alone));
    FurniturePieceParams off;
    off.grow = false;
    EXPECT_NEAR(MeasureFurniturePiece({&view}, cad, fit, off, {}, {cabinet}).max().x(), 0.9f,
                0.01f);
    // An empty box takes no space.
    EXPECT_FALSE(FurnitureTakenSpace{}.Contains(Eigen::Vector2f::Zero()));
}

// A wall takes a band of floor along its plane: the part of the wall seen below a table's top,
// within the fitted model's footprint, is no part of the table.
TEST(FurniturePiece, TheBoxKeepsOutOfAWallsBand) {
    const auto [cad, fit] = TableModelFit(1.2f, Eigen::Vector2f(0.0f, 0.0f));
    FurnitureParts view;
    std::vector<Eigen::Vector3f> top, below;  // the table's top; the wall at y = -0.48 below it
    for (float x = -0.6f; x <= 0.6f + 1e-4f; x += 0.03f) {
        for (float y = -0.4f; y <= 0.4f + 1e-4f; y += 0.03f) top.emplace_back(x, y, 0.75f);
        for (float z = 0.0f; z <= 0.7f; z += 0.03f) below.emplace_back(x, -0.48f, z);
    }
    AddPart(view, top);
    AddPart(view, below);
    view.cloud.width = static_cast<std::uint32_t>(view.cloud.points.size());
    FurnitureWall wall;
    wall.point = Eigen::Vector2f(0.0f, -0.48f);
    wall.normal = Eigen::Vector2f(0.0f, 1.0f);  // towards the room
    wall.lo = -3.0f, wall.hi = 3.0f;            // along (-1, 0)
    const FurnitureTakenSpace band = FurnitureWallBand(wall, 0.05f);
    EXPECT_TRUE(band.Contains(Eigen::Vector2f(1.0f, -0.45f)));
    EXPECT_TRUE(band.Contains(Eigen::Vector2f(-2.9f, -0.52f)));
    EXPECT_FALSE(band.Contains(Eigen::Vector2f(1.0f, -0.40f)));   // 8 cm in front of it
    EXPECT_FALSE(band.Contains(Eigen::Vector2f(-3.5f, -0.48f)));  // beyond its end
    EXPECT_THROW(FurnitureWallBand(wall, 0.0f), InvalidArgument);
    const FurniturePieceParams params;
    // Without the band the wall's part grows the box to the wall; with it the box stays the
    // table's.
    EXPECT_NEAR(MeasureFurniturePiece({&view}, cad, fit, params).min().y(), -0.48f, 0.01f);
    EXPECT_NEAR(MeasureFurniturePiece({&view}, cad, fit, params, {}, {band}).min().y(), -0.4f,
                0.01f);
}

// Walls among a view's parts: a long upright part above every piece is a wall facing the sensor,
// even with a few stray points (a corner's, an object's touching it) in its part; two walls
// grown into one part around a corner, a short part and a low one are no wall.
TEST(FurnitureWalls, AWallKeepsItsStrayPointsAndACornerIsNoWall) {
    FurnitureParts v;
    v.sensor_origin = Eigen::Vector3f(0.0f, 0.0f, 1.5f);
    auto add_part = [&](const std::vector<Eigen::Vector3f>& pts) {
        FurniturePart part;
        for (const auto& p : pts) {
            part.indices.push_back(static_cast<Index>(v.cloud.points.size()));
            v.cloud.points.push_back(p);
            part.top = std::max(part.top, p.z());
        }
        v.parts.push_back(part);
    };
    std::vector<Eigen::Vector3f> wall, corner, low, narrow;
    for (float x = -2.0f; x <= 2.0f; x += 0.05f) {
        for (float z = 0.1f; z <= 2.2f; z += 0.05f) {
            wall.emplace_back(x, 3.0f + 0.005f * std::sin(20.0f * x), z);
            if (z < 1.0f) low.emplace_back(x, -3.0f, z);
        }
    }
    for (int k = 0; k < 8; ++k) wall.emplace_back(-2.0f, 3.0f - 0.1f * k, 2.0f);  // the corner's
    for (float t = 0.0f; t <= 2.0f; t += 0.05f) {
        for (float z = 0.1f; z <= 2.2f; z += 0.1f) {
            corner.emplace_back(-4.0f, -2.0f + t, z);  // along y ...
            corner.emplace_back(-4.0f + t, -2.0f, z);  // ... and along x, one part
        }
    }
    for (float x = 3.0f; x <= 3.5f; x += 0.05f) {
        for (float z = 0.1f; z <= 2.2f; z += 0.1f) narrow.emplace_back(x, 1.0f, z);
    }
    add_part(wall);
    add_part(corner);
    add_part(low);
    add_part(narrow);
    v.cloud.width = static_cast<std::uint32_t>(v.cloud.points.size());
    const auto walls = FindFurnitureWalls(v, 1.9f, 1.0f);
    ASSERT_EQ(walls.size(), 1u);
    EXPECT_NEAR(walls[0].normal.y(), -1.0f, 1e-3f);  // towards the sensor
    EXPECT_NEAR(walls[0].Distance(Eigen::Vector2f(0.5f, 2.7f)), 0.3f, 0.02f);
    EXPECT_NEAR(walls[0].hi - walls[0].lo, 4.0f, 0.1f);
    EXPECT_TRUE(walls[0].Behind(Eigen::Vector2f(0.0f, 3.5f), 0.2f));
    EXPECT_TRUE(std::isnan(walls[0].Distance(Eigen::Vector2f(5.0f, 2.7f))));  // beside it
    EXPECT_TRUE(FindFurnitureWalls(v, 2.5f, 1.0f).empty());  // nothing reaches 2.5 m
    EXPECT_TRUE(FindFurnitureWalls(FurnitureParts{}, 1.9f, 1.0f).empty());
    EXPECT_THROW(FindFurnitureWalls(v, 1.9f, 0.0f), InvalidArgument);
    EXPECT_THROW(FindFurnitureWalls(v, std::nanf(""), 1.0f), InvalidArgument);
}

// The learned verifier: trained on the fits in three simulated rooms, it ranks the right fits of
// two other rooms above the wrong ones; it travels in the model file (version 1 files, without
// one, still load); detection uses its confidence as the score and rejects below
// min_confidence; bad verifiers and parameters are refused.
TEST(FurnitureVerifier, RanksTheFitsOfUnseenRoomsAndTravelsInTheModelFile) {
    auto to = SmallTraining();
    to.verifier_rooms = 3;
    to.verifier_spec = "rtrees:trees=50";
    const auto pieces = training::FurnitureTrainingPieces(to);
    FurnitureModel model;
    ASSERT_TRUE(training::TrainFurnitureModel(pieces, to, model));
    ASSERT_NE(model.verifier(), nullptr);
    EXPECT_EQ(model.verifier()->feature_names(), FurnitureVerifierFeatureNames(model));

    auto held = to;
    held.verifier_rooms = 2;
    held.verifier_seed = 7000;
    const ml::Dataset rows = training::CollectFurnitureVerifierRows(model, held);
    const int right = rows.FindClass("right");
    std::vector<std::pair<float, bool>> scored;
    const ml::FeatureMatrix p = model.verifier()->PredictProba(rows);
    const auto& names = model.verifier()->class_names();
    const auto col = std::find(names.begin(), names.end(), "right") - names.begin();
    for (std::size_t i = 0; i < rows.rows(); ++i)
        scored.push_back({p(static_cast<Eigen::Index>(i), col), rows.labels[i] == right});
    // Area under the ROC curve: the chance that a right fit outranks a wrong one.
    double pairs = 0.0, above = 0.0;
    for (const auto& a : scored) {
        for (const auto& b : scored) {
            if (!a.second || b.second) continue;
            pairs += 1.0;
            above += a.first > b.first ? 1.0 : (a.first == b.first ? 0.5 : 0.0);
        }
    }
    ASSERT_GT(pairs, 0.0) << "the held-out rooms need right and wrong fits";
    EXPECT_GT(above / pairs, 0.75);

    // Model file round trip; a version 1 file has no verifier.
    const auto dir = std::filesystem::temp_directory_path() / "multicue_test_furniture_verifier";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    model.Save(dir / "m.mcfm");
    const FurnitureModel loaded = FurnitureModel::Load(dir / "m.mcfm");
    ASSERT_NE(loaded.verifier(), nullptr);
    EXPECT_TRUE(loaded.verifier()->PredictProba(rows).isApprox(p));
    FurnitureModel bare = model;
    bare.SetVerifier(nullptr);
    bare.Save(dir / "bare.mcfm");
    std::string payload = ml::UnwrapContainer(ml::ReadBytes(dir / "bare.mcfm"), "MCFURNIT", 2,
                                              "furniture model", "bare");
    payload.pop_back();  // the verifier flag
    io::WriteFileAtomically(dir / "v1.mcfm", [&](std::ostream& os) {
        os << ml::WrapContainer("MCFURNIT", 1, payload);
    });
    const FurnitureModel v1 = FurnitureModel::Load(dir / "v1.mcfm");
    EXPECT_EQ(v1.verifier(), nullptr);
    EXPECT_EQ(v1.cads().size(), model.cads().size());

    // Detection in a room of neither set.
    const auto room =
        training::SimulateFurnitureRoom({}, sim::FurnitureSource({}, 1.0f), 2, to, 7100);
    std::vector<FurnitureView> views;
    for (std::size_t v = 0; v < room.scans.size(); ++v)
        views.push_back({&room.scans[v], room.T_world_sensor[v]});
    FurnitureDetectionParams dp;
    dp.num_threads = 2;
    const FurnitureFitContext context(model, dp.fit);
    const FurnitureScene scene = PrepareFurnitureScene(views, model, dp);
    const auto det = DetectFurniture(scene, {}, model, &context, dp);
    std::size_t confident = 0;
    for (const auto& d : det.detections) {
        EXPECT_GE(d.confidence, dp.min_confidence);
        EXPECT_EQ(d.score, d.confidence);
    }
    for (const auto& d : det.rejected) {
        if (d.rejection == "confidence") {
            EXPECT_LT(d.confidence, dp.min_confidence);
        }
        confident += d.confidence >= 0.0f ? 1 : 0;
    }
    EXPECT_GT(det.detections.size() + confident, 0u);
    // A single scan has its own cut.
    dp.min_confidence_single = 0.6f;
    for (const auto& d : DetectFurniture(scene, {0}, model, &context, dp).rejected) {
        if (d.rejection == "confidence") {
            EXPECT_LT(d.confidence, 0.6f);
        }
    }
    for (const auto& d : DetectFurniture(scene, {0}, model, &context, dp).detections)
        EXPECT_GE(d.confidence, 0.6f);
    dp.min_confidence = 1.0f;
    for (const auto& d : DetectFurniture(scene, {}, model, &context, dp).detections)
        EXPECT_EQ(d.confidence, 1.0f);
    dp.learned = false;
    const auto rules = DetectFurniture(scene, {}, model, &context, dp);
    for (const auto* list : {&rules.detections, &rules.rejected}) {
        for (const auto& d : *list) {
            EXPECT_EQ(d.confidence, -1.0f);
            EXPECT_NE(d.rejection, "confidence");
        }
    }

    // A verifier of an older model, trained on fewer features, gets those.
    const std::vector<std::string> few = {"coverage", "explained", "free_share",
                                          "class_" + model.classes()[0].name};
    ml::Dataset few_rows = ml::Dataset::WithBlocks({{"fit", few}});
    const FurnitureDetection* fitted = nullptr;
    for (const auto* list : {&rules.detections, &rules.rejected}) {
        for (const auto& d : *list) {
            if (!d.fitted) continue;
            fitted = &d;
            few_rows.AppendRow(FurnitureVerifierFeatures(d, model, few),
                               d.fit.coverage >= 0.6f ? "right" : "wrong");
        }
    }
    ASSERT_NE(fitted, nullptr);
    few_rows.ClassId("right");
    few_rows.ClassId("wrong");
    std::shared_ptr<ml::Classifier> older = ml::CreateClassifier("rtrees:trees=5");
    older->Fit(few_rows);
    FurnitureModel with_older = model;
    with_older.SetVerifier(older);
    dp.learned = true;
    dp.min_confidence = 0.4f;
    const FurnitureFitContext older_context(with_older, dp.fit);
    for (const auto& d : DetectFurniture(scene, {}, with_older, &older_context, dp).detections)
        EXPECT_GE(d.confidence, dp.min_confidence);
    const auto some = FurnitureVerifierFeatures(*fitted, model, {few[1], few[0]});
    const auto full = FurnitureVerifierFeatures(*fitted, model);
    const auto all_names = FurnitureVerifierFeatureNames(model);
    ASSERT_EQ(full.size(), all_names.size());
    const auto at = [&](const std::string& n) {
        return full[static_cast<std::size_t>(std::find(all_names.begin(), all_names.end(), n) -
                                             all_names.begin())];
    };
    EXPECT_EQ(some, (std::vector<float>{at(few[1]), at(few[0])}));
    EXPECT_THROW(FurnitureVerifierFeatures(*fitted, model, {"coverage", "no_such_feature"}),
                 InvalidArgument);

    // Bad verifiers and parameters.
    EXPECT_THROW(bare.SetVerifier(ml::CreateClassifier("rtrees:trees=5")), InvalidArgument);
    ml::Dataset other = ml::Dataset::WithColumns(2);
    for (int i = 0; i < 20; ++i) {
        const float x[2] = {static_cast<float>(i), static_cast<float>(i % 3)};
        other.AppendRow(x, i < 10 ? "yes" : "no");
    }
    std::shared_ptr<ml::Classifier> yes_no = ml::CreateClassifier("rtrees:trees=5");
    yes_no->Fit(other);
    EXPECT_THROW(bare.SetVerifier(yes_no), InvalidArgument);
    for (int i = 0; i < 20; ++i) other.labels[static_cast<std::size_t>(i)] = i < 10 ? 0 : 1;
    other.class_names = {"right", "wrong"};
    std::shared_ptr<ml::Classifier> narrow = ml::CreateClassifier("rtrees:trees=5");
    narrow->Fit(other);
    bare.SetVerifier(narrow);  // the classes are right, the features are not
    dp = {};
    const FurnitureFitContext bare_context(bare, dp.fit);
    EXPECT_THROW(DetectFurniture(scene, {}, bare, &bare_context, dp), InvalidArgument);
    // Rows of other features are no verifier's; the held-out rows refit one.
    EXPECT_THROW(training::FitFurnitureVerifier(model, other, to), DataError);
    const auto refit = training::FitFurnitureVerifier(model, rows, to);
    EXPECT_EQ(refit->feature_names(), FurnitureVerifierFeatureNames(model));
    dp.min_confidence = 1.5f;
    EXPECT_THROW(dp.Validate(), InvalidArgument);
    dp = {};
    dp.min_confidence_single = -0.1f;
    EXPECT_THROW(dp.Validate(), InvalidArgument);
    auto bad = to;
    bad.verifier_rooms = -1;
    EXPECT_THROW(bad.Validate(), InvalidArgument);
    bad = to;
    bad.verifier_spec = "oracle";
    EXPECT_THROW(bad.Validate(), InvalidArgument);
    std::filesystem::remove_all(dir);
}

// Verifier rows from library pieces: rooms of each half of the training library's pieces, fitted
// by a stand-in model of the procedural pieces and the other half, give right and wrong fits, the
// same for the same options; nothing without library pieces or with no rooms; rows of other
// features and a negative room count are refused.
TEST(FurnitureVerifier, LibraryRoomsAreFittedByAModelThatNeverSawTheirPieces) {
    auto to = SmallTraining();
    to.views.views = 4;
    std::vector<sim::FurniturePiece> pieces = training::FurnitureTrainingPieces(to);
    const std::size_t procedural = pieces.size();
    int k = 0;
    for (const std::string category : {"table", "table", "cabinet"}) {
        sim::StreamRng rng(91 + k, std::hash<std::string>{}(category)&0xffff);
        sim::FurniturePiece p = sim::MakeProceduralFurniture(category, rng);
        p.id = "library/" + category + std::to_string(k++);
        EXPECT_FALSE(training::IsProceduralFurniture(p));
        pieces.push_back(std::move(p));
    }
    EXPECT_TRUE(training::IsProceduralFurniture(pieces.front()));
    const training::FurnitureLibraryHalves split = training::SplitFurnitureLibrary(pieces);
    EXPECT_EQ(split.procedural.size(), procedural);
    ASSERT_EQ(split.library[0].size(), 2u);  // the first table and the cabinet
    ASSERT_EQ(split.library[1].size(), 1u);
    EXPECT_EQ(split.library[1][0].id, "library/table1");
    FurnitureModel model;
    ASSERT_TRUE(training::TrainFurnitureModel(pieces, to, model));
    auto empty = [&] {
        return ml::Dataset::WithBlocks({{"fit", FurnitureVerifierFeatureNames(model)}});
    };
    // No rooms: nothing appended.
    to.verifier_library_rooms = 0;
    ml::Dataset rows = empty();
    training::AppendFurnitureLibraryVerifierRows(rows, model, pieces, to);
    EXPECT_EQ(rows.rows(), 0u);
    to.verifier_library_rooms = 2;  // one room per half
    to.verifier_library_seed = 7200;
    training::AppendFurnitureLibraryVerifierRows(rows, model, pieces, to);
    ASSERT_GT(rows.rows(), 0u);
    const int right = rows.FindClass("right");
    const auto n_right = std::count(rows.labels.begin(), rows.labels.end(), right);
    EXPECT_GT(n_right, 0) << "the stand-in models fit some library pieces right";
    EXPECT_LT(static_cast<std::size_t>(n_right), rows.rows());
    for (const auto g : rows.groups) EXPECT_TRUE(g == 7200 || g == 7201) << g;
    EXPECT_GT(std::count(rows.groups.begin(), rows.groups.end(), 7201), 0) << "both halves";
    ml::Dataset again = empty();
    training::AppendFurnitureLibraryVerifierRows(again, model, pieces, to);
    EXPECT_EQ(again.values, rows.values);
    EXPECT_EQ(again.labels, rows.labels);
    // Procedural pieces alone: no library rooms.
    const std::vector<sim::FurniturePiece> only_procedural(pieces.begin(),
                                                           pieces.begin() + procedural);
    ml::Dataset none = empty();
    training::AppendFurnitureLibraryVerifierRows(none, model, only_procedural, to);
    EXPECT_EQ(none.rows(), 0u);
    ml::Dataset other = ml::Dataset::WithColumns(3);
    EXPECT_THROW(training::AppendFurnitureLibraryVerifierRows(other, model, pieces, to),
                 InvalidArgument);
    to.verifier_library_rooms = -1;
    EXPECT_THROW(to.Validate(), InvalidArgument);
}

/// Exit status of the CLI with `args`.
int Cli(const std::string& args) {
    const int rc =
        std::system((std::string(test::CliPath()) + " " + args + " 2>/dev/null").c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(MapFurnitureCli, RefusesBadParametersAndScansWithoutASensorPose) {
    const auto dir = std::filesystem::temp_directory_path() / "multicue_test_map_furniture";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    PointCloud scan;
    for (int i = 0; i < 100; ++i) scan.points.emplace_back(0.01f * i, 0.0f, 0.5f);
    scan.width = 100;
    io::WritePointCloud(dir / "no_pose.pcd", scan);
    const std::string model = (dir / "missing.mcfm").string();
    const std::string out = (dir / "out").string();
    // Parameters are checked before anything is read or trained.
    EXPECT_NE(Cli("map furniture " + (dir / "no_pose.pcd").string() + " --model " + model +
                  " --out " + out + " --min-coverage 2"),
              0);
    EXPECT_NE(Cli("map furniture " + (dir / "no_pose.pcd").string() + " --model " + model +
                  " --out " + out + " --min-confidence 1.5"),
              0);
    EXPECT_NE(Cli("map furniture " + (dir / "no_pose.pcd").string() + " --model " + model +
                  " --out " + out + " --fit-models 0"),
              0);
    EXPECT_NE(Cli("map furniture " + (dir / "no_pose.pcd").string() + " --model " + model +
                  " --out " + out),
              0);
    EXPECT_FALSE(std::filesystem::exists(model));  // nothing trained for a bad scan
    EXPECT_FALSE(std::filesystem::exists(dir / "out" / "detections.json"));
    EXPECT_NE(Cli("map furniture " + (dir / "absent.pcd").string() + " --model " + model +
                  " --out " + out),
              0);
    std::filesystem::remove_all(dir);
}

// train furniture writes a model, detect furniture reads it and writes result.json, models.ply
// and report.html; a missing model is an error, not a training run.
TEST(DetectFurnitureCli, TrainThenDetectWritesTheResultAndTheReport) {
    const auto dir = std::filesystem::temp_directory_path() / "multicue_test_detect_furniture";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const std::string rooms = (dir / "rooms").string(), model = (dir / "m.mcfm").string();
    ASSERT_EQ(Cli("simulate furniture --out " + rooms +
                  " --rooms 1 --heads 1 --types office --split procedural -q"),
              0);
    const std::string scan = (dir / "rooms" / "room_00_scan_00.pcd").string();
    EXPECT_NE(
        Cli("detect furniture " + scan + " --model " + model + " --out " + (dir / "out").string()),
        0);  // no model yet: refused, nothing trained
    EXPECT_FALSE(std::filesystem::exists(model));
    EXPECT_NE(Cli("train furniture --out " + model + " --views 0"), 0);
    EXPECT_NE(Cli("train furniture --out " + model + " --features some"), 0);
    EXPECT_NE(Cli("train furniture --out " + model + " --verifier-rooms -1"), 0);
    EXPECT_NE(Cli("train furniture --out " + model + " --verifier-classifier oracle"), 0);
    EXPECT_NE(Cli("train --views 1"), 0);  // the part-graph training still needs --out
    ASSERT_EQ(Cli("train furniture --out " + model +
                  " --meshes '' --kitchen '' --procedural 1 --views 4 --words 8 --cad-spacing 0.1 "
                  "--verifier-rooms 0 -q"),
              0);
    const FurnitureModel m = FurnitureModel::Load(model);
    EXPECT_EQ(m.classes().size(), 4u);
    ASSERT_EQ(Cli("detect furniture " + scan + " --model " + model + " --out " +
                  (dir / "out").string() + " -q"),
              0);
    const auto result = nlohmann::json::parse(io::ReadFileBytes(dir / "out" / "result.json"));
    EXPECT_TRUE(result["detections"].is_array());
    EXPECT_TRUE(result["rejected"].is_array());
    EXPECT_GT(result["detections"].size() + result["rejected"].size(), 0u);
    std::size_t fitted = 0;
    for (const auto* list : {&result["detections"], &result["rejected"]}) {
        for (const auto& d : *list) {
            if (!d.contains("cad_model")) continue;  // not fitted
            ++fitted;
            ASSERT_TRUE(d.contains("shape"));
            EXPECT_GE(d["shape"]["inside_share"].get<double>(), 0.0);
            EXPECT_LE(d["shape"]["inside_share"].get<double>(), 1.0);
            EXPECT_TRUE(d["shape"].contains("beyond"));
        }
    }
    EXPECT_GT(fitted, 0u);
    const std::string report = io::ReadFileBytes(dir / "out" / "report.html");
    EXPECT_NE(report.find("<svg"), std::string::npos);
    EXPECT_NE(report.find("</html>"), std::string::npos);
    ASSERT_EQ(Cli("detect furniture " + scan + " --model " + model + " --out " +
                  (dir / "out2").string() + " --no-report -q"),
              0);
    EXPECT_FALSE(std::filesystem::exists(dir / "out2" / "report.html"));
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace multicue
