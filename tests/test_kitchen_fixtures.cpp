// Fixture evidence and fronts between outlines on small synthetic kitchens: the local background
// of a face (closed form), one evidence row per candidate with the handle's measured shape, a
// fixture classifier trained on synthetic rows deciding what is a fixture, fronts bounded by the
// gaps around a door, fronts without fixtures cut from a face along its gaps, image edges of an
// organized scan, the room structure and the fixtures on any thread count, and bad parameters.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <set>

#include "kitchen_test_data.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/mapping/fixture_evidence.hpp"
#include "multicue/mapping/fixtures.hpp"
#include "multicue/mapping/front_edges.hpp"
#include "multicue/mapping/fronts.hpp"
#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/mapping/room_structure.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/sim/kitchen_procedural.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/training/kitchen_scan_truth.hpp"
#include "multicue/training/kitchen_training.hpp"

namespace multicue {
namespace {

using namespace mapping;

/// Adds the ground-truth field `semantic` to the synthetic kitchen: its handle points (standing
/// more than 1 cm out of the face y = 2.4, below the worktop) are handles, the rest none.
void AddHandleTruth(PointCloud& c) {
    ExtraField f;
    f.name = "semantic";
    f.type = 'U';
    f.size = 1;
    f.data.assign(c.size(), 0);
    for (std::size_t i = 0; i < c.size(); ++i) {
        const Eigen::Vector3f& p = c.points[i];
        if (p.y() < 2.39f && p.y() > 2.3f && p.z() < 0.88f && p.x() > 0.3f && p.x() < 2.7f) {
            f.data[i] = static_cast<std::uint8_t>(sim::KitchenClass::kHandle);
        }
    }
    c.extra_fields.push_back(std::move(f));
}

TEST(FixtureEvidence, LocalBackgroundOfAFaceWithAProudDoor) {
    // A face at height 0 with a door standing 2 cm proud (u 0.3 .. 0.9) and a 4 cm bump on it.
    FaceSamples s;
    for (int i = 0; i <= 120; ++i) {
        for (int j = 0; j <= 60; ++j) {
            const Eigen::Vector2f q(0.01f * static_cast<float>(i), 0.01f * static_cast<float>(j));
            float h = q.x() >= 0.3f && q.x() <= 0.9f ? 0.02f : 0.0f;
            const bool bump = std::abs(q.x() - 0.6f) < 0.015f && std::abs(q.y() - 0.3f) < 0.05f;
            if (bump) h += 0.04f;
            s.points.push_back(static_cast<Index>(s.q.size()));
            s.q.push_back(q);
            s.height.push_back(h);
            s.appearance.push_back(100.0f);
            s.sigma.push_back(0.002f);
            s.range.push_back(1.5f);
        }
    }
    ComputeFaceResiduals(s, 0.03f, 3, 2);
    ASSERT_EQ(s.residual.size(), s.size());
    for (std::size_t k = 0; k < s.size(); ++k) {
        const Eigen::Vector2f& q = s.q[k];
        const bool bump = std::abs(q.x() - 0.6f) < 0.015f && std::abs(q.y() - 0.3f) < 0.05f;
        // Well inside the door or the frame the background is the surface itself; the bump
        // stands 4 cm out of the door, not 6 cm out of the face plane.
        if (bump) {
            EXPECT_NEAR(s.residual[k], 0.04f, 0.005f) << q.transpose();
        } else if (std::abs(q.x() - 0.3f) > 0.12f && std::abs(q.x() - 0.9f) > 0.12f) {
            EXPECT_NEAR(s.residual[k], 0.0f, 1e-4f) << q.transpose();
        }
    }
    EXPECT_THROW(ComputeFaceResiduals(s, 0.0f, 3), InvalidArgument);
    EXPECT_THROW(ComputeFaceResiduals(s, 0.03f, -1), InvalidArgument);
    FaceSamples empty;
    EXPECT_NO_THROW(ComputeFaceResiduals(empty, 0.03f, 3));
    EXPECT_TRUE(empty.residual.empty());
}

TEST(FixtureEvidence, AppearanceContrastMeasuresGreyAndChroma) {
    // A flat face of grey level 100 and chroma (10, 10) with a 4 x 4 cm patch of the same grey
    // level and chroma (60, -40) at its middle.
    FaceSamples s;
    for (int i = 0; i < 60; ++i) {
        for (int j = 0; j < 60; ++j) {
            const Eigen::Vector2f q(0.01f * static_cast<float>(i), 0.01f * static_cast<float>(j));
            const bool patch = (q - Eigen::Vector2f(0.3f, 0.3f)).cwiseAbs().maxCoeff() < 0.02f;
            s.points.push_back(static_cast<Index>(s.q.size()));
            s.q.push_back(q);
            s.height.push_back(0.0f);
            s.appearance.push_back(100.0f);
            s.chroma.push_back(patch ? Eigen::Vector2f(60, -40) : Eigen::Vector2f(10, 10));
            s.sigma.push_back(0.002f);
            s.range.push_back(1.5f);
        }
    }
    EXPECT_TRUE(std::isnan(AppearanceContrast(s, 3).front()));  // no grid yet
    ComputeFaceResiduals(s, 0.03f, 3, 2);
    const std::vector<float> colour = AppearanceContrast(s, 3);
    ASSERT_EQ(colour.size(), s.size());
    for (std::size_t k = 0; k < s.size(); ++k) {
        const bool patch = (s.q[k] - Eigen::Vector2f(0.3f, 0.3f)).cwiseAbs().maxCoeff() < 0.02f;
        EXPECT_NEAR(colour[k], patch ? std::hypot(50.0f, 50.0f) : 0.0f, 1e-3f);
    }
    // Grey alone does not see it; a sample without appearance has no contrast.
    FaceSamples grey = s;
    grey.chroma.clear();
    grey.appearance[0] = std::numeric_limits<float>::quiet_NaN();
    const std::vector<float> level = AppearanceContrast(grey, 3);
    EXPECT_TRUE(std::isnan(level[0]));
    for (std::size_t k = 1; k < s.size(); ++k) EXPECT_NEAR(level[k], 0.0f, 1e-3f);
}

TEST(RoomStructure, TheSameOnAnyThreadCount) {
    const test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    RoomStructureParams p;
    p.num_threads = 1;
    const RoomStructure one = SegmentRoomStructure(k.cloud, RoomFrame{}, p);
    ASSERT_GE(one.components.size(), 4u);
    std::set<int> axes;
    for (const auto& c : one.components) axes.insert(c.axis);
    EXPECT_EQ(axes.size(), 3u);  // planes of every axis, joined from parallel work
    for (const int threads : {2, 0}) {
        p.num_threads = threads;
        const RoomStructure s = SegmentRoomStructure(k.cloud, RoomFrame{}, p);
        ASSERT_EQ(s.components.size(), one.components.size());
        for (std::size_t c = 0; c < s.components.size(); ++c) {
            EXPECT_EQ(s.components[c].indices, one.components[c].indices);
            EXPECT_EQ(s.components[c].label, one.components[c].label);
            EXPECT_EQ(s.components[c].area, one.components[c].area);
            EXPECT_EQ(s.components[c].plane, one.components[c].plane);
        }
        EXPECT_EQ(s.point_component, one.point_component);
        EXPECT_EQ(s.plane_axis, one.plane_axis);
        EXPECT_EQ(s.floor_height, one.floor_height);
    }
    p.num_threads = -1;
    EXPECT_THROW(SegmentRoomStructure(k.cloud, RoomFrame{}, p), InvalidArgument);
}

TEST(Fixtures, TheSameOnAnyThreadCount) {
    const test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    const RoomStructure s = SegmentRoomStructure(k.cloud, RoomFrame{}, {});
    FixtureParams p;
    p.num_threads = 1;
    p.min_contrast = 40.0f;  // the grey-level candidates too
    const FixtureResult one = DetectFixtures(k.cloud, RoomFrame{}, s, p);
    ASSERT_GE(one.candidates.size(), 2u);
    auto same_floats = [](const std::vector<float>& a, const std::vector<float>& b) {
        return a.size() == b.size() &&
               std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
    };
    for (const int threads : {2, 0}) {
        p.num_threads = threads;
        const FixtureResult r = DetectFixtures(k.cloud, RoomFrame{}, s, p);
        ASSERT_EQ(r.candidates.size(), one.candidates.size());
        for (std::size_t c = 0; c < r.candidates.size(); ++c) {
            EXPECT_EQ(FixtureFeatureRow(r.candidates[c].evidence),
                      FixtureFeatureRow(one.candidates[c].evidence));
            EXPECT_EQ(r.candidates[c].accepted, one.candidates[c].accepted);
            EXPECT_EQ(r.candidates[c].fixture.center, one.candidates[c].fixture.center);
        }
        ASSERT_EQ(r.fixtures.size(), one.fixtures.size());
        ASSERT_EQ(r.rejected.size(), one.rejected.size());
        EXPECT_EQ(r.candidate_points, one.candidate_points);
        EXPECT_EQ(r.point_face, one.point_face);
        EXPECT_TRUE(same_floats(r.point_residual, one.point_residual));
    }
    p.num_threads = -1;
    EXPECT_THROW(DetectFixtures(k.cloud, RoomFrame{}, s, p), InvalidArgument);
}

TEST(Fixtures, AThinHandleOfAnotherColourIsACandidateByItsContrast) {
    // Three flat bars 7 mm out of the brown door (less than the 12 mm a depth candidate needs):
    // a light one at z 0.5, one of the door's colour at z 0.3 and a blue one of the door's grey
    // level at z 0.7.
    test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    std::mt19937 rng(5);
    const float y = k.face_y - 0.007f;
    const Eigen::Vector3f light(0.8f, y, 0.5f), dark(0.8f, y, 0.3f), hue(0.8f, y, 0.7f);
    test::AddPatch(k.cloud, light - Eigen::Vector3f(0.075f, 0, 0.005f), {0.15f, 0, 0},
                   {0, 0, 0.01f}, 0.003f, -Eigen::Vector3f::UnitY(), Color{185, 185, 190, 255},
                   0.0f, rng);
    test::AddPatch(k.cloud, dark - Eigen::Vector3f(0.075f, 0, 0.005f), {0.15f, 0, 0}, {0, 0, 0.01f},
                   0.003f, -Eigen::Vector3f::UnitY(), Color{90, 60, 40, 255}, 0.0f, rng);
    test::AddPatch(k.cloud, hue - Eigen::Vector3f(0.075f, 0, 0.005f), {0.15f, 0, 0}, {0, 0, 0.01f},
                   0.003f, -Eigen::Vector3f::UnitY(), Color{40, 70, 110, 255}, 0.0f, rng);
    k.cloud.width = static_cast<std::uint32_t>(k.cloud.size());
    const RoomStructure s = SegmentRoomStructure(k.cloud, RoomFrame{}, {});
    auto near = [](const FixtureResult& r, const Eigen::Vector3f& at) {
        return std::count_if(r.candidates.begin(), r.candidates.end(),
                             [&](const auto& c) { return (c.fixture.center - at).norm() < 0.03f; });
    };
    FixtureParams p;
    const FixtureResult depth = DetectFixtures(k.cloud, RoomFrame{}, s, p);
    EXPECT_EQ(near(depth, light), 0);
    EXPECT_EQ(near(depth, dark), 0);
    EXPECT_EQ(near(depth, hue), 0);
    p.min_contrast = 40.0f;
    const FixtureResult both = DetectFixtures(k.cloud, RoomFrame{}, s, p);
    EXPECT_EQ(near(both, light), 1);
    EXPECT_EQ(near(both, dark), 0);
    // Grey levels 66 and 67: the blue bar stands out of the brown door by its colour alone.
    EXPECT_EQ(near(both, hue), 1);
    for (const auto& c : both.candidates) {
        if ((c.fixture.center - hue).norm() < 0.03f) {
            EXPECT_GT(c.evidence.contrast, 40.0f);
        }
    }
    // The depth candidates (the two handles) stay exactly as they were.
    ASSERT_GE(depth.candidates.size(), 2u);
    for (const auto& c : depth.candidates) {
        EXPECT_EQ(std::count_if(both.candidates.begin(), both.candidates.end(),
                                [&](const auto& b) {
                                    return b.fixture.center == c.fixture.center &&
                                           FixtureFeatureRow(b.evidence) ==
                                               FixtureFeatureRow(c.evidence);
                                }),
                  1);
    }
    // Without colours the cue is off.
    PointCloud grey = k.cloud;
    grey.colors.clear();
    EXPECT_EQ(near(DetectFixtures(grey, RoomFrame{}, s, p), light), 0);
    EXPECT_EQ(near(DetectFixtures(grey, RoomFrame{}, s, p), hue), 0);
    p.min_contrast = -1.0f;
    EXPECT_THROW(DetectFixtures(k.cloud, RoomFrame{}, s, p), InvalidArgument);
}

TEST(FixtureEvidence, OneRowPerCandidateDescribingTheHandle) {
    const test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    const RoomStructure s = SegmentRoomStructure(k.cloud, RoomFrame{}, {});
    const FixtureResult r = DetectFixtures(k.cloud, RoomFrame{}, s, {});
    ASSERT_GE(r.candidates.size(), 2u);
    EXPECT_EQ(r.point_face.size(), k.cloud.size());
    EXPECT_EQ(r.point_residual.size(), k.cloud.size());
    int door = 0, drawer = 0;
    for (const FixtureCandidate& c : r.candidates) {
        const std::vector<float> row = FixtureFeatureRow(c.evidence);
        ASSERT_EQ(row.size(), FixtureFeatureNames().size());
        for (const float x : row) EXPECT_TRUE(std::isfinite(x));
        EXPECT_EQ(row[0], c.evidence.length);
        if (!c.accepted) continue;
        const FixtureEvidence& e = c.evidence;
        const bool is_door = std::abs(c.fixture.center.x() - 1.03f) < 0.02f;
        door += is_door;
        drawer += !is_door;
        // The bars: 16 and 20 cm long, 1.2 cm wide, 3.5 cm out of a flat front.
        EXPECT_NEAR(e.length, is_door ? 0.16f : 0.2f, 0.015f);
        EXPECT_LT(e.width, 0.03f);
        EXPECT_GT(e.elongation, 4.0f);
        EXPECT_NEAR(e.local_protrusion, 0.035f, 0.006f);
        EXPECT_NEAR(e.plane_protrusion, 0.035f, 0.006f);
        EXPECT_NEAR(e.verticality, is_door ? 1.0f : 0.0f, 0.05f);
        EXPECT_EQ(e.sides, 4.0f);
        EXPECT_EQ(e.border, 0.0f);
        EXPECT_NEAR(e.height, c.fixture.center.z(), 0.02f);  // floor at z = 0
        EXPECT_GT(e.protrusion_snr, 3.0f);
        EXPECT_GT(e.range, 1.0f);
    }
    EXPECT_EQ(door, 1);
    EXPECT_EQ(drawer, 1);
}

/// Rows of the synthetic kitchen's candidates (labelled by their truth) and of flat bumps
/// labelled `flat_label`.
ml::Dataset SyntheticRows(const FixtureResult& r, const PointCloud& scan,
                          const std::string& handle_label, const std::string& flat_label) {
    ml::Dataset data = training::EmptyFixtureDataset();
    const std::vector<int> labels = training::LabelFixtureCandidates(scan, r.candidates, 0.03f);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> jitter(0.9f, 1.1f);
    for (int copy = 0; copy < 20; ++copy) {
        for (std::size_t k = 0; k < r.candidates.size(); ++k) {
            FixtureEvidence e = r.candidates[k].evidence;
            e.length *= jitter(rng);
            e.local_protrusion *= jitter(rng);
            const std::string label = labels[k] == 1 ? handle_label : "none";
            data.AppendRow(FixtureFeatureRow(e), label, -1, -1, "synthetic");
            // The same shape lying flat on the face: no fixture.
            e.local_protrusion = e.plane_protrusion = e.median_residual = 0.004f * jitter(rng);
            e.depth_extent = 0.005f;
            e.protrusion_snr = 1.0f;
            data.AppendRow(FixtureFeatureRow(e), flat_label, -1, -1, "synthetic");
        }
    }
    return data;
}

TEST(FixtureClassifier, TrainedOnSyntheticRowsDecidesWhatIsAFixture) {
    test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    AddHandleTruth(k.cloud);
    const RoomStructure s = SegmentRoomStructure(k.cloud, RoomFrame{}, {});
    const FixtureResult rules = DetectFixtures(k.cloud, RoomFrame{}, s, {});
    const std::vector<int> labels =
        training::LabelFixtureCandidates(k.cloud, rules.candidates, 0.03f);
    int handles = 0;
    for (const int l : labels) handles += l == 1;
    ASSERT_EQ(handles, 2);

    const auto good = training::TrainFixtureClassifier(
        SyntheticRows(rules, k.cloud, "handle", "none"), "rtrees:trees=20");
    EXPECT_NO_THROW(CheckFixtureClassifier(*good));
    const FixtureResult learned = DetectFixtures(k.cloud, RoomFrame{}, s, {}, {}, good.get());
    ASSERT_EQ(learned.fixtures.size(), 2u);
    for (const Fixture& f : learned.fixtures) EXPECT_EQ(f.type, FixtureType::kHandle);
    for (const FixtureCandidate& c : learned.candidates) {
        EXPECT_EQ(c.accepted, c.confidence >= FixtureParams{}.min_confidence);
    }
    // The laser's lower cut accepts what the default does and every candidate above it.
    const FixtureParams laser = KitchenParamsFor(KitchenSensor::kLaser).fixtures;
    EXPECT_LT(laser.min_confidence, FixtureParams{}.min_confidence);
    FixtureParams lower;
    lower.min_confidence = laser.min_confidence;
    const FixtureResult low = DetectFixtures(k.cloud, RoomFrame{}, s, lower, {}, good.get());
    EXPECT_GE(low.fixtures.size(), learned.fixtures.size());
    for (const FixtureCandidate& c : low.candidates) {
        EXPECT_EQ(c.accepted, c.confidence >= laser.min_confidence);
    }
    // Taught that protruding bars are nothing and flat patches are handles, it finds none.
    const auto wrong = training::TrainFixtureClassifier(
        SyntheticRows(rules, k.cloud, "none", "handle"), "rtrees:trees=20");
    EXPECT_TRUE(DetectFixtures(k.cloud, RoomFrame{}, s, {}, {}, wrong.get()).fixtures.empty());

    // Rows of one class cannot train; a classifier of other columns is refused.
    ml::Dataset one = training::EmptyFixtureDataset();
    one.AppendRow(FixtureFeatureRow(FixtureEvidence{}), "none", -1, -1, "x");
    one.AppendRow(FixtureFeatureRow(FixtureEvidence{}), "none", -1, -1, "x");
    EXPECT_THROW(training::TrainFixtureClassifier(one, "rtrees:trees=5"), DataError);
    ml::Dataset other = ml::Dataset::WithBlocks({{"other", {"a", "b"}}});
    other.AppendRow(std::vector<float>{0.0f, 1.0f}, "none", -1, -1, "x");
    other.AppendRow(std::vector<float>{1.0f, 0.0f}, "handle", -1, -1, "x");
    auto foreign = ml::CreateClassifier("rtrees:trees=5");
    foreign->Fit(other);
    EXPECT_THROW(CheckFixtureClassifier(*foreign), InvalidArgument);
    EXPECT_THROW(DetectFixtures(k.cloud, RoomFrame{}, s, {}, {}, foreign.get()), InvalidArgument);
    // Labels need the ground truth.
    const test::SyntheticKitchen bare = test::MakeSyntheticKitchen(1);
    EXPECT_THROW(training::LabelFixtureCandidates(bare.cloud, rules.candidates, 0.03f), DataError);
}

/// A candidate with a fixture of `type` centred at `c`, along `dir`, `length` long.
FixtureCandidate LoneCandidate(FixtureType type, const Eigen::Vector3f& c,
                               const Eigen::Vector3f& dir, float length, float confidence) {
    FixtureCandidate k;
    k.fixture.type = type;
    k.fixture.center = c;
    k.fixture.direction = dir;
    k.fixture.length = length;
    k.confidence = confidence;
    k.reason = "classifier";
    return k;
}

TEST(FixtureClassifier, LoneCandidatesBelowTheCutAreFixturesWhereNoneIsNear) {
    const Eigen::Vector3f up = Eigen::Vector3f::UnitZ(), side = Eigen::Vector3f::UnitX();
    // A: a vertical handle accepted by the cut, 0.9-1.1 m high.
    // F: a vertical handle above it, its centre 25 cm from A's but its end 5 cm from A's.
    // B: parallel to A, 10 cm beside it. C: a knob 60 cm away. D: a handle 5 cm beside C.
    // E: far from all, below the lone cut.
    std::vector<FixtureCandidate> c = {
        LoneCandidate(FixtureType::kHandle, {0, 0, 1}, up, 0.2f, 0.9f),
        LoneCandidate(FixtureType::kHandle, {0, 0, 1.25f}, up, 0.2f, 0.45f),
        LoneCandidate(FixtureType::kHandle, {0.1f, 0, 1}, up, 0.2f, 0.4f),
        LoneCandidate(FixtureType::kKnob, {0.6f, 0, 1}, -Eigen::Vector3f::UnitY(), 0.03f, 0.35f),
        LoneCandidate(FixtureType::kHandle, {0.7f, 0, 1}, side, 0.1f, 0.3f),
        LoneCandidate(FixtureType::kHandle, {2, 0, 1}, side, 0.1f, 0.1f)};
    c[0].accepted = true;
    c[0].reason = "";
    FixtureParams p;
    p.lone_min_confidence = 0.25f;
    p.lone_clearance = 0.2f;
    auto run = [&](std::vector<FixtureCandidate> cands) {
        std::vector<FixtureCandidate*> ptr;
        for (auto& k : cands) ptr.push_back(&k);
        AcceptLoneCandidates(ptr, p);
        std::vector<bool> accepted;
        for (const auto& k : cands) {
            accepted.push_back(k.accepted);
            EXPECT_STREQ(k.reason, k.accepted ? "" : "classifier");
        }
        return accepted;
    };
    EXPECT_EQ(run(c), (std::vector<bool>{true, false, false, true, false, false}));
    // The more confident of two near candidates wins; a second run gives the same.
    std::swap(c[3].confidence, c[4].confidence);
    EXPECT_EQ(run(c), (std::vector<bool>{true, false, false, false, true, false}));
    EXPECT_EQ(run(c), run(c));
    // Without the accepted handle, the most confident one near it takes its place.
    c[0].accepted = false;
    c[0].reason = "classifier";
    c[0].confidence = 0.2f;
    EXPECT_EQ(run(c), (std::vector<bool>{false, true, false, false, true, false}));
    // No clearance: every candidate at the lone cut; an empty list is no error.
    p.lone_clearance = 0.0f;
    EXPECT_EQ(run(c), (std::vector<bool>{false, true, true, true, true, false}));
    EXPECT_NO_THROW(AcceptLoneCandidates({}, p));
    // Bad parameters are refused before any candidate changes.
    for (const FixtureParams& bad :
         {FixtureParams{.lone_min_confidence = 1.5f}, FixtureParams{.lone_min_confidence = -0.1f},
          FixtureParams{.lone_clearance = -1.0f}}) {
        std::vector<FixtureCandidate> copy = c;
        std::vector<FixtureCandidate*> ptr;
        for (auto& k : copy) ptr.push_back(&k);
        EXPECT_THROW(AcceptLoneCandidates(ptr, bad), InvalidArgument);
        for (const auto& k : copy) EXPECT_FALSE(k.accepted);
    }
    // The defaults leave it off: nothing below the cut passes.
    EXPECT_GE(FixtureParams{}.lone_min_confidence, FixtureParams{}.min_confidence);
}

/// A door front of DoorsInGaps: x and z ranges on the face y = 2.4.
struct DoorRect {
    float x0, x1, z0, z1;
};

/// A room (floor, back wall y = 3, left wall x = 0) with a cupboard face y = 2.4 (x 0.3 .. 1.6,
/// z 0.1 .. 0.85) holding `doors` of the face's colour, each set in a 1 cm gap that shows the
/// carcass 2 cm behind (in `gap_colour`), and, when `handle`, a vertical handle at x = 1.04,
/// z = 0.5. Doors that
/// reach the face's edges cover the carcass (overlay doors, as most kitchen fronts).
PointCloud DoorsInGaps(const std::vector<DoorRect>& doors, std::uint32_t seed = 5,
                       bool handle = false, Color gap_colour = {40, 40, 40, 255}) {
    std::mt19937 rng(seed);
    PointCloud c;
    const float step = 0.005f, y = 2.4f;
    const Color white{230, 230, 230, 255};
    const Eigen::Vector3f n = -Eigen::Vector3f::UnitY();
    test::AddPatch(c, {0, 0, 0}, {3, 0, 0}, {0, 3, 0}, 0.02f, Eigen::Vector3f::UnitZ(),
                   Color{120, 110, 100, 255}, 0.001f, rng);
    test::AddPatch(c, {0, 3, 0}, {3, 0, 0}, {0, 0, 2.0f}, 0.02f, n, white, 0.001f, rng);
    test::AddPatch(c, {0, 0, 0}, {0, 3, 0}, {0, 0, 2.0f}, 0.02f, Eigen::Vector3f::UnitX(), white,
                   0.001f, rng);
    for (float x = 0.3f; x <= 1.6f; x += step) {
        for (float z = 0.1f; z <= 0.85f; z += step) {
            bool door = false, gap = false;
            for (const DoorRect& d : doors) {
                door = door || (x >= d.x0 && x <= d.x1 && z >= d.z0 && z <= d.z1);
                gap = gap || (x >= d.x0 - 0.01f && x <= d.x1 + 0.01f && z >= d.z0 - 0.01f &&
                              z <= d.z1 + 0.01f);
            }
            gap = gap && !door;
            c.points.emplace_back(x, gap ? y + 0.02f : y, z);
            c.normals.push_back(n);
            c.colors.push_back(gap ? gap_colour : white);
        }
    }
    if (handle) test::AddHandle(c, {1.04f, y, 0.5f}, 0.16f, rng, true);
    c.width = static_cast<std::uint32_t>(c.size());
    c.height = 1;
    c.sensor_origin = Eigen::Vector3f(1.0f, 1.0f, 1.3f);
    return c;
}

/// One door x 0.6 .. 1.1, z 0.15 .. 0.8 in its gap, with a vertical handle near its right edge.
PointCloud DoorInAGap() { return DoorsInGaps({{0.6f, 1.1f, 0.15f, 0.8f}}, 4, true); }

/// A scan's room structure, its fixtures (by the rules) and the outline evidence they give.
struct FaceScene {
    RoomStructure s;
    FixtureResult fx;
    FrontEvidence ev;
};

FaceScene SceneOf(const PointCloud& c) {
    FaceScene sc;
    sc.s = SegmentRoomStructure(c, RoomFrame{}, {});
    sc.fx = DetectFixtures(c, RoomFrame{}, sc.s, {});
    sc.ev.point_face = sc.fx.point_face;
    sc.ev.point_residual = sc.fx.point_residual;
    return sc;
}

/// A front of fixture 0 on its face over the rectangle between the face points at a and b,
/// holding the points of `candidates` inside it (the part a region grew over).
Front PartOfFace(const PointCloud& c, const FaceScene& sc, const Eigen::Vector3f& a,
                 const Eigen::Vector3f& b, const Indices& candidates) {
    const int f = sc.fx.fixtures.at(0).face;
    const PlanarComponent& face = sc.s.components.at(static_cast<std::size_t>(f));
    Front part;
    part.face = f;
    part.fixtures = {0};
    part.u_axis = PlaneU(face, RoomFrame{});
    part.v_axis = PlaneV(face, RoomFrame{});
    part.normal = face.plane.head<3>();
    const Eigen::Vector2f qa = PlaneCoordinates(face, RoomFrame{}, a);
    const Eigen::Vector2f qb = PlaneCoordinates(face, RoomFrame{}, b);
    part.min = qa.cwiseMin(qb);
    part.max = qa.cwiseMax(qb);
    for (const Index i : candidates) {
        const Eigen::Vector2f q = PlaneCoordinates(face, RoomFrame{}, c.points[i]);
        if ((q.array() >= part.min.array()).all() && (q.array() <= part.max.array()).all())
            part.indices.push_back(i);
    }
    return part;
}

TEST(FrontsFromEdges, DoorBoundedByItsGap) {
    const PointCloud c = DoorInAGap();
    const FaceScene sc = SceneOf(c);
    const RoomStructure& s = sc.s;
    const FixtureResult& fx = sc.fx;
    ASSERT_EQ(fx.fixtures.size(), 1u);
    const FrontEvidence& ev = sc.ev;
    const std::vector<Front> fronts = FrontsFromEdges(c, RoomFrame{}, s, fx.fixtures, ev, {});
    ASSERT_EQ(fronts.size(), 1u);
    const Front& f = fronts[0];
    EXPECT_EQ(f.fixtures, std::vector<int>{0});
    // Face coordinates: v is z; u runs along x (either sign).
    const float x0 = std::min(f.min.x() * f.u_axis.x(), f.max.x() * f.u_axis.x());
    const float x1 = std::max(f.min.x() * f.u_axis.x(), f.max.x() * f.u_axis.x());
    EXPECT_NEAR(x0, 0.6f, 0.025f);
    EXPECT_NEAR(x1, 1.1f, 0.025f);
    EXPECT_NEAR(f.min.y(), 0.15f, 0.025f);
    EXPECT_NEAR(f.max.y(), 0.8f, 0.025f);
    // Its points are the door's (fixture points excluded).
    for (const Index i : f.indices) {
        EXPECT_GT(c.points[i].x(), 0.57f);
        EXPECT_LT(c.points[i].x(), 1.13f);
        EXPECT_GT(c.points[i].y(), 2.39f);
    }
    // Without a fixture there is no front; evidence of the wrong size and bad parameters throw.
    EXPECT_TRUE(FrontsFromEdges(c, RoomFrame{}, s, {}, ev, {}).empty());
    FrontEvidence bad = ev;
    bad.point_residual.resize(3);
    EXPECT_THROW(FrontsFromEdges(c, RoomFrame{}, s, fx.fixtures, bad, {}), InvalidArgument);
    EXPECT_THROW(FrontsFromEdges(c, RoomFrame{}, s, fx.fixtures, ev, {.cell = 0.0f}),
                 InvalidArgument);
    EXPECT_THROW(FrontsFromEdges(c, RoomFrame{}, s, fx.fixtures, ev, {.min_support = 0.0f}),
                 InvalidArgument);
    EXPECT_THROW(FrontsFromEdges(c, RoomFrame{}, s, fx.fixtures, ev, {.rounds = 0}),
                 InvalidArgument);
}

TEST(FrontsFromEdges, AGrownFrontExtendsToItsOutline) {
    const PointCloud c = DoorInAGap();
    const FaceScene sc = SceneOf(c);
    const RoomStructure& s = sc.s;
    const FixtureResult& fx = sc.fx;
    ASSERT_EQ(fx.fixtures.size(), 1u);
    const FrontEvidence& ev = sc.ev;
    // A front grown over the door's middle only (x 0.8 .. 1.0, z 0.4 .. 0.6).
    const PlanarComponent& face = s.components[static_cast<std::size_t>(fx.fixtures[0].face)];
    const Front part = PartOfFace(c, sc, {0.8f, 2.4f, 0.4f}, {1.0f, 2.4f, 0.6f}, face.indices);
    std::vector<Front> fronts = {part};
    ExtendFrontsToOutlines(c, RoomFrame{}, s, fx.fixtures, ev, fronts);
    ASSERT_EQ(fronts.size(), 1u);
    const Front& f = fronts[0];
    const float x0 = std::min(f.min.x() * f.u_axis.x(), f.max.x() * f.u_axis.x());
    const float x1 = std::max(f.min.x() * f.u_axis.x(), f.max.x() * f.u_axis.x());
    // Each side goes to the gap, not to the first cell beside it (within 1 cm: the gap is 1 cm
    // wide, and the door's edge cell may hold the step into it).
    EXPECT_NEAR(x0, 0.6f, 0.008f);
    EXPECT_NEAR(x1, 1.1f, 0.008f);
    EXPECT_NEAR(f.min.y(), 0.15f, 0.008f);
    EXPECT_NEAR(f.max.y(), 0.8f, 0.008f);
    EXPECT_GT(f.indices.size(), 3 * part.indices.size());
    EXPECT_TRUE(std::is_sorted(f.indices.begin(), f.indices.end()));
    // A front already on its outline stays; a neighbour's rectangle stops the extension.
    std::vector<Front> again = fronts;
    ExtendFrontsToOutlines(c, RoomFrame{}, s, fx.fixtures, ev, again);
    EXPECT_TRUE(again[0].min.isApprox(f.min, 1e-5f));
    EXPECT_TRUE(again[0].max.isApprox(f.max, 1e-5f));
    Front neighbour = part;
    neighbour.fixtures = {};
    neighbour.indices.clear();
    const Eigen::Vector2f na = PlaneCoordinates(face, RoomFrame{}, {0.6f, 2.4f, 0.15f});
    const Eigen::Vector2f nb = PlaneCoordinates(face, RoomFrame{}, {1.1f, 2.4f, 0.3f});
    neighbour.min = na.cwiseMin(nb);
    neighbour.max = na.cwiseMax(nb);
    std::vector<Front> pair = {part, neighbour};
    ExtendFrontsToOutlines(c, RoomFrame{}, s, fx.fixtures, ev, pair);
    EXPECT_NEAR(pair[0].min.y(), 0.3f, 0.005f);
    FrontEvidence bad = ev;
    bad.point_face.resize(2);
    EXPECT_THROW(ExtendFrontsToOutlines(c, RoomFrame{}, s, fx.fixtures, bad, fronts),
                 InvalidArgument);
    EXPECT_THROW(
        ExtendFrontsToOutlines(c, RoomFrame{}, s, fx.fixtures, ev, fronts, {.max_extend = 0.0f}),
        InvalidArgument);
}

/// x range of a front's rectangle (u runs along x, either sign).
std::pair<float, float> FrontXRange(const Front& f) {
    const float a = f.min.x() * f.u_axis.x(), b = f.max.x() * f.u_axis.x();
    return {std::min(a, b), std::max(a, b)};
}

/// Fronts in the order of their rectangles along x.
std::vector<Front> ByX(std::vector<Front> v) {
    std::sort(v.begin(), v.end(), [](const Front& a, const Front& b) {
        return FrontXRange(a).first < FrontXRange(b).first;
    });
    return v;
}

/// Doors of the face's colour in their recessed gaps, with a vertical bar handle `length` long
/// centred at height z at each of `xs`.
PointCloud DoorsWithHandles(const std::vector<DoorRect>& doors, std::initializer_list<float> xs,
                            float z, float length, std::uint32_t seed) {
    PointCloud c = DoorsInGaps(doors, 7, false, Color{230, 230, 230, 255});
    std::mt19937 rng(seed);
    for (const float x : xs) test::AddHandle(c, {x, 2.4f, z}, length, rng, true);
    c.width = static_cast<std::uint32_t>(c.size());
    return c;
}

/// Each front (sorted along x) spans its door along x, within 2.5 cm.
void ExpectFrontsOnDoors(const std::vector<Front>& fronts, const std::vector<DoorRect>& doors) {
    ASSERT_EQ(fronts.size(), doors.size());
    for (std::size_t k = 0; k < doors.size(); ++k) {
        const auto [x0, x1] = FrontXRange(fronts[k]);
        EXPECT_NEAR(x0, doors[k].x0, 0.025f) << k;
        EXPECT_NEAR(x1, doors[k].x1, 0.025f) << k;
    }
}

TEST(SegmentFronts, OverlappingRegionsSplitAtTheGapBetweenTheirFixtures) {
    // Two doors side by side, each with a vertical handle near its right edge. The gap between
    // them has the doors' colour and shows only as a recess: the regions grown from the two
    // handles both cover the face.
    const std::vector<DoorRect> doors = {{0.3f, 0.9f, 0.1f, 0.85f}, {0.92f, 1.6f, 0.1f, 0.85f}};
    const PointCloud c = DoorsWithHandles(doors, {0.84f, 1.54f}, 0.5f, 0.16f, 3);
    const FaceScene sc = SceneOf(c);
    ASSERT_EQ(sc.fx.fixtures.size(), 2u);
    // Without the outline evidence each point goes to the nearer handle: the left door's front
    // runs on to halfway between the handles (x 1.19), far over its gap.
    const std::vector<Front> nearest = ByX(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures));
    ASSERT_EQ(nearest.size(), 2u);
    EXPECT_TRUE(nearest[0].overlapping);
    EXPECT_GT(FrontXRange(nearest[0]).second, 1.1f);
    // With it, the fronts part at the gap.
    const std::vector<Front> split =
        ByX(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, {}, &sc.ev));
    ExpectFrontsOnDoors(split, doors);
    ASSERT_EQ(split.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
        for (const Index i : split[k].indices) {
            ASSERT_GT(c.points[i].x(), doors[k].x0 - 0.02f) << k;
            ASSERT_LT(c.points[i].x(), doors[k].x1 + 0.02f) << k;
        }
    }
    // The same input gives the same fronts; off, the split is the nearest handle's again.
    const std::vector<Front> again =
        ByX(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, {}, &sc.ev));
    ASSERT_EQ(again.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) EXPECT_EQ(again[k].indices, split[k].indices);
    const std::vector<Front> off = ByX(
        SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, {.split_at_outlines = false}, &sc.ev));
    ASSERT_EQ(off.size(), 2u);
    EXPECT_EQ(off[0].indices, nearest[0].indices);
    // A fixture without points grows nothing; the other's region is no longer split.
    std::vector<Fixture> hollow = sc.fx.fixtures;
    hollow[1].indices.clear();
    const std::vector<Front> one = SegmentFronts(c, RoomFrame{}, sc.s, hollow, {}, &sc.ev);
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one[0].fixtures, std::vector<int>{0});
    // Bad parameters and evidence of the wrong size are refused.
    EXPECT_THROW(
        SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, {.split_support = 0.0f}, &sc.ev),
        InvalidArgument);
    FrontEvidence bad = sc.ev;
    bad.point_residual.resize(5);
    EXPECT_THROW(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, {}, &bad), InvalidArgument);
    EXPECT_THROW(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, {}, &sc.ev, {.cell = 0.0f}),
                 InvalidArgument);
}

