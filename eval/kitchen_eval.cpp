// Accuracy of kitchen maps (thesis section 4.1) on simulated kitchens built from held-out kitchen
// models: per-class IoU of points (wall, floor, ceiling, worktop, front), handle and knob
// detection (a detection within 3 cm of a true fixture), front segmentation IoU per front, joint
// types and hinge axes against each kitchen's ground-truth URDF, container types (confusion
// matrix), and joints from opened-front scan pairs.
//
// The fixture classifiers (one per sensor, CollectFixtureRows + TrainFixtureClassifier) and the
// container classifier are trained on kitchens of the other half of the models (never the ones
// scored; --train-split tune trains on the tune half when the tune half is scored, to validate);
// --fixture-kitchens 0 finds fixtures by rules, --rules types containers by rules.
// The fixture training kitchens' handles are varied (sim::VaryHandles: length, reach out of the
// front, thickness; --no-vary-handles keeps them); --vary-scored-handles varies those of the
// scored kitchens (--scored-reach, --scored-thickness): a validation on handle designs the
// classifier has not seen.
//
//   build/eval/kitchen_eval [--kitchens 10] [--train-kitchens 48] [--fixture-kitchens 24]
//                           [--views 3] [--seed 1] [--sensor both|kinect|laser] [--split test]
//                           [--train-split other|tune|test] [--rules] [--json F]
//                           [--save-containers MODEL] [--save-fixtures PREFIX]
//                           [--load-containers MODEL] [--load-fixtures PREFIX]

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "driver_options.hpp"
#include "kitchen_truth.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/mapping/kitchen_map.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/sim/kitchen_procedural.hpp"
#include "multicue/sim/kitchen_scene.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/training/kitchen_training.hpp"

#ifndef MULTICUE_SHARED_DATA_DIR
#define MULTICUE_SHARED_DATA_DIR "../shared/data"
#endif

namespace {

using namespace multicue;
using namespace multicue::eval;
using mapping::MapClass;

struct Options {
    int kitchens = 10;
    int train_kitchens = 48;
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
    std::string train_split = "other";
    int tune_fold = -1;
    int fixture_kitchens = training::FixtureTrainingOptions{}.kitchens;
    int fixture_views = 0;  ///< scans per training kitchen (0: --views / --laser-views)
    std::uint64_t fixture_seed = 7;
    std::string fixture_spec = "rtrees:trees=100";
    float fixture_confidence = -1.0f;  ///< < 0: the sensor's default (KitchenParamsFor)
    float lone_confidence = -1.0f;     ///< < 0: the sensor's default (KitchenParamsFor)
    float lone_clearance = -1.0f;      ///< < 0: the default
    std::string save_fixtures;
    std::string fronts = "grow";
    std::vector<std::string> front_params;  ///< NAME=VALUE of mapping::FrontParams
    float min_slide_coverage = -1.0f;       ///< < 0: the library's MotionParams default
    float min_seen_slide_coverage = -1.0f;  ///< < 0: the library's MotionParams default
    bool wall_drawers = mapping::ArticulationParams{}.wall_drawers;
    float flap_min_width = -1.0f;         ///< < 0: the library's ArticulationParams default
    float side_share = -1.0f;             ///< < 0: the library's ArticulationParams default
    float stack_tolerance = -1.0f;        ///< < 0: the library's ArticulationParams default
    float stack_centre_share = -1.0f;     ///< < 0: the library's ArticulationParams default
    float drawer_max_height = -1.0f;      ///< < 0: the library's ArticulationParams default
    float axis_snap_deg = -1.0f;          ///< < 0: the library's MotionParams default
    float max_hinge_gap = -1.0f;          ///< < 0: the library's MotionParams default
    float vacated_max_share = -1.0f;      ///< < 0: the library's MotionParams default
    float max_beyond_turn_share = -1.0f;  ///< < 0: the library's MotionParams default
    float min_through_share = -1.0f;      ///< < 0: the library's MotionParams default
    float drawer_turn_coverage = -1.0f;   ///< < 0: the library's MotionParams default
    bool select_by_vacated = mapping::MotionParams{}.select_by_vacated;
    bool seen_coverage = mapping::MotionParams{}.seen_coverage;
    std::string load_fixtures;
    std::string load_containers;   ///< a container classifier (`multicue train containers`)
    std::string joints = "rules";  ///< one-scan joints: rules, or learned (ClassifyJoints)
    std::string load_joints;       ///< a joint classifier (`multicue train joints`)
    bool vary_handles = training::FixtureTrainingOptions{}.vary_handles;
    bool vary_scored_handles = false;
    float vary_chance = sim::HandleVariation{}.chance;
    float vary_min_shrink = sim::HandleVariation{}.min_shrink;
    /// Scale ranges of the training handles' reach and thickness
    std::vector<float> vary_reach = {
        training::FixtureTrainingOptions{}.handle_variation.min_reach_scale,
        training::FixtureTrainingOptions{}.handle_variation.max_reach_scale};
    std::vector<float> vary_thickness = {
        training::FixtureTrainingOptions{}.handle_variation.min_thickness_scale,
        training::FixtureTrainingOptions{}.handle_variation.max_thickness_scale};
    std::vector<float> scored_reach = {1.0f, 1.0f};  ///< the same for --vary-scored-handles
    std::vector<float> scored_thickness = {1.0f, 1.0f};
    int procedural = training::FixtureTrainingOptions{}.procedural;  ///< per kind, training
    float procedural_share = training::FixtureTrainingOptions{}.procedural_share;
    int scored_procedural = 0;  ///< per kind, scored kitchens (tune half only)
    /// per cupboard and appliance kind, container training only (beside `procedural`)
    int container_procedural = 20;
    /// Map each sensor's scans of a kitchen together (one merged map per kitchen and sensor)
    bool merge = false;
};

/// The library id of a kitchen's model instance as the truth's `model` field numbers it (1 +
/// instance); `none` for 0 (room structure, objects).
std::string ModelIdOf(const sim::KitchenScene& k, std::size_t instance, const char* none) {
    return instance >= 1 && instance <= k.instances.size() ? k.instances[instance - 1].model->id
                                                           : std::string(none);
}

/// Sets one parameter of the fronts (outline, gap fronts) or, as fixture_NAME, of the fixture
/// candidates from NAME=VALUE (--front-param).
void SetMapParam(mapping::MapKitchenParams& m, const std::string& assignment) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos) throw InvalidArgument("--front-param: expected NAME=VALUE");
    const std::string name = assignment.substr(0, eq);
    const float v = std::stof(assignment.substr(eq + 1));
    mapping::FrontParams& p = m.fronts;
    const std::map<std::string, float*> fields = {
        {"alpha_mads", &p.alpha_mads},
        {"min_alpha", &p.min_alpha},
        {"local_alpha", &p.local_alpha},
        {"min_offset_alpha", &p.min_offset_alpha},
        {"min_fill", &p.min_fill},
        {"split_support", &p.split_support},
        {"pair_end_reach", &p.pair_end_reach},
        {"cell_size", &p.cell_size},
        {"seed_max", &p.seed_max},
        {"rect_percentile", &p.rect_percentile},
        {"nest_share", &p.nest_share},
        {"nest_depth", &p.nest_depth},
        {"claim_front", &p.claim_front},
        {"claim_behind", &p.claim_behind},
        {"claim_margin", &p.claim_margin},
        {"max_extend", &m.outline.max_extend},
        {"min_support", &m.outline.min_support},
        {"extend_support", &m.outline.extend_support},
        {"min_coverage", &m.outline.min_coverage},
        {"recess", &m.outline.recess},
        {"step", &m.outline.step},
        {"gap_cut_support", &m.gap_fronts.cut_support},
        {"gap_cut_coverage", &m.gap_fronts.cut_coverage},
        {"gap_cut_run", &m.gap_fronts.cut_run},
        {"gap_min_size", &m.gap_fronts.min_size},
        {"gap_cut_margin", &m.gap_fronts.cut_margin},
        {"gap_min_fill", &m.gap_fronts.min_fill},
        {"gap_max_taken", &m.gap_fronts.max_taken},
        {"fixture_merge_gap", &m.fixtures.merge_gap},
        {"fixture_cluster_tolerance", &m.fixtures.cluster_tolerance},
        {"fixture_min_height", &m.fixtures.min_height},
        {"fixture_min_residual", &m.fixtures.min_residual},
        {"fixture_residual_sigmas", &m.fixtures.residual_sigmas},
        {"fixture_point_sigmas", &m.fixtures.point_sigmas},
        {"fixture_residual_cell", &m.fixtures.residual_cell},
        {"fixture_min_contrast", &m.fixtures.min_contrast},
        {"fixture_contrast_min_residual", &m.fixtures.contrast_min_residual}};
    if (name == "extend") {
        m.extend_fronts = v != 0.0f;
    } else if (name == "split") {
        p.split_at_outlines = v != 0.0f;
    } else if (name == "gap") {
        m.gap_fronts.enabled = v != 0.0f;
    } else if (name == "gap_grow") {
        m.gap_fronts.grow_fixture_fronts = v != 0.0f;
    } else if (name == "gap_split") {
        m.gap_fronts.split_fixture_fronts = v != 0.0f;
    } else if (const auto it = fields.find(name); it != fields.end()) {
        *it->second = v;
    } else {
        throw InvalidArgument("--front-param: unknown parameter " + name);
    }
}

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
    std::size_t AtMost(double t) const {
        return static_cast<std::size_t>(
            std::count_if(v.begin(), v.end(), [t](double x) { return x <= t; }));
    }
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
    std::map<std::string, std::size_t> fp_on;     ///< class of the point under a false detection
    std::map<std::string, std::size_t> fp_model;  ///< model of the point under it
    std::map<std::string, std::size_t> fn_why;    ///< why true fixtures were missed
    /// Visible fronts with a visible fixture segmented with IoU under 0.5, by what went wrong.
    std::map<std::string, std::size_t> front_why;
    /// Per kitchen model (its library id): visible true fixtures and those found (either type).
    std::map<std::string, std::pair<std::size_t, std::size_t>> fixtures_by_model;
    Stats front_iou_detectable, front_iou_all, front_iou_found;
    /// Fronts whose fixture was detected and that were matched: share of the predicted front's
    /// points on the true front (precision) and of the true front's points covered (recall).
    Stats front_precision, front_recall;
    Stats front_on_face;  ///< share of those fronts' true points the map put on a face
    /// Where the rest went: true points on the face in no front, in another front; the front's
    /// points of another true front, of none.
    Stats front_lost_free, front_lost_other, front_extra_other, front_extra_none;
    /// Those fronts' true points the map put off every face, by the class it gave them.
    std::array<std::size_t, mapping::kNumMapClasses> front_off_face{};
    std::size_t front_true_points = 0;
    std::size_t joint_correct = 0, joint_total = 0;
    std::size_t joint_none = 0;  ///< matched fronts without a fixture (no joint)
    std::size_t sign_correct = 0;
    Stats axis_angle, axis_position;
    /// Hinge positions of the fronts whose hinge edge the scan saw (those it did not, the edge
    /// out of the view or hidden, are hinge_seen_flag[0]).
    Stats axis_position_seen;
    /// The map's own word (Articulation::hinge_seen) against the truth's: [truth][map].
    std::array<std::array<std::size_t, 2>, 2> hinge_seen_flag{};
    /// Hinge positions of the fronts the map says it saw the hinge edge of, and of the others.
    Stats axis_position_flagged, axis_position_flagged_unseen;
    /// Points pooled over frames: [true class][map class].
    std::vector<std::array<std::size_t, mapping::kNumMapClasses>> point_confusion =
        std::vector<std::array<std::size_t, mapping::kNumMapClasses>>(
            sim::KitchenClassNames().size());
    std::vector<std::vector<std::size_t>> confusion =
        std::vector<std::vector<std::size_t>>(7, std::vector<std::size_t>(7, 0));
    std::size_t open_correct = 0, open_total = 0, open_missed = 0;
    /// Pairs where the map, offered all its fronts, takes the matched front for the opened one.
    std::size_t open_picked_right = 0, open_picked_total = 0;
    /// Pairs not scored: opening swung the front out of the sensor's view (fewer points of it
    /// in the opened scan than a visible front has).
    std::size_t open_out_of_view = 0;
    /// Wrong pairs whose front's points in the opened scan lie mostly behind the face plane of
    /// the matched front: its front panel left the view and the inside of its box, seen through
    /// the front's place, is what shows (ArticulationFromMotion reads points in front of the face).
    std::size_t open_wrong_behind = 0;
    /// The same for the pairs of fronts without a fixture (found from their outlines alone).
    std::size_t open_correct_bare = 0, open_total_bare = 0, open_missed_bare = 0;
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
using Frame = training::KitchenFrame;

