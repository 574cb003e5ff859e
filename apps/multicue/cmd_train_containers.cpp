// `multicue train containers --out MODEL`: the container classifier of `map kitchen
// --containers` (thesis section 4.1.3: cupboards, drawer units, ovens, dishwashers, fridges,
// microwaves, tables), and `multicue train joints --out MODEL`: the one-scan joint classifier of
// `map kitchen --joints` (drawer, or door hinged at a side, the bottom or the top edge). Both are
// trained on maps of simulated kitchens of one half of the articulated kitchen models with
// procedural units and appliances beside them (docs/kitchens.md).

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "commands.hpp"
#include "default_paths.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/mapping/fixtures.hpp"
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/dataset.hpp"
#include "multicue/sim/kitchen_library.hpp"
#include "multicue/sim/kitchen_procedural.hpp"
#include "multicue/sim/rng.hpp"
#include "multicue/training/kitchen_training.hpp"

namespace multicue::cli {
namespace {

/// What the maps teach: furniture types or one-scan joints.
enum class Target { kContainers, kJoints };

struct TrainOnMapsOptions {
    Target target = Target::kContainers;
    std::string out;
    std::string kitchen = DefaultKitchenDir();
    std::string sensor = "both";
    std::string split = "tune";
    int fold = -1;
    int procedural = 20;
    std::string spec = "rtrees:trees=100";
    std::string kinect_fixtures, laser_fixtures;
    std::string rows;  // also write the labelled pieces (dataset) here
    training::ContainerTrainingOptions t;
    bool quiet = false;
};

void TrainOnMaps(TrainOnMapsOptions& o, int threads) {
    // Everything checked before any kitchen is simulated.
    if (o.sensor != "both" && o.sensor != "kinect" && o.sensor != "laser") {
        throw InvalidArgument(
            fmt::format("--sensor must be both, kinect or laser, got '{}'", o.sensor));
    }
    if (o.sensor == "laser") o.t.views = 0;
    if (o.sensor == "kinect") o.t.laser_views = 0;
    if (o.fold < -1 || o.fold > 1) {
        throw InvalidArgument(fmt::format("--fold must be -1, 0 or 1, got {}", o.fold));
    }
    if (o.procedural < 0 || o.procedural > sim::kMaxProceduralPerKind) {
        throw InvalidArgument(fmt::format("--procedural must lie in [0, {}], got {}",
                                          sim::kMaxProceduralPerKind, o.procedural));
    }
    if (o.kitchen == "none" && o.procedural == 0) {
        throw InvalidArgument("--kitchen none needs --procedural N (N > 0)");
    }
    const sim::MeshSplit split = sim::ParseMeshSplit(o.split);
    o.t.num_threads = threads;
    o.t.Validate();
    ml::CreateClassifier(o.spec);  // throws for a bad spec
    CheckOutputFolder("--out", o.out);
    CheckOutputFolder("--rows", o.rows);
    std::unique_ptr<ml::Classifier> kinect_fixtures, laser_fixtures;
    for (auto [file, classifier] : {std::pair{&o.kinect_fixtures, &kinect_fixtures},
                                    std::pair{&o.laser_fixtures, &laser_fixtures}}) {
        if (file->empty()) continue;
        *classifier = ml::LoadClassifier(*file);
        mapping::CheckFixtureClassifier(**classifier);
    }
    o.t.kinect_fixtures = kinect_fixtures.get();
    o.t.laser_fixtures = laser_fixtures.get();
    // The models: one half of the library (or none), one fold of it, and procedural units of
    // every cupboard and appliance kind.
    std::vector<sim::KitchenModelEntry> models;
    if (o.kitchen != "none") {
        models = sim::SelectKitchenSplit(sim::ReadKitchenLibrary(o.kitchen), split);
        if (o.fold >= 0) models = training::SelectKitchenFold(models, o.fold);
    }
    for (auto& e : sim::ProceduralKitchenEntries(o.procedural, sim::SubSeed(o.t.seed, 96), true)) {
        models.push_back(std::move(e));
    }
    sim::KitchenModelCache cache;
    const bool joints = o.target == Target::kJoints;
    const char* job = joints ? "train joints" : "train containers";
    const ml::Dataset rows = CollectTrainAndSave(
        job, o.t.kitchens,
        [&](Progress* progress) {
            return joints ? training::CollectJointRows(models, cache, o.t, progress)
                          : training::CollectContainerRows(models, cache, o.t, progress);
        },
        [&](const ml::Dataset& r) {
            return joints ? training::TrainJointClassifier(r, o.spec)
                          : training::TrainContainerClassifier(r, o.spec);
        },
        o.out, o.rows);
    if (!o.quiet) {
        const std::vector<std::size_t> per_type = rows.ClassCounts();
        std::string types;
        for (std::size_t c = 0; c < per_type.size(); ++c) {
            types += fmt::format("{}{} {}", c > 0 ? ", " : "", rows.class_names[c], per_type[c]);
        }
        std::printf(
            "multicue %s: %s, %d kitchens of %s, %zu %s (%s) -> %s\n", job, o.sensor.c_str(),
            o.t.kitchens,
            (o.kitchen == "none"
                 ? std::string("procedural units")
                 : (o.fold >= 0 ? fmt::format("fold {} of ", o.fold) : std::string()) + "the " +
                       o.split + " half" + (o.procedural > 0 ? " and procedural units" : ""))
                .c_str(),
            rows.rows(), joints ? "fronts" : "pieces", types.c_str(), o.out.c_str());
    }
}

void AddTrainOnMapsCommand(CLI::App& train_command, const GlobalOptions& global, Target target) {
    const bool joints = target == Target::kJoints;
    auto* cmd = train_command.add_subcommand(
        joints ? "joints" : "containers",
        joints ? "Train the one-scan joint classifier of `map kitchen --joints` (drawer, or door "
                 "hinged at a side, the bottom or the top) on simulated kitchens"
               : "Train the furniture type classifier of `map kitchen --containers` on simulated "
                 "kitchens");
    auto o = std::make_shared<TrainOnMapsOptions>();
    o->target = target;
    AddKitchenTrainingOptions(cmd,
                              {.out = o->out,
                               .library = o->kitchen,
                               .split = o->split,
                               .fold = o->fold,
                               .kitchens = o->t.kitchens,
                               .procedural_share = o->t.procedural_share,
                               .spec = o->spec,
                               .rows = o->rows,
                               .seed = o->t.seed,
                               .quiet = o->quiet},
                              joints ? "fronts" : "pieces");
    cmd->add_option("--sensor", o->sensor,
                    "both, kinect or laser: the scans whose maps the classifier will serve")
        ->capture_default_str();
    cmd->add_option("--views", o->t.views, "Kinect frames per kitchen")->capture_default_str();
    cmd->add_option("--laser-views", o->t.laser_views, "laser sweeps per kitchen")
        ->capture_default_str();
    cmd->add_option("--kinect-fixtures", o->kinect_fixtures,
                    "fixture classifier the Kinect maps use (`train fixtures`); unset: rules");
    cmd->add_option("--laser-fixtures", o->laser_fixtures,
                    "fixture classifier the laser maps use (`train fixtures`); unset: rules");
    cmd->add_option("--procedural", o->procedural,
                    "procedural units per cupboard and appliance kind (dishwasher, oven, fridge) "
                    "added to the models")
        ->capture_default_str();
    cmd->callback([o, &global] { TrainOnMaps(*o, global.threads); });
}

}  // namespace

void AddTrainContainersCommand(CLI::App& train_command, const GlobalOptions& global) {
    AddTrainOnMapsCommand(train_command, global, Target::kContainers);
}

void AddTrainJointsCommand(CLI::App& train_command, const GlobalOptions& global) {
    AddTrainOnMapsCommand(train_command, global, Target::kJoints);
}

}  // namespace multicue::cli
