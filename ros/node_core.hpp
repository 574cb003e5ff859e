#pragma once
/// \file What multicue_node does with a frame, behind a C++17 interface: ROS 1's message headers
/// do not compile as C++20 (they rebind std::allocator<void>), so the node's ROS code is built as
/// C++17 and reaches the library only through this class. It holds the configuration, the
/// learned models, the executive and the newest perceived frame.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "multicue/io/point_cloud2_message.hpp"

namespace multicue::ros1 {

struct CoreOptions {
    std::string config_file;    ///< JSON parameter file (empty: none)
    std::string config_json;    ///< the same keys from ROS parameters, as JSON (empty: none)
    std::string config_source;  ///< names config_json in error messages
    int threads = 0;            ///< 0 = the configuration's (all cores by default)
    std::string database;       ///< object model database for the task service (empty: none)
};

/// A text marker: object id, position [m], "id category confidence", colour in [0, 1].
struct TextMarker {
    int id = 0;
    float position[3] = {0, 0, 0};
    std::string text;
    float rgb[3] = {1, 1, 1};
};

/// What the node publishes for a frame (headers are set by the caller).
struct FrameOutput {
    io::PointCloud2Message labels;    ///< the input's points with label (object), object, category
    std::string result_json;          ///< result.json of `multicue perceive`
    std::vector<float> triangles;     ///< the models: x y z per vertex, three vertices a triangle
    std::vector<float> triangle_rgb;  ///< r g b in [0, 1] per vertex
    std::vector<TextMarker> texts;    ///< one per object
    std::size_t objects = 0;
};

/// A depth image in metres (0 or NaN: no depth) with its intrinsics and, optionally, a colour
/// image of the same size (r g b bytes per pixel).
struct DepthFrame {
    std::uint32_t width = 0, height = 0;
    std::vector<float> depth;
    std::vector<std::uint8_t> rgb;
    double fx = 0, fy = 0, cx = 0, cy = 0;
};

class NodeCore {
  public:
    /// Reads and checks the configuration, loads the models, opens the database; throws a
    /// std::exception naming the bad value.
    explicit NodeCore(const CoreOptions& options);
    ~NodeCore();
    NodeCore(const NodeCore&) = delete;
    NodeCore& operator=(const NodeCore&) = delete;

    /// Perceives one cloud (`name` labels it in result.json and for the task service). Throws
    /// for a message whose layout does not fit (no x/y/z, truncated data) or without a finite
    /// point.
    FrameOutput Perceive(const io::PointCloud2Message& message, const std::string& name);
    FrameOutput PerceiveDepth(const DepthFrame& frame, const std::string& name);

    /// Runs a task (JSON: task, target, learn, possible_objects, region) on the newest perceived
    /// frame; returns its frame report as JSON. Throws when there is no frame yet or the task is
    /// malformed. Safe to call while another thread perceives.
    std::string RunTask(const std::string& task_json);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace multicue::ros1