/// The scans of one sensor as one frame: their points and ground-truth fields in order, as
/// MapKitchen merges them (mapping::MergeScansWithNormals), so that the merged map's point
/// indices index it; the pose is the first scan's.
Frame MergedFrame(const std::vector<const Frame*>& frames) {
    Frame out;
    out.laser = frames.front()->laser;
    out.T_world_sensor = frames.front()->T_world_sensor;
    out.cloud.extra_fields = frames.front()->cloud.extra_fields;
    for (auto& field : out.cloud.extra_fields) field.data.clear();
    for (const Frame* f : frames) {
        out.cloud.points.insert(out.cloud.points.end(), f->cloud.points.begin(),
                                f->cloud.points.end());
        for (auto& field : out.cloud.extra_fields) {
            const ExtraField* from = f->cloud.FindExtraField(field.name);
            if (from == nullptr || from->BytesPerPoint() != field.BytesPerPoint()) {
                throw DataError("merged frames differ in their ground-truth fields");
            }
            field.data.insert(field.data.end(), from->data.begin(), from->data.end());
        }
    }
    out.cloud.width = static_cast<std::uint32_t>(out.cloud.points.size());
    out.cloud.height = 1;
    return out;
}

class Evaluator {
  public:
    explicit Evaluator(const Options& o) : o_(o) {}

    /// The scans of a kitchen by the chosen sensors, as `simulate kitchens` makes them.
    std::vector<Frame> Frames(const sim::KitchenScene& k, std::uint64_t seed) const {
        return training::ScanKitchen(k, o_.sensor != "laser" ? o_.views : 0,
                                     o_.sensor != "kinect" ? o_.laser_views : 0, seed);
    }

    /// The map's parameters for one sensor, with the options that change them.
    mapping::MapKitchenParams Params(bool laser) const {
        mapping::MapKitchenParams params = mapping::KitchenParamsFor(
            laser ? mapping::KitchenSensor::kLaser : mapping::KitchenSensor::kKinect);
        if (o_.fixture_confidence >= 0.0f) params.fixtures.min_confidence = o_.fixture_confidence;
        if (o_.lone_confidence >= 0.0f) params.fixtures.lone_min_confidence = o_.lone_confidence;
        if (o_.lone_clearance >= 0.0f) params.fixtures.lone_clearance = o_.lone_clearance;
        params.front_segmentation = o_.fronts == "grow" ? mapping::FrontSegmentation::kRegionGrowing
                                                        : mapping::FrontSegmentation::kOutline;
        for (const auto& a : o_.front_params) SetMapParam(params, a);
        params.articulation.wall_drawers = o_.wall_drawers;
        if (o_.drawer_max_height >= 0.0f)
            params.articulation.drawer_max_height = o_.drawer_max_height;
        if (o_.flap_min_width >= 0.0f) params.articulation.flap_min_width = o_.flap_min_width;
        if (o_.side_share >= 0.0f) params.articulation.side_share = o_.side_share;
        if (o_.stack_tolerance >= 0.0f) params.articulation.stack_tolerance = o_.stack_tolerance;
        if (o_.stack_centre_share >= 0.0f) {
            params.articulation.stack_centre_share = o_.stack_centre_share;
        }
        return params;
    }

    /// The map of scans of one sensor.
    mapping::MapKitchenResult Map(const std::vector<PointCloud>& clouds, bool laser,
                                  const ml::Classifier* classifier) const {
        const auto& fixtures = laser ? fixtures_laser_ : fixtures_kinect_;
        return mapping::MapKitchen(clouds, Params(laser), classifier, fixtures.get(),
                                   joints_.get());
    }