TEST(SegmentFronts, AGapBesideALongHandleStillSplits) {
    // Doors 75 cm tall with bar handles 45 cm long right at the gap: the handle's mask (its
    // shadow and edges) covers the gap over 63 cm of its 75, and the line beside it shows its gap
    // only above and below the mask. It still parts the two fronts.
    const std::vector<DoorRect> doors = {{0.3f, 0.9f, 0.1f, 0.85f}, {0.92f, 1.6f, 0.1f, 0.85f}};
    const PointCloud c = DoorsWithHandles(doors, {0.875f, 1.575f}, 0.475f, 0.45f, 4);
    const FaceScene sc = SceneOf(c);
    ASSERT_EQ(sc.fx.fixtures.size(), 2u);
    ExpectFrontsOnDoors(ByX(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, {}, &sc.ev)),
                        doors);
}

TEST(SegmentFronts, TwoKnobsNearTheEndsOfOneFrontStayOneFront) {
    // A front 80 cm wide with a knob 8 cm from either end and nothing between them: one front
    // with both. Knobs near its middle are two doors meeting there: split between them.
    const std::vector<DoorRect> door = {{0.3f, 1.1f, 0.1f, 0.85f}};
    auto fronts_of = [&](float left, float right, const FrontParams& fp) {
        PointCloud c = DoorsInGaps(door, 7);
        std::mt19937 rng(5);
        for (const float x : {left, right}) test::AddKnob(c, {x, 2.4f, 0.75f}, rng);
        c.width = static_cast<std::uint32_t>(c.size());
        const FaceScene sc = SceneOf(c);
        EXPECT_EQ(sc.fx.fixtures.size(), 2u);
        return ByX(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, fp, &sc.ev));
    };
    const std::vector<Front> one = fronts_of(0.38f, 1.02f, {});
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one[0].fixtures, (std::vector<int>{0, 1}));
    EXPECT_NEAR(FrontXRange(one[0]).first, 0.3f, 0.025f);
    EXPECT_NEAR(FrontXRange(one[0]).second, 1.1f, 0.025f);
    // Off, each knob keeps the half nearer to it.
    const std::vector<Front> halves = fronts_of(0.38f, 1.02f, {.pair_end_reach = 0.0f});
    ASSERT_EQ(halves.size(), 2u);
    EXPECT_NEAR(FrontXRange(halves[0]).second, 0.7f, 0.03f);
    // Knobs meeting in the middle: two doors.
    const std::vector<Front> two = fronts_of(0.66f, 0.74f, {});
    ASSERT_EQ(two.size(), 2u);
    EXPECT_NEAR(FrontXRange(two[0]).second, 0.7f, 0.03f);
    // Too wide for one front: split.
    EXPECT_EQ(fronts_of(0.38f, 1.02f, {.pair_max_width = 0.5f}).size(), 2u);
    PointCloud c = DoorsInGaps(door, 7);
    const FaceScene sc = SceneOf(c);
    EXPECT_THROW(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, {.pair_end_reach = -1.0f}),
                 InvalidArgument);
}

