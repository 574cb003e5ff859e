#pragma once
/// \file multicue_node: perceive on a robot. Subscribes to a PointCloud2 topic (or depth and
/// colour images with camera_info), runs the perceive pipeline in a worker thread on the newest
/// frame only (a frame that arrives while one is processed replaces the waiting one: frames are
/// dropped, never queued), and publishes the labelled cloud, the models as markers and the
/// result JSON with the input's frame id and stamp. A service runs executive tasks on the newest
/// frame. Parameters: see docs/ros.md.

#include <ros/ros.h>

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include "multicue/RunTask.h"
#include "node_core.hpp"

namespace multicue::ros1 {

class PerceptionNode {
  public:
    /// Reads the parameters (throws for a bad configuration), advertises and subscribes, starts
    /// the worker. C++17 (ROS 1's headers); the library is reached through NodeCore.
    PerceptionNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);
    ~PerceptionNode();
    PerceptionNode(const PerceptionNode&) = delete;
    PerceptionNode& operator=(const PerceptionNode&) = delete;

  private:
    /// A frame waiting for the worker.
    struct Pending {
        sensor_msgs::PointCloud2ConstPtr cloud;  ///< or the images below
        sensor_msgs::ImageConstPtr depth;
        sensor_msgs::ImageConstPtr colour;
        sensor_msgs::CameraInfo info;
        ros::Time received;
    };

    void OnCloud(const sensor_msgs::PointCloud2ConstPtr& msg);
    void OnDepth(const sensor_msgs::ImageConstPtr& msg);
    void OnColour(const sensor_msgs::ImageConstPtr& msg);
    void OnCameraInfo(const sensor_msgs::CameraInfoConstPtr& msg);
    void Offer(Pending frame);
    void Worker();
    void Process(const Pending& frame);
    bool OnTask(multicue::RunTask::Request& request, multicue::RunTask::Response& response);
    void OnStatsTimer(const ros::WallTimerEvent& event);

    ros::NodeHandle nh_, pnh_;
    std::unique_ptr<NodeCore> core_;

    ros::Subscriber cloud_sub_, depth_sub_, colour_sub_, info_sub_;
    ros::Publisher labels_pub_, markers_pub_, result_pub_, stats_pub_;
    ros::ServiceServer task_srv_;
    ros::WallTimer stats_timer_;

    std::mutex mutex_;
    std::condition_variable wake_;
    std::optional<Pending> pending_;
    sensor_msgs::ImageConstPtr last_colour_;
    std::optional<sensor_msgs::CameraInfo> last_info_;
    bool stop_ = false;

    std::atomic<std::uint64_t> received_{0}, processed_{0}, dropped_{0}, failed_{0};
    std::uint64_t stats_received_ = 0, stats_processed_ = 0;  // at the last report
    ros::WallTime stats_time_;
    double last_latency_ms_ = 0.0, last_pipeline_ms_ = 0.0;
    std::thread worker_;
};

}  // namespace multicue::ros1
