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
#include "multicue/system/executive_json.hpp"
#include "multicue/training/part_graph_training.hpp"
#include "task_file.hpp"

namespace multicue::cli {
namespace fs = std::filesystem;

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
            nlohmann::ordered_json jf = FrameReportJson(report, t.task, db ? &*db : nullptr);
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
