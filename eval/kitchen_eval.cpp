// Accuracy of kitchen maps (thesis section 4.1) on simulated kitchens built from held-out kitchen
// models: per-class IoU of points (wall, floor, ceiling, worktop, front), handle and knob
// detection (a detection within 3 cm of a true fixture), front segmentation IoU per front, joint
// types and hinge axes against each kitchen's ground-truth URDF, container types (confusion
// matrix), and joints from opened-front scan pairs.
//
// The container classifier is trained on kitchens of the other half of the models (never the
// ones scored); --rules types containers by rules instead.
//
//   build/eval/kitchen_eval [--kitchens 10] [--train-kitchens 12] [--views 3] [--seed 1]
//                           [--sensor both|kinect|laser] [--split test] [--rules] [--json F]
//                           [--save-containers MODEL]

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "driver_options.hpp"
#include "kitchen_truth.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/sensors.hpp"

#ifndef MULTICUE_SHARED_DATA_DIR
#define MULTICUE_SHARED_DATA_DIR "../shared/data"
#endif

namespace {

using namespace multicue;
using namespace multicue::eval;
using mapping::MapClass;

struct Options {
    int kitchens = 10;
    int train_kitchens = 12;
    int views = 3;
    int laser_views = 1;
    int open = 3;
    std::uint64_t seed = 1;
    std::string sensor = "both";
    std::string split = "test";
    std::string models = std::string(MULTICUE_SHARED_DATA_DIR) + "/meshes/kitchen";
    bool rules = false;
    bool verbose = false;
    std::string json;
    std::string save_containers;
};

/// Summary statistics of a list of values.
struct Stats {
    std::vector<double> v;
    void Add(double x) { v.push_back(x); }
    double Mean() const {
        double s = 0;
        for (double x : v) s += x;
        return v.empty() ? 0.0 : s / static_cast<double>(v.size());
    }
    double Median() const {
        if (v.empty()) return 0.0;
        auto w = v;
        std::nth_element(w.begin(), w.begin() + static_cast<long>(w.size() / 2), w.end());
        return w[w.size() / 2];
    }
    double Min() const { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); }
    double Max() const { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); }
    nlohmann::json Json() const {
        return {{"n", v.size()},
                {"mean", Mean()},
                {"median", Median()},
                {"min", Min()},
                {"max", Max()}};
    }
};

const std::vector<std::string> kIouClasses = {"wall", "floor", "ceiling", "worktop", "front"};

/// The evaluation class of a true and of a predicted point (-1: none of them).
int TrueIouClass(KitchenClass c) {
    switch (c) {
        case KitchenClass::kWall:
            return 0;
        case KitchenClass::kFloor:
            return 1;
        case KitchenClass::kCeiling:
            return 2;
        case KitchenClass::kWorktop:
            return 3;
        case KitchenClass::kDoor:
        case KitchenClass::kDrawer:
            return 4;
        default:
            return -1;
    }
}
int PredIouClass(MapClass c) {
    switch (c) {
        case MapClass::kWall:
            return 0;
        case MapClass::kFloor:
            return 1;
        case MapClass::kCeiling:
            return 2;
        case MapClass::kWorktop:
            return 3;
        case MapClass::kFront:
            return 4;
        default:
            return -1;
    }
}

/// Scores of one sensor.
struct Scores {
    std::array<double, 5> inter{}, uni{};
    std::array<Stats, 5> frame_iou;
    std::size_t handle_tp = 0, handle_fp = 0, handle_fn = 0;
    std::size_t knob_tp = 0, knob_fp = 0, knob_fn = 0;
    std::size_t any_tp = 0, any_fp = 0, any_fn = 0;
    std::map<std::string, std::size_t> fp_on;   ///< class of the point under a false detection
    std::map<std::string, std::size_t> fn_why;  ///< why true fixtures were missed
    Stats front_iou_detectable, front_iou_all, front_iou_found;
    std::size_t joint_correct = 0, joint_total = 0;
    std::size_t sign_correct = 0;
    Stats axis_angle, axis_position;
    std::vector<std::vector<std::size_t>> confusion =
        std::vector<std::vector<std::size_t>>(7, std::vector<std::size_t>(7, 0));
    std::size_t open_correct = 0, open_total = 0, open_missed = 0;
    std::map<std::string, std::size_t> open_confusion;  ///< "true -> predicted"
    Stats open_angle, open_position;
    Stats time_ms;
    std::size_t frames = 0;
    std::size_t failed = 0;  ///< frames the map refused (DataError)
};