    /// The fixture classifier of one sensor, trained on simulated kitchens (or loaded).
    std::unique_ptr<ml::Classifier> TrainFixtures(
        const std::vector<sim::KitchenModelEntry>& library, sim::MeshSplit split,
        sim::KitchenModelCache& cache, bool laser) {
        if (!o_.load_fixtures.empty()) {
            return ml::LoadClassifier(o_.load_fixtures + (laser ? "_laser.mcm" : "_kinect.mcm"));
        }
        training::FixtureTrainingOptions t;
        t.kitchens = o_.fixture_kitchens;
        t.views = o_.fixture_views > 0 ? o_.fixture_views : laser ? o_.laser_views : o_.views;
        t.sensor = laser ? mapping::KitchenSensor::kLaser : mapping::KitchenSensor::kKinect;
        t.split = split;
        t.seed = o_.fixture_seed;
        t.fold = o_.tune_fold >= 0 ? 1 - o_.tune_fold : -1;
        t.vary_handles = o_.vary_handles;
        t.procedural = o_.procedural;
        t.procedural_share = o_.procedural_share;
        t.handle_variation.chance = o_.vary_chance;
        t.handle_variation.min_shrink = o_.vary_min_shrink;
        t.handle_variation.min_reach_scale = o_.vary_reach[0];
        t.handle_variation.max_reach_scale = o_.vary_reach[1];
        t.handle_variation.min_thickness_scale = o_.vary_thickness[0];
        t.handle_variation.max_thickness_scale = o_.vary_thickness[1];
        {
            // The candidates the classifier learns from are found as the scored scans' are.
            mapping::MapKitchenParams mp = mapping::KitchenParamsFor(t.sensor);
            for (const auto& a : o_.front_params) SetMapParam(mp, a);
            t.fixture_params = mp.fixtures;
        }
        const ml::Dataset rows = training::CollectFixtureRows(library, cache, t);
        std::size_t positive = 0;
        for (const int l : rows.labels) positive += l > 0;
        std::printf(
            "%s fixture classifier: %zu candidates (%zu fixtures) from %d kitchens (%s half, "
            "seed %llu)\n",
            laser ? "laser" : "kinect", rows.rows(), positive, t.kitchens,
            std::string(sim::MeshSplitName(split)).c_str(),
            static_cast<unsigned long long>(t.seed));
        auto c = training::TrainFixtureClassifier(rows, o_.fixture_spec);
        if (!o_.save_fixtures.empty()) {
            c->Save(o_.save_fixtures + (laser ? "_laser.mcm" : "_kinect.mcm"));
        }
        return c;
    }

