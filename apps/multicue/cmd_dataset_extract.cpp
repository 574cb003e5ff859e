// `multicue dataset extract`: the feature extraction tool of section 3.1.4. Point clouds of a
// simulator manifest or of a labelled directory tree in, one dataset row per object (or file) out,
// one block per feature type. Resumable and interruptible; the output is written atomically.

#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/recognition/dataset_extraction.hpp"

namespace multicue::cli {
namespace {

struct ExtractOptions {
    std::string features = "vfh,grsd-minus,part-stats,colour";
    std::string manifest;
    std::string tree;
    std::string out;
    bool resume = false;
    bool per_cluster = false;
    float voxel = 0.005f;
    float normal_radius = 0.015f;
    float radius = 0.03f;
    std::size_t min_points = 30;
    std::size_t save_every = 20;
    bool quiet = false;
};

std::vector<std::string> SplitNames(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) {
        if (!item.empty()) out.push_back(item);
    }
    return out;
}

}  // namespace

void AddDatasetExtractCommand(CLI::App& app, const GlobalOptions& global) {
    CLI::App* ds = app.get_subcommand("dataset");
    auto* cmd = ds->add_subcommand(
        "extract", "Feature dataset from a simulator manifest or a labelled folder of clouds");
    auto o = std::make_shared<ExtractOptions>();
    cmd->add_option("--features", o->features,
                    "comma-separated: rsd, grsd, grsd-minus, vfh, pfh, fpfh, pfhrgb, part-stats, "
                    "colour")
        ->capture_default_str();
    auto* manifest = cmd->add_option("--manifest", o->manifest,
                                     "manifest.json of `multicue simulate`: one row per object "
                                     "per frame");
    auto* tree = cmd->add_option("--tree", o->tree,
                                 "folder of .pcd/.ply files; the folders below it are the label");
    manifest->excludes(tree);
    tree->excludes(manifest);
    cmd->add_option("-o,--out", o->out, "output dataset (.mcd or .csv)")->required();
    cmd->add_flag("--resume", o->resume, "keep the rows in --out and skip their files");
    cmd->add_flag("--per-cluster", o->per_cluster,
                  "--tree: one row per label value of each file instead of one per file");
    cmd->add_option("--voxel", o->voxel, "voxel grid before the features [m]; 0 = none")
        ->capture_default_str();
    cmd->add_option("--normal-radius", o->normal_radius, "normal estimation radius [m]")
        ->capture_default_str();
    cmd->add_option("--radius", o->radius, "radius of the pair histograms (pfh, fpfh) [m]")
        ->capture_default_str();
    cmd->add_option("--min-points", o->min_points, "smaller clusters are skipped")
        ->capture_default_str();
    cmd->add_option("--save-every", o->save_every, "files between saves of the partial output")
        ->capture_default_str();
    cmd->add_flag("-q,--quiet", o->quiet, "no progress and no summary");
    cmd->callback([o, &global] {
        if (o->manifest.empty() == o->tree.empty()) {
            throw InvalidArgument("dataset extract: give exactly one of --manifest or --tree");
        }
        DatasetExtractionParams params;
        params.features = SplitNames(o->features);
        EmptyFeatureDataset(params.features);  // validates the names first
        params.voxel_size = o->voxel;
        params.normal_radius = o->normal_radius;
        params.feature_params.radius = o->radius;
        params.feature_params.num_threads = global.threads;
        params.min_points = o->min_points;
        params.save_every = o->save_every;
        params.resume = o->resume;
        if (!(o->radius > 0.0f)) throw InvalidArgument("--radius must be > 0");
        const auto inputs =
            o->manifest.empty() ? TreeInputs(o->tree, o->per_cluster) : ManifestInputs(o->manifest);
        InstallInterruptHandler();
        Progress progress("extract", inputs.size(),
                          o->quiet ? ProgressStyle::kSilent : ProgressStyle::kAuto);
        const DatasetExtractionSummary s = ExtractDataset(inputs, o->out, params, progress);
        progress.Finish();
        if (s.interrupted) {
            throw Error(
                fmt::format("interrupted after {} of {} files; {} holds {} rows, continue "
                            "with --resume",
                            s.files_done + s.files_resumed, s.files, o->out, s.rows));
        }
        if (!o->quiet) {
            std::printf(
                "multicue dataset extract: %zu files (%zu resumed), %zu rows added, %zu rows in "
                "%s; %zu clusters too small, %zu with non-finite features\n",
                s.files, s.files_resumed, s.rows_added, s.rows, o->out.c_str(), s.small_clusters,
                s.bad_features);
        }
    });
}

}  // namespace multicue::cli
