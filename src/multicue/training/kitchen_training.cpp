#include "multicue/training/kitchen_training.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/sim/kitchen_procedural.hpp"
#include "multicue/sim/raycaster.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/training/kitchen_scan_truth.hpp"

namespace multicue::training {

sim::KinectParams KitchenKinectParams() {
    sim::KinectParams p;
    p.shading = 0.3f;
    return p;
}

sim::LaserParams KitchenLaserParams() {
    sim::LaserParams p;
    p.tilt_min_deg = -40.0f;  // up to the ceiling
    p.tilt_max_deg = 60.0f;
    return p;
}

std::vector<KitchenFrame> ScanKitchen(const sim::KitchenScene& kitchen, int views, int laser_views,
                                      std::uint64_t seed) {
    std::vector<KitchenFrame> out;
    const sim::RayCaster caster(kitchen.scene);
    std::uint64_t v = 0;
    // The order and seeds of `simulate kitchens`: laser sweeps first, then the Kinect frames.
    for (const auto& pose : sim::KitchenLaserPoses(kitchen, laser_views, seed)) {
        KitchenFrame f{
            sim::ScanLaser(caster, pose, KitchenLaserParams(), sim::SubSeed(seed, 100 + v++)), true,
            pose};
        sim::AddKitchenTruth(kitchen, f.cloud);
        sim::ScanToWorld(f.cloud, pose);
        out.push_back(std::move(f));
    }
    for (const auto& pose : sim::KitchenCameraPoses(kitchen, views, seed)) {
        KitchenFrame f{
            sim::ScanKinect(caster, pose, KitchenKinectParams(), sim::SubSeed(seed, 100 + v++)),
            false, pose};
        sim::AddKitchenTruth(kitchen, f.cloud);
        sim::ScanToWorld(f.cloud, pose);
        out.push_back(std::move(f));
    }
    return out;
}

std::vector<sim::KitchenModelEntry> SelectKitchenFold(
    const std::vector<sim::KitchenModelEntry>& entries, int fold) {
    if (fold != 0 && fold != 1) {
        throw InvalidArgument(fmt::format("kitchen models: fold must be 0 or 1, got {}", fold));
    }
    auto annotation = [](const sim::KitchenModelEntry& e) {
        return std::filesystem::path(e.id).filename().string();
    };
    std::map<std::string, std::vector<std::pair<std::uint64_t, std::string>>> by_kind;
    std::map<std::string, int> kinds_of_id;
    for (const auto& e : entries) {
        by_kind[e.kind].emplace_back(sim::MeshNameHash(annotation(e)), annotation(e));
        ++kinds_of_id[annotation(e)];
    }
    std::map<std::pair<std::string, std::string>, int> fold_of;
    for (auto& [kind, ids] : by_kind) {
        std::sort(ids.begin(), ids.end());
        for (std::size_t r = 0; r < ids.size(); ++r) {
            fold_of[{kind, ids[r].second}] = static_cast<int>(r % 2);
        }
    }
    std::vector<sim::KitchenModelEntry> out;
    for (const auto& e : entries) {
        const int f = kinds_of_id[annotation(e)] > 1 ? 0 : fold_of.at({e.kind, annotation(e)});
        if (f == fold) out.push_back(e);
    }
    return out;
}

namespace {

/// Builds `kitchens` kitchens of `models` (kitchen i from sim::SubSeed(seed, i), passed to
/// `prepare` before it is scanned), scans each with `views` Kinect frames and `laser_views`
/// laser sweeps, and calls `visit(kitchen, frame, source)` per scan, `source` naming it. A scan
/// whose `visit` throws DataError (the map refuses it) is skipped; stops early when an
/// interruption is requested.
template <typename Prepare, typename Visit>
void ForEachTrainingScan(const std::vector<sim::KitchenModelEntry>& models,
                         sim::KitchenModelCache& cache, float procedural_share, int kitchens,
                         std::uint64_t seed, int views, int laser_views, const char* what,
                         Progress* progress, Prepare prepare, Visit visit) {
    sim::KitchenSceneParams scene;
    scene.procedural_share = procedural_share;
    for (int i = 0; i < kitchens && !InterruptRequested(); ++i) {
        const std::uint64_t s = sim::SubSeed(seed, static_cast<std::uint64_t>(i));
        sim::KitchenScene kitchen = sim::MakeKitchenScene(models, cache, scene, s);
        prepare(kitchen, s);
        const auto frames = ScanKitchen(kitchen, views, laser_views, s);
        for (std::size_t f = 0; f < frames.size(); ++f) {
            try {
                visit(kitchen, frames[f],
                      fmt::format("kitchen_{:04}_{}_{:02}", i, frames[f].laser ? "laser" : "kinect",
                                  f));
            } catch (const DataError& e) {
                // A scan the map refuses (no vertical plane in view) gives no rows.
                LogInfo("{}: kitchen {} scan {}: {}", what, i, f, e.what());
            }
        }
        if (progress != nullptr) progress->Advance();
    }
}

/// A classifier of `spec` fitted to `rows`; DataError (naming `job` and the rows' `noun`) when
/// fewer than two classes have rows.
std::unique_ptr<ml::Classifier> TrainOnRows(const ml::Dataset& rows, const std::string& spec,
                                            std::uint32_t seed, const char* job, const char* noun) {
    const auto counts = rows.ClassCounts();
    if (std::count_if(counts.begin(), counts.end(), [](std::size_t n) { return n > 0; }) < 2) {
        throw DataError(
            fmt::format("{}: the {} {} rows hold fewer than two classes", job, rows.rows(), noun));
    }
    std::unique_ptr<ml::Classifier> c = ml::CreateClassifier(spec);
    c->seed = seed;
    c->Fit(rows);
    return c;
}

}  // namespace

void FixtureTrainingOptions::Validate() const {
    if (kitchens < 1 || views < 1) {
        throw InvalidArgument(fmt::format(
            "train fixtures: kitchens and views must be >= 1, got {} and {}", kitchens, views));
    }
    if (!(match_distance > 0.0f) || !std::isfinite(match_distance)) {
        throw InvalidArgument(
            fmt::format("train fixtures: match_distance must be > 0, got {}", match_distance));
    }
    if (fold < -1 || fold > 1) {
        throw InvalidArgument(fmt::format("train fixtures: fold must be -1, 0 or 1, got {}", fold));
    }
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("train fixtures: num_threads must be >= 0, got {}", num_threads));
    }
    if (procedural < 0 || procedural > sim::kMaxProceduralPerKind) {
        throw InvalidArgument(fmt::format("train fixtures: procedural must lie in [0, {}], got {}",
                                          sim::kMaxProceduralPerKind, procedural));
    }
    if (!(procedural_share >= 0.0f && procedural_share <= 1.0f)) {
        throw InvalidArgument(fmt::format(
            "train fixtures: procedural_share must lie in [0, 1], got {}", procedural_share));
    }
    handle_variation.Validate();
    if (fixture_params) fixture_params->Validate();
}

