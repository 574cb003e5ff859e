// `multicue dataset ...`, `multicue classifier ...` and `multicue ensemble ...`: the dataset
// tools, the classifier manager and the ensembles of sections 3.1.4 and 3.3 as composable
// commands (files in, files out), so experiments are shell scripts over these primitives.

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/ml/dataset_tools.hpp"
#include "multicue/ml/ensemble.hpp"
#include "multicue/ml/evaluation.hpp"
#include "multicue/ml/kmeans.hpp"
#include "multicue/ml/split.hpp"
#include "multicue/ml/transform.hpp"

namespace multicue::cli {
namespace {

using namespace multicue::ml;

std::vector<std::string> SplitList(const std::string& s, char sep = ',') {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, sep)) {
        if (!item.empty()) out.push_back(item);
    }
    return out;
}

std::vector<std::size_t> ParseIndices(const std::string& s, const std::string& option) {
    std::vector<std::size_t> out;
    for (const auto& item : SplitList(s)) {
        try {
            std::size_t n = 0;
            const long v = std::stol(item, &n);
            if (n != item.size() || v < 0) throw std::invalid_argument(item);
            out.push_back(static_cast<std::size_t>(v));
        } catch (const std::exception&) {
            throw InvalidArgument(option + " must be column numbers like 0,3,4, got '" + s + "'");
        }
    }
    return out;
}

std::string WithSuffix(const std::string& prefix, const std::string& suffix,
                       const std::string& ext) {
    return prefix + suffix + "." + ext;
}

void PrintJson(const nlohmann::json& j) { std::printf("%s\n", j.dump(2).c_str()); }

// --- dataset -----------------------------------------------------------------------------------

// `info`
void AddDatasetInfo(CLI::App* ds) {
    auto* cmd = ds->add_subcommand("info", "Rows, columns, feature blocks, classes, instances");
    auto in = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    cmd->add_option("IN", *in, "dataset (.mcd or .csv)")->required();
    cmd->add_flag("--json", *json, "print JSON");
    cmd->callback([in, json] {
        const Dataset d = ReadDatasetFile(*in);
        const std::vector<std::size_t> counts = d.ClassCounts();
        const std::size_t unlabelled =
            static_cast<std::size_t>(std::count(d.labels.begin(), d.labels.end(), kNoLabel));
        const auto keys = GroupKeys(d);
        const std::size_t instances = std::set<std::int64_t>(keys.begin(), keys.end()).size();
        nlohmann::json j = {{"rows", d.rows()},
                            {"columns", d.cols()},
                            {"instances", instances},
                            {"unlabelled", unlabelled}};
        for (const auto& b : d.blocks)
            j["blocks"].push_back({{"name", b.name}, {"columns", b.count}});
        for (std::size_t c = 0; c < d.num_classes(); ++c) {
            j["classes"].push_back({{"name", d.class_names[c]}, {"rows", counts[c]}});
        }
        if (*json) {
            PrintJson(j);
            return;
        }
        std::printf("%s: %zu rows, %zu columns, %zu instances, %zu classes\n", in->c_str(),
                    d.rows(), d.cols(), instances, d.num_classes());
        for (const auto& b : d.blocks)
            std::printf("  block %-16s %zu columns\n", b.name.c_str(), b.count);
        for (std::size_t c = 0; c < d.num_classes(); ++c) {
            std::printf("  class %-24s %zu rows\n", d.class_names[c].c_str(), counts[c]);
        }
    });
}

// `convert`
void AddDatasetConvert(CLI::App* ds) {
    auto* cmd = ds->add_subcommand("convert", "Binary <-> CSV (by extension: .csv or .mcd)");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    cmd->add_option("IN", *in, "input dataset")->required();
    cmd->add_option("OUT", *out, "output dataset")->required();
    cmd->callback([in, out] { WriteDatasetFile(ReadDatasetFile(*in), *out); });
}

