#pragma once
/// \file Reading recorded ROS messages: one interface over ROS 2 bags (rosbag2's SQLite `.db3`
/// and MCAP `.mcap` storage, read here without any ROS library) and ROS 1 `.bag` files (read
/// by io/ros1_bag.hpp when the build has it). Messages come as their serialised
/// bytes with the topic's type and serialisation; DecodePointCloud2 turns a point cloud message
/// into a PointCloud2Message whatever the source.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "multicue/io/point_cloud2.hpp"

namespace multicue::io {

/// A topic of a bag.
struct BagTopic {
    std::string name;  ///< "/camera/depth_registered/points"
    std::string type;  ///< "sensor_msgs/msg/PointCloud2" (ROS 2), "sensor_msgs/PointCloud2"
    std::string serialization;   ///< "cdr" (ROS 2) or "ros1"
    std::uint64_t messages = 0;  ///< messages recorded on the topic (0 if the file does not say)
};

/// One recorded message.
struct BagMessage {
    std::string topic;
    std::int64_t log_time_ns = 0;    ///< when it was recorded [ns since the epoch]
    std::vector<std::uint8_t> data;  ///< serialised message (CDR with its header, or ROS 1)
};

/// Reads the messages of a bag in recording order.
class BagReader {
  public:
    virtual ~BagReader() = default;
    /// Every topic of the bag, also those not selected.
    virtual const std::vector<BagTopic>& Topics() const = 0;
    /// The next message of the selected topics; false at the end. Throws FormatError naming the
    /// file when it is truncated or corrupt (the messages before were returned).
    virtual bool Next(BagMessage& message) = 0;

    /// The topic called `name`, nullptr if the bag has none.
    const BagTopic* FindTopic(const std::string& name) const;
    /// Messages of the selected topics as the file counts them (0 if unknown).
    std::uint64_t CountMessages(const std::vector<std::string>& topics) const;
    /// "name (type, N messages), ..." for error messages.
    std::string DescribeTopics() const;
};

/// Opens a ROS 2 bag: a `.db3` or `.mcap` file, or a bag folder (metadata.yaml beside its
/// storage files, read in name order). Only messages on `topics` are returned (all when empty).
/// Throws IoError for a missing file, FormatError for a file that is no bag.
std::unique_ptr<BagReader> OpenRos2Bag(const std::filesystem::path& path,
                                       const std::vector<std::string>& topics = {});

/// Whether `path` is read by OpenRos2Bag (.db3, .mcap, or a folder holding one).
bool IsRos2BagPath(const std::filesystem::path& path);

/// A point cloud message of `topic` (its serialisation picks the decoder). Throws FormatError
/// naming `source` for a topic that is not sensor_msgs PointCloud2 or bytes that do not decode.
PointCloud2Message DecodePointCloud2(const BagTopic& topic, std::span<const std::uint8_t> data,
                                     const std::string& source);

}  // namespace multicue::io