std::vector<int> LabelFixtureCandidates(const PointCloud& scan,
                                        const std::vector<mapping::FixtureCandidate>& candidates,
                                        float match_distance) {
    const ExtraField* field = scan.FindExtraField("semantic");
    if (field == nullptr || field->data.size() != scan.size()) {
        throw DataError("train fixtures: the scan has no ground-truth field 'semantic'");
    }
    const auto handle = static_cast<std::uint8_t>(sim::KitchenClass::kHandle);
    const auto knob = static_cast<std::uint8_t>(sim::KitchenClass::kKnob);
    std::vector<Index> truth;
    for (std::size_t i = 0; i < scan.size(); ++i) {
        const std::uint8_t c = field->data[i];
        if ((c == handle || c == knob) && scan.IsFinite(i)) truth.push_back(static_cast<Index>(i));
    }
    std::vector<int> labels(candidates.size(), 0);
    const float d2 = match_distance * match_distance;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const Eigen::Vector3f& c = candidates[k].fixture.center;
        float best = d2;
        for (const Index i : truth) {
            const float d = (scan.points[i] - c).squaredNorm();
            if (d <= best) {
                best = d;
                labels[k] = field->data[i] == handle ? 1 : 2;
            }
        }
    }
    return labels;
}

ml::Dataset EmptyFixtureDataset() {
    ml::Dataset data = ml::Dataset::WithBlocks({{"fixture", mapping::FixtureFeatureNames()}});
    for (const auto& name : mapping::FixtureClassNames()) data.ClassId(name);
    return data;
}

