#include "part_graph_training.hpp"

#include <cstdlib>
#include <mutex>
#include <optional>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/parallel.hpp"
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
    OrganizedNormalParams np = perceive.organized_normals;
    np.num_threads = 1;
    np.mask.assign(scan.size(), 0);
    for (Index i : object) np.mask[i] = 1;
    SetNormals(scan, EstimateNormalsOrganized(scan, np));
    const KdTree tree(scan, object);
    RegionGrowingParams rg = perceive.parts;
    rg.subset = object;
    return RegionGrowing(scan, tree, rg).parts;
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
};

}  // namespace

bool TrainPartGraphModel(PartGraphModel& model, const PartGraphTrainingOptions& o,
                         Progress* progress) {
    if (o.views < 1) throw InvalidArgument("views must be >= 1");
    if (o.objects_per_category < 0) throw InvalidArgument("objects_per_category must be >= 0");
    if (o.mesh_modulo < 1 || o.mesh_remainder < 0 || o.mesh_remainder >= o.mesh_modulo) {
        throw InvalidArgument("mesh split: need 0 <= mesh_remainder < mesh_modulo");
    }
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
    if (!o.meshes.empty()) {
        sim::ObjectSource source(sim::ReadMeshLibrary(o.meshes, sim::TabletopCategories()), false);
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
    if (progress) progress->Advance(0);
    std::vector<std::vector<Sample>> samples(jobs.size());
    std::atomic<bool> stopped{false};
    const PerceiveParams perceive;
    ParallelFor(
        jobs.size(), o.num_threads,
        [&](std::size_t j) {
            if (InterruptRequested()) {
                stopped = true;
                return;
            }
            sim::TurntableParams tp;
            tp.distance = o.camera_distance;
            const sim::Scene scene = sim::MakeTurntableScene(jobs[j].object, tp, jobs[j].seed);
            const sim::RayCaster caster(scene);
            const auto poses = sim::TurntableViews(scene, o.views, tp);
            sim::KinectParams kp;
            kp.num_threads = 1;
            const Category category = ParseCategory(jobs[j].object.category);
            for (std::size_t v = 0; v < poses.size(); ++v) {
                PointCloud scan = sim::ScanKinect(caster, poses[v], kp, jobs[j].seed + v);
                Indices object;
                for (std::size_t i = 0; i < scan.size(); ++i) {
                    if (scan.labels[i] == 20 && scan.IsFinite(i)) object.push_back(Index(i));
                }
                const auto parts = DecomposeObject(scan, object, perceive);
                if (parts.empty()) continue;
                Sample s{ComputePartDescriptors(scan, parts, model.descriptor_params),
                         BuildPartGraph(scan, parts, model.graph_params), category};
                samples[j].push_back(std::move(s));
            }
            if (progress) progress->Advance();
        },
        1);
    // Added in job order: the model does not depend on the thread count.
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        for (std::size_t v = 0; v < samples[j].size(); ++v) {
            PartGraphTrainParams tp = o.train;
            tp.seed = sim::SubSeed(o.train.seed, j * 1000 + v);
            model.AddObject(samples[j][v].descriptors, samples[j][v].graph, samples[j][v].category,
                            tp);
        }
    }
    model.Build();
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
           ("part-graph-default-v" + std::to_string(kPartGraphModelVersion) + ".mcpg");
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