int TypeIndex(const std::string& t) {
    const auto& names = mapping::ContainerTypeNames();
    return static_cast<int>(std::find(names.begin(), names.end(), t) - names.begin());
}

/// One scanned frame with its ground truth.
struct Frame {
    PointCloud cloud;
    bool laser = false;
    Eigen::Isometry3f pose;
};

class Evaluator {
  public:
    explicit Evaluator(const Options& o) : o_(o) {
        kinect_.shading = 0.3f;
        laser_.tilt_min_deg = -40.0f;
        laser_.tilt_max_deg = 60.0f;
    }

    /// Kitchens of `split` with their frames.
    std::vector<Frame> Frames(sim::KitchenScene& k, std::uint64_t seed) const {
        std::vector<Frame> out;
        const sim::RayCaster caster(k.scene);
        std::size_t v = 0;
        if (o_.sensor != "kinect") {
            for (const auto& pose : sim::KitchenLaserPoses(k, o_.laser_views, seed)) {
                Frame f{sim::ScanLaser(caster, pose, laser_, sim::SubSeed(seed, 100 + v++)), true,
                        pose};
                sim::AddKitchenTruth(k, f.cloud);
                sim::ScanToWorld(f.cloud, pose);
                out.push_back(std::move(f));
            }
        }
        if (o_.sensor != "laser") {
            for (const auto& pose : sim::KitchenCameraPoses(k, o_.views, seed)) {
                Frame f{sim::ScanKinect(caster, pose, kinect_, sim::SubSeed(seed, 100 + v++)),
                        false, pose};
                sim::AddKitchenTruth(k, f.cloud);
                sim::ScanToWorld(f.cloud, pose);
                out.push_back(std::move(f));
            }
        }
        return out;
    }

    mapping::MapKitchenResult Map(const Frame& f, const ml::Classifier* classifier) const {
        const auto sensor =
            f.laser ? mapping::KitchenSensor::kLaser : mapping::KitchenSensor::kKinect;
        return mapping::MapKitchen({f.cloud}, mapping::KitchenParamsFor(sensor), classifier);
    }

    /// Training rows: the features of predicted furniture labelled by the true model whose fronts
    /// they hold most of.
    void CollectTraining(const sim::KitchenScene& k, const Frame& f,
                         const mapping::MapKitchenResult& r, ml::Dataset& data) const {
        const ScanTruth t(f.cloud);
        const auto fronts = TrueFronts(f.cloud, t);
        const auto match = MatchFronts(r.map, t, fronts);
        std::map<int, std::map<int, std::size_t>> votes;  // furniture -> instance -> points
        for (const auto& [key, m] : match) {
            if (m.second < 0.3f) continue;
            const int furn = r.map.fronts[static_cast<std::size_t>(m.first)].furniture;
            votes[furn][static_cast<int>(key >> 16) - 1] += fronts.at(key).points;
        }
        for (const auto& [furn, v] : votes) {
            int best = -1;
            std::size_t n = 0;
            for (const auto& [inst, c] : v) {
                if (c > n) {
                    n = c;
                    best = inst;
                }
            }
            const auto x = mapping::ContainerFeatures(r.map, static_cast<std::size_t>(furn));
            data.AppendRow(x, sim::ContainerTypeOfKind(
                                  k.instances[static_cast<std::size_t>(best)].model->kind));
        }
    }

