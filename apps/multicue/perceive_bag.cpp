#include "perceive_bag.hpp"

#include <chrono>
#include <cstdio>
#include <optional>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/point_cloud2.hpp"
#include "multicue/io/ros_messages.hpp"
#include "multicue/system/perceive_output.hpp"
#include "multicue/system/report_writer.hpp"
#ifdef MULTICUE_HAVE_ROS1_BAG
#include "multicue/io/ros1_bag.hpp"
#endif

namespace multicue::cli {
namespace {

namespace fs = std::filesystem;

/// The folder name of a message: its header stamp, else its recording time; "_2", "_3", ...
/// for repeated stamps.
std::string MessageFolder(const io::MessageStamp& stamp, std::int64_t log_time_ns,
                          std::set<std::string>& used) {
    const io::MessageStamp s =
        stamp.Nanoseconds() != 0 ? stamp : io::MessageStamp::FromNanoseconds(log_time_ns);
    std::string name = s.ToString();
    for (int k = 2; used.count(name) != 0; ++k) name = fmt::format("{}_{}", s.ToString(), k);
    used.insert(name);
    return name;
}

}  // namespace

std::unique_ptr<io::BagReader> OpenBag(const fs::path& path,
                                       const std::vector<std::string>& topics) {
    if (io::LowerExtension(path) == "bag") {
#ifdef MULTICUE_HAVE_ROS1_BAG
        return io::OpenRos1Bag(path, topics);
#else
        throw IoError(fmt::format(
            "{}: this build reads no ROS 1 bags (install librosbag-dev with scripts/setup.sh, "
            "then configure and build again)",
            path.string()));
#endif
    }
    if (io::IsRos2BagPath(path)) return io::OpenRos2Bag(path, topics);
    std::error_code ec;
    if (!fs::exists(path, ec)) throw IoError(fmt::format("{}: no such file", path.string()));
    throw IoError(fmt::format("{}: not a bag (expected .bag, .db3, .mcap or a ROS 2 bag folder)",
                              path.string()));
}

namespace {

/// The pipeline and what it needs, shared by every message of a run.
struct BagRun {
    const PerceiveBagOptions& options;
    const PerceiveParams& pipeline;
    const ReportParams& report;
    const PerceiveModels& models;
    const io::BagTopic& topic;
    std::set<std::string> used_folders;
    ReportWriter* reports = nullptr;  ///< writes the pages off the stream's path; none: no pages
};

/// Perceives one message into OUT/<stamp>/; its index.json entry, with "skipped" and the reason
/// when the message cannot be read.
nlohmann::ordered_json PerceiveMessage(BagRun& run, const io::BagMessage& message,
                                       std::size_t index) {
    const std::string bag_name = run.options.bag.string();
    const std::string source =
        fmt::format("{} message {} on {}", bag_name, index, run.options.topic);
    nlohmann::ordered_json entry;
    entry["index"] = index;
    entry["log_time_ns"] = message.log_time_ns;
    try {
        const auto start = std::chrono::steady_clock::now();
        const io::PointCloud2Message msg = io::DecodePointCloud2(run.topic, message.data, source);
        PointCloud cloud = io::FromPointCloud2(msg, source);
        if (cloud.CountFinite() == 0) {
            throw DataError(fmt::format("{}: no finite point among {}", source, cloud.size()));
        }
        const double load_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        const std::string folder = MessageFolder(msg.stamp, message.log_time_ns, run.used_folders);
        entry["stamp"] = msg.stamp.ToString();
        entry["frame_id"] = msg.frame_id;
        entry["folder"] = folder;
        PerceiveResult result = Perceive(cloud, run.pipeline, run.models);
        auto out = PerceiveResultJson(source, result, {{"load", load_ms}});
        out["message"] = {{"bag", bag_name},          {"topic", run.options.topic},
                          {"index", index},           {"stamp", msg.stamp.ToString()},
                          {"frame_id", msg.frame_id}, {"log_time_ns", message.log_time_ns}};
        const fs::path dir = run.options.out / folder;
        if (run.reports != nullptr) RemoveStaleReport(dir);
        WritePerceiveOutputs(dir, out, PerceiveLabelsCloud(cloud, result),
                             PerceiveModelsMesh(result));
        entry["objects"] = result.objects.size();
        if (run.reports != nullptr)
            run.reports->Submit(dir, std::move(cloud), std::move(result), std::move(out));
    } catch (const FormatError& e) {
        entry["skipped"] = e.what();
    } catch (const DataError& e) {
        entry["skipped"] = e.what();
    }
    if (entry.contains("skipped")) LogWarning("skipping: {}", entry["skipped"].get<std::string>());
    return entry;
}

}  // namespace

void RunPerceiveBag(const PerceiveBagOptions& options, const PerceiveParams& pipeline,
                    const ReportParams& report, const PerceiveModels& models) {
    if (options.topic.empty()) throw InvalidArgument("perceive: --bag needs --topic");
    auto bag = OpenBag(options.bag, {options.topic});
    const std::string bag_name = options.bag.string();
    const io::BagTopic* topic = bag->FindTopic(options.topic);
    if (topic == nullptr) {
        throw InvalidArgument(fmt::format("{}: no topic {}; the bag has {}", bag_name,
                                          options.topic, bag->DescribeTopics()));
    }
    if (!io::IsPointCloud2Type(topic->type)) {
        throw FormatError(fmt::format("{}: topic {} carries {}, not sensor_msgs PointCloud2",
                                      bag_name, topic->name, topic->type));
    }
    fs::create_directories(options.out);

    std::uint64_t total = topic->messages;
    if (options.max_messages > 0 && (total == 0 || total > options.max_messages))
        total = options.max_messages;
    InstallInterruptHandler();
    Progress progress("perceive", total,
                      options.quiet ? ProgressStyle::kSilent : ProgressStyle::kAuto);
    nlohmann::ordered_json index;
    index["format"] = "multicue.bag_index/1";
    index["bag"] = bag_name;
    index["topic"] = options.topic;
    index["type"] = topic->type;
    index["messages"] = nlohmann::ordered_json::array();
    std::size_t perceived = 0, skipped = 0, seen = 0;
    std::string first_problem;
    const auto write_index = [&](bool complete) {
        index["perceived"] = perceived;
        index["skipped"] = skipped;
        index["complete"] = complete;
        const std::string text = index.dump(1) + "\n";
        io::WriteFileAtomically(options.out / "index.json", [&](std::ostream& o) { o << text; });
    };

    // The pages are written by a thread of their own while the next messages are perceived.
    std::optional<ReportWriter> reports;
    if (report.enabled) reports.emplace(report);
    BagRun run{options, pipeline, report, models, *topic, {}, reports ? &*reports : nullptr};
    io::BagMessage message;
    try {
        while (!InterruptRequested() &&
               (options.max_messages == 0 || seen < options.max_messages) && bag->Next(message)) {
            auto entry = PerceiveMessage(run, message, seen++);
            if (entry.contains("skipped")) {
                if (first_problem.empty()) first_problem = entry["skipped"].get<std::string>();
                ++skipped;
            } else {
                ++perceived;
                if (!options.quiet && progress.total() == 0) {
                    std::printf("%s: %zu objects -> %s\n",
                                entry["stamp"].get<std::string>().c_str(),
                                entry["objects"].get<std::size_t>(),
                                (options.out / entry["folder"].get<std::string>()).c_str());
                }
            }
            index["messages"].push_back(std::move(entry));
            write_index(false);
            progress.Advance();
        }
    } catch (const FormatError&) {
        // A truncated or corrupt bag: what was perceived stays, the index says where it ended.
        write_index(false);
        throw;
    }
    progress.Finish();
    if (reports) reports->Finish();
    write_index(!InterruptRequested());
    if (!options.quiet) {
        std::printf(
            "%s %s: %zu messages perceived, %zu skipped; outputs in %s/<stamp>/, index in "
            "%s\n",
            bag_name.c_str(), options.topic.c_str(), perceived, skipped, options.out.c_str(),
            (options.out / "index.json").c_str());
    }
    if (InterruptRequested()) {
        throw DataError(
            fmt::format("interrupted after {} messages; their outputs were written", seen));
    }
    if (perceived == 0 && skipped > 0) {
        throw FormatError(fmt::format("{}: no message on {} could be perceived; first: {}",
                                      bag_name, options.topic, first_problem));
    }
    if (seen == 0) {
        throw DataError(fmt::format("{}: no message on {}", bag_name, options.topic));
    }
}

}  // namespace multicue::cli