// `concat`
void AddDatasetConcat(CLI::App* ds) {
    auto* cmd = ds->add_subcommand(
        "concat", "Concatenate features column-wise (rows joined by row id) or rows (--rows)");
    auto ins = std::make_shared<std::vector<std::string>>();
    auto out = std::make_shared<std::string>();
    auto rows = std::make_shared<bool>(false);
    auto drop = std::make_shared<bool>(false);
    cmd->add_option("IN", *ins, "two or more datasets")->required()->expected(2, -1);
    cmd->add_option("-o,--output", *out, "output dataset")->required();
    cmd->add_flag("--rows", *rows, "append rows instead of columns");
    cmd->add_flag("--drop-unmatched", *drop, "column-wise: drop rows missing in a later input");
    cmd->callback([ins, out, rows, drop] {
        Dataset acc = ReadDatasetFile(ins->front());
        for (std::size_t i = 1; i < ins->size(); ++i) {
            const Dataset next = ReadDatasetFile((*ins)[i]);
            acc = *rows ? ConcatRows(acc, next) : ConcatColumns(acc, next, *drop);
        }
        WriteDatasetFile(acc, *out);
    });
}

// `select`
void AddDatasetSelect(CLI::App* ds) {
    auto* cmd = ds->add_subcommand("select", "Keep or drop feature blocks or columns");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto blocks = std::make_shared<std::string>();
    auto drop_blocks = std::make_shared<std::string>();
    auto columns = std::make_shared<std::string>();
    auto drop_columns = std::make_shared<std::string>();
    cmd->add_option("IN", *in, "input dataset")->required();
    cmd->add_option("-o,--output", *out, "output dataset")->required();
    cmd->add_option("--blocks", *blocks, "blocks to keep, in this order (a,b)");
    cmd->add_option("--drop-blocks", *drop_blocks, "blocks to drop");
    cmd->add_option("--columns", *columns, "column numbers to keep (0,3,4)");
    cmd->add_option("--drop-columns", *drop_columns, "column numbers to drop");
    cmd->callback([=] {
        const int given =
            !blocks->empty() + !drop_blocks->empty() + !columns->empty() + !drop_columns->empty();
        if (given != 1) {
            throw InvalidArgument(
                "give exactly one of --blocks, --drop-blocks, --columns, "
                "--drop-columns");
        }
        const Dataset d = ReadDatasetFile(*in);
        Dataset r;
        if (!blocks->empty()) r = SelectBlocks(d, SplitList(*blocks));
        if (!drop_blocks->empty()) r = DropBlocks(d, SplitList(*drop_blocks));
        if (!columns->empty()) r = SelectColumns(d, ParseIndices(*columns, "--columns"));
        if (!drop_columns->empty())
            r = DropColumns(d, ParseIndices(*drop_columns, "--drop-columns"));
        WriteDatasetFile(r, *out);
    });
}

// `relabel`
void AddDatasetRelabel(CLI::App* ds) {
    auto* cmd = ds->add_subcommand("relabel", "Flatten label hierarchies or rename classes");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto depth = std::make_shared<std::size_t>(0);
    auto maps = std::make_shared<std::vector<std::string>>();
    cmd->add_option("IN", *in, "input dataset")->required();
    cmd->add_option("-o,--output", *out, "output dataset")->required();
    cmd->add_option("--depth", *depth, "keep the first N label path components");
    cmd->add_option("--map", *maps, "old=new (repeatable)");
    cmd->callback([=] {
        if ((*depth == 0) == maps->empty()) throw InvalidArgument("give --depth or --map");
        Dataset d = ReadDatasetFile(*in);
        if (*depth > 0) d = FlattenLabels(d, *depth);
        std::map<std::string, std::string> mapping;
        for (const auto& m : *maps) {
            const auto eq = m.find('=');
            if (eq == std::string::npos || eq == 0) {
                throw InvalidArgument("--map must be old=new, got '" + m + "'");
            }
            mapping[m.substr(0, eq)] = m.substr(eq + 1);
        }
        if (!mapping.empty()) d = Relabel(d, mapping);
        WriteDatasetFile(d, *out);
    });
}

