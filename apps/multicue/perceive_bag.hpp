#pragma once
// `multicue perceive --bag FILE --topic TOPIC`: every point cloud message of a topic perceived on
// its own, outputs per message in OUT/<stamp>/ and an index of all messages in OUT/index.json.

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "multicue/io/bag.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_report.hpp"

namespace multicue::cli {

struct PerceiveBagOptions {
    std::filesystem::path bag;  ///< .bag (ROS 1), .db3 / .mcap / bag folder (ROS 2)
    std::string topic;          ///< a sensor_msgs PointCloud2 topic
    std::filesystem::path out;
    std::size_t max_messages = 0;  ///< 0 = all
    bool quiet = false;
};

/// Opens a ROS 1 or ROS 2 bag by its name, reading only `topics`. Throws IoError for a format
/// this build cannot read (a .bag without librosbag) or a file that is no bag.
std::unique_ptr<io::BagReader> OpenBag(const std::filesystem::path& path,
                                       const std::vector<std::string>& topics);

/// Perceives every message; a message that cannot be read (not a point cloud layout, no finite
/// point) is skipped with a warning and listed in index.json. Interruptible between messages.
/// Throws InvalidArgument for a missing topic, FormatError for a topic of another type, a
/// truncated bag (after writing what came before) or a bag in which no message could be read.
void RunPerceiveBag(const PerceiveBagOptions& options, const PerceiveParams& pipeline,
                    const ReportParams& report, const PerceiveModels& models);

}  // namespace multicue::cli
