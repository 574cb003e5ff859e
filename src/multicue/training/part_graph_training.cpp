#include "multicue/training/part_graph_training.hpp"

#include <algorithm>
#include <array>
#include <cstdlib>
#include <mutex>
#include <optional>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
#include "multicue/features/part_stats.hpp"
#include "multicue/search/kdtree.hpp"
#include "multicue/sim/mesh.hpp"
#include "multicue/sim/objects.hpp"
#include "multicue/sim/procedural.hpp"
#include "multicue/sim/raycaster.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/sim/scene_gen.hpp"
#include "multicue/sim/sensors.hpp"
#include "multicue/surface/normals.hpp"

namespace multicue::training {

std::vector<Indices> DecomposeObject(PointCloud& scan, const Indices& object,
                                     const PerceiveParams& perceive) {
    if (object.empty()) return {};
    OrganizedNormalParams np = perceive.normals.organized;
    np.num_threads = 1;
    np.mask.assign(scan.size(), 0);
    for (Index i : object) np.mask[i] = 1;
    SetNormals(scan, EstimateNormalsOrganized(scan, np));
    const KdTree tree(scan, object);
    RegionGrowingParams rg = perceive.parts.region_growing;
    rg.subset = object;
    return RegionGrowing(scan, tree, rg).parts;
}

FeatureMatrix ComputePartStatisticsRows(const PointCloud& scan, const std::vector<Indices>& parts,
                                        const Eigen::Vector3f& up) {
    FeatureMatrix out =
        FeatureMatrix::Zero(static_cast<Eigen::Index>(parts.size()), kPartStatsSize);
    PartStatsParams sp;
    sp.up = up.normalized();
    sp.num_threads = 1;
    for (std::size_t p = 0; p < parts.size(); ++p) {
        PointCloud part;
        for (Index i : parts[p]) {
            if (!scan.points[i].allFinite()) continue;
            part.points.push_back(scan.points[i]);
            part.normals.push_back(scan.normals[i]);
        }
        part.width = static_cast<std::uint32_t>(part.points.size());
        part.height = 1;
        out.row(static_cast<Eigen::Index>(p)) = ComputePartStatistics(part, sp).transpose();
    }
    return out;
}

namespace {

struct Job {
    sim::ObjectModel object;
    std::uint64_t seed;
};

struct Sample {
    FeatureMatrix descriptors;
    PartGraph graph;
    Category category;
    FeatureMatrix statistics;
    FeatureVector cluster;
};

// The optional baseline features of one training object.
void AddBaselineFeatures(Sample& s, const PointCloud& scan, const std::vector<Indices>& parts,
                         const Indices& object, const Eigen::Vector3f& up,
                         const PartGraphTrainingOptions& o) {
    // The model keeps each object's whole-cluster descriptor (its third expert).
    s.cluster = ComputeClusterDescriptor(scan, object, o.cluster_params);
    if (!o.objects_out) return;
    if (o.part_statistics) s.statistics = ComputePartStatisticsRows(scan, parts, up);
}

// ParallelFor (one item per task) that skips the remaining items once an interrupt was
// requested, and then sets `stopped`.
template <typename Fn>
void InterruptibleFor(std::size_t n, int threads, std::atomic<bool>& stopped, Fn&& fn) {
    ParallelFor(
        n, threads,
        [&](std::size_t i) {
            if (InterruptRequested()) {
                stopped = true;
                return;
            }
            fn(i);
        },
        1);
}

// Each view of a table scene scanned by the simulated Kinect, with perceive's normals, perceived
// by `pp` (single-threaded: scenes run in parallel) and handed to `fn(scan, result, truth, pose)`
// (truth: the per-point category field).
template <typename Fn>
void PerceiveTableViews(const sim::Scene& scene, int views, std::uint64_t seed,
                        const PartGraphTrainingOptions& o, const PerceiveParams& pp, Fn&& fn) {
    const sim::RayCaster caster(scene);
    const auto poses = sim::TableViewpoints(scene, views, o.table_viewpoints, seed);
    sim::KinectParams kp = o.kinect;
    kp.num_threads = 1;
    for (std::size_t v = 0; v < poses.size(); ++v) {
        PointCloud scan = sim::ScanKinect(caster, poses[v], kp, seed + v);
        const auto* truth = scan.FindExtraField("category");
        if (!truth) continue;
        OrganizedNormalParams np = pp.normals.organized;
        np.num_threads = 1;
        SetNormals(scan, EstimateNormalsOrganized(scan, np));
        const PerceiveResult r = Perceive(scan, pp);
        fn(scan, r, *truth, poses[v]);
    }
}

// The most frequent category of an object's points (not kNone) and its count.
std::pair<Category, std::size_t> MajorityCategory(const Indices& object, const ExtraField& truth) {
    std::array<std::size_t, kNumCategories> hist{};
    for (Index i : object) {
        const int t = static_cast<int>(truth.data[i]);
        if (t >= 0 && t < static_cast<int>(kNumCategories)) ++hist[t];
    }
    const auto best =
        static_cast<std::size_t>(std::max_element(hist.begin() + 1, hist.end()) - hist.begin());
    return {static_cast<Category>(best), hist[best]};
}

// The stacker's training rows: every perceived object of the held-out scenes with its majority
// truth, the experts computed exactly as perceive's "stacked" categoriser computes them. Frames
// are perceived in parallel; rows are collected in scene and view order.
bool TrainStacker(PartGraphModel& model, const std::vector<sim::Scene>& scenes,
                  const PartGraphTrainingOptions& o, Progress* progress) {
    std::vector<std::vector<std::pair<std::array<float, kStackerInputSize>, Category>>> rows(
        scenes.size());
    std::atomic<bool> stopped{false};
    PerceiveParams pp;
    pp.num_threads = 1;
    InterruptibleFor(scenes.size(), o.num_threads, stopped, [&](std::size_t s) {
        PerceiveTableViews(
            scenes[s], o.stacker_views, sim::SubSeed(o.seed, 9500000u + s), o, pp,
            [&](const PointCloud& scan, const PerceiveResult& r, const ExtraField& truth,
                const Eigen::Isometry3f&) {
                const Eigen::Vector4f plane =
                    r.support.found ? r.support.plane : Eigen::Vector4f::Zero();
                const PartGraphVotes pg = VotePartGraph(model, scan, r.objects, plane, pp.category);
                for (std::size_t k = 0; k < r.objects.size(); ++k) {
                    const auto& obj = r.objects[k];
                    if (obj.parts.empty() || obj.category.category == Category::kNone) continue;
                    const auto [best, count] = MajorityCategory(obj.indices, truth);
                    if (count == 0) continue;
                    rows[s].emplace_back(
                        StackerInputs(obj.category, pg.objects[k],
                                      ClusterExpert(model, scan, obj.indices, pp.category)),
                        best);
                }
            });
        if (progress) progress->Advance();
    });
    if (stopped) return false;
    std::vector<std::array<float, kStackerInputSize>> inputs;
    std::vector<Category> truth;
    for (const auto& scene_rows : rows) {
        for (const auto& [x, c] : scene_rows) {
            inputs.push_back(x);
            truth.push_back(c);
        }
    }
    if (inputs.empty()) throw DataError("stacker scenes: no perceived object with a category");
    model.stacker.Fit(inputs, truth, o.stacker);
    LogInfo("stacker: {} objects from {} held-out scenes", inputs.size(), scenes.size());
    return true;
}

// Throws InvalidArgument for bad turntable options (checked before any object is made).
void CheckObjectOptions(const PartGraphTrainingOptions& o) {
    if (o.views < 1) throw InvalidArgument("views must be >= 1");
    if (o.objects_per_category < 0) throw InvalidArgument("objects_per_category must be >= 0");
    if (o.mesh_modulo < 1 || o.mesh_remainder < 0 || o.mesh_remainder >= o.mesh_modulo) {
        throw InvalidArgument("mesh split: need 0 <= mesh_remainder < mesh_modulo");
    }
}

// The turntable objects: objects_per_category procedural ones per category, then (with
// mesh_turntable) the meshes of the library in this split, each with its own seed.
std::vector<Job> TurntableJobs(const PartGraphTrainingOptions& o) {
    std::vector<Job> jobs;
    const auto& categories = o.categories.empty() ? sim::TabletopCategories() : o.categories;
    for (const auto& category : categories) {
        for (int i = 0; i < o.objects_per_category; ++i) {
            sim::StreamRng rng(
                o.seed, sim::SubSeed(static_cast<std::uint64_t>(sim::CategoryIndex(category)),
                                     static_cast<std::uint64_t>(i)));
            sim::ProceduralObject p = sim::MakeProceduralObject(category, rng);
            sim::ObjectModel m;
            m.mesh = std::make_shared<const sim::PartMesh>(std::move(p.mesh));
            m.category = p.category;
            m.source = p.kind;
            jobs.push_back({std::move(m), rng()});
        }
    }
    if (!o.meshes.empty() && o.mesh_turntable) {
        sim::ObjectSource source(
            sim::ReadMeshLibrary(o.meshes, sim::TabletopCategories(), o.labels), false);
        int used = 0;
        for (std::size_t i = 0; i < source.library().size(); ++i) {
            if (static_cast<int>(i % static_cast<std::size_t>(o.mesh_modulo)) != o.mesh_remainder) {
                continue;
            }
            if (o.max_meshes > 0 && used >= o.max_meshes) break;
            sim::StreamRng rng(o.seed, 1000003u + i);
            auto m = source.FromEntry(i, rng);
            if (!m) continue;
            jobs.push_back({std::move(*m), rng()});
            ++used;
        }
    }
    return jobs;
}

// Throws InvalidArgument for bad table-scene options; checked after the turntable objects are
// made, so that an unreadable mesh library is still the first error reported.
void CheckSceneOptions(const PartGraphTrainingOptions& o) {
    if (o.table_scenes < 0 || o.table_views < 1) {
        throw InvalidArgument("table_scenes must be >= 0 and table_views >= 1");
    }
    if (o.stacker_scenes < 0 || o.stacker_views < 1) {
        throw InvalidArgument("stacker_scenes must be >= 0 and stacker_views >= 1");
    }
}

// The objects of the table scenes (none when there are no scenes): the meshes of the library in
// this split, else procedural objects of the categories.
std::optional<sim::ObjectSource> SceneObjectSource(const PartGraphTrainingOptions& o) {
    std::optional<sim::ObjectSource> source;
    if (o.table_scenes > 0 || o.stacker_scenes > 0) {
        if (!o.meshes.empty()) {
            auto all = sim::ReadMeshLibrary(o.meshes, sim::TabletopCategories(), o.labels);
            std::vector<sim::MeshEntry> selected;
            for (std::size_t i = 0; i < all.size(); ++i) {
                if (static_cast<int>(i % static_cast<std::size_t>(o.mesh_modulo)) ==
                    o.mesh_remainder) {
                    selected.push_back(all[i]);
                }
            }
            if (o.max_meshes > 0 && selected.size() > static_cast<std::size_t>(o.max_meshes)) {
                selected.resize(static_cast<std::size_t>(o.max_meshes));
            }
            source.emplace(std::move(selected), false);
        } else {
            source.emplace(o.categories);
        }
    }
    return source;
}

// `count` cluttered table scenes with seeds SubSeed(seed, base + s), drawn sequentially: the
// object source caches meshes.
std::vector<sim::Scene> DrawTableScenes(const sim::TableSceneParams& params,
                                        std::optional<sim::ObjectSource>& source, int count,
                                        std::uint64_t seed, std::uint64_t base) {
    std::vector<sim::Scene> scenes;
    for (int s = 0; s < count; ++s) {
        scenes.push_back(
            sim::MakeTableScene(params, *source, sim::SubSeed(seed, base + std::uint64_t(s))));
    }
    return scenes;
}

// The samples of one turntable object: each view scanned by the simulated Kinect, the object's
// points (label 20) decomposed into parts, with up (world z) in the scan's frame.
std::vector<Sample> TurntableSamples(const Job& job, const PartGraphTrainingOptions& o,
                                     const PartGraphModel& model, const PerceiveParams& perceive) {
    std::vector<Sample> samples;
    sim::TurntableParams tp;
    tp.distance = o.camera_distance;
    const sim::Scene scene = sim::MakeTurntableScene(job.object, tp, job.seed);
    const sim::RayCaster caster(scene);
    const auto poses = sim::TurntableViews(scene, o.views, tp);
    sim::KinectParams kp = o.kinect;
    kp.num_threads = 1;
    const Category category = ParseCategory(job.object.category);
    for (std::size_t v = 0; v < poses.size(); ++v) {
        PointCloud scan = sim::ScanKinect(caster, poses[v], kp, job.seed + v);
        Indices object;
        for (std::size_t i = 0; i < scan.size(); ++i) {
            if (scan.labels[i] == 20 && scan.IsFinite(i)) object.push_back(Index(i));
        }
        const auto parts = DecomposeObject(scan, object, perceive);
        if (parts.empty()) continue;
        // Up (world z) in the scan's frame: the support plane's normal.
        const Eigen::Vector3f up = poses[v].linear().transpose() * Eigen::Vector3f::UnitZ();
        Sample s{ComputePartDescriptors(scan, parts, model.descriptor_params, up),
                 BuildPartGraph(scan, parts, model.graph_params),
                 category,
                 {},
                 {}};
        AddBaselineFeatures(s, scan, parts, object, up, o);
        samples.push_back(std::move(s));
    }
    return samples;
}

// The samples of table scene s: every perceived object with parts whose points are mostly (60%)
// of one true category, the objects as perceive segments them in clutter.
std::vector<Sample> TableSceneSamples(const sim::Scene& scene, std::size_t s,
                                      const PartGraphTrainingOptions& o,
                                      const PartGraphModel& model, const PerceiveParams& perceive) {
    std::vector<Sample> samples;
    PerceiveParams pp = perceive;
    pp.num_threads = 1;
    PerceiveTableViews(
        scene, o.table_views, sim::SubSeed(o.seed, 8000000u + s), o, pp,
        [&](const PointCloud& scan, const PerceiveResult& r, const ExtraField& truth,
            const Eigen::Isometry3f& pose) {
            const Eigen::Vector3f up = pose.linear().transpose() * Eigen::Vector3f::UnitZ();
            for (const auto& obj : r.objects) {
                if (obj.parts.empty()) continue;
                const auto [best, count] = MajorityCategory(obj.indices, truth);
                if (count == 0 || 10 * count < 6 * obj.indices.size()) continue;
                Sample sample{ComputePartDescriptors(scan, obj.parts, model.descriptor_params, up),
                              BuildPartGraph(scan, obj.parts, model.graph_params),
                              best,
                              {},
                              {}};
                AddBaselineFeatures(sample, scan, obj.parts, obj.indices, up, o);
                samples.push_back(std::move(sample));
            }
        });
    return samples;
}

// Adds the samples to the model in job order (the model does not depend on the thread count),
// each with its own training seed, and hands them to objects_out when asked.
void AddSamples(std::vector<std::vector<Sample>>& samples, const PartGraphTrainingOptions& o,
                PartGraphModel& model) {
    for (std::size_t j = 0; j < samples.size(); ++j) {
        for (std::size_t v = 0; v < samples[j].size(); ++v) {
            PartGraphTrainParams tp = o.train;
            tp.seed = sim::SubSeed(o.train.seed, j * 1000 + v);
            model.AddObject(samples[j][v].descriptors, samples[j][v].graph, samples[j][v].category,
                            tp);
            model.AddCluster(samples[j][v].cluster, samples[j][v].category);
            if (o.objects_out) {
                o.objects_out->push_back({std::move(samples[j][v].descriptors),
                                          std::move(samples[j][v].statistics),
                                          std::move(samples[j][v].cluster), samples[j][v].category,
                                          std::move(samples[j][v].graph), tp.seed});
            }
        }
    }
}

}  // namespace

bool TrainPartGraphModel(PartGraphModel& model, const PartGraphTrainingOptions& o,
                         Progress* progress) {
    CheckObjectOptions(o);
    const std::vector<Job> jobs = TurntableJobs(o);
    CheckSceneOptions(o);
    std::optional<sim::ObjectSource> source = SceneObjectSource(o);
    sim::TableSceneParams scene_params;
    scene_params.clutter = 0.6f;
    const std::vector<sim::Scene> scenes =
        DrawTableScenes(scene_params, source, o.table_scenes, o.seed, 7000000u);
    if (progress) progress->Advance(0);

    // Samples of the turntable objects and the table scenes, scanned in parallel.
    std::vector<std::vector<Sample>> samples(jobs.size() + scenes.size());
    std::atomic<bool> stopped{false};
    const PerceiveParams perceive;
    InterruptibleFor(jobs.size(), o.num_threads, stopped, [&](std::size_t j) {
        samples[j] = TurntableSamples(jobs[j], o, model, perceive);
        if (progress) progress->Advance();
    });
    InterruptibleFor(scenes.size(), o.num_threads, stopped, [&](std::size_t s) {
        samples[jobs.size() + s] = TableSceneSamples(scenes[s], s, o, model, perceive);
        if (progress) progress->Advance();
    });
    model.cluster_size_weight = o.cluster_params.size_weight;
    AddSamples(samples, o, model);
    model.Build();
    if (o.stacker_scenes > 0 && !stopped) {
        const std::vector<sim::Scene> held_out =
            DrawTableScenes(scene_params, source, o.stacker_scenes, o.seed, 9000000u);
        if (!TrainStacker(model, held_out, o, progress)) stopped = true;
    }
    return !stopped;
}

PartGraphModel TrainDefaultPartGraphModel(Progress* progress) {
    PartGraphModel model;
    TrainPartGraphModel(model, PartGraphTrainingOptions{}, progress);
    return model;
}

std::filesystem::path DefaultPartGraphModelPath() {
    std::filesystem::path base;
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) {
        base = x;
    } else if (const char* h = std::getenv("HOME"); h && *h) {
        base = std::filesystem::path(h) / ".cache";
    } else {
        base = std::filesystem::temp_directory_path();
    }
    return base / "multicue" /
           ("part-graph-default-v" + std::to_string(kPartGraphModelVersion) + "." +
            std::to_string(kDefaultTrainingRevision) + ".mcpg");
}