// `split`
void AddDatasetSplit(CLI::App* ds) {
    auto* cmd =
        ds->add_subcommand("split",
                           "Training/test partitions: random, group (whole instances), kfold, logo "
                           "(leave one instance out), three-way (stacking)");
    auto in = std::make_shared<std::string>();
    auto prefix = std::make_shared<std::string>();
    auto method = std::make_shared<std::string>("group");
    auto fraction = std::make_shared<double>(0.25);
    auto k = std::make_shared<std::size_t>(5);
    auto seed = std::make_shared<std::uint32_t>(1);
    auto ext = std::make_shared<std::string>("mcd");
    auto shuffle = std::make_shared<bool>(false);
    cmd->add_option("IN", *in, "input dataset")->required();
    cmd->add_option("-o,--output", *prefix, "output prefix (PREFIX_train.mcd, ...)")->required();
    cmd->add_option("--method", *method, "random, group, kfold, group-kfold, logo, three-way")
        ->capture_default_str();
    cmd->add_option("--test-fraction", *fraction, "random/group: test part")->capture_default_str();
    cmd->add_option("--k", *k, "folds")->capture_default_str();
    cmd->add_option("--seed", *seed, "random seed")->capture_default_str();
    cmd->add_option("--format", *ext, "mcd or csv")->capture_default_str();
    cmd->add_flag("--shuffle", *shuffle,
                  "three-way: shuffle instances with --seed (default: ascending group id)");
    cmd->callback([=] {
        if (*ext != "mcd" && *ext != "csv") throw InvalidArgument("--format must be mcd or csv");
        const Dataset d = ReadDatasetFile(*in);
        auto write = [&](const std::vector<std::size_t>& rows, const std::string& suffix) {
            WriteDatasetFile(SelectRows(d, rows), WithSuffix(*prefix, suffix, *ext));
        };
        std::vector<Split> splits;
        if (*method == "random") {
            splits.push_back(RandomSplit(d, *fraction, *seed));
        } else if (*method == "group") {
            splits.push_back(GroupSplit(d, *fraction, *seed));
        } else if (*method == "kfold" || *method == "group-kfold") {
            splits = KFold(d, *k, *seed, *method == "group-kfold");
        } else if (*method == "logo") {
            splits = LeaveOneGroupOut(d);
        } else if (*method == "three-way") {
            const auto t = SplitThreeWay(d, *shuffle ? std::max<std::uint32_t>(*seed, 1) : 0);
            write(t.level0_train, "_level0");
            write(t.level1_train, "_level1");
            write(t.test, "_test");
            return;
        } else {
            throw InvalidArgument("unknown --method '" + *method + "'");
        }
        if (splits.size() == 1) {
            write(splits[0].train, "_train");
            write(splits[0].test, "_test");
            return;
        }
        for (std::size_t i = 0; i < splits.size(); ++i) {
            write(splits[i].train, fmt::format("_fold{}_train", i));
            write(splits[i].test, fmt::format("_fold{}_test", i));
        }
    });
}

// `normalise`
void AddDatasetNormalise(CLI::App* ds) {
    auto* cmd =
        ds->add_subcommand("normalise",
                           "Min-max or z-score scaling fitted on this (training) dataset and saved "
                           "(--save), or a saved one applied (--apply)");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto method = std::make_shared<std::string>("minmax");
    auto save = std::make_shared<std::string>();
    auto apply = std::make_shared<std::string>();
    cmd->add_option("IN", *in, "input dataset")->required();
    cmd->add_option("-o,--output", *out, "output dataset")->required();
    cmd->add_option("--method", *method, "minmax or zscore")->capture_default_str();
    cmd->add_option("--save", *save, "write the fitted transform (.mcx)");
    cmd->add_option("--apply", *apply, "apply a saved transform instead of fitting");
    cmd->callback([=] {
        const Dataset d = ReadDatasetFile(*in);
        FeatureTransform t;
        if (!apply->empty()) {
            t = LoadTransform(*apply);
        } else if (*method == "minmax") {
            t = FitMinMax(d);
        } else if (*method == "zscore") {
            t = FitZScore(d);
        } else {
            throw InvalidArgument("--method must be minmax or zscore, got '" + *method + "'");
        }
        if (!save->empty()) SaveTransform(t, *save);
        WriteDatasetFile(t.Apply(d), *out);
    });
}