    void Score(sim::KitchenScene& k, const std::map<std::string, Axis>& axes, const Frame& f,
               const mapping::MapKitchenResult& r, Scores& s, std::uint64_t seed) const {
        const ScanTruth t(f.cloud);
        const auto& map = r.map;
        ++s.frames;
        s.time_ms.Add(r.time_ms);
        // Point IoU per class.
        std::array<double, 5> inter{}, uni{};
        for (std::size_t i = 0; i < f.cloud.size(); ++i) {
            if (!f.cloud.IsFinite(i)) continue;
            const int a = TrueIouClass(t.Class(i)), b = PredIouClass(map.point_class[i]);
            if (a >= 0 && a == b) inter[static_cast<std::size_t>(a)] += 1;
            if (a >= 0) uni[static_cast<std::size_t>(a)] += 1;
            if (b >= 0 && b != a) uni[static_cast<std::size_t>(b)] += 1;
        }
        for (std::size_t c = 0; c < 5; ++c) {
            s.inter[c] += inter[c];
            s.uni[c] += uni[c];
            if (uni[c] > 0) s.frame_iou[c].Add(inter[c] / uni[c]);
        }
        // Fixtures: greedy 1:1 by distance from the detection's centre to the true points.
        const std::size_t min_fixture = f.laser ? 4 : 15;
        const auto fixtures = TrueFixtures(f.cloud, t, min_fixture);
        {
            // Either type: a detection within 3 cm of any true fixture.
            std::vector<std::pair<float, std::pair<std::size_t, std::size_t>>> cand;
            for (std::size_t d = 0; d < map.fixtures.size(); ++d) {
                for (std::size_t g = 0; g < fixtures.size(); ++g) {
                    float best = 1e9f;
                    for (const Index i : fixtures[g].points) {
                        best = std::min(best, (f.cloud.points[i] - map.fixtures[d].center).norm());
                    }
                    if (best <= 0.03f) cand.push_back({best, {d, g}});
                }
            }
            std::sort(cand.begin(), cand.end());
            std::vector<bool> du(map.fixtures.size()), gu(fixtures.size());
            std::size_t tp = 0;
            for (const auto& [dist, dg] : cand) {
                if (du[dg.first] || gu[dg.second]) continue;
                du[dg.first] = gu[dg.second] = true;
                ++tp;
            }
            if (std::getenv("KITCHEN_EVAL_FIXTURES") != nullptr) {
                for (std::size_t d = 0; d < map.fixtures.size(); ++d) {
                    const auto& fx = map.fixtures[d];
                    std::fprintf(stderr, "FIX %d %d %.4f %.4f %.4f %zu %.3f %.3f %d\n",
                                 du[d] ? 1 : 0, fx.type == mapping::FixtureType::kHandle ? 1 : 0,
                                 fx.length, fx.width, fx.protrusion, fx.indices.size(),
                                 fx.line_inlier_ratio, fx.circle_inlier_ratio, f.laser ? 1 : 0);
                }
            }
            for (std::size_t d = 0; d < map.fixtures.size(); ++d) {
                if (du[d] || map.fixtures[d].indices.empty()) continue;
                const Index mid = map.fixtures[d].indices[map.fixtures[d].indices.size() / 2];
                ++s.fp_on[sim::KitchenClassNames()[t.semantic[mid]]];
            }
            for (std::size_t g = 0; g < fixtures.size(); ++g) {
                if (gu[g]) continue;
                Eigen::Vector3f c = Eigen::Vector3f::Zero();
                std::map<std::string, std::size_t> cls;
                for (const Index i : fixtures[g].points) {
                    c += f.cloud.points[i];
                    ++cls[mapping::MapClassNames()[static_cast<std::size_t>(map.point_class[i])]];
                }
                c /= static_cast<float>(fixtures[g].points.size());
                std::string why;
                for (const auto& rj : r.rejected_fixtures) {
                    if ((rj.center - c).norm() < 0.05f) why = rj.reason;
                }
                if (why.empty()) {
                    std::size_t most = 0;
                    for (const auto& [name, n] : cls) {
                        if (n > most) {
                            most = n;
                            why = "no cluster, points labelled " + name;
                        }
                    }
                }
                ++s.fn_why[why];
            }
            s.any_tp += tp;
            s.any_fp += map.fixtures.size() - tp;
            s.any_fn += fixtures.size() - tp;
        }
        for (const bool handle : {true, false}) {
            std::vector<std::pair<float, std::pair<std::size_t, std::size_t>>> cand;
            std::size_t n_det = 0, n_true = 0;
            for (std::size_t d = 0; d < map.fixtures.size(); ++d) {
                if ((map.fixtures[d].type == mapping::FixtureType::kHandle) != handle) continue;
                ++n_det;
                for (std::size_t g = 0; g < fixtures.size(); ++g) {
                    if (fixtures[g].handle != handle) continue;
                    float best = 1e9f;
                    for (const Index i : fixtures[g].points) {
                        best = std::min(best, (f.cloud.points[i] - map.fixtures[d].center).norm());
                    }
                    if (best <= 0.03f) cand.push_back({best, {d, g}});
                }
            }
            for (const auto& g : fixtures) n_true += g.handle == handle;
            std::sort(cand.begin(), cand.end());
            std::vector<bool> du(map.fixtures.size()), gu(fixtures.size());
            std::size_t tp = 0;
            for (const auto& [dist, dg] : cand) {
                if (du[dg.first] || gu[dg.second]) continue;
                du[dg.first] = gu[dg.second] = true;
                ++tp;
            }
            (handle ? s.handle_tp : s.knob_tp) += tp;
            (handle ? s.handle_fp : s.knob_fp) += n_det - tp;
            (handle ? s.handle_fn : s.knob_fn) += n_true - tp;
        }
        // Fronts.
        const std::size_t min_front = f.laser ? 40 : 400;
        const auto fronts = TrueFronts(f.cloud, t);
        const auto match = MatchFronts(map, t, fronts);
        std::map<int, std::map<int, std::size_t>> furniture_votes;  // instance -> furniture
        for (const auto& [key, tf] : fronts) {
            if (tf.points < min_front) continue;
            const auto it = match.find(key);
            const float iou = it == match.end() ? 0.0f : it->second.second;
            s.front_iou_all.Add(iou);
            if (tf.fixture_points >= min_fixture) s.front_iou_detectable.Add(iou);
            // Fronts whose fixture was detected: how well the region grew.
            bool found = false;
            for (const auto& g : fixtures) {
                if (g.key != key) continue;
                for (const auto& d : map.fixtures) {
                    for (const Index i : g.points) {
                        found = found || (f.cloud.points[i] - d.center).norm() <= 0.03f;
                        if (found) break;
                    }
                }
            }
            if (found) s.front_iou_found.Add(iou);
            if (it == match.end() || iou < 0.5f || tf.joint < 0) continue;
            const mapping::Front& pf = map.fronts[static_cast<std::size_t>(it->second.first)];
            furniture_votes[static_cast<int>(key >> 16) - 1][pf.furniture] += tf.points;
            const sim::KitchenJoint& kj = k.joints[static_cast<std::size_t>(tf.joint)];
            const bool revolute = kj.type != io::UrdfJointType::kPrismatic;
            const auto pt = pf.articulation.type;
            ++s.joint_total;
            const bool correct = (revolute && pt == mapping::JointType::kRevolute) ||
                                 (!revolute && pt == mapping::JointType::kPrismatic);
            s.joint_correct += correct;
            if (revolute && correct) {
                const Axis& gt = axes.at(kj.name);
                const Axis pred{pf.articulation.origin, pf.articulation.axis};
                s.axis_angle.Add(LineAngleDeg(pred.direction, gt.direction));
                s.axis_position.Add(LineDistanceAt(pred, gt, pf.center));
                s.sign_correct += pred.direction.dot(gt.direction) > 0;
            }
        }
        // Container types: the piece holding most of a model's matched fronts.
        for (const auto& [inst, votes] : furniture_votes) {
            int best = -1;
            std::size_t n = 0;
            for (const auto& [furn, c] : votes) {
                if (c > n) {
                    n = c;
                    best = furn;
                }
            }
            if (best < 0) continue;
            const int gt = TypeIndex(
                sim::ContainerTypeOfKind(k.instances[static_cast<std::size_t>(inst)].model->kind));
            const int pr = TypeIndex(map.furniture[static_cast<std::size_t>(best)].type);
            if (gt < 7 && pr < 7)
                ++s.confusion[static_cast<std::size_t>(gt)][static_cast<std::size_t>(pr)];
        }
        // Opened-front pairs: the robot opens matched fronts of this view one at a time.
        if (o_.open <= 0) return;
        std::vector<std::uint32_t> keys;
        for (const auto& [key, tf] : fronts) {
            const auto it = match.find(key);
            if (tf.points >= 3 * min_front && tf.joint >= 0 && it != match.end() &&
                it->second.second >= 0.5f && k.joints[static_cast<std::size_t>(tf.joint)].front) {
                keys.push_back(key);
            }
        }
        sim::StreamRng rng(seed, 29);
        std::shuffle(keys.begin(), keys.end(), rng);
        if (keys.size() > static_cast<std::size_t>(o_.open))
            keys.resize(static_cast<std::size_t>(o_.open));
        for (const std::uint32_t key : keys) {
            const TrueFront& tf = fronts.at(key);
            const std::size_t j = static_cast<std::size_t>(tf.joint);
            const sim::KitchenJoint kj = k.joints[j];
            const auto& aj = k.instances[static_cast<std::size_t>(kj.instance)]
                                 .model->joints[static_cast<std::size_t>(kj.joint)];
            const float closed = aj.Closed();
            const bool revolute = kj.type != io::UrdfJointType::kPrismatic;
            float value = 0.0f;
            if (revolute) {
                const float far = aj.Opened(1.0f);
                value = closed + std::copysign(std::min(static_cast<float>(rng.Uniform(0.6, 1.4)),
                                                        std::abs(far - closed)),
                                               far - closed);
            } else {
                value = aj.Opened(static_cast<float>(rng.Uniform(0.4, 0.9)));
            }
            k.SetJoint(j, value);
            Frame opened;
            {
                const sim::RayCaster caster(k.scene);
                Eigen::Isometry3f pose = f.pose;
                opened.cloud = f.laser ? sim::ScanLaser(caster, pose, laser_, rng())
                                       : sim::ScanKinect(caster, pose, kinect_, rng());
                sim::ScanToWorld(opened.cloud, pose);
            }
            k.SetJoint(j, closed);
            const mapping::Front& pf = map.fronts[static_cast<std::size_t>(match.at(key).first)];
            mapping::MotionParams mp;
            if (f.laser) {
                mp.change_distance = 0.04f;
                mp.plane_threshold = 0.03f;
                mp.min_points = 10;
            }
            const auto motion = mapping::ArticulationFromMotion(f.cloud, opened.cloud, pf, mp);
            ++s.open_total;
            if (!motion.found) {
                ++s.open_missed;
                continue;
            }
            const auto pt = motion.articulation.type;
            const bool correct = (revolute && pt == mapping::JointType::kRevolute) ||
                                 (!revolute && pt == mapping::JointType::kPrismatic);
            ++s.open_confusion[std::string(revolute ? "revolute" : "prismatic") + " -> " +
                               mapping::JointTypeName(pt)];
            s.open_correct += correct;
            if (!correct) continue;
            const Axis& gt = axes.at(kj.name);
            const Axis pred{motion.articulation.origin, motion.articulation.axis};
            s.open_angle.Add(LineAngleDeg(pred.direction, gt.direction));
            if (revolute) s.open_position.Add(LineDistanceAt(pred, gt, pf.center));
        }
    }

