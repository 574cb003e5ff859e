// `multicue run TASK.yaml`: the perception executive over a sequence of frames, identifying what it
// sees against the object model database and learning from it.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.hpp"
#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/config.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/system/executive.hpp"
#include "multicue/training/part_graph_training.hpp"
#include "task_file.hpp"

namespace multicue::cli {
namespace {

namespace fs = std::filesystem;

nlohmann::ordered_json HypothesisJson(const Hypothesis& h, const ObjectDatabase* db) {
    nlohmann::ordered_json j;
    j["id"] = h.id;
    j["object_id"] = h.object_id;
    if (db != nullptr && h.object_id > 0) {
        if (const auto o = db->GetObject(h.object_id)) j["object"] = o->name;
    }
    j["novel"] = h.novel;
    j["by_position"] = h.by_position;
    j["category"] = h.Category();
    j["categories"] = h.categories;
    nlohmann::ordered_json identities = nlohmann::ordered_json::object();
    for (const auto& [id, p] : h.identities) identities[std::to_string(id)] = p;
    j["identities"] = identities;
    j["position"] = {h.position.x(), h.position.y(), h.position.z()};
    j["extents"] = {h.extents.x(), h.extents.y(), h.extents.z()};
    j["points"] = h.indices.size();
    j["model"] = h.model;
    j["provenance"] = h.provenance;
    return j;
}

}  // namespace

void AddRunCommand(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "run", "run a perception task (enumerate, find, model) over a sequence of frames");
    auto path = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    cmd->add_option("TASK", *path, "task file (.yaml or .json)")->required();
    cmd->add_option("--out", *out, "result JSON (default: the task file's 'output', else stdout)");
    cmd->callback([path, out, &global] {
        TaskFile t = ReadTaskFile(*path);
        ExecutiveParams params;
        if (!t.params.empty()) {
            auto config = io::ConfigSection::Load(t.params);
            ReadPerceiveParams(config, params.perceive);
            config.CheckAllUsed();
        }
        if (global.threads != 0) params.perceive.num_threads = global.threads;
        std::optional<ObjectDatabase> db;
        if (!t.database.empty())
            db = ObjectDatabase::Open(t.database, DatabaseMode::kCreateOrWrite);
        PerceptionExecutive executive(db ? &*db : nullptr, params,
                                      training::LoadPerceiveModels(params.perceive));
        const auto plan = executive.Plan(t.task);

        InstallInterruptHandler();
        Progress progress("run", t.frames.size());
        nlohmann::ordered_json frames = nlohmann::ordered_json::array();
        for (std::size_t i = 0; i < t.frames.size() && !InterruptRequested(); ++i) {
            Frame& frame = t.frames[i];
            frame.cloud = ReadNonEmptyCloud(t.files[i]);
            const FrameReport report = executive.Run(frame, t.task);
            frame.cloud = PointCloud();
            nlohmann::ordered_json jf;
            jf["frame"] = report.frame;
            jf["time"] = report.time;
            jf["methods"] = report.methods;
            jf["learnt_objects"] = report.learnt_objects;
            jf["learnt_views"] = report.learnt_views;
            if (t.task.kind == Task::Kind::kFind) {
                jf["found"] = report.found
                                  ? nlohmann::ordered_json(report.hypotheses[*report.found].id)
                                  : nlohmann::ordered_json(nullptr);
            }
            nlohmann::ordered_json hyps = nlohmann::ordered_json::array();
            for (const auto& h : report.hypotheses)
                hyps.push_back(HypothesisJson(h, db ? &*db : nullptr));
            jf["hypotheses"] = hyps;
            nlohmann::ordered_json timings = nlohmann::ordered_json::object();
            for (const auto& [stage, ms] : report.timings_ms) timings[stage] = ms;
            jf["timings_ms"] = timings;
            frames.push_back(std::move(jf));
            progress.Advance();
        }
        progress.Finish();
        nlohmann::ordered_json result;
        result["task"] = *path;
        result["plan"] = plan;
        result["interrupted"] = InterruptRequested();
        result["frames"] = frames;
        const fs::path target = !out->empty() ? fs::path(*out) : t.output;
        const std::string text = result.dump(1) + "\n";
        if (target.empty()) {
            std::fwrite(text.data(), 1, text.size(), stdout);
        } else {
            io::WriteFileAtomically(target, [&](std::ostream& o) { o << text; });
            std::fprintf(stderr, "run: %zu frames, result in %s\n", frames.size(), target.c_str());
        }
        if (InterruptRequested())
            throw DataError("interrupted; the frames done so far were written");
    });
}

}  // namespace multicue::cli