TEST(SegmentFronts, TheTwoMountsOfEachDrawersBarInAStackAreOneFront) {
    // Three drawers stacked across the face (1.3 m wide), each with only the two mounts of its
    // bar found (knobs 8 cm from its ends): the regions of all six cover the face, the gaps
    // between the drawers part the rows, and nothing parts the two mounts of a drawer. Each
    // drawer is one front with both mounts (fronts up to 1.4 m wide allowed).
    const std::vector<DoorRect> drawers = {
        {0.3f, 1.6f, 0.1f, 0.33f}, {0.3f, 1.6f, 0.35f, 0.58f}, {0.3f, 1.6f, 0.6f, 0.85f}};
    PointCloud c = DoorsInGaps(drawers, 7, false, Color{230, 230, 230, 255});
    std::mt19937 rng(6);
    for (const DoorRect& d : drawers) {
        for (const float x : {0.38f, 1.52f}) test::AddKnob(c, {x, 2.4f, d.z1 - 0.06f}, rng);
    }
    c.width = static_cast<std::uint32_t>(c.size());
    const FaceScene sc = SceneOf(c);
    ASSERT_EQ(sc.fx.fixtures.size(), 6u);
    const FrontParams wide{.pair_max_width = 1.4f};
    auto by_z = [](std::vector<Front> f) {
        std::sort(f.begin(), f.end(),
                  [](const Front& a, const Front& b) { return a.center.z() < b.center.z(); });
        return f;
    };
    const std::vector<Front> rows =
        by_z(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, wide, &sc.ev));
    ASSERT_EQ(rows.size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(rows[k].fixtures.size(), 2u) << k;
        EXPECT_NEAR(FrontXRange(rows[k]).first, 0.3f, 0.025f) << k;
        EXPECT_NEAR(FrontXRange(rows[k]).second, 1.6f, 0.025f) << k;
        for (const Index i : rows[k].indices) {
            ASSERT_GT(c.points[i].z(), drawers[k].z0 - 0.025f) << k;
            ASSERT_LT(c.points[i].z(), drawers[k].z1 + 0.025f) << k;
        }
    }
    // The same input gives the same fronts.
    const std::vector<Front> again =
        by_z(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, wide, &sc.ev));
    ASSERT_EQ(again.size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(again[k].indices, rows[k].indices);
    // Narrower fronts only, or pairs off: each mount keeps its half of its drawer.
    EXPECT_EQ(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, {}, &sc.ev).size(), 6u);
    const FrontParams off{.pair_end_reach = 0.0f, .pair_max_width = 1.4f};
    EXPECT_EQ(SegmentFronts(c, RoomFrame{}, sc.s, sc.fx.fixtures, off, &sc.ev).size(), 6u);
}