    int Run() {
        const auto library = sim::ReadKitchenLibrary(o_.models);
        const auto test_split = sim::ParseMeshSplit(o_.split);
        const auto train_split =
            test_split == sim::MeshSplit::kTest ? sim::MeshSplit::kTune : sim::MeshSplit::kTest;
        const auto test_lib = sim::SelectKitchenSplit(library, test_split);
        const auto train_lib = sim::SelectKitchenSplit(library, train_split);
        sim::KitchenModelCache cache;
        std::unique_ptr<ml::Classifier> classifier;
        std::size_t train_rows = 0;
        if (!o_.rules && o_.train_kitchens > 0) {
            ml::Dataset data =
                ml::Dataset::WithBlocks({{"container", mapping::ContainerFeatureNames()}});
            for (int i = 0; i < o_.train_kitchens; ++i) {
                const std::uint64_t seed =
                    sim::SubSeed(o_.seed ^ 0x7261696eull, static_cast<std::uint64_t>(i));
                sim::KitchenScene k = sim::MakeKitchenScene(train_lib, cache, {}, seed);
                for (const Frame& f : Frames(k, seed)) {
                    try {
                        CollectTraining(k, f, Map(f, nullptr), data);
                    } catch (const DataError& e) {
                        std::fprintf(stderr, "training kitchen %d, %s frame: %s\n", i,
                                     f.laser ? "laser" : "kinect", e.what());
                    }
                }
            }
            train_rows = data.rows();
            if (data.num_classes() >= 2) {
                classifier = ml::CreateClassifier("rtrees:trees=100");
                classifier->Fit(data);
                if (!o_.save_containers.empty()) classifier->Save(o_.save_containers);
            }
            std::printf("container classifier: %zu training pieces from %d kitchens (%s half)\n",
                        train_rows, o_.train_kitchens,
                        std::string(sim::MeshSplitName(train_split)).c_str());
        }
        Scores kinect, laser;
        for (int i = 0; i < o_.kitchens; ++i) {
            const std::uint64_t seed = sim::SubSeed(o_.seed, static_cast<std::uint64_t>(i));
            sim::KitchenScene k = sim::MakeKitchenScene(test_lib, cache, {}, seed);
            // The ground truth of joint axes comes from the kitchen's URDF, written and re-read.
            const io::UrdfModel gt = io::ParseUrdf(io::UrdfToXml(sim::KitchenGroundTruthUrdf(k)),
                                                   fmt::format("kitchen_{}.urdf", i));
            const auto axes = UrdfJointAxes(gt);
            for (const Frame& f : Frames(k, seed)) {
                Scores& s = f.laser ? laser : kinect;
                try {
                    const auto r = Map(f, classifier.get());
                    Score(k, axes, f, r, s, seed ^ 0x5eedull);
                } catch (const DataError& e) {
                    // A frame the map refuses (nothing in range, no vertical plane) counts.
                    ++s.failed;
                    std::fprintf(stderr, "kitchen %d, %s frame: %s\n", i,
                                 f.laser ? "laser" : "kinect", e.what());
                }
            }
            if (o_.verbose) std::fprintf(stderr, "kitchen %d done\n", i);
        }
        nlohmann::json out = {{"split", o_.split},
                              {"kitchens", o_.kitchens},
                              {"seed", o_.seed},
                              {"containers", o_.rules ? "rules" : "rtrees"},
                              {"train_rows", train_rows}};
        if (o_.sensor != "laser") out["kinect"] = Report("kinect", kinect);
        if (o_.sensor != "kinect") out["laser"] = Report("laser", laser);
        if (!o_.json.empty()) {
            std::ofstream(o_.json) << out.dump(1) << "\n";
        }
        return 0;
    }

