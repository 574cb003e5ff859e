// `multicue train fixtures --out MODEL`: the fixture classifier of `map kitchen --fixtures`
// (thesis section 4.1.2: handles and knobs), trained on simulated kitchens of one half of the
// articulated kitchen models scanned by one sensor (docs/kitchens.md).

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
#include "multicue/ml/classifier.hpp"
#include "multicue/ml/dataset.hpp"
#include "multicue/sim/kitchen_library.hpp"
#include "multicue/training/kitchen_training.hpp"

namespace multicue::cli {
namespace {

struct TrainFixturesOptions {
    std::string out;
    std::string kitchen = DefaultKitchenDir();
    std::string sensor = "kinect";
    std::string split = "tune";
    std::string spec = "rtrees:trees=100";
    int views = 0;     // 0: 3 Kinect frames or 1 laser sweep per kitchen
    std::string rows;  // also write the candidate rows (dataset) here
    training::FixtureTrainingOptions t;
    std::vector<float> lengths = {t.handle_variation.min_length, t.handle_variation.max_length};
    std::vector<float> reach = {t.handle_variation.min_reach_scale,
                                t.handle_variation.max_reach_scale};
    std::vector<float> thickness = {t.handle_variation.min_thickness_scale,
                                    t.handle_variation.max_thickness_scale};
    bool quiet = false;
};

void TrainFixtures(TrainFixturesOptions& o, int threads) {
    // Everything checked before any kitchen is simulated.
    if (o.sensor != "kinect" && o.sensor != "laser") {
        throw InvalidArgument(fmt::format("--sensor must be kinect or laser, got '{}'", o.sensor));
    }
    if (o.views < 0) throw InvalidArgument(fmt::format("--views must be >= 1, got {}", o.views));
    const bool laser = o.sensor == "laser";
    o.t.sensor = laser ? mapping::KitchenSensor::kLaser : mapping::KitchenSensor::kKinect;
    o.t.split = sim::ParseMeshSplit(o.split);
    o.t.views = o.views > 0 ? o.views : laser ? 1 : 3;
    o.t.num_threads = threads;
    for (const auto& [name, range] :
         {std::pair{"--handle-lengths", &o.lengths}, std::pair{"--handle-reach", &o.reach},
          std::pair{"--handle-thickness", &o.thickness}}) {
        if (range->size() != 2) {
            throw InvalidArgument(
                fmt::format("{} needs MIN,MAX, got {} values", name, range->size()));
        }
    }
    o.t.handle_variation.min_length = o.lengths[0];
    o.t.handle_variation.max_length = o.lengths[1];
    o.t.handle_variation.min_reach_scale = o.reach[0];
    o.t.handle_variation.max_reach_scale = o.reach[1];
    o.t.handle_variation.min_thickness_scale = o.thickness[0];
    o.t.handle_variation.max_thickness_scale = o.thickness[1];
    o.t.Validate();
    if (o.kitchen == "none" && o.t.procedural == 0) {
        throw InvalidArgument("--kitchen none needs --procedural N (N > 0)");
    }
    ml::CreateClassifier(o.spec);  // throws for a bad spec
    CheckOutputFolder("--out", o.out);
    CheckOutputFolder("--rows", o.rows);
    // "none": training kitchens of procedural units only.
    const auto library = o.kitchen == "none" ? std::vector<sim::KitchenModelEntry>{}
                                             : sim::ReadKitchenLibrary(o.kitchen);
    sim::KitchenModelCache cache;
    const ml::Dataset rows = CollectTrainAndSave(
        "train fixtures", o.t.kitchens,
        [&](Progress* progress) {
            return training::CollectFixtureRows(library, cache, o.t, progress);
        },
        [&](const ml::Dataset& r) { return training::TrainFixtureClassifier(r, o.spec); }, o.out,
        o.rows);
    if (!o.quiet) {
        std::size_t fixtures = 0;
        for (const int l : rows.labels) fixtures += l > 0;
        std::printf(
            "multicue train fixtures: %s, %d kitchens of %s, %zu candidates (%zu handles and "
            "knobs) -> %s\n",
            o.sensor.c_str(), o.t.kitchens,
            (o.kitchen == "none"
                 ? std::string("procedural units")
                 : "the " + o.split + " half" + (o.t.procedural > 0 ? " and procedural units" : ""))
                .c_str(),
            rows.rows(), fixtures, o.out.c_str());
    }
}

}  // namespace

void AddTrainFixturesCommand(CLI::App& train_command, const GlobalOptions& global) {
    auto* cmd = train_command.add_subcommand(
        "fixtures",
        "Train the handle and knob classifier of `map kitchen --fixtures` on simulated kitchens "
        "of one sensor");
    auto o = std::make_shared<TrainFixturesOptions>();
    AddKitchenTrainingOptions(cmd,
                              {.out = o->out,
                               .library = o->kitchen,
                               .split = o->split,
                               .fold = o->t.fold,
                               .kitchens = o->t.kitchens,
                               .procedural_share = o->t.procedural_share,
                               .spec = o->spec,
                               .rows = o->rows,
                               .seed = o->t.seed,
                               .quiet = o->quiet},
                              "candidate rows");
    cmd->add_option("--sensor", o->sensor, "kinect or laser: the scans the classifier will see")
        ->capture_default_str();
    cmd->add_option("--views", o->views,
                    "scans per kitchen (default: 3 Kinect frames or 1 laser sweep)");
    cmd->add_flag("--vary-handles,!--no-vary-handles", o->t.vary_handles,
                  "vary the training kitchens' handles: length, reach and thickness "
                  "(sim::VaryHandles; on by default)");
    cmd->add_option("--handle-lengths", o->lengths,
                    "MIN,MAX: range of the varied handle lengths with --vary-handles [m]")
        ->delimiter(',')
        ->capture_default_str();
    cmd->add_option("--handle-reach", o->reach,
                    "MIN,MAX: scale of a varied handle's reach out of its front with "
                    "--vary-handles")
        ->delimiter(',')
        ->capture_default_str();
    cmd->add_option("--handle-thickness", o->thickness,
                    "MIN,MAX: scale of a varied handle's thickness with --vary-handles")
        ->delimiter(',')
        ->capture_default_str();
    cmd->add_option("--procedural", o->t.procedural,
                    "procedural units of random designs per cupboard kind added to the "
                    "training kitchens' models")
        ->capture_default_str();
    cmd->callback([o, &global] { TrainFixtures(*o, global.threads); });
}

}  // namespace multicue::cli