TEST(MergeNestedFronts, APanelInsideADoorJoinsItAndNeighboursStay) {
    // Faces facing -y: the doors' plane y = 2.4, a recessed panel's plane 2 cm behind it and a
    // carcass' back 20 cm behind it.
    RoomStructure s;
    for (const float y : {2.4f, 2.42f, 2.6f}) {
        PlanarComponent c;
        c.axis = 1;
        c.plane = Eigen::Vector4f(0.0f, -1.0f, 0.0f, y);
        c.label = MapClass::kFace;
        s.components.push_back(c);
    }
    // A front on face `face` over x0..x1, z0..z1 (u may run along -x: corners in the world).
    auto front = [&](int face, float x0, float x1, float z0, float z1, Indices idx,
                     std::vector<int> fx) {
        Front f;
        f.face = face;
        f.indices = std::move(idx);
        f.fixtures = std::move(fx);
        const PlanarComponent& c = s.components[static_cast<std::size_t>(face)];
        const float y = c.plane.w();
        const Eigen::Vector2f a = PlaneCoordinates(c, RoomFrame{}, {x0, y, z0});
        const Eigen::Vector2f b = PlaneCoordinates(c, RoomFrame{}, {x1, y, z1});
        SetFrontRectangle(f, c, RoomFrame{}, a.cwiseMin(b), a.cwiseMax(b));
        return f;
    };
    const std::vector<Front> input = {
        front(0, 0.0f, 0.6f, 0.1f, 0.8f, {1, 2, 3}, {0}),  // the door's frame, its handle
        front(1, 0.1f, 0.5f, 0.2f, 0.7f, {4, 5}, {1}),     // its recessed panel
        front(0, 0.62f, 1.2f, 0.1f, 0.8f, {6}, {2}),       // the next door
        front(2, 0.1f, 0.5f, 0.2f, 0.7f, {7}, {}),         // far behind the door
        front(0, 0.3f, 0.9f, 0.85f, 1.0f, {8}, {3}),       // above, beside both doors
        front(0, 0.7f, 0.9f, 0.3f, 0.5f, {9, 10}, {}),     // inside the next door, same face
    };
    auto check = [](const std::vector<Front>& out) {
        ASSERT_EQ(out.size(), 5u);
        std::set<Index> firsts;
        for (const Front& f : out) firsts.insert(f.indices.front());
        EXPECT_EQ(firsts, (std::set<Index>{1, 6, 7, 8, 9}));
        for (const Front& f : out) {
            if (f.indices.front() == 1) {
                EXPECT_EQ(f.indices, (Indices{1, 2, 3, 4, 5}));
                EXPECT_EQ(f.fixtures, std::vector<int>{0});       // the panel's fixture is no one's
                EXPECT_NEAR(f.max.y() - f.min.y(), 0.7f, 1e-5f);  // its rectangle stays
            }
            // On its own face the larger front is the one in error (run on over a neighbour).
            if (f.indices.front() == 6) {
                EXPECT_EQ(f.indices, Indices{6});
            }
        }
    };
    std::vector<Front> fronts = input;
    MergeNestedFronts(s, fronts);
    check(fronts);
    // In any order the same fronts come out.
    std::vector<Front> reversed(input.rbegin(), input.rend());
    MergeNestedFronts(s, reversed);
    check(reversed);
    // Off, or with a shallower nesting depth than the panel's recess, the panel stays its own.
    std::vector<Front> off = input;
    MergeNestedFronts(s, off, {.nest_share = 2.0f});
    EXPECT_EQ(off.size(), input.size());
    std::vector<Front> shallow = input;
    MergeNestedFronts(s, shallow, {.nest_depth = 0.01f});
    EXPECT_EQ(shallow.size(), input.size());
    // No fronts, bad parameters, a front on no face.
    std::vector<Front> none;
    EXPECT_NO_THROW(MergeNestedFronts(s, none));
    EXPECT_THROW(MergeNestedFronts(s, fronts, {.nest_share = 0.0f}), InvalidArgument);
    EXPECT_THROW(MergeNestedFronts(s, fronts, {.nest_depth = -1.0f}), InvalidArgument);
    std::vector<Front> stray = input;
    stray[2].face = 7;
    EXPECT_THROW(MergeNestedFronts(s, stray), InvalidArgument);
    EXPECT_EQ(stray.size(), input.size());
}