void AppendFixtureRows(const PointCloud& scan,
                       const std::vector<mapping::FixtureCandidate>& candidates,
                       float match_distance, const std::string& source, ml::Dataset& data) {
    const std::vector<int> labels = LabelFixtureCandidates(scan, candidates, match_distance);
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const std::vector<float> row = mapping::FixtureFeatureRow(candidates[k].evidence);
        data.AppendRow(row, mapping::FixtureClassNames()[static_cast<std::size_t>(labels[k])], -1,
                       -1, source);
    }
}

ml::Dataset CollectFixtureRows(const std::vector<sim::KitchenModelEntry>& library,
                               sim::KitchenModelCache& cache, const FixtureTrainingOptions& o,
                               Progress* progress) {
    o.Validate();
    auto models = sim::SelectKitchenSplit(library, o.split);
    if (o.fold >= 0) models = SelectKitchenFold(models, o.fold);
    for (auto& e : sim::ProceduralKitchenEntries(o.procedural, sim::SubSeed(o.seed, 97))) {
        models.push_back(std::move(e));
    }
    ml::Dataset data = EmptyFixtureDataset();
    const bool laser = o.sensor == mapping::KitchenSensor::kLaser;
    mapping::MapKitchenParams params = mapping::KitchenParamsFor(o.sensor);
    if (o.fixture_params) params.fixtures = *o.fixture_params;
    params.num_threads = o.num_threads;
    params.gap_fronts.enabled = false;  // the rows are the candidates; fronts are not needed
    ForEachTrainingScan(
        models, cache, o.procedural_share, o.kitchens, o.seed, laser ? 0 : o.views,
        laser ? o.views : 0, "train fixtures", progress,
        [&](sim::KitchenScene& kitchen, std::uint64_t seed) {
            if (o.vary_handles) {
                sim::VaryHandles(kitchen, o.handle_variation, sim::SubSeed(seed, 41));
            }
        },
        [&](const sim::KitchenScene&, const KitchenFrame& frame, const std::string& source) {
            const auto r = mapping::MapKitchen({frame.cloud}, params);
            AppendFixtureRows(frame.cloud, r.fixture_candidates, o.match_distance, source, data);
        });
    return data;
}

std::unique_ptr<ml::Classifier> TrainFixtureClassifier(const ml::Dataset& rows,
                                                       const std::string& spec,
                                                       std::uint32_t seed) {
    // Classes without rows (no knob in view) are left out: the model predicts the others.
    return TrainOnRows(rows, spec, seed, "train fixtures", "candidate");
}

void ContainerTrainingOptions::Validate() const {
    if (kitchens < 1) {
        throw InvalidArgument(
            fmt::format("train containers: kitchens must be >= 1, got {}", kitchens));
    }
    if (views < 0 || laser_views < 0 || views + laser_views < 1) {
        throw InvalidArgument(fmt::format(
            "train containers: views and laser_views must be >= 0 and not both 0, got {} and {}",
            views, laser_views));
    }
    if (num_threads < 0) {
        throw InvalidArgument(
            fmt::format("train containers: num_threads must be >= 0, got {}", num_threads));
    }
    if (!(procedural_share >= 0.0f && procedural_share <= 1.0f)) {
        throw InvalidArgument(fmt::format(
            "train containers: procedural_share must lie in [0, 1], got {}", procedural_share));
    }
    if (kinect_params) kinect_params->Validate();
    if (laser_params) laser_params->Validate();
}

ml::Dataset EmptyContainerDataset() {
    return ml::Dataset::WithBlocks({{"container", mapping::ContainerFeatureNames()}});
}

void AppendContainerRows(const sim::KitchenScene& kitchen, const PointCloud& scan,
                         const mapping::KitchenMap& map, const std::string& source,
                         ml::Dataset& data) {
    for (const auto& [furniture, instance] : FurnitureInstances(map, scan)) {
        const auto& model = kitchen.instances.at(static_cast<std::size_t>(instance)).model;
        data.AppendRow(mapping::ContainerFeatures(map, static_cast<std::size_t>(furniture)),
                       sim::ContainerTypeOfModel(*model), -1, -1, source);
    }
}