// `pca`
void AddDatasetPca(CLI::App* ds) {
    auto* cmd = ds->add_subcommand("pca", "PCA (optionally whitened) fitted here or applied");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto params = std::make_shared<PcaParams>();
    auto save = std::make_shared<std::string>();
    auto apply = std::make_shared<std::string>();
    cmd->add_option("IN", *in, "input dataset")->required();
    cmd->add_option("-o,--output", *out, "output dataset")->required();
    cmd->add_option("--components", params->components, "0 = by --variance")->capture_default_str();
    cmd->add_option("--variance", params->variance, "kept variance fraction")
        ->capture_default_str();
    cmd->add_flag("--whiten", params->whiten, "unit variance per component");
    cmd->add_option("--save", *save, "write the fitted transform (.mcx)");
    cmd->add_option("--apply", *apply, "apply a saved transform instead of fitting");
    cmd->callback([=] {
        const Dataset d = ReadDatasetFile(*in);
        const FeatureTransform t = apply->empty() ? FitPca(d, *params) : LoadTransform(*apply);
        if (!save->empty()) SaveTransform(t, *save);
        WriteDatasetFile(t.Apply(d), *out);
    });
}

// `bow`
void AddDatasetBow(CLI::App* ds, const GlobalOptions& global) {
    auto* cmd = ds->add_subcommand(
        "bow", "Bag of words from local features: rows grouped by (source, group, view)");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto params = std::make_shared<KMeansParams>();
    auto codebook = std::make_shared<std::string>();
    auto save = std::make_shared<std::string>();
    auto block = std::make_shared<std::string>("bow");
    cmd->add_option("IN", *in, "local features dataset")->required();
    cmd->add_option("-o,--output", *out, "output dataset (one row per bag)")->required();
    cmd->add_option("--words", params->k, "codebook size (k-means k)")->capture_default_str();
    cmd->add_option("--seed", params->seed, "k-means++ seed")->capture_default_str();
    cmd->add_option("--codebook", *codebook, "use this codebook (.mcd) instead of k-means");
    cmd->add_option("--save-codebook", *save, "write the learnt codebook (.mcd)");
    cmd->add_option("--block", *block, "name of the output block")->capture_default_str();
    cmd->callback([=, &global] {
        const Dataset local = ReadDatasetFile(*in);
        FeatureMatrix words;
        if (!codebook->empty()) {
            words = ReadDatasetFile(*codebook).features();
        } else {
            local.CheckFinite(*in);
            KMeansParams p = *params;
            p.num_threads = global.threads;
            words = KMeans(local.features(), p).centers;
        }
        if (!save->empty()) WriteDatasetFile(CodebookToDataset(words, local.feature_names), *save);
        WriteDatasetFile(BagOfWords(local, words, *block, global.threads), *out);
    });
}

void AddDatasetCommands(CLI::App& app, const GlobalOptions& global) {
    auto* ds = app.add_subcommand("dataset",
                                  "Dataset tools: extract, info, convert, concat, select, "
                                  "relabel, split, normalise, pca, bow");
    ds->require_subcommand(1);

    AddDatasetInfo(ds);
    AddDatasetConvert(ds);
    AddDatasetConcat(ds);
    AddDatasetSelect(ds);
    AddDatasetRelabel(ds);
    AddDatasetSplit(ds);
    AddDatasetNormalise(ds);
    AddDatasetPca(ds);
    AddDatasetBow(ds, global);
}

// --- classifier --------------------------------------------------------------------------------

Dataset MaybeBlocks(const Dataset& d, const std::string& blocks) {
    return blocks.empty() ? d : SelectBlocks(d, SplitList(blocks));
}