TEST(ClaimUnexplainedPoints, NoisyPointsInsideARectangleJoinItsFront) {
    // One face facing -y at y = 2.4 with two doors side by side and a small front nested in the
    // first; points no component explains around them (claimed within 3 cm of the face, and
    // within 4 cm beside a rectangle).
    RoomStructure s;
    PlanarComponent c;
    c.axis = 1;
    c.plane = Eigen::Vector4f(0.0f, -1.0f, 0.0f, 2.4f);
    c.label = MapClass::kFace;
    s.components.push_back(c);
    auto front = [&](float x0, float x1, float z0, float z1, Index own) {
        Front f;
        f.face = 0;
        f.indices = {own};
        const Eigen::Vector2f a = PlaneCoordinates(c, RoomFrame{}, {x0, 2.4f, z0});
        const Eigen::Vector2f b = PlaneCoordinates(c, RoomFrame{}, {x1, 2.4f, z1});
        SetFrontRectangle(f, c, RoomFrame{}, a.cwiseMin(b), a.cwiseMax(b));
        return f;
    };
    const std::vector<Front> input = {front(0.0f, 0.6f, 0.1f, 0.8f, 20),
                                      front(0.62f, 1.2f, 0.1f, 0.8f, 21),
                                      front(0.1f, 0.3f, 0.2f, 0.4f, 22)};
    PointCloud cloud;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    cloud.points = {
        {0.3f, 2.385f, 0.5f},  // 0: 1.5 cm out of the first door
        {0.3f, 2.42f, 0.5f},   // 1: 2 cm behind it
        {0.3f, 2.33f, 0.5f},   // 2: 7 cm out: something else
        {0.605f, 2.4f, 0.5f},  // 3: in the gap between the doors, nearer the first
        {0.2f, 2.39f, 0.3f},   // 4: in the nested front
        {0.9f, 2.39f, 0.5f},   // 5: explained by the face
        {0.9f, 2.39f, 0.6f},   // 6: a fixture's
        {0.9f, 2.395f, 0.4f},  // 7: on the second door
        {nan, nan, nan},       // 8
        {1.23f, 2.39f, 0.5f},  // 9: 3 cm beside the second door
        {1.3f, 2.39f, 0.5f},   // 10: 10 cm beside it
    };
    cloud.width = static_cast<std::uint32_t>(cloud.points.size());
    cloud.height = 1;
    s.point_component.assign(cloud.size(), -1);
    s.point_component[5] = 0;
    Fixture handle;
    handle.face = 0;
    handle.indices = {6};
    const FrontParams p;  // 3 cm out of the face and behind it
    auto claims = [&](std::vector<Front> fronts) {
        ClaimUnexplainedPoints(cloud, RoomFrame{}, s, {handle}, fronts, p);
        std::map<Index, Indices> by_own;  // the front's own point -> its points
        for (const Front& f : fronts) by_own[f.indices.back()] = f.indices;
        return by_own;
    };
    const std::map<Index, Indices> expected = {
        {20, {0, 1, 3, 20}}, {21, {7, 9, 21}}, {22, {4, 22}}};
    EXPECT_EQ(claims(input), expected);
    // In any order the same points join the same fronts.
    EXPECT_EQ(claims(std::vector<Front>(input.rbegin(), input.rend())), expected);
    // Off, and points behind the face not claimed when claim_behind is 0.
    std::vector<Front> off = input;
    ClaimUnexplainedPoints(cloud, RoomFrame{}, s, {handle}, off, {.claim_front = 0.0f});
    for (std::size_t f = 0; f < off.size(); ++f) EXPECT_EQ(off[f].indices, input[f].indices);
    std::vector<Front> front_only = input;
    ClaimUnexplainedPoints(cloud, RoomFrame{}, s, {handle}, front_only,
                           {.claim_front = 0.03f, .claim_behind = 0.0f, .claim_margin = 0.0f});
    EXPECT_EQ(front_only[0].indices, (Indices{0, 20}));
    EXPECT_EQ(front_only[1].indices, (Indices{7, 21}));  // nothing beside the rectangles
    // No fronts, bad parameters, a front on no face.
    std::vector<Front> none;
    EXPECT_NO_THROW(ClaimUnexplainedPoints(cloud, RoomFrame{}, s, {}, none, p));
    std::vector<Front> bad = input;
    EXPECT_THROW(ClaimUnexplainedPoints(cloud, RoomFrame{}, s, {}, bad, {.claim_front = -0.01f}),
                 InvalidArgument);
    EXPECT_THROW(ClaimUnexplainedPoints(cloud, RoomFrame{}, s, {}, bad,
                                        {.claim_front = 0.03f, .claim_behind = nan}),
                 InvalidArgument);
    EXPECT_THROW(ClaimUnexplainedPoints(cloud, RoomFrame{}, s, {}, bad, {.claim_margin = -1.0f}),
                 InvalidArgument);
    bad[1].face = 3;
    EXPECT_THROW(ClaimUnexplainedPoints(cloud, RoomFrame{}, s, {}, bad, p), InvalidArgument);
    EXPECT_EQ(bad[0].indices, input[0].indices);  // nothing changed
}