namespace {

/// Rows of every scan of `o.kitchens` kitchens of `models`, each scan mapped on its own with its
/// sensor's parameters and fixture classifier: `append(kitchen, scan, map, params, source, rows)`.
template <typename Append>
ml::Dataset CollectMapRows(const std::vector<sim::KitchenModelEntry>& models,
                           sim::KitchenModelCache& cache, const ContainerTrainingOptions& o,
                           const char* what, ml::Dataset rows, Progress* progress, Append append) {
    o.Validate();
    mapping::MapKitchenParams params[2] = {
        o.kinect_params.value_or(mapping::KitchenParamsFor(mapping::KitchenSensor::kKinect)),
        o.laser_params.value_or(mapping::KitchenParamsFor(mapping::KitchenSensor::kLaser))};
    for (auto& p : params) p.num_threads = o.num_threads;
    ForEachTrainingScan(
        models, cache, o.procedural_share, o.kitchens, o.seed, o.views, o.laser_views, what,
        progress, [](sim::KitchenScene&, std::uint64_t) {},
        [&](const sim::KitchenScene& kitchen, const KitchenFrame& frame,
            const std::string& source) {
            const mapping::MapKitchenParams& p = params[frame.laser ? 1 : 0];
            const auto r = mapping::MapKitchen({frame.cloud}, p, nullptr,
                                               frame.laser ? o.laser_fixtures : o.kinect_fixtures);
            append(kitchen, frame.cloud, r.map, p, source, rows);
        });
    return rows;
}

}  // namespace

ml::Dataset CollectContainerRows(const std::vector<sim::KitchenModelEntry>& models,
                                 sim::KitchenModelCache& cache, const ContainerTrainingOptions& o,
                                 Progress* progress) {
    return CollectMapRows(
        models, cache, o, "train containers", EmptyContainerDataset(), progress,
        [](const sim::KitchenScene& kitchen, const PointCloud& scan, const mapping::KitchenMap& map,
           const mapping::MapKitchenParams&, const std::string& source,
           ml::Dataset& rows) { AppendContainerRows(kitchen, scan, map, source, rows); });
}

std::unique_ptr<ml::Classifier> TrainContainerClassifier(const ml::Dataset& rows,
                                                         const std::string& spec,
                                                         std::uint32_t seed) {
    return TrainOnRows(rows, spec, seed, "train containers", "furniture");
}

ml::Dataset EmptyJointDataset() {
    return ml::Dataset::WithBlocks({{"joint", mapping::JointFeatureNames()}});
}

void AppendJointRows(const sim::KitchenScene& kitchen, const PointCloud& scan,
                     const mapping::KitchenMap& map, const std::string& source, ml::Dataset& data,
                     const mapping::ArticulationParams& params) {
    const ScanTruth truth(scan);
    const auto fronts = TrueFronts(scan, truth);
    for (const auto& [key, match] : MatchFronts(map, truth, fronts)) {
        const TrueFront& tf = fronts.at(key);
        const auto index = static_cast<std::size_t>(match.first);
        const mapping::Front& f = map.fronts[index];
        if (match.second < 0.5f || tf.joint < 0 || f.fixtures.empty() ||
            f.articulation.source != "fixture") {
            continue;
        }
        const sim::KitchenJoint& j = kitchen.joints.at(static_cast<std::size_t>(tf.joint));
        const mapping::JointType type = j.type == io::UrdfJointType::kPrismatic
                                            ? mapping::JointType::kPrismatic
                                            : mapping::JointType::kRevolute;
        data.AppendRow(mapping::JointFeatures(map, index, params),
                       mapping::JointClassOf(type, j.axis_direction, j.axis_point, f, map.frame),
                       -1, -1, source);
    }
}

ml::Dataset CollectJointRows(const std::vector<sim::KitchenModelEntry>& models,
                             sim::KitchenModelCache& cache, const ContainerTrainingOptions& o,
                             Progress* progress) {
    return CollectMapRows(
        models, cache, o, "train joints", EmptyJointDataset(), progress,
        [](const sim::KitchenScene& kitchen, const PointCloud& scan, const mapping::KitchenMap& map,
           const mapping::MapKitchenParams& p, const std::string& source, ml::Dataset& rows) {
            AppendJointRows(kitchen, scan, map, source, rows, p.articulation);
        });
}

std::unique_ptr<ml::Classifier> TrainJointClassifier(const ml::Dataset& rows,
                                                     const std::string& spec, std::uint32_t seed) {
    return TrainOnRows(rows, spec, seed, "train joints", "front");
}

}  // namespace multicue::training