PerceiveModels LoadPerceiveModels(const PerceiveParams& params) {
    PerceiveModels models;
    const CategorizationParams& c = params.category;
    if (!c.NeedsPartGraph()) return models;
    if (!c.part_graph_model.empty()) {
        models.part_graph =
            std::make_shared<const PartGraphModel>(PartGraphModel::Load(c.part_graph_model));
    } else if (c.categoriser == Categoriser::kStacked) {
        throw InvalidArgument(
            "category.categoriser stacked needs category.part_graph_model: a model trained with "
            "multicue train --stacker-scenes N");
    } else {
        models.part_graph =
            std::make_shared<const PartGraphModel>(LoadOrTrainDefaultPartGraphModel());
    }
    return models;
}

PartGraphModel LoadOrTrainDefaultPartGraphModel() {
    const auto path = DefaultPartGraphModelPath();
    std::error_code ec;
    if (std::filesystem::exists(path, ec)) {
        try {
            return PartGraphModel::Load(path);
        } catch (const Error& e) {
            LogWarning("{}: unusable cached part-graph model ({}), training it again",
                       path.string(), e.what());
        }
    }
    LogInfo("training the default part-graph model into {} (once)", path.string());
    PartGraphModel model = TrainDefaultPartGraphModel();
    std::filesystem::create_directories(path.parent_path(), ec);
    try {
        model.Save(path);
    } catch (const Error& e) {
        LogWarning("{}: cannot cache the part-graph model: {}", path.string(), e.what());
    }
    return model;
}

}  // namespace multicue::training