TEST(FrontsFromGaps, DoorsWithoutHandlesBetweenTheirGaps) {
    // Two overlay doors and a drawer above the right one.
    const std::vector<DoorRect> doors = {
        {0.3f, 0.9f, 0.1f, 0.85f}, {0.93f, 1.6f, 0.1f, 0.55f}, {0.93f, 1.6f, 0.58f, 0.85f}};
    const PointCloud c = DoorsInGaps(doors);
    const FaceScene sc = SceneOf(c);
    const RoomStructure& s = sc.s;
    const FixtureResult& fx = sc.fx;
    EXPECT_TRUE(fx.fixtures.empty());
    const FrontEvidence& ev = sc.ev;
    std::vector<Front> fronts;
    AddFrontsFromGaps(c, RoomFrame{}, s, {}, ev, fronts);
    ASSERT_EQ(fronts.size(), 3u);
    auto order = [](std::vector<Front>& v) {
        std::sort(v.begin(), v.end(), [](const Front& a, const Front& b) {
            return std::pair(FrontXRange(a).first, a.min.y()) <
                   std::pair(FrontXRange(b).first, b.min.y());
        });
    };
    order(fronts);
    for (std::size_t k = 0; k < 3; ++k) {
        const auto [x0, x1] = FrontXRange(fronts[k]);
        EXPECT_NEAR(x0, doors[k].x0, 0.025f) << k;
        EXPECT_NEAR(x1, doors[k].x1, 0.025f) << k;
        EXPECT_NEAR(fronts[k].min.y(), doors[k].z0, 0.025f) << k;
        EXPECT_NEAR(fronts[k].max.y(), doors[k].z1, 0.025f) << k;
        EXPECT_TRUE(fronts[k].fixtures.empty());
        EXPECT_TRUE(std::is_sorted(fronts[k].indices.begin(), fronts[k].indices.end()));
        // Its points are its door's, and nearly all of them.
        std::size_t inside = 0;
        for (const Index i : fronts[k].indices) {
            const Eigen::Vector3f& q = c.points[i];
            inside += q.x() > doors[k].x0 - 0.015f && q.x() < doors[k].x1 + 0.015f &&
                      q.z() > doors[k].z0 - 0.015f && q.z() < doors[k].z1 + 0.015f;
        }
        EXPECT_GT(inside, fronts[k].indices.size() * 97 / 100) << k;
        const std::size_t door_points = static_cast<std::size_t>(
            (doors[k].x1 - doors[k].x0) * (doors[k].z1 - doors[k].z0) / (0.005f * 0.005f));
        EXPECT_GT(fronts[k].indices.size(), door_points * 9 / 10) << k;
    }
    // A front found already (the left door's, of its fixture) keeps its door: only the others
    // are added, and its points are not taken again.
    std::vector<Front> known = {fronts[0]};
    AddFrontsFromGaps(c, RoomFrame{}, s, {}, ev, known);
    ASSERT_EQ(known.size(), 3u);
    for (std::size_t k = 1; k < 3; ++k) {
        EXPECT_NEAR(FrontXRange(known[k]).first, doors[1].x0, 0.025f);
        for (const Index i : known[k].indices) {
            EXPECT_FALSE(std::binary_search(fronts[0].indices.begin(), fronts[0].indices.end(), i));
        }
    }
    // The same input gives the same fronts.
    std::vector<Front> again;
    AddFrontsFromGaps(c, RoomFrame{}, s, {}, ev, again);
    ASSERT_EQ(again.size(), 3u);
    order(again);
    for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(again[k].indices, fronts[k].indices);
    // A frame narrower than cut_margin around an inset door stays with it.
    const DoorRect inset{0.34f, 0.9f, 0.14f, 0.81f};
    const PointCloud framed = DoorsInGaps({inset, doors[1], doors[2]});
    const FaceScene fsc = SceneOf(framed);
    std::vector<Front> with_frame;
    AddFrontsFromGaps(framed, RoomFrame{}, fsc.s, {}, fsc.ev, with_frame);
    ASSERT_EQ(with_frame.size(), 3u);
    order(with_frame);
    EXPECT_NEAR(FrontXRange(with_frame[0]).first, 0.3f, 0.01f);
    EXPECT_NEAR(with_frame[0].min.y(), 0.1f, 0.01f);
}

TEST(FrontsFromGaps, ADashedLineAcrossADoorCutsItOnlyWithoutTheRunRule) {
    // One door without a handle, crossed at z = 0.45 by dashes 4 cm long, 2 cm apart, 2 cm deep
    // (texture, noise): outline along two thirds of the row, but no run longer than a dash.
    const DoorRect door{0.6f, 1.1f, 0.1f, 0.85f};
    PointCloud c = DoorsInGaps({door});
    for (Eigen::Vector3f& q : c.points) {
        if (std::abs(q.z() - 0.45f) < 0.001f && q.x() > door.x0 && q.x() < door.x1 &&
            std::fmod(q.x() - door.x0, 0.06f) < 0.04f) {
            q.y() += 0.02f;
        }
    }
    const FaceScene sc = SceneOf(c);
    ASSERT_TRUE(sc.fx.fixtures.empty());
    // The fronts over the door (the carcass beside it gives fronts of its own).
    auto on_door = [&](const std::vector<Front>& fronts) {
        std::vector<Front> out;
        for (const Front& f : fronts) {
            const auto [x0, x1] = FrontXRange(f);
            if (0.5f * (x0 + x1) > door.x0 && 0.5f * (x0 + x1) < door.x1) out.push_back(f);
        }
        return out;
    };
    std::vector<Front> runs;
    AddFrontsFromGaps(c, RoomFrame{}, sc.s, {}, sc.ev, runs);
    const std::vector<Front> door_runs = on_door(runs);
    ASSERT_EQ(door_runs.size(), 1u);
    EXPECT_NEAR(door_runs[0].min.y(), door.z0, 0.025f);
    EXPECT_NEAR(door_runs[0].max.y(), door.z1, 0.025f);
    std::vector<Front> shares;
    AddFrontsFromGaps(c, RoomFrame{}, sc.s, {}, sc.ev, shares, {}, {.cut_run = 0.0f});
    EXPECT_EQ(on_door(shares).size(), 2u);
    EXPECT_THROW(AddFrontsFromGaps(c, RoomFrame{}, sc.s, {}, sc.ev, shares, {}, {.cut_run = 1.5f}),
                 InvalidArgument);
}