    nlohmann::json Report(const char* name, const Scores& s) const {
        auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
        std::printf("\n== %s: %zu frames of %d kitchens (%s half), %zu refused ==\n", name,
                    s.frames, o_.kitchens, o_.split.c_str(), s.failed);
        nlohmann::json j;
        j["frames"] = s.frames;
        j["refused_frames"] = s.failed;
        std::printf("point IoU (all frames pooled; worst frame):\n");
        for (std::size_t c = 0; c < 5; ++c) {
            const double iou = ratio(s.inter[c], s.uni[c]);
            if (s.uni[c] == 0) {
                std::printf("  %-8s -      (no points of the class)\n", kIouClasses[c].c_str());
                continue;
            }
            std::printf("  %-8s %.3f  (worst %.3f)\n", kIouClasses[c].c_str(), iou,
                        s.frame_iou[c].Min());
            j["iou"][kIouClasses[c]] = {{"pooled", iou}, {"frames", s.frame_iou[c].Json()}};
        }
        auto pr = [&](const char* what, std::size_t tp, std::size_t fp, std::size_t fn) {
            const double p = ratio(static_cast<double>(tp), static_cast<double>(tp + fp));
            const double r = ratio(static_cast<double>(tp), static_cast<double>(tp + fn));
            std::printf("  %-7s precision %.3f recall %.3f (tp %zu, fp %zu, fn %zu)\n", what, p, r,
                        tp, fp, fn);
            j["fixtures"][what] = {
                {"precision", p}, {"recall", r}, {"tp", tp}, {"fp", fp}, {"fn", fn}};
        };
        std::printf("fixtures (within 3 cm):\n");
        pr("handle", s.handle_tp, s.handle_fp, s.handle_fn);
        pr("knob", s.knob_tp, s.knob_fp, s.knob_fn);
        pr("any", s.any_tp, s.any_fp, s.any_fn);
        if (o_.verbose) {
            std::printf("  missed fixtures:");
            for (const auto& [c, n] : s.fn_why) std::printf(" [%s] %zu", c.c_str(), n);
            std::printf("\n");
            std::printf("  false detections on:");
            for (const auto& [c, n] : s.fp_on) std::printf(" %s %zu", c.c_str(), n);
            std::printf("\n");
        }
        std::printf(
            "front IoU: fronts with a visible fixture mean %.3f median %.3f (n %zu); all "
            "visible fronts mean %.3f (n %zu)\n",
            s.front_iou_detectable.Mean(), s.front_iou_detectable.Median(),
            s.front_iou_detectable.v.size(), s.front_iou_all.Mean(), s.front_iou_all.v.size());
        std::printf(
            "front IoU of fronts whose fixture was detected: mean %.3f median %.3f worst "
            "%.3f (n %zu)\n",
            s.front_iou_found.Mean(), s.front_iou_found.Median(), s.front_iou_found.Min(),
            s.front_iou_found.v.size());
        j["front_iou"] = {{"fixture_detected", s.front_iou_found.Json()},
                          {"with_fixture", s.front_iou_detectable.Json()},
                          {"all", s.front_iou_all.Json()}};
        const double jacc =
            ratio(static_cast<double>(s.joint_correct), static_cast<double>(s.joint_total));
        std::printf("joint type accuracy %.3f (%zu of %zu matched fronts)\n", jacc, s.joint_correct,
                    s.joint_total);
        std::printf(
            "hinge axis: angle mean %.2f median %.2f max %.2f deg; position mean %.3f "
            "median %.3f max %.3f m; opening sign right %zu of %zu\n",
            s.axis_angle.Mean(), s.axis_angle.Median(), s.axis_angle.Max(), s.axis_position.Mean(),
            s.axis_position.Median(), s.axis_position.Max(), s.sign_correct, s.axis_angle.v.size());
        j["joint_type_accuracy"] = jacc;
        j["joint_total"] = s.joint_total;
        j["hinge_angle_deg"] = s.axis_angle.Json();
        j["hinge_position_m"] = s.axis_position.Json();
        j["hinge_sign_correct"] = s.sign_correct;
        std::size_t correct = 0, total = 0;
        const auto& names = mapping::ContainerTypeNames();
        std::printf("container types (rows true, columns predicted):\n  %-12s", "");
        for (const auto& n : names) std::printf(" %6.6s", n.c_str());
        std::printf("\n");
        for (std::size_t r = 0; r < 7; ++r) {
            std::printf("  %-12s", names[r].c_str());
            for (std::size_t c = 0; c < 7; ++c) {
                std::printf(" %6zu", s.confusion[r][c]);
                total += s.confusion[r][c];
                if (r == c) correct += s.confusion[r][c];
            }
            std::printf("\n");
        }
        const double cacc = ratio(static_cast<double>(correct), static_cast<double>(total));
        std::printf("container type accuracy %.3f (%zu of %zu)\n", cacc, correct, total);
        j["container_accuracy"] = cacc;
        j["container_confusion"] = s.confusion;
        const double oacc =
            ratio(static_cast<double>(s.open_correct), static_cast<double>(s.open_total));
        std::printf(
            "opened pairs: joint type accuracy %.3f (%zu of %zu, %zu without motion); axis "
            "angle mean %.2f median %.2f max %.2f deg; hinge position mean %.3f m\n",
            oacc, s.open_correct, s.open_total, s.open_missed, s.open_angle.Mean(),
            s.open_angle.Median(), s.open_angle.Max(), s.open_position.Mean());
        std::printf("  opened pairs (true -> estimated):");
        for (const auto& [c, n] : s.open_confusion) std::printf(" [%s] %zu", c.c_str(), n);
        std::printf("\n");
        j["opened"] = {{"joint_type_accuracy", oacc},
                       {"confusion", s.open_confusion},
                       {"pairs", s.open_total},
                       {"no_motion", s.open_missed},
                       {"axis_angle_deg", s.open_angle.Json()},
                       {"hinge_position_m", s.open_position.Json()}};
        std::printf("time per frame: median %.0f ms, worst %.0f ms (shared machine)\n",
                    s.time_ms.Median(), s.time_ms.Max());
        j["time_ms"] = s.time_ms.Json();
        return j;
    }