nlohmann::json ConfusionJson(const ConfusionMatrix& m) {
    nlohmann::json j = {{"accuracy", m.Accuracy()},
                        {"error_rate", m.ErrorRate()},
                        {"rows", m.total()},
                        {"classes", m.class_names}};
    for (Eigen::Index r = 0; r < m.counts.rows(); ++r) {
        std::vector<int> copy;
        for (Eigen::Index c = 0; c < m.counts.cols(); ++c) copy.push_back(m.counts(r, c));
        j["confusion"].push_back(copy);
    }
    return j;
}

// `train`
void AddClassifierTrain(CLI::App* cl) {
    auto* cmd = cl->add_subcommand("train", "Train a classifier and save it");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto spec = std::make_shared<std::string>("knn:k=5");
    auto blocks = std::make_shared<std::string>();
    cmd->add_option("TRAIN", *in, "training dataset")->required();
    cmd->add_option("-o,--output", *out, "model file (.mcm)")->required();
    cmd->add_option("--spec", *spec,
                    "classifier spec, e.g. knn:k=5,metric=hellinger | svm:kernel=rbf,grid=1 | "
                    "boost:type=real,weak=100 | mlp:hidden=32 | rtrees:trees=100")
        ->capture_default_str();
    cmd->add_option("--blocks", *blocks, "train on these feature blocks only");
    cmd->callback([=] {
        auto c = CreateClassifier(*spec);
        const Dataset d = MaybeBlocks(ReadDatasetFile(*in), *blocks);
        Progress progress("training " + c->type(), c->FitSteps(d.num_classes()));
        c->Fit(d, &progress);
        progress.Finish();
        c->Save(*out);
    });
}

// `predict`
void AddClassifierPredict(CLI::App* cl) {
    auto* cmd = cl->add_subcommand("predict",
                                   "Per-class confidences of a model as a dataset (for stacking)");
    auto model = std::make_shared<std::string>();
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto blocks = std::make_shared<std::string>();
    auto block = std::make_shared<std::string>("confidence");
    cmd->add_option("MODEL", *model, "model file")->required();
    cmd->add_option("DATA", *in, "dataset")->required();
    cmd->add_option("-o,--output", *out, "confidences dataset")->required();
    cmd->add_option("--blocks", *blocks, "feature blocks the model was trained on");
    cmd->add_option("--block", *block, "name of the output block")->capture_default_str();
    cmd->callback([=] {
        const auto c = LoadClassifier(*model);
        const Dataset d = MaybeBlocks(ReadDatasetFile(*in), *blocks);
        WriteDatasetFile(ConfidencesToDataset(c->PredictProba(d), c->class_names(), d, *block),
                         *out);
    });
}

// `eval`
void AddClassifierEval(CLI::App* cl) {
    auto* cmd = cl->add_subcommand("eval", "Accuracy, confusion matrix and timing on a test set");
    auto model = std::make_shared<std::string>();
    auto in = std::make_shared<std::string>();
    auto blocks = std::make_shared<std::string>();
    auto image = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    cmd->add_option("MODEL", *model, "model file")->required();
    cmd->add_option("TEST", *in, "labelled test dataset")->required();
    cmd->add_option("--blocks", *blocks, "feature blocks the model was trained on");
    cmd->add_option("--confusion-image", *image, "write the confusion matrix as PPM");
    cmd->add_flag("--json", *json, "print JSON");
    cmd->callback([=] {
        const auto c = LoadClassifier(*model);
        const auto r = Evaluate(*c, MaybeBlocks(ReadDatasetFile(*in), *blocks));
        if (!image->empty()) r.confusion.WriteImage(*image);
        if (*json) {
            auto j = ConfusionJson(r.confusion);
            j["predict_ms_per_row"] = r.predict_ms_per_row;
            PrintJson(j);
        } else {
            std::printf("%s%.4f ms per row\n", r.confusion.ToText().c_str(), r.predict_ms_per_row);
        }
    });
}