TEST(FrontsFromGaps, AFixturesFrontGrowsToTheOutlinesHoldingItsFixture) {
    // Two overlay doors; the right one has a handle, and its front was grown over a part only.
    const std::vector<DoorRect> doors = {{0.3f, 0.9f, 0.1f, 0.85f}, {0.93f, 1.6f, 0.1f, 0.85f}};
    const PointCloud c = DoorsInGaps(doors, 6, true);
    const FaceScene sc = SceneOf(c);
    const RoomStructure& s = sc.s;
    const FixtureResult& fx = sc.fx;
    ASSERT_EQ(fx.fixtures.size(), 1u);
    const FrontEvidence& ev = sc.ev;
    Indices measured;  // the points measured against the handle's face
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (fx.point_face[i] == fx.fixtures[0].face) measured.push_back(static_cast<Index>(i));
    }
    const Front part = PartOfFace(c, sc, {1.0f, 2.4f, 0.35f}, {1.25f, 2.4f, 0.65f}, measured);
    std::vector<Front> fronts = {part};
    AddFrontsFromGaps(c, RoomFrame{}, s, fx.fixtures, ev, fronts);
    ASSERT_EQ(fronts.size(), 2u);
    const auto [x0, x1] = FrontXRange(fronts[0]);
    EXPECT_NEAR(x0, doors[1].x0, 0.025f);
    EXPECT_NEAR(x1, doors[1].x1, 0.025f);
    EXPECT_NEAR(fronts[0].min.y(), doors[1].z0, 0.025f);
    EXPECT_NEAR(fronts[0].max.y(), doors[1].z1, 0.025f);
    EXPECT_EQ(fronts[0].fixtures, std::vector<int>{0});
    EXPECT_TRUE(std::is_sorted(fronts[0].indices.begin(), fronts[0].indices.end()));
    EXPECT_TRUE(std::includes(fronts[0].indices.begin(), fronts[0].indices.end(),
                              part.indices.begin(), part.indices.end()));
    EXPECT_NEAR(FrontXRange(fronts[1]).first, doors[0].x0, 0.025f);
    EXPECT_TRUE(fronts[1].fixtures.empty());
    // Without growing, the front keeps its part.
    std::vector<Front> kept = {part};
    AddFrontsFromGaps(c, RoomFrame{}, s, fx.fixtures, ev, kept, {}, {.grow_fixture_fronts = false});
    EXPECT_EQ(kept[0].indices, part.indices);
    EXPECT_TRUE(kept[0].min.isApprox(part.min));
}

TEST(FrontsFromGaps, AFixturesFrontOverTwoDoorsKeepsTheDoorOfItsFixture) {
    // Two overlay doors; the right one has a handle, the left one's was missed, and the handle's
    // front ran on over the gap into the left door.
    const std::vector<DoorRect> doors = {{0.3f, 0.9f, 0.1f, 0.85f}, {0.93f, 1.6f, 0.1f, 0.85f}};
    const PointCloud c = DoorsInGaps(doors, 6, true);
    const FaceScene sc = SceneOf(c);
    const FixtureResult& fx = sc.fx;
    ASSERT_EQ(fx.fixtures.size(), 1u);
    Indices measured;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (fx.point_face[i] == fx.fixtures[0].face) measured.push_back(static_cast<Index>(i));
    }
    const Front both = PartOfFace(c, sc, {0.3f, 2.4f, 0.1f}, {1.6f, 2.4f, 0.85f}, measured);
    GapFrontParams split;
    split.split_fixture_fronts = true;
    std::vector<Front> fronts = {both};
    AddFrontsFromGaps(c, RoomFrame{}, sc.s, fx.fixtures, sc.ev, fronts, {}, split);
    ASSERT_EQ(fronts.size(), 2u);
    EXPECT_EQ(fronts[0].fixtures, std::vector<int>{0});
    EXPECT_NEAR(FrontXRange(fronts[0]).first, doors[1].x0, 0.025f);
    EXPECT_NEAR(FrontXRange(fronts[0]).second, doors[1].x1, 0.025f);
    for (const Index i : fronts[0].indices) ASSERT_GT(c.points[i].x(), doors[1].x0 - 0.02f);
    // The left door is a front without fixtures of the points the handle's front gave up.
    EXPECT_TRUE(fronts[1].fixtures.empty());
    EXPECT_NEAR(FrontXRange(fronts[1]).first, doors[0].x0, 0.025f);
    EXPECT_NEAR(FrontXRange(fronts[1]).second, doors[0].x1, 0.025f);
    Indices shared;
    std::set_intersection(fronts[0].indices.begin(), fronts[0].indices.end(),
                          fronts[1].indices.begin(), fronts[1].indices.end(),
                          std::back_inserter(shared));
    EXPECT_TRUE(shared.empty());
    // The same input gives the same fronts.
    std::vector<Front> again = {both};
    AddFrontsFromGaps(c, RoomFrame{}, sc.s, fx.fixtures, sc.ev, again, {}, split);
    ASSERT_EQ(again.size(), 2u);
    EXPECT_EQ(again[0].indices, fronts[0].indices);
    EXPECT_EQ(again[1].indices, fronts[1].indices);
    // Off (the default, and the laser's), the front spans both doors as it came.
    std::vector<Front> off = {both};
    AddFrontsFromGaps(c, RoomFrame{}, sc.s, fx.fixtures, sc.ev, off);
    ASSERT_EQ(off.size(), 1u);
    EXPECT_EQ(off[0].indices, both.indices);
    // A door of one front with its handle is not cut.
    const Front one = PartOfFace(c, sc, {0.93f, 2.4f, 0.1f}, {1.6f, 2.4f, 0.85f}, measured);
    std::vector<Front> whole = {one};
    AddFrontsFromGaps(c, RoomFrame{}, sc.s, fx.fixtures, sc.ev, whole, {}, split);
    ASSERT_GE(whole.size(), 1u);
    EXPECT_EQ(whole[0].indices, one.indices);
}

TEST(FrontsFromGaps, AFaceWithoutGapsWiderThanAFrontHasNone) {
    const PointCloud c = DoorsInGaps({});
    const FaceScene sc = SceneOf(c);
    const RoomStructure& s = sc.s;
    const FrontEvidence& ev = sc.ev;
    std::vector<Front> fronts;
    AddFrontsFromGaps(c, RoomFrame{}, s, {}, ev, fronts);
    EXPECT_TRUE(fronts.empty());  // 1.3 m wide: no front
    // Allowed that wide, the whole face is one.
    AddFrontsFromGaps(c, RoomFrame{}, s, {}, ev, fronts, {}, {.max_width = 1.5f});
    EXPECT_EQ(fronts.size(), 1u);
    // Empty input, bad parameters and evidence of the wrong size.
    std::vector<Front> none;
    AddFrontsFromGaps(PointCloud{}, RoomFrame{}, RoomStructure{}, {}, {}, none);
    EXPECT_TRUE(none.empty());
    EXPECT_THROW(AddFrontsFromGaps(c, RoomFrame{}, s, {}, ev, none, {}, {.cut_support = 0.0f}),
                 InvalidArgument);
    EXPECT_THROW(AddFrontsFromGaps(c, RoomFrame{}, s, {}, ev, none, {}, {.max_width = 0.1f}),
                 InvalidArgument);
    EXPECT_THROW(AddFrontsFromGaps(c, RoomFrame{}, s, {}, ev, none, {}, {.min_fill = 2.0f}),
                 InvalidArgument);
    EXPECT_THROW(AddFrontsFromGaps(c, RoomFrame{}, s, {}, ev, none, {.cell = -1.0f}, {}),
                 InvalidArgument);
    FrontEvidence bad = ev;
    bad.point_face.resize(5);
    EXPECT_THROW(AddFrontsFromGaps(c, RoomFrame{}, s, {}, bad, none), InvalidArgument);
    EXPECT_TRUE(none.empty());
}

TEST(ImageEdges, ColourStepOfAnOrganizedScan) {
    PointCloud c;
    c.width = 40;
    c.height = 30;
    for (int v = 0; v < 30; ++v) {
        for (int u = 0; u < 40; ++u) {
            c.points.emplace_back(0.01f * static_cast<float>(u), 0.01f * static_cast<float>(v), 1);
            const std::uint8_t g = u < 20 ? 50 : 200;
            c.colors.push_back(Color{g, g, g, 255});
        }
    }
    const std::vector<std::uint8_t> e = ImageEdges(c);
    ASSERT_EQ(e.size(), c.size());
    for (int v = 2; v < 28; ++v) {
        const auto row = static_cast<std::size_t>(v * 40);
        EXPECT_TRUE(e[row + 19] || e[row + 20]) << v;
        EXPECT_FALSE(e[row + 8]) << v;
        EXPECT_FALSE(e[row + 32]) << v;
    }
    // Unorganized or without colour and intensity: no edges.
    PointCloud flat = c;
    flat.width = static_cast<std::uint32_t>(flat.size());
    flat.height = 1;
    for (const auto x : ImageEdges(flat)) EXPECT_EQ(x, 0);
    PointCloud grey = c;
    grey.colors.clear();
    for (const auto x : ImageEdges(grey)) EXPECT_EQ(x, 0);
    EXPECT_THROW(ImageEdges(c, {.low = 60.0f, .high = 50.0f}), InvalidArgument);
    EXPECT_THROW(ImageEdges(c, {.stretch_quantile = 0.5f}), InvalidArgument);
}