  private:
    Options o_;
    sim::KinectParams kinect_;
    sim::LaserParams laser_;
};

}  // namespace

int main(int argc, char** argv) {
    Options o;
    CLI::App app{"kitchen_eval: accuracy of kitchen maps on held-out simulated kitchens"};
    app.add_option("--kitchens", o.kitchens, "kitchens scored")->capture_default_str();
    app.add_option("--train-kitchens", o.train_kitchens,
                   "kitchens of the other half that train the container classifier")
        ->capture_default_str();
    app.add_option("--views", o.views, "Kinect views per kitchen")->capture_default_str();
    app.add_option("--laser-views", o.laser_views, "laser sweeps per kitchen")
        ->capture_default_str();
    app.add_option("--open", o.open, "fronts opened per frame for the pair test")
        ->capture_default_str();
    app.add_option("--seed", o.seed, "seed of the kitchens")->capture_default_str();
    app.add_option("--sensor", o.sensor, "both, kinect or laser")->capture_default_str();
    app.add_option("--split", o.split, "model half scored: test (default) or tune")
        ->capture_default_str();
    app.add_option("--models", o.models, "kitchen model library")->capture_default_str();
    app.add_flag("--rules", o.rules, "type containers by rules (no training)");
    app.add_flag("-v,--verbose", o.verbose, "progress on stderr");
    app.add_option("--json", o.json, "also write the figures as JSON");
    app.add_option("--save-containers", o.save_containers,
                   "also save the container classifier (for map kitchen --containers)");
    if (auto code = eval::ParseDriverOptions(app, "kitchen_eval", [&] {
            app.parse(argc, argv);
            if (o.sensor != "both" && o.sensor != "kinect" && o.sensor != "laser") {
                throw CLI::ValidationError("--sensor", "must be both, kinect or laser");
            }
            if (o.split != "test" && o.split != "tune") {
                throw CLI::ValidationError("--split", "must be test or tune");
            }
        })) {
        return *code;
    }
    try {
        return Evaluator(o).Run();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "kitchen_eval: %s\n", e.what());
        return 1;
    }
}