// `cv`
void AddClassifierCv(CLI::App* cl) {
    auto* cmd = cl->add_subcommand("cv", "k-fold cross-validation of a classifier spec");
    auto in = std::make_shared<std::string>();
    auto spec = std::make_shared<std::string>("knn:k=5");
    auto k = std::make_shared<std::size_t>(5);
    auto seed = std::make_shared<std::uint32_t>(1);
    auto by_group = std::make_shared<bool>(false);
    auto json = std::make_shared<bool>(false);
    cmd->add_option("DATA", *in, "labelled dataset")->required();
    cmd->add_option("--spec", *spec, "classifier spec")->capture_default_str();
    cmd->add_option("--k", *k, "folds")->capture_default_str();
    cmd->add_option("--seed", *seed, "fold seed")->capture_default_str();
    cmd->add_flag("--by-group", *by_group, "keep each instance inside one fold");
    cmd->add_flag("--json", *json, "print JSON");
    cmd->callback([=] {
        const Dataset d = ReadDatasetFile(*in);
        Progress progress("cross-validation", *k);
        const auto r = CrossValidate(*spec, d, *k, *seed, *by_group, &progress);
        progress.Finish();
        auto j = ConfusionJson(r.confusion);
        j["fold_accuracy"] = r.fold_accuracy;
        j["mean_accuracy"] = r.mean_accuracy;
        j["stddev_accuracy"] = r.stddev_accuracy;
        j["train_seconds"] = r.train_seconds;
        j["predict_seconds"] = r.predict_seconds;
        if (*json) {
            PrintJson(j);
        } else {
            std::printf("%s%zu-fold accuracy %.4f +- %.4f, training %.3f s, prediction %.3f s\n",
                        r.confusion.ToText().c_str(), *k, r.mean_accuracy, r.stddev_accuracy,
                        r.train_seconds, r.predict_seconds);
        }
    });
}

void AddClassifierCommands(CLI::App& app, const GlobalOptions&) {
    auto* cl = app.add_subcommand("classifier",
                                  "Train, apply and evaluate classifiers "
                                  "(knn, svm, boost, mlp, rtrees)");
    cl->require_subcommand(1);
    AddClassifierTrain(cl);
    AddClassifierPredict(cl);
    AddClassifierEval(cl);
    AddClassifierCv(cl);
}

// --- ensemble ----------------------------------------------------------------------------------

// `train`
void AddEnsembleTrain(CLI::App* en) {
    auto* cmd =
        en->add_subcommand("train",
                           "Members on LEVEL0, statistics and the level-1 classifier on LEVEL1 "
                           "(three-way split: dataset split --method three-way)");
    auto l0 = std::make_shared<std::string>();
    auto l1 = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto params = std::make_shared<EnsembleParams>();
    auto subsets = std::make_shared<std::string>("singles");
    auto rule = std::make_shared<std::string>();
    cmd->add_option("LEVEL0", *l0, "level-0 training dataset")->required();
    cmd->add_option("LEVEL1", *l1, "level-1 training dataset (disjoint rows)")->required();
    cmd->add_option("-o,--output", *out, "ensemble file (.mce)")->required();
    cmd->add_option("--member", params->member_spec, "classifier spec of every member")
        ->capture_default_str();
    cmd->add_option("--subsets", *subsets,
                    "singles, doubles, triples, singles+doubles, all, or blocks 'a+b,c'")
        ->capture_default_str();
    cmd->add_option("--level1", params->level1_spec, "stacking's level-1 classifier spec");
    cmd->add_option("--rule", *rule, "default rule stored in the file");
    cmd->add_option("--seed", params->seed, "seed of every member")->capture_default_str();
    cmd->callback([=] {
        const Dataset d0 = ReadDatasetFile(*l0);
        const Dataset d1 = ReadDatasetFile(*l1);
        const auto names = d0.BlockNames();
        const std::map<std::string, std::pair<std::size_t, std::size_t>> sizes = {
            {"singles", {1, 1}},
            {"doubles", {2, 2}},
            {"triples", {3, 3}},
            {"singles+doubles", {1, 2}},
            {"all", {1, names.size()}}};
        EnsembleParams p = *params;
        if (const auto it = sizes.find(*subsets); it != sizes.end()) {
            p.subsets = FeatureSubsets(names, it->second.first, it->second.second);
        } else {
            for (const auto& s : SplitList(*subsets)) p.subsets.push_back(SplitList(s, '+'));
        }
        if (p.subsets.empty()) throw InvalidArgument("--subsets selects no block subset");
        Progress progress("training ensemble", p.subsets.size() + 1);
        Ensemble e = TrainEnsemble(d0, d1, p, &progress);
        progress.Finish();
        if (!rule->empty()) e.rule = ParseEnsembleRule(*rule);
        if (e.rule == EnsembleRule::kStacking && !e.level1) {
            throw InvalidArgument("--rule stacking needs --level1");
        }
        e.Save(*out);
    });
}

