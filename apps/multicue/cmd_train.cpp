// `multicue train`: a part-graph hashing model (thesis section 5.1; docs/training.md) from
// simulated turntable scans.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/sim/mesh.hpp"
#include "multicue/training/part_graph_training.hpp"

namespace multicue::cli {

namespace {

struct TrainOptions {
    std::string out;
    std::string meshes;
    std::string labels;
    training::PartGraphTrainingOptions t;
    std::size_t max_parts = 8;
    float size_weight = PartDescriptorParams{}.size_weight;
    PartDescriptorParams d;
    std::vector<float> extents;
};

// Every option of `multicue train`; returns --table-scenes (its default depends on --meshes).
CLI::Option* AddTrainOptions(CLI::App* cmd, TrainOptions* o) {
    // Not ->required(): `train furniture` has its own --out (checked in the callback).
    cmd->add_option("--out", o->out, "model file to write (.mcpg); required");
    cmd->add_option("--meshes", o->meshes,
                    "mesh library folder with labels.csv (added to the procedural objects)");
    cmd->add_option("--labels", o->labels,
                    "labels CSV of the mesh library (columns file, category; default: "
                    "MESHES/labels.csv; file names relative to MESHES)");
    cmd->add_option("--axial-noise", o->t.kinect.axial_noise,
                    "depth noise of the simulated sensor: sigma = this * z^2 [1/m]")
        ->capture_default_str();
    cmd->add_option("--objects", o->t.objects_per_category, "procedural objects per category")
        ->capture_default_str();
    cmd->add_option("--max-meshes", o->t.max_meshes, "at most this many library meshes (0 = all)")
        ->capture_default_str();
    cmd->add_option("--views", o->t.views, "turntable views per object")->capture_default_str();
    cmd->add_option("--max-parts", o->max_parts, "largest stored subgraph [parts]")
        ->capture_default_str();
    cmd->add_option("--size-weight", o->size_weight,
                    "weight of the group extents in the k-NN distance [1/m] (0: shape only)")
        ->capture_default_str();
    cmd->add_option("--extent-weights", o->extents,
                    "factors of the largest, middle and smallest extent (default 1 1 1)")
        ->expected(3);
    cmd->add_option("--grsd-weight", o->d.grsd_weight, "weight of the GRSD- block")
        ->capture_default_str();
    cmd->add_option("--elevation-weight", o->d.elevation_weight,
                    "weight of the normal elevation block (0: unused)")
        ->capture_default_str();
    cmd->add_option("--rsd-weight", o->d.rsd_weight, "weight of the curvature block (0: unused)")
        ->capture_default_str();
    cmd->add_option("--rsd-quantile", o->d.voxels.rsd.angle_quantile,
                    "RSD: share of a distance bin's normal angles at or below its largest, (0, 1] "
                    "(1: the extreme angle)")
        ->capture_default_str();
    CLI::Option* table_scenes =
        cmd->add_option("--table-scenes", o->t.table_scenes,
                        "cluttered table scenes segmented by perceive (robot-head views); "
                        "default 40, " +
                            std::to_string(training::kLibraryTableScenes) + " with --meshes");
    cmd->add_option("--table-views", o->t.table_views, "views per table scene")
        ->capture_default_str();
    cmd->add_option("--stacker-scenes", o->t.stacker_scenes,
                    "further table scenes whose perceived objects train the stacker over the "
                    "experts (perceive's \"stacked\" categoriser; 0: none)")
        ->capture_default_str();
    cmd->add_option("--stacker-views", o->t.stacker_views, "views per stacker scene")
        ->capture_default_str();
    cmd->add_option("--table-distance", o->t.table_viewpoints.max_distance,
                    "largest horizontal camera distance from the table centre [m]")
        ->capture_default_str();
    cmd->add_option("--seed", o->t.seed, "random seed")->capture_default_str();
    return table_scenes;
}

// The option values, checked before any work.
void CheckTrainOptions(TrainOptions* o) {
    if (o->t.views < 1) throw InvalidArgument("--views must be >= 1");
    if (o->t.objects_per_category < 0) throw InvalidArgument("--objects must be >= 0");
    if (!(o->size_weight >= 0.0f) || !std::isfinite(o->size_weight)) {
        throw InvalidArgument("--size-weight must be >= 0 and finite");
    }
    auto weight_ok = [](float w) { return w >= 0.0f && std::isfinite(w); };
    for (float w : o->extents) {
        if (!weight_ok(w)) throw InvalidArgument("--extent-weights must be >= 0 and finite");
    }
    if (!weight_ok(o->d.grsd_weight)) {
        throw InvalidArgument("--grsd-weight must be >= 0 and finite");
    }
    if (!weight_ok(o->d.elevation_weight)) {
        throw InvalidArgument("--elevation-weight must be >= 0 and finite");
    }
    if (!weight_ok(o->d.rsd_weight)) {
        throw InvalidArgument("--rsd-weight must be >= 0 and finite");
    }
    const float q = o->d.voxels.rsd.angle_quantile;
    if (!(q > 0.0f && q <= 1.0f)) throw InvalidArgument("--rsd-quantile must be in (0, 1]");
    if (o->t.table_scenes < 0) throw InvalidArgument("--table-scenes must be >= 0");
    if (o->t.table_views < 1) throw InvalidArgument("--table-views must be >= 1");
    if (o->t.stacker_scenes < 0) throw InvalidArgument("--stacker-scenes must be >= 0");
    if (o->t.stacker_views < 1) throw InvalidArgument("--stacker-views must be >= 1");
    if (!(o->t.table_viewpoints.max_distance > 0.0f)) {
        throw InvalidArgument("--table-distance must be > 0");
    }
    o->t.table_viewpoints.min_distance =
        std::min(o->t.table_viewpoints.min_distance, o->t.table_viewpoints.max_distance);
    if (o->max_parts < 1 || o->max_parts > 15) {
        throw InvalidArgument("--max-parts must be in [1, 15]");
    }
    if (!o->labels.empty() && o->meshes.empty()) {
        throw InvalidArgument("--labels needs --meshes (the folder its file names are in)");
    }
}

// Trains and writes the model; Ctrl-C stops between objects and writes nothing.
void Train(TrainOptions* o, int threads) {
    o->t.meshes = o->meshes;
    o->t.labels = o->labels;
    o->t.num_threads = threads;
    o->t.train.max_parts = o->max_parts;
    o->t.train.seed = o->t.seed;
    InstallInterruptHandler();
    std::size_t meshes = 0;  // library meshes on the turntable (one progress step each)
    if (!o->meshes.empty()) {
        meshes = sim::ReadMeshLibrary(o->meshes, sim::TabletopCategories(), o->labels).size();
        if (o->t.max_meshes > 0) {
            meshes = std::min(meshes, static_cast<std::size_t>(o->t.max_meshes));
        }
    }
    const std::size_t jobs = static_cast<std::size_t>(o->t.objects_per_category) * 6 + meshes +
                             static_cast<std::size_t>(std::max(o->t.table_scenes, 0)) +
                             static_cast<std::size_t>(std::max(o->t.stacker_scenes, 0));
    Progress progress("training part graphs", jobs);
    PartGraphModel model;
    model.descriptor_params = o->d;
    model.descriptor_params.size_weight = o->size_weight;
    if (o->extents.size() == 3) {
        std::copy(o->extents.begin(), o->extents.end(),
                  model.descriptor_params.extent_weights.begin());
    }
    const bool complete = training::TrainPartGraphModel(model, o->t, &progress);
    progress.Finish();
    if (!complete) throw DataError("interrupted; no model written");
    if (model.num_rows() == 0) throw DataError("no training subgraphs: nothing to write");
    model.Save(o->out);
    const auto per = model.rows_per_category();
    std::fprintf(stderr,
                 "train: %zu subgraphs in %zu buckets (sphere %zu, box %zu, flat %zu, "
                 "cylinder %zu, plate %zu, other %zu; %d table scenes) -> %s\n",
                 model.num_rows(), model.num_buckets(), per[1], per[2], per[3], per[4], per[5],
                 per[6], o->t.table_scenes, o->out.c_str());
    if (model.stacker.trained()) {
        std::fprintf(stderr, "train: stacker over the experts from %zu perceived objects\n",
                     model.stacker.train_rows());
    }
}

}  // namespace

void AddTrainCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "train", "Train the part-graph hashing categoriser on simulated turntable scans");
    auto o = std::make_shared<TrainOptions>();
    CLI::Option* table_scenes = AddTrainOptions(cmd, o.get());
    cmd->callback([cmd, o, &global, table_scenes] {
        if (!cmd->get_subcommands().empty()) return;  // `train furniture` ran instead
        if (o->out.empty()) throw InvalidArgument("train: --out is required");
        if (table_scenes->count() == 0 && !o->meshes.empty()) {
            o->t.table_scenes = training::kLibraryTableScenes;
        }
        CheckTrainOptions(o.get());
        Train(o.get(), global.threads);
    });
}

}  // namespace multicue::cli