TEST(FixtureParams, BadValuesNameTheField) {
    const test::SyntheticKitchen k = test::MakeSyntheticKitchen(1);
    const RoomStructure s = SegmentRoomStructure(k.cloud, RoomFrame{}, {});
    for (const FixtureParams& p :
         {FixtureParams{.background_cell = 0.0f}, FixtureParams{.background_radius = -1},
          FixtureParams{.background_passes = 0}, FixtureParams{.min_confidence = 1.5f},
          FixtureParams{.residual_sigmas = -1.0f}, FixtureParams{.surround_outer = 0.001f}}) {
        EXPECT_THROW(p.Validate(), InvalidArgument);
        EXPECT_THROW(DetectFixtures(k.cloud, RoomFrame{}, s, p), InvalidArgument);
    }
    EXPECT_THROW(DetectFixtures(k.cloud, RoomFrame{}, s, {}, std::vector<float>(5, 1.0f)),
                 InvalidArgument);
    MapKitchenParams m = KitchenParamsFor(KitchenSensor::kKinect);
    m.outline.hole_reach = -1;
    EXPECT_THROW(m.Validate(), InvalidArgument);
    m = KitchenParamsFor(KitchenSensor::kLaser);
    m.image_edges.high = -1.0f;
    EXPECT_THROW(m.Validate(), InvalidArgument);
    auto options = [](auto change) {
        training::FixtureTrainingOptions o;
        change(o);
        return o;
    };
    using Options = training::FixtureTrainingOptions;
    EXPECT_THROW(options([](Options& o) { o.kitchens = 0; }).Validate(), InvalidArgument);
    EXPECT_THROW(options([](Options& o) { o.match_distance = 0.0f; }).Validate(), InvalidArgument);
    EXPECT_THROW(options([](Options& o) { o.fold = 2; }).Validate(), InvalidArgument);
    EXPECT_THROW(options([](Options& o) { o.handle_variation.max_length = 0.01f; }).Validate(),
                 InvalidArgument);
    EXPECT_THROW(training::SelectKitchenFold({}, 2), InvalidArgument);
}

/// Adds a ground-truth field of `T` values (as sim::AddKitchenTruth writes them) to `c`.
template <typename T>
void AddTruthField(PointCloud& c, const char* name, const std::vector<T>& values) {
    ExtraField f{name, 'U', sizeof(T), 1, {}};
    f.data.resize(values.size() * sizeof(T));
    std::memcpy(f.data.data(), values.data(), f.data.size());
    c.extra_fields.push_back(std::move(f));
}

TEST(ContainerTraining, PiecesBelongToTheModelHoldingMostOfTheirMatchedFronts) {
    // 350 points: a door (model 1, link 1), a drawer (model 1, link 2), a door (model 2, link 1)
    // of 100 points each, and 50 body points of model 2.
    PointCloud c;
    std::vector<std::uint8_t> semantic;
    std::vector<std::uint16_t> model, link;
    auto add = [&](int n, sim::KitchenClass cls, std::uint16_t m, std::uint16_t l) {
        for (int i = 0; i < n; ++i) {
            c.points.emplace_back(0.01f * static_cast<float>(c.size()), 0.0f, 0.0f);
            semantic.push_back(static_cast<std::uint8_t>(cls));
            model.push_back(m);
            link.push_back(l);
        }
    };
    add(100, sim::KitchenClass::kDoor, 1, 1);
    add(100, sim::KitchenClass::kDrawer, 1, 2);
    add(100, sim::KitchenClass::kDoor, 2, 1);
    add(50, sim::KitchenClass::kBody, 2, 0);
    c.width = static_cast<std::uint32_t>(c.size());
    c.height = 1;
    AddTruthField(c, "semantic", semantic);
    AddTruthField(c, "model", model);
    AddTruthField(c, "link", link);
    auto range = [](Index a, Index b) {
        Indices out;
        for (Index i = a; i < b; ++i) out.push_back(i);
        return out;
    };
    // Fronts: the first door exactly and the drawer with 20 points of the second door (piece
    // 0), the rest of the second door (piece 1), the body (piece 2).
    KitchenMap map;
    map.fronts.resize(4);
    map.fronts[0].indices = range(0, 100);
    map.fronts[1].indices = range(100, 220);
    map.fronts[2].indices = range(220, 300);
    map.fronts[3].indices = range(300, 350);
    for (const int f : {0, 1, 2, 3}) map.fronts[static_cast<std::size_t>(f)].furniture = f;
    map.fronts[1].furniture = 0;
    map.fronts[2].furniture = 1;
    map.fronts[3].furniture = 2;

    const training::ScanTruth truth(c);
    const auto fronts = training::TrueFronts(c, truth);
    ASSERT_EQ(fronts.size(), 3u);  // the body is no front
    const auto match = training::MatchFronts(map, truth, fronts);
    ASSERT_EQ(match.size(), 3u);
    EXPECT_EQ(match.at((1u << 16) | 1u).first, 0);
    EXPECT_FLOAT_EQ(match.at((1u << 16) | 1u).second, 1.0f);
    EXPECT_EQ(match.at((1u << 16) | 2u).first, 1);
    EXPECT_NEAR(match.at((1u << 16) | 2u).second, 100.0f / 120.0f, 1e-6f);
    EXPECT_EQ(match.at((2u << 16) | 1u).first, 2);  // front 1 is taken by its better match
    EXPECT_NEAR(match.at((2u << 16) | 1u).second, 0.8f, 1e-6f);

    const auto pieces = training::FurnitureInstances(map, c);
    EXPECT_EQ(pieces, (std::map<int, int>{{0, 0}, {1, 1}}));  // instances count from 0
    EXPECT_EQ(training::FurnitureInstances(map, c, 0.9f), (std::map<int, int>{{0, 0}}));
    // A scan without the ground-truth fields has no true fronts, hence no pieces.
    PointCloud bare;
    bare.points = c.points;
    EXPECT_TRUE(training::FurnitureInstances(map, bare).empty());
}

TEST(ContainerTraining, RowsOfAProceduralKitchenAreLabelledAndReproducible) {
    const auto models = sim::ProceduralKitchenEntries(2, 5, true);
    training::ContainerTrainingOptions o;
    o.kitchens = 1;
    o.views = 1;
    o.laser_views = 0;
    sim::KitchenModelCache cache;
    const ml::Dataset rows = training::CollectContainerRows(models, cache, o);
    ASSERT_GT(rows.rows(), 2u);
    EXPECT_EQ(rows.cols(), ContainerFeatureNames().size());
    for (const auto& name : rows.class_names) {
        EXPECT_NE(std::find(ContainerTypeNames().begin(), ContainerTypeNames().end(), name),
                  ContainerTypeNames().end())
            << name;
    }
    const ml::Dataset again = training::CollectContainerRows(models, cache, o);
    EXPECT_EQ(again.values, rows.values);
    EXPECT_EQ(again.labels, rows.labels);
    EXPECT_EQ(again.class_names, rows.class_names);
    ASSERT_GE(rows.num_classes(), 2u);  // appliances and cupboards in one kitchen
    // The forest learns its own rows.
    const auto classifier = training::TrainContainerClassifier(rows, "rtrees:trees=20");
    const std::vector<int> predicted = classifier->Predict(rows);
    std::size_t right = 0;
    for (std::size_t r = 0; r < rows.rows(); ++r) right += predicted[r] == rows.labels[r];
    EXPECT_GE(right * 10, rows.rows() * 8);
    EXPECT_NO_THROW(CheckContainerClassifier(*classifier));
    // A classifier of other columns, or of the right columns with a class that is no container
    // type, is refused before it types anything.
    ml::Dataset foreign_rows = training::EmptyContainerDataset();
    for (std::size_t r = 0; r < rows.rows(); ++r) {
        foreign_rows.AppendRow(rows.row(r), r % 2 == 0 ? "cupboard" : "wardrobe");
    }
    const auto foreign = training::TrainContainerClassifier(foreign_rows, "rtrees:trees=5");
    EXPECT_THROW(CheckContainerClassifier(*foreign), InvalidArgument);
    KitchenMap one_piece;
    one_piece.furniture.resize(1);
    EXPECT_THROW(TypeContainers(one_piece, foreign.get()), InvalidArgument);
    EXPECT_NO_THROW(TypeContainers(one_piece, classifier.get()));
    EXPECT_THROW(CheckContainerClassifier(*training::TrainFixtureClassifier(
                     [] {
                         ml::Dataset d = training::EmptyFixtureDataset();
                         d.AppendRow(FixtureFeatureRow(FixtureEvidence{}), "none");
                         d.AppendRow(std::vector<float>(FixtureFeatureNames().size(), 1.0f),
                                     "handle");
                         return d;
                     }(),
                     "rtrees:trees=5")),
                 InvalidArgument);
    // One type cannot train; bad options are refused before any kitchen is built.
    ml::Dataset one = training::EmptyContainerDataset();
    one.AppendRow(std::vector<float>(ContainerFeatureNames().size(), 0.0f), "cupboard");
    EXPECT_THROW(training::TrainContainerClassifier(one, "rtrees:trees=5"), DataError);
    for (auto change : std::initializer_list<void (*)(training::ContainerTrainingOptions&)>{
             [](training::ContainerTrainingOptions& b) { b.kitchens = 0; },
             [](training::ContainerTrainingOptions& b) { b.views = b.laser_views = 0; },
             [](training::ContainerTrainingOptions& b) { b.views = -1; },
             [](training::ContainerTrainingOptions& b) { b.procedural_share = 2.0f; },
             [](training::ContainerTrainingOptions& b) { b.num_threads = -1; }}) {
        training::ContainerTrainingOptions bad = o;
        change(bad);
        EXPECT_THROW(training::CollectContainerRows(models, cache, bad), InvalidArgument);
    }
    // No models: no kitchen can be built.
    EXPECT_THROW(training::CollectContainerRows({}, cache, o), DataError);
}

}  // namespace
}  // namespace multicue