// `eval`
void AddEnsembleEval(CLI::App* en) {
    auto* cmd = en->add_subcommand("eval", "Error rate of each rule and of each member");
    auto model = std::make_shared<std::string>();
    auto in = std::make_shared<std::string>();
    auto rule = std::make_shared<std::string>("all");
    auto image = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    cmd->add_option("ENSEMBLE", *model, "ensemble file")->required();
    cmd->add_option("TEST", *in, "labelled test dataset")->required();
    cmd->add_option("--rule", *rule, "a rule name, 'stored' or 'all'")->capture_default_str();
    cmd->add_option("--confusion-image", *image, "PPM of the (single) rule's confusion");
    cmd->add_flag("--json", *json, "print JSON");
    cmd->callback([=] {
        const Ensemble e = Ensemble::Load(*model);
        const Dataset test = ReadDatasetFile(*in);
        const auto truth = MapLabels(test, e.class_names);
        std::vector<EnsembleRule> rules;
        if (*rule == "all") {
            rules = SimpleRules();
            if (e.level1) rules.push_back(EnsembleRule::kStacking);
        } else {
            rules.push_back(*rule == "stored" ? e.rule : ParseEnsembleRule(*rule));
        }
        nlohmann::json j;
        const auto conf = e.MemberConfidences(test);
        for (std::size_t i = 0; i < e.members.size(); ++i) {
            const double err = 1.0 - Accuracy(truth, ArgMaxRows(conf[i]));
            j["members"].push_back({{"name", e.members[i].name}, {"error_rate", err}});
        }
        for (auto r : rules) {
            const auto predicted = ArgMaxRows(
                r == EnsembleRule::kStacking ? e.PredictProba(test, r)
                                             : CombineConfidences(r, conf, e.stats, e.weights));
            const auto m = Confusion(truth, predicted, e.class_names);
            j["rules"].push_back({{"rule", ToString(r)}, {"error_rate", m.ErrorRate()}});
            if (!image->empty() && rules.size() == 1) m.WriteImage(*image);
        }
        if (*json) {
            PrintJson(j);
            return;
        }
        for (const auto& m : j["members"]) {
            std::printf("member %-32s error rate %.4f\n", m["name"].get<std::string>().c_str(),
                        m["error_rate"].get<double>());
        }
        for (const auto& r : j["rules"]) {
            std::printf("rule   %-32s error rate %.4f\n", r["rule"].get<std::string>().c_str(),
                        r["error_rate"].get<double>());
        }
    });
}

void AddEnsembleCommands(CLI::App& app, const GlobalOptions&) {
    auto* en = app.add_subcommand("ensemble",
                                  "Ensembles of classifiers on feature-block subsets "
                                  "(max rules, product, voting, error correlation, "
                                  "stacking)");
    en->require_subcommand(1);
    AddEnsembleTrain(en);
    AddEnsembleEval(en);
}

}  // namespace

void AddMlCommands(CLI::App& app, const GlobalOptions& global) {
    AddDatasetCommands(app, global);
    AddClassifierCommands(app, global);
    AddEnsembleCommands(app, global);
}

}  // namespace multicue::cli