    /// "kinect MODEL" or "laser MODEL" of a joint's model, for the -v lines.
    static std::string Who(const Frame& f, const sim::KitchenScene& k,
                           const sim::KitchenJoint& kj) {
        return std::string(f.laser ? "laser " : "kinect ") +
               k.instances[static_cast<std::size_t>(kj.instance)].model->id;
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
            ++s.point_confusion.at(
                static_cast<std::size_t>(t.Class(i)))[static_cast<std::size_t>(map.point_class[i])];
            if (a >= 0 && a == b) inter[static_cast<std::size_t>(a)] += 1;
            if (a >= 0) uni[static_cast<std::size_t>(a)] += 1;
            if (b >= 0 && b != a) uni[static_cast<std::size_t>(b)] += 1;
        }
        for (std::size_t c = 0; c < 5; ++c) {
            s.inter[c] += inter[c];
            s.uni[c] += uni[c];
            if (uni[c] > 0) s.frame_iou[c].Add(inter[c] / uni[c]);
            if (o_.verbose && uni[c] > 0 && inter[c] < 0.5 * uni[c]) {
                std::size_t truth = 0, predicted = 0;
                std::array<std::size_t, mapping::kNumMapClasses> as{};
                for (std::size_t i = 0; i < f.cloud.size(); ++i) {
                    if (!f.cloud.IsFinite(i)) continue;
                    const bool is = TrueIouClass(t.Class(i)) == static_cast<int>(c);
                    truth += is;
                    if (is) ++as[static_cast<std::size_t>(map.point_class[i])];
                    predicted += PredIouClass(map.point_class[i]) == static_cast<int>(c);
                }
                std::string labels;
                for (std::size_t m = 0; m < as.size(); ++m) {
                    if (as[m] > 0) {
                        labels += " " + mapping::MapClassNames()[m] + " " + std::to_string(as[m]);
                    }
                }
                std::fprintf(stderr,
                             "frame %s kitchen seed %llu: %s IoU %.2f (%zu true points, %zu "
                             "labelled, sensor %.2f m above the floor; true points labelled%s)\n",
                             f.laser ? "laser" : "kinect", static_cast<unsigned long long>(seed),
                             kIouClasses[c].c_str(), inter[c] / uni[c], truth, predicted,
                             f.T_world_sensor.translation().z(), labels.c_str());
            }
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
                ++s.fp_model[ModelIdOf(k, t.model[mid], "room")];
            }
            for (std::size_t g = 0; g < fixtures.size(); ++g) {
                const std::string id = ModelIdOf(k, t.model[fixtures[g].points.front()], "unknown");
                auto& [visible, found] = s.fixtures_by_model[id];
                ++visible;
                found += gu[g] ? 1 : 0;
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
                ++s.fn_why[(fixtures[g].handle ? "" : "knob: ") + why];
                if (o_.verbose) {
                    // The nearest detection: a fixture merged with its neighbour shows as one
                    // taken by the other.
                    float nearest = std::numeric_limits<float>::infinity();
                    std::size_t nd = 0;
                    for (std::size_t d = 0; d < map.fixtures.size(); ++d) {
                        for (const Index i : fixtures[g].points) {
                            const float dist = (f.cloud.points[i] - map.fixtures[d].center).norm();
                            if (dist < nearest) {
                                nearest = dist;
                                nd = d;
                            }
                        }
                    }
                    std::string detection = "no detection";
                    if (std::isfinite(nearest)) {
                        detection = fmt::format("nearest detection {:.2f} m away ({:.2f} m long{})",
                                                nearest, map.fixtures[nd].length,
                                                du[nd] ? ", another fixture's" : "");
                    }
                    std::fprintf(stderr,
                                 "fixture %s %s: missed, %s (%zu points, %.2f m away); %s\n",
                                 f.laser ? "laser" : "kinect",
                                 ModelIdOf(k, t.model[fixtures[g].points.front()], "?").c_str(),
                                 why.c_str(), fixtures[g].points.size(),
                                 (c - f.T_world_sensor.translation()).norm(), detection.c_str());
                }
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
        // Where a true front's points went in the map: on a face (or a front) at all, on the
        // face in no front, in a front other than `mine` (map front + 1; 0: none), and per such
        // front how many.
        struct WhereItWent {
            std::size_t on_face = 0, free_face = 0, other_front = 0;
            std::map<std::uint32_t, std::size_t> others;                  // map front + 1 -> points
            std::array<std::size_t, mapping::kNumMapClasses> off_face{};  // by map class
        };
        auto where_it_went = [&](std::uint32_t key, std::uint32_t mine) {
            WhereItWent w;
            for (std::size_t i = 0; i < f.cloud.size(); ++i) {
                if (!t.IsFront(i) || t.Key(i) != key) continue;
                const auto pc = map.point_class[i];
                w.on_face += pc == MapClass::kFace || pc == MapClass::kFront;
                w.free_face += pc == MapClass::kFace;
                if (pc != MapClass::kFace && pc != MapClass::kFront)
                    ++w.off_face[static_cast<std::size_t>(pc)];
                if (pc == MapClass::kFront && map.point_front[i] != mine) {
                    ++w.other_front;
                    ++w.others[map.point_front[i]];
                }
            }
            return w;
        };
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
            if (tf.fixture_points >= min_fixture && iou < 0.5f) {
                // What went wrong: no front over it, a front much larger (merged with its
                // neighbours), or one covering a part of it.
                std::string why = found ? "fixture found, " : "fixture missed, ";
                double precision = 0.0, recall = 0.0;
                if (it == match.end()) {
                    why += "no front";
                    // The map's front holding most of it, if any: merged with a neighbour
                    // whose front it was matched to.
                    std::size_t best_hit = 0;
                    for (const auto& mf : map.fronts) {
                        std::size_t hit = 0;
                        for (const Index i : mf.indices) hit += t.IsFront(i) && t.Key(i) == key;
                        best_hit = std::max(best_hit, hit);
                    }
                    if (best_hit * 2 >= tf.points) why += " of its own (inside a neighbour's)";
                } else {
                    const auto& pidx =
                        map.fronts[static_cast<std::size_t>(it->second.first)].indices;
                    std::size_t hit = 0;
                    for (const Index i : pidx) hit += t.IsFront(i) && t.Key(i) == key;
                    precision = static_cast<double>(hit) /
                                static_cast<double>(std::max<std::size_t>(1, pidx.size()));
                    recall = static_cast<double>(hit) /
                             static_cast<double>(std::max<std::size_t>(1, tf.points));
                    why += precision < 0.5 && recall >= 0.5   ? "front too large"
                           : precision >= 0.5 && recall < 0.5 ? "front too small"
                                                              : "front off";
                }
                ++s.front_why[why];
                if (o_.verbose) {
                    const auto inst = static_cast<std::size_t>(key >> 16) - 1;
                    const WhereItWent w = where_it_went(
                        key,
                        it == match.end() ? 0u : static_cast<std::uint32_t>(it->second.first + 1));
                    // The other front holding most of it: with fixtures or from the outlines,
                    // and how much of it lies on this front (a split) or beyond (a neighbour).
                    std::string other_what;
                    if (!w.others.empty()) {
                        const auto best = std::max_element(
                            w.others.begin(), w.others.end(),
                            [](const auto& a, const auto& b) { return a.second < b.second; });
                        const mapping::Front& of = map.fronts[best->first - 1];
                        other_what = fmt::format(
                            "; the other front has {} fixtures, {:.2f} of it on this front",
                            of.fixtures.size(),
                            static_cast<double>(best->second) /
                                static_cast<double>(std::max<std::size_t>(1, of.indices.size())));
                    }
                    std::fprintf(
                        stderr,
                        "front %s %s: %s (%zu points, IoU %.2f, precision %.2f, recall "
                        "%.2f, on a face %.2f: in no front %.2f, in another %.2f%s)\n",
                        f.laser ? "laser" : "kinect",
                        inst < k.instances.size() ? k.instances[inst].model->id.c_str() : "?",
                        why.c_str(), tf.points, iou, precision, recall,
                        static_cast<double>(w.on_face) / static_cast<double>(tf.points),
                        static_cast<double>(w.free_face) / static_cast<double>(tf.points),
                        static_cast<double>(w.other_front) / static_cast<double>(tf.points),
                        other_what.c_str());
                }
            }
            if (found && it != match.end()) {
                const auto& pidx = map.fronts[static_cast<std::size_t>(it->second.first)].indices;
                std::size_t hit = 0, other_true = 0;
                for (const Index i : pidx) {
                    hit += t.IsFront(i) && t.Key(i) == key;
                    other_true += t.IsFront(i) && t.Key(i) != key;
                }
                const double np = static_cast<double>(std::max<std::size_t>(1, pidx.size()));
                const double nt = static_cast<double>(tf.points);
                s.front_precision.Add(static_cast<double>(hit) / np);
                s.front_recall.Add(static_cast<double>(hit) / nt);
                s.front_extra_other.Add(static_cast<double>(other_true) / np);
                s.front_extra_none.Add(static_cast<double>(pidx.size() - hit - other_true) / np);
                const WhereItWent w =
                    where_it_went(key, static_cast<std::uint32_t>(it->second.first + 1));
                s.front_on_face.Add(static_cast<double>(w.on_face) / nt);
                s.front_lost_free.Add(static_cast<double>(w.free_face) / nt);
                s.front_lost_other.Add(static_cast<double>(w.other_front) / nt);
                for (std::size_t c = 0; c < w.off_face.size(); ++c)
                    s.front_off_face[c] += w.off_face[c];
                s.front_true_points += tf.points;
            }
            if (it == match.end() || iou < 0.5f || tf.joint < 0) continue;
            const mapping::Front& pf = map.fronts[static_cast<std::size_t>(it->second.first)];
            furniture_votes[static_cast<int>(key >> 16) - 1][pf.furniture] += tf.points;
            const sim::KitchenJoint& kj = k.joints[static_cast<std::size_t>(tf.joint)];
            const bool revolute = kj.type != io::UrdfJointType::kPrismatic;
            const auto pt = pf.articulation.type;
            // A front without a fixture has no joint from one scan: counted apart.
            if (pf.fixtures.empty() && pt == mapping::JointType::kUnknown) {
                ++s.joint_none;
                continue;
            }
            ++s.joint_total;
            const bool correct = (revolute && pt == mapping::JointType::kRevolute) ||
                                 (!revolute && pt == mapping::JointType::kPrismatic);
            s.joint_correct += correct;
            if (o_.verbose) {
                std::fprintf(stderr, "joint %s %s: %s -> %s (front IoU %.2f, %.2f x %.2f m)\n",
                             Who(f, k, kj).c_str(), kj.name.c_str(),
                             revolute ? "revolute" : "prismatic", mapping::JointTypeName(pt), iou,
                             pf.max.x() - pf.min.x(), pf.max.y() - pf.min.y());
            }
            if (revolute && correct) {
                const Axis& gt = axes.at(kj.name);
                const Axis pred{pf.articulation.origin, pf.articulation.axis};
                s.axis_angle.Add(LineAngleDeg(pred.direction, gt.direction));
                const float position = LineDistanceAt(pred, gt, pf.center);
                s.axis_position.Add(position);
                s.sign_correct += pred.direction.dot(gt.direction) > 0;
                // The hinge edge was seen when as many of the front's points as a visible
                // fixture needs lie within 5 cm of the true hinge line.
                std::size_t near_hinge = 0;
                const Eigen::Vector3f gd = gt.direction.normalized();
                for (std::size_t i = 0; i < f.cloud.size() && near_hinge < min_fixture; ++i) {
                    if (!t.IsFront(i) || t.Key(i) != key) continue;
                    const Eigen::Vector3f to_point = f.cloud.points[i] - gt.point;
                    near_hinge += (to_point - gd * gd.dot(to_point)).norm() <= 0.05f;
                }
                if (near_hinge >= min_fixture) s.axis_position_seen.Add(position);
                ++s.hinge_seen_flag[near_hinge >= min_fixture][pf.articulation.hinge_seen];
                (pf.articulation.hinge_seen ? s.axis_position_flagged
                                            : s.axis_position_flagged_unseen)
                    .Add(position);
                if (o_.verbose) {
                    // Where the true hinge lies from the estimated one: into the front (from its
                    // edge towards its centre) and behind its surface.
                    const Eigen::Vector3f d = pred.direction.normalized();
                    const Eigen::Vector3f off = LineOffsetAt(pred, gt, pf.center);
                    Eigen::Vector3f into = pf.center - LinePointNear(pred, pf.center);
                    into -= d * d.dot(into) + pf.normal * pf.normal.dot(into);
                    std::fprintf(
                        stderr,
                        "hinge %s: true hinge %.3f m into the front, %.3f m behind it, %.0f "
                        "deg%s\n",
                        Who(f, k, kj).c_str(), off.dot(into.normalized()), -off.dot(pf.normal),
                        LineAngleDeg(pred.direction, gt.direction),
                        near_hinge >= min_fixture ? "" : " (edge not seen)");
                }
            }
        }
        // Container types: the piece holding most of a model's matched fronts.
        for (const auto& [inst, votes] : furniture_votes) {
            const int best = training::MostVoted(votes);
            if (best < 0) continue;
            const sim::ArticulatedModel& model = *k.instances[static_cast<std::size_t>(inst)].model;
            const std::string truth = sim::ContainerTypeOfModel(model);
            const std::string& type = map.furniture[static_cast<std::size_t>(best)].type;
            const int gt = TypeIndex(truth), pr = TypeIndex(type);
            if (gt < 7 && pr < 7)
                ++s.confusion[static_cast<std::size_t>(gt)][static_cast<std::size_t>(pr)];
            if (o_.verbose) {
                const auto x = mapping::ContainerFeatures(map, static_cast<std::size_t>(best));
                std::string features;
                for (std::size_t c = 0; c < x.size(); ++c) {
                    features +=
                        fmt::format(" {}={:.2f}", mapping::ContainerFeatureNames()[c], x[c]);
                }
                std::fprintf(stderr, "container %s %s: %s -> %s;%s\n", f.laser ? "laser" : "kinect",
                             model.id.c_str(), truth.c_str(), type.c_str(), features.c_str());
            }
        }
        // Opened-front pairs: the robot opens matched fronts of this view one at a time.
        if (o_.open <= 0 || o_.merge) return;  // pairs are a single scan's
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
                Eigen::Isometry3f pose = f.T_world_sensor;
                opened.cloud =
                    f.laser ? sim::ScanLaser(caster, pose, training::KitchenLaserParams(), rng())
                            : sim::ScanKinect(caster, pose, training::KitchenKinectParams(), rng());
                sim::AddKitchenTruth(k, opened.cloud);
                sim::ScanToWorld(opened.cloud, pose);
            }
            k.SetJoint(j, closed);
            const mapping::Front& pf = map.fronts[static_cast<std::size_t>(match.at(key).first)];
            mapping::MotionParams mp = mapping::MotionParamsFor(
                f.laser ? mapping::KitchenSensor::kLaser : mapping::KitchenSensor::kKinect);
            if (o_.min_slide_coverage >= 0.0f) mp.min_slide_coverage = o_.min_slide_coverage;
            if (o_.min_seen_slide_coverage >= 0.0f)
                mp.min_seen_slide_coverage = o_.min_seen_slide_coverage;
            if (o_.axis_snap_deg >= 0.0f) mp.axis_snap_deg = o_.axis_snap_deg;
            if (o_.max_hinge_gap >= 0.0f) mp.max_hinge_gap = o_.max_hinge_gap;
            if (o_.vacated_max_share >= 0.0f) mp.vacated_max_share = o_.vacated_max_share;
            if (o_.max_beyond_turn_share >= 0.0f)
                mp.max_beyond_turn_share = o_.max_beyond_turn_share;
            if (o_.min_through_share >= 0.0f) mp.min_through_share = o_.min_through_share;
            if (o_.drawer_turn_coverage >= 0.0f)
                mp.min_turn_coverage_for_drawer = o_.drawer_turn_coverage;
            mp.select_by_vacated = o_.select_by_vacated;
            mp.seen_coverage = o_.seen_coverage;
            // The front's points in the opened scan, and those behind the matched front's face.
            // A front swung out of the view (a door near the image border) shows no motion to
            // anyone: such pairs test the aim of the sensor, not the estimate.
            std::size_t opened_front_points = 0, front_behind = 0;
            {
                const ScanTruth ot(opened.cloud);
                const float plane_d = -pf.normal.dot(pf.center);
                for (std::size_t i = 0; i < opened.cloud.size(); ++i) {
                    if (!opened.cloud.IsFinite(i) || ot.joint[i] != j + 1) continue;
                    ++opened_front_points;
                    front_behind += pf.normal.dot(opened.cloud.points[i]) + plane_d < mp.min_offset;
                }
            }
            if (opened_front_points < min_front) {
                ++s.open_out_of_view;
                continue;
            }
            const auto motion = mapping::ArticulationFromMotion(f.cloud, opened.cloud, pf, mp);
            {
                // Which front the map takes for the opened one, from all of its fronts.
                mapping::KitchenMap copy = map;
                const int picked =
                    mapping::UpdateArticulationFromOpenedScan(copy, f.cloud, opened.cloud, mp);
                ++s.open_picked_total;
                s.open_picked_right += picked == match.at(key).first;
            }
            const bool bare = pf.fixtures.empty();
            ++s.open_total;
            s.open_total_bare += bare;
            if (!motion.found) {
                ++s.open_missed;
                s.open_missed_bare += bare;
                if (o_.verbose) {
                    std::fprintf(stderr,
                                 "pair %s %s %s: no motion (front %.2f x %.2f m, %zu points; "
                                 "opened by %.2f; moved %zu; the front's true points in the opened "
                                 "scan %zu)\n",
                                 f.laser ? "laser" : "kinect", ModelIdOf(k, key >> 16, "?").c_str(),
                                 revolute ? "revolute" : "prismatic", pf.max.x() - pf.min.x(),
                                 pf.max.y() - pf.min.y(), pf.indices.size(),
                                 std::abs(value - closed), motion.moved_points,
                                 opened_front_points);
                }
                continue;
            }
            const auto pt = motion.articulation.type;
            if (o_.verbose) {
                const Axis& gt = axes.at(kj.name);
                std::fprintf(
                    stderr,
                    "pair %s %s: slide coverage %.2f, turn coverage %.2f -> %s (axis %.1f deg, "
                    "front %.2f x %.2f m, moved part %.2f x %.2f m; opened by %.2f, travel %.2f "
                    "m; moved %zu, on the front slid %zu, turned %zu; coverage of the seen cells "
                    "slid %.2f, turned %.2f; the front's true points in the opened scan %zu, %zu "
                    "of them behind the face; within the outline %zu moved, %zu beyond the turn's "
                    "reach %.2f m, %zu of them off its plane%s; turned plane %zu out, %zu behind; "
                    "one scan: %s)\n",
                    Who(f, k, kj).c_str(), revolute ? "revolute" : "prismatic",
                    motion.slide_coverage, motion.turn_coverage, mapping::JointTypeName(pt),
                    LineAngleDeg(motion.articulation.axis, gt.direction), pf.max.x() - pf.min.x(),
                    pf.max.y() - pf.min.y(), motion.front_max.x() - motion.front_min.x(),
                    motion.front_max.y() - motion.front_min.y(), std::abs(value - closed),
                    motion.slide_travel, motion.moved_points, motion.slide_points,
                    motion.turn_points, motion.slide_seen_coverage, motion.turn_seen_coverage,
                    opened_front_points, front_behind, motion.outline_points,
                    motion.beyond_turn_points, motion.turn_reach, motion.beyond_off_plane,
                    motion.turn_flap ? ", a flap" : "", motion.turned_points, motion.through_points,
                    mapping::JointTypeName(pf.articulation.type));
            }
            const bool correct = (revolute && pt == mapping::JointType::kRevolute) ||
                                 (!revolute && pt == mapping::JointType::kPrismatic);
            ++s.open_confusion[std::string(revolute ? "revolute" : "prismatic") + " -> " +
                               mapping::JointTypeName(pt)];
            s.open_correct += correct;
            s.open_correct_bare += bare && correct;
            s.open_wrong_behind += !correct && 2 * front_behind > opened_front_points;
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
        const auto train_split = o_.train_split != "other" ? sim::ParseMeshSplit(o_.train_split)
                                 : test_split == sim::MeshSplit::kTest ? sim::MeshSplit::kTune
                                                                       : sim::MeshSplit::kTest;
        auto test_lib = sim::SelectKitchenSplit(library, test_split);
        auto train_lib = sim::SelectKitchenSplit(library, train_split);
        if (o_.tune_fold >= 0) {
            // Validation on models never trained on, within the tune half.
            test_lib = training::SelectKitchenFold(test_lib, o_.tune_fold);
            train_lib = training::SelectKitchenFold(train_lib, 1 - o_.tune_fold);
        }
        // Procedural units: the container training's and the scored kitchens' from seeds of
        // their own (the fixture training draws its own from --fixture-seed).
        for (auto& e : sim::ProceduralKitchenEntries(o_.procedural, sim::SubSeed(o_.seed, 98))) {
            train_lib.push_back(std::move(e));
        }
        for (auto& e : sim::ProceduralKitchenEntries(o_.container_procedural,
                                                     sim::SubSeed(o_.seed, 96), true)) {
            train_lib.push_back(std::move(e));
        }
        for (auto& e :
             sim::ProceduralKitchenEntries(o_.scored_procedural, sim::SubSeed(o_.seed, 99))) {
            test_lib.push_back(std::move(e));
        }
        sim::KitchenSceneParams scene;
        scene.procedural_share = o_.procedural_share;
        sim::KitchenModelCache cache;
        if (o_.fixture_kitchens > 0) {
            if (o_.sensor != "laser")
                fixtures_kinect_ = TrainFixtures(library, train_split, cache, false);
            if (o_.sensor != "kinect")
                fixtures_laser_ = TrainFixtures(library, train_split, cache, true);
        }
        // The container and joint classifiers learn from maps of the same training kitchens.
        training::ContainerTrainingOptions t;
        t.kitchens = o_.train_kitchens;
        t.views = o_.sensor != "laser" ? o_.views : 0;
        t.laser_views = o_.sensor != "kinect" ? o_.laser_views : 0;
        t.seed = o_.seed ^ 0x7261696eull;
        t.procedural_share = o_.procedural_share;
        t.kinect_params = Params(false);
        t.laser_params = Params(true);
        t.kinect_fixtures = fixtures_kinect_.get();
        t.laser_fixtures = fixtures_laser_.get();
        if (!o_.load_joints.empty()) {
            joints_ = ml::LoadClassifier(o_.load_joints);
            mapping::CheckJointClassifier(*joints_);
        } else if (o_.joints == "learned" && o_.train_kitchens > 0) {
            const ml::Dataset data = training::CollectJointRows(train_lib, cache, t);
            joints_ = training::TrainJointClassifier(data, "rtrees:trees=100");
            const std::vector<std::size_t> per_class = data.ClassCounts();
            std::string classes;
            for (std::size_t c = 0; c < per_class.size(); ++c) {
                classes += fmt::format(" {} {}", data.class_names[c], per_class[c]);
            }
            std::printf("joint classifier: %zu training fronts from %d kitchens:%s\n", data.rows(),
                        o_.train_kitchens, classes.c_str());
        }
        std::unique_ptr<ml::Classifier> classifier;
        std::size_t train_rows = 0;
        if (!o_.load_containers.empty()) {
            classifier = ml::LoadClassifier(o_.load_containers);
            mapping::CheckContainerClassifier(*classifier);
        } else if (!o_.rules && o_.train_kitchens > 0) {
            const ml::Dataset data = training::CollectContainerRows(train_lib, cache, t);
            train_rows = data.rows();
            if (data.num_classes() >= 2) {
                classifier = training::TrainContainerClassifier(data, "rtrees:trees=100");
                if (!o_.save_containers.empty()) classifier->Save(o_.save_containers);
            }
            const std::vector<std::size_t> per_type = data.ClassCounts();
            std::string types;
            for (std::size_t c = 0; c < per_type.size(); ++c) {
                types += fmt::format(" {} {}", data.class_names[c], per_type[c]);
            }
            std::printf("container classifier: %zu training pieces from %d kitchens (%s half):%s\n",
                        train_rows, o_.train_kitchens,
                        std::string(sim::MeshSplitName(train_split)).c_str(), types.c_str());
        }
        Scores kinect, laser;
        for (int i = 0; i < o_.kitchens; ++i) {
            const std::uint64_t seed = sim::SubSeed(o_.seed, static_cast<std::uint64_t>(i));
            sim::KitchenScene k = sim::MakeKitchenScene(test_lib, cache, scene, seed);
            if (o_.vary_scored_handles) {
                sim::HandleVariation sv;
                sv.min_reach_scale = o_.scored_reach[0];
                sv.max_reach_scale = o_.scored_reach[1];
                sv.min_thickness_scale = o_.scored_thickness[0];
                sv.max_thickness_scale = o_.scored_thickness[1];
                sim::VaryHandles(k, sv, sim::SubSeed(seed, 43));
            }
            // The ground truth of joint axes comes from the kitchen's URDF, written and re-read.
            const io::UrdfModel gt = io::ParseUrdf(io::UrdfToXml(sim::KitchenGroundTruthUrdf(k)),
                                                   fmt::format("kitchen_{}.urdf", i));
            const auto axes = UrdfJointAxes(gt);
            const std::vector<Frame> frames = Frames(k, seed);
            if (o_.merge) {
                // One map per sensor of all its scans of the kitchen, scored as one frame.
                for (const bool l : {false, true}) {
                    std::vector<const Frame*> group;
                    std::vector<PointCloud> clouds;
                    for (const Frame& f : frames) {
                        if (f.laser != l) continue;
                        group.push_back(&f);
                        clouds.push_back(f.cloud);
                    }
                    if (group.empty()) continue;
                    Scores& s = l ? laser : kinect;
                    try {
                        const auto r = Map(clouds, l, classifier.get());
                        Score(k, axes, MergedFrame(group), r, s, seed ^ 0x5eedull);
                    } catch (const DataError& e) {
                        ++s.failed;
                        std::fprintf(stderr, "kitchen %d, merged %s scans: %s\n", i,
                                     l ? "laser" : "kinect", e.what());
                    }
                }
                if (o_.verbose) std::fprintf(stderr, "kitchen %d done\n", i);
                continue;
            }
            for (const Frame& f : frames) {
                Scores& s = f.laser ? laser : kinect;
                try {
                    const auto r = Map({f.cloud}, f.laser, classifier.get());
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
                              {"containers", !o_.load_containers.empty() ? o_.load_containers
                                             : o_.rules                  ? "rules"
                                                                         : "rtrees"},
                              {"fixtures", o_.fixture_kitchens > 0 ? o_.fixture_spec : "rules"},
                              {"joints", !o_.load_joints.empty() ? o_.load_joints : o_.joints},
                              {"fixture_kitchens", o_.fixture_kitchens},
                              {"vary_handles", o_.vary_handles},
                              {"vary_scored_handles", o_.vary_scored_handles},
                              {"vary_reach", o_.vary_reach},
                              {"vary_thickness", o_.vary_thickness},
                              {"scored_reach", o_.scored_reach},
                              {"scored_thickness", o_.scored_thickness},
                              {"procedural", o_.procedural},
                              {"procedural_share", o_.procedural_share},
                              {"scored_procedural", o_.scored_procedural},
                              {"container_procedural", o_.container_procedural},
                              {"merge", o_.merge},
                              {"fixture_confidence",
                               {{"kinect", Params(false).fixtures.min_confidence},
                                {"laser", Params(true).fixtures.min_confidence}}},
                              {"lone_confidence",
                               {{"kinect", Params(false).fixtures.lone_min_confidence},
                                {"laser", Params(true).fixtures.lone_min_confidence}}},
                              {"lone_clearance", Params(false).fixtures.lone_clearance},
                              {"train_split", std::string(sim::MeshSplitName(train_split))},
                              {"tune_fold", o_.tune_fold},
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
        if (o_.verbose) {
            // Where each true class's points went, pooled over the frames.
            const auto& tn = sim::KitchenClassNames();
            const auto& mn = mapping::MapClassNames();
            for (std::size_t tc = 0; tc < tn.size(); ++tc) {
                std::string row;
                for (std::size_t mc = 0; mc < mn.size(); ++mc) {
                    const std::size_t n = s.point_confusion[tc][mc];
                    if (n > 0) row += fmt::format(" {} {}", mn[mc], n);
                }
                if (!row.empty())
                    std::fprintf(stderr, "points true %s -> map:%s\n", tn[tc].c_str(), row.c_str());
            }
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
        {
            // The worst models: the kitchen models whose fixtures are missed most (ties: lower
            // recall first), with found / visible.
            std::vector<std::tuple<std::size_t, double, std::string>> models;
            for (const auto& [id, vf] : s.fixtures_by_model) {
                models.emplace_back(
                    vf.first - vf.second,
                    ratio(static_cast<double>(vf.second), static_cast<double>(vf.first)), id);
            }
            std::sort(models.begin(), models.end(), [](const auto& a, const auto& b) {
                return std::get<0>(a) > std::get<0>(b) ||
                       (std::get<0>(a) == std::get<0>(b) && std::get<1>(a) < std::get<1>(b));
            });
            std::printf("  most missed models (found / visible):");
            for (std::size_t m = 0; m < models.size() && (o_.verbose || m < 5); ++m) {
                const auto& vf = s.fixtures_by_model.at(std::get<2>(models[m]));
                std::printf(" %s %zu/%zu", std::get<2>(models[m]).c_str(), vf.second, vf.first);
            }
            std::printf("\n");
            for (const auto& [id, vf] : s.fixtures_by_model) {
                j["fixtures"]["by_model"][id] = {{"visible", vf.first}, {"found", vf.second}};
            }
        }
        if (o_.verbose) {
            std::printf("  missed fixtures:");
            for (const auto& [c, n] : s.fn_why) std::printf(" [%s] %zu", c.c_str(), n);
            std::printf("\n");
            std::printf("  false detections on:");
            for (const auto& [c, n] : s.fp_on) std::printf(" %s %zu", c.c_str(), n);
            std::printf("\n");
            std::vector<std::pair<std::size_t, std::string>> fp_models;
            for (const auto& [m, n] : s.fp_model) fp_models.emplace_back(n, m);
            std::sort(fp_models.rbegin(), fp_models.rend());
            std::printf("  false detections by model:");
            for (const auto& [n, m] : fp_models) std::printf(" %s %zu", m.c_str(), n);
            std::printf("\n");
            std::printf("  fronts with a visible fixture under IoU 0.5:");
            for (const auto& [c, n] : s.front_why) std::printf(" [%s] %zu", c.c_str(), n);
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
        std::printf(
            "  matched fronts of those: point precision mean %.3f, recall mean %.3f (on a face "
            "%.3f)\n",
            s.front_precision.Mean(), s.front_recall.Mean(), s.front_on_face.Mean());
        std::printf(
            "  their true points on a face but in no front %.3f, in another front %.3f; their "
            "points of another true front %.3f, of none %.3f\n",
            s.front_lost_free.Mean(), s.front_lost_other.Mean(), s.front_extra_other.Mean(),
            s.front_extra_none.Mean());
        std::printf("  their true points off every face, by the map's class (share of all):");
        nlohmann::json off_face = nlohmann::json::object();
        for (std::size_t c = 0; c < s.front_off_face.size(); ++c) {
            if (s.front_off_face[c] == 0) continue;
            const double share = static_cast<double>(s.front_off_face[c]) /
                                 static_cast<double>(std::max<std::size_t>(1, s.front_true_points));
            std::printf(" %s %.3f", mapping::MapClassNames()[c].c_str(), share);
            off_face[mapping::MapClassNames()[c]] = share;
        }
        std::printf("\n");
        j["front_iou"] = {{"fixture_detected", s.front_iou_found.Json()},
                          {"found_precision", s.front_precision.Json()},
                          {"found_recall", s.front_recall.Json()},
                          {"found_lost_in_no_front", s.front_lost_free.Json()},
                          {"found_lost_in_another_front", s.front_lost_other.Json()},
                          {"found_extra_of_another_front", s.front_extra_other.Json()},
                          {"found_extra_of_no_front", s.front_extra_none.Json()},
                          {"found_off_face_by_class", off_face},
                          {"with_fixture", s.front_iou_detectable.Json()},
                          {"all", s.front_iou_all.Json()}};
        const double jacc =
            ratio(static_cast<double>(s.joint_correct), static_cast<double>(s.joint_total));
        std::printf(
            "joint type accuracy %.3f (%zu of %zu matched fronts with a fixture; %zu matched "
            "fronts without one have no joint)\n",
            jacc, s.joint_correct, s.joint_total, s.joint_none);
        std::printf(
            "hinge axis: angle mean %.2f median %.2f max %.2f deg; position mean %.3f "
            "median %.3f max %.3f m (%zu within 3 cm); opening sign right %zu of %zu\n",
            s.axis_angle.Mean(), s.axis_angle.Median(), s.axis_angle.Max(), s.axis_position.Mean(),
            s.axis_position.Median(), s.axis_position.Max(), s.axis_position.AtMost(0.03),
            s.sign_correct, s.axis_angle.v.size());
        std::printf(
            "  hinges whose edge the scan saw: position median %.3f m (%zu of %zu within 3 cm); "
            "%zu more with the edge out of view or hidden\n",
            s.axis_position_seen.Median(), s.axis_position_seen.AtMost(0.03),
            s.axis_position_seen.v.size(), s.hinge_seen_flag[0][0] + s.hinge_seen_flag[0][1]);
        std::printf(
            "  the map's flag (hinge_seen): seen for %zu of the %zu with the true edge seen and "
            "%zu of the %zu others; position median over those it flags seen %.3f m (%zu of %zu "
            "within 3 cm), over the others %.3f m (%zu of %zu)\n",
            s.hinge_seen_flag[1][1], s.hinge_seen_flag[1][0] + s.hinge_seen_flag[1][1],
            s.hinge_seen_flag[0][1], s.hinge_seen_flag[0][0] + s.hinge_seen_flag[0][1],
            s.axis_position_flagged.Median(), s.axis_position_flagged.AtMost(0.03),
            s.axis_position_flagged.v.size(), s.axis_position_flagged_unseen.Median(),
            s.axis_position_flagged_unseen.AtMost(0.03), s.axis_position_flagged_unseen.v.size());
        j["joint_type_accuracy"] = jacc;
        j["joint_total"] = s.joint_total;
        j["joint_none"] = s.joint_none;
        j["hinge_angle_deg"] = s.axis_angle.Json();
        j["hinge_position_m"] = s.axis_position.Json();
        j["hinge_position_within_3cm"] = s.axis_position.AtMost(0.03);
        j["hinge_sign_correct"] = s.sign_correct;
        j["hinge_position_edge_seen_m"] = s.axis_position_seen.Json();
        j["hinge_position_edge_seen_within_3cm"] = s.axis_position_seen.AtMost(0.03);
        j["hinge_edge_unseen"] = s.hinge_seen_flag[0][0] + s.hinge_seen_flag[0][1];
        j["hinge_seen_flag"] = {{"seen_flagged_seen", s.hinge_seen_flag[1][1]},
                                {"seen_flagged_unseen", s.hinge_seen_flag[1][0]},
                                {"unseen_flagged_seen", s.hinge_seen_flag[0][1]},
                                {"unseen_flagged_unseen", s.hinge_seen_flag[0][0]}};
        j["hinge_position_flagged_seen_m"] = s.axis_position_flagged.Json();
        j["hinge_position_flagged_unseen_m"] = s.axis_position_flagged_unseen.Json();
        std::size_t correct = 0, total = 0;
        std::array<std::size_t, 7> row_total{};  // pieces of each true type
        const auto& names = mapping::ContainerTypeNames();
        std::printf("container types (rows true, columns predicted):\n  %-12s", "");
        for (const auto& n : names) std::printf(" %6.6s", n.c_str());
        std::printf("\n");
        for (std::size_t r = 0; r < 7; ++r) {
            std::printf("  %-12s", names[r].c_str());
            for (std::size_t c = 0; c < 7; ++c) {
                std::printf(" %6zu", s.confusion[r][c]);
                row_total[r] += s.confusion[r][c];
                total += s.confusion[r][c];
                if (r == c) correct += s.confusion[r][c];
            }
            std::printf("\n");
        }
        const double cacc = ratio(static_cast<double>(correct), static_cast<double>(total));
        std::printf("container type accuracy %.3f (%zu of %zu)\n", cacc, correct, total);
        j["container_accuracy"] = cacc;
        j["container_confusion"] = s.confusion;
        // The worst case behind the pooled accuracy: each true type's share typed right.
        std::printf("  right by true type:");
        double worst = 2.0;
        std::string worst_type;
        for (std::size_t r = 0; r < 7; ++r) {
            if (row_total[r] == 0) continue;
            std::printf(" %s %zu/%zu", names[r].c_str(), s.confusion[r][r], row_total[r]);
            const double share =
                static_cast<double>(s.confusion[r][r]) / static_cast<double>(row_total[r]);
            j["container_right_by_type"][names[r]] = share;
            if (share < worst) {
                worst = share;
                worst_type = names[r];
            }
        }
        if (!worst_type.empty()) std::printf("; worst %s (%.2f)", worst_type.c_str(), worst);
        std::printf("\n");
        const double oacc =
            ratio(static_cast<double>(s.open_correct), static_cast<double>(s.open_total));
        std::printf(
            "opened pairs: joint type accuracy %.3f (%zu of %zu, %zu without motion; %zu more not "
            "scored: the opened front left the view); axis angle mean %.2f median %.2f max %.2f "
            "deg; hinge position median %.3f max %.3f m (%zu of %zu within 3 cm)\n",
            oacc, s.open_correct, s.open_total, s.open_missed, s.open_out_of_view,
            s.open_angle.Mean(), s.open_angle.Median(), s.open_angle.Max(),
            s.open_position.Median(), s.open_position.Max(), s.open_position.AtMost(0.03),
            s.open_position.v.size());
        std::printf("  of those, fronts without a fixture: %zu of %zu right, %zu without motion\n",
                    s.open_correct_bare, s.open_total_bare, s.open_missed_bare);
        std::printf("  opened front found among all fronts: %zu of %zu\n", s.open_picked_right,
                    s.open_picked_total);
        std::printf(
            "  wrong pairs whose front's points in the opened scan lie mostly behind the face "
            "(its box seen, its front out of view): %zu\n",
            s.open_wrong_behind);
        std::printf("  opened pairs (true -> estimated):");
        for (const auto& [c, n] : s.open_confusion) std::printf(" [%s] %zu", c.c_str(), n);
        std::printf("\n");
        j["opened"] = {{"joint_type_accuracy", oacc},
                       {"confusion", s.open_confusion},
                       {"pairs", s.open_total},
                       {"no_motion", s.open_missed},
                       {"out_of_view", s.open_out_of_view},
                       {"wrong_mostly_behind_face", s.open_wrong_behind},
                       {"bare",
                        {{"correct", s.open_correct_bare},
                         {"pairs", s.open_total_bare},
                         {"no_motion", s.open_missed_bare}}},
                       {"axis_angle_deg", s.open_angle.Json()},
                       {"hinge_position_m", s.open_position.Json()},
                       {"hinge_position_within_3cm", s.open_position.AtMost(0.03)},
                       {"front_found", s.open_picked_right},
                       {"front_found_of", s.open_picked_total}};
        std::printf("time per frame: median %.0f ms, worst %.0f ms (shared machine)\n",
                    s.time_ms.Median(), s.time_ms.Max());
        j["time_ms"] = s.time_ms.Json();
        return j;
    }

  private:
    Options o_;
    std::unique_ptr<ml::Classifier> fixtures_kinect_, fixtures_laser_;
    std::unique_ptr<ml::Classifier> joints_;  ///< null: one-scan joints by the fixture rules
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
    app.add_flag("--merge", o.merge,
                 "map each sensor's scans of a kitchen together and score the merged maps (no "
                 "opened pairs)");
    app.add_option("--seed", o.seed, "seed of the kitchens")->capture_default_str();
    app.add_option("--sensor", o.sensor, "both, kinect or laser")->capture_default_str();
    app.add_option("--split", o.split, "model half scored: test (default) or tune")
        ->capture_default_str();
    app.add_option("--models", o.models, "kitchen model library")->capture_default_str();
    app.add_flag("--rules", o.rules, "type containers by rules (no training)");
    app.add_option("--train-split", o.train_split,
                   "models the classifiers train on: other (the half not scored), tune or test")
        ->capture_default_str();
    app.add_option("--tune-fold", o.tune_fold,
                   "with --split tune --train-split tune: score kitchens of fold 0 or 1 of the "
                   "tune models, train on the other fold")
        ->capture_default_str();
    app.add_option("--fixture-kitchens", o.fixture_kitchens,
                   "kitchens that train each sensor's fixture classifier (0: fixtures by rules)")
        ->capture_default_str();
    app.add_option("--fixture-views", o.fixture_views,
                   "scans of each sensor per fixture training kitchen (0: --views / --laser-views)")
        ->capture_default_str();
    app.add_option("--fixture-seed", o.fixture_seed, "seed of those kitchens")
        ->capture_default_str();
    app.add_option("--fixture-classifier", o.fixture_spec, "classifier spec of the fixtures")
        ->capture_default_str();
    app.add_option(
           "--fixture-confidence", o.fixture_confidence,
           fmt::format(
               "P(handle) + P(knob) a fixture needs (< 0: the sensor's "
               "default, {} for the Kinect and {} for the laser)",
               mapping::KitchenParamsFor(mapping::KitchenSensor::kKinect).fixtures.min_confidence,
               mapping::KitchenParamsFor(mapping::KitchenSensor::kLaser).fixtures.min_confidence))
        ->capture_default_str();
    app.add_option("--lone-confidence", o.lone_confidence,
                   "confidence a candidate with no fixture near it needs (< 0: the sensor's "
                   "default; FixtureParams::lone_min_confidence)")
        ->capture_default_str();
    app.add_option("--lone-clearance", o.lone_clearance,
                   "no fixture within this of such a candidate [m] (< 0: the default)")
        ->capture_default_str();
    app.add_flag("--vary-handles,!--no-vary-handles", o.vary_handles,
                 "vary the handles of the fixture training kitchens (on by default)");
    app.add_option("--vary-chance", o.vary_chance, "chance that a training handle is varied")
        ->capture_default_str();
    app.add_option("--vary-min-shrink", o.vary_min_shrink,
                   "shortest varied training handle as a share of its own length")
        ->capture_default_str();
    app.add_flag("--vary-scored-handles", o.vary_scored_handles,
                 "vary the handles of the scored kitchens too (handle designs unseen in "
                 "training)");
    // MIN,MAX scale ranges of the handles' cross-section.
    auto range = [&app](const char* name, std::vector<float>& value, const std::string& help) {
        app.add_option(name, value, "MIN,MAX: " + help)->delimiter(',')->expected(2);
    };
    range("--vary-reach", o.vary_reach,
          "scale of a varied training handle's reach out of its front");
    range("--vary-thickness", o.vary_thickness, "scale of a varied training handle's thickness");
    range("--scored-reach", o.scored_reach,
          "the same for the scored kitchens' handles (--vary-scored-handles)");
    range("--scored-thickness", o.scored_thickness,
          "the same for the scored kitchens' handles (--vary-scored-handles)");
    app.add_option("--procedural", o.procedural,
                   "procedural units per cupboard kind added to the training kitchens' models "
                   "(fixtures and containers)")
        ->capture_default_str()
        ->check(CLI::Range(0, sim::kMaxProceduralPerKind));
    app.add_option("--procedural-share", o.procedural_share,
                   "chance that a unit of a kind with procedural and library models is procedural")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1.0));
    app.add_option("--container-procedural", o.container_procedural,
                   "procedural units per cupboard and appliance kind added to the container "
                   "training's models alone (beside --procedural's)")
        ->capture_default_str()
        ->check(CLI::Range(0, sim::kMaxProceduralPerKind));
    app.add_option("--scored-procedural", o.scored_procedural,
                   "procedural units per cupboard kind added to the scored kitchens' models, of "
                   "other seeds than training's (--split tune only)")
        ->capture_default_str()
        ->check(CLI::Range(0, sim::kMaxProceduralPerKind));
    app.add_option("--save-fixtures", o.save_fixtures,
                   "also save the fixture classifiers as PREFIX_kinect.mcm and PREFIX_laser.mcm");
    app.add_option("--fronts", o.fronts,
                   "front segmentation: outline (rectangles between outlines) or grow (region "
                   "growing)")
        ->capture_default_str();
    // Overrides of one library parameter each: a negative value keeps the library's default.
    auto override = [&app](const char* name, float& value, const std::string& help, double max) {
        app.add_option(name, value, help + " (default: the library's)")
            ->check(CLI::Range(-1.0, max));
    };
    override("--min-slide-coverage", o.min_slide_coverage,
             "opened pairs: share of the slid front the moved points must cover for a drawer "
             "(0: the planes' support decides)",
             1.0);
    override("--min-seen-slide-coverage", o.min_seen_slide_coverage,
             "opened pairs: the same share among the cells the opened scan could see", 1.0);
    override("--flap-min-width", o.flap_min_width,
             "one scan: a front narrower than this is never hinged at its bottom edge [m] (0: any)",
             100.0);
    override("--side-share", o.side_share,
             "one scan: a horizontal handle within this share of its front's width from a side "
             "edge marks a door hinged at the other side (0: off)",
             0.49);
    override("--stack-tolerance", o.stack_tolerance,
             "one scan: a front with its handle near the top is a drawer, not a flap, when a "
             "front of its column (all of its width but twice this) lies within this above or "
             "below it [m] (0: off)",
             0.2);
    override("--stack-centre-share", o.stack_centre_share,
             "one scan: ... and both handles lie within this share of its width of its middle",
             0.49);
    override("--drawer-max-height", o.drawer_max_height,
             "one scan: a front taller than this with a horizontal handle is a door [m]", 100.0);
    app.add_flag("--wall-drawers", o.wall_drawers,
                 "one scan: wall cupboards' fronts with a horizontal handle away from their "
                 "bottom and sides are drawers (as lower fronts), not doors");
    override("--axis-snap", o.axis_snap_deg,
             "opened pairs: a hinge axis this close to the front's vertical or horizontal is that "
             "direction [deg] (0: off)",
             44.0);
    override("--max-hinge-gap", o.max_hinge_gap,
             "opened pairs: a hinge no moved point comes this close to is replaced by the best "
             "edge's [m] (0: off)",
             10.0);
    override("--vacated-share", o.vacated_max_share,
             "opened pairs: the part of a front's rectangle the motion vacated is taken for the "
             "front when it covers less than this share of it (0: off)",
             1.0);
    override("--beyond-turn-share", o.max_beyond_turn_share,
             "opened pairs: a flap's turn is taken for a slide when this share of the moved "
             "points within the front's outline lie beyond its reach, a quarter of them off its "
             "plane (0: off)",
             1.0);
    override("--through-share", o.min_through_share,
             "opened pairs: a flap's turn is taken for a slide when the new points behind the "
             "face on its plane number this share of its points out of the face (0: off)",
             100.0);
    override("--drawer-turn-coverage", o.drawer_turn_coverage,
             "opened pairs: a front held for a drawer from one scan is taken for a turn only when "
             "the turn covers this share of the cells the opened scan could see (0: off)",
             1.0);
    app.add_flag("--select-by-vacated,!--select-by-moved", o.select_by_vacated,
                 "opened pairs: the map takes the front that lost the most of its own points for "
                 "the opened one (default), or the one with the most moved points");
    app.add_flag("--seen-coverage,!--no-seen-coverage", o.seen_coverage,
                 "opened pairs: coverages count the cells the opened scan could see (default), or "
                 "every cell of the front's rectangle");
    app.add_option("--front-param", o.front_params,
                   "NAME=VALUE of the fronts' parameters, or fixture_NAME=VALUE of the "
                   "fixture candidates' (repeatable)");
    app.add_option("--load-fixtures", o.load_fixtures,
                   "fixture classifiers saved by --save-fixtures PREFIX (instead of training)");
    app.add_flag("-v,--verbose", o.verbose, "progress on stderr");
    app.add_option("--json", o.json, "also write the figures as JSON");
    app.add_option("--save-containers", o.save_containers,
                   "also save the container classifier (for map kitchen --containers)");
    app.add_option("--joints", o.joints,
                   "one-scan joints: rules (the fixture rules), or learned (a joint classifier "
                   "trained on the container training's kitchens)")
        ->check(CLI::IsMember({"rules", "learned"}))
        ->capture_default_str();
    app.add_option("--load-joints", o.load_joints,
                   "score with this joint classifier (`multicue train joints`) instead");
    app.add_option("--load-containers", o.load_containers,
                   "a container classifier (`multicue train containers`) instead of training one");
    if (auto code = eval::ParseDriverOptions(app, "kitchen_eval", [&] {
            app.parse(argc, argv);
            if (o.sensor != "both" && o.sensor != "kinect" && o.sensor != "laser") {
                throw CLI::ValidationError("--sensor", "must be both, kinect or laser");
            }
            if (o.split != "test" && o.split != "tune") {
                throw CLI::ValidationError("--split", "must be test or tune");
            }
            if (o.train_split != "other" && o.train_split != "tune" && o.train_split != "test") {
                throw CLI::ValidationError("--train-split", "must be other, tune or test");
            }
            if (o.scored_procedural > 0 && o.split != "tune") {
                throw CLI::ValidationError("--scored-procedural",
                                           "only with --split tune (the test half stays the "
                                           "library's held-out models)");
            }
            if (o.fronts != "outline" && o.fronts != "grow") {
                throw CLI::ValidationError("--fronts", "must be outline or grow");
            }
            if (o.tune_fold != -1 &&
                !(o.split == "tune" && o.train_split == "tune" && o.tune_fold <= 1)) {
                throw CLI::ValidationError("--tune-fold",
                                           "0 or 1, only with --split tune --train-split tune");
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
