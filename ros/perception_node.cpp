#include "perception_node.hpp"

#include <chrono>

#include <fmt/format.h>
#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>
#include <nlohmann/json.hpp>

#include "msg_conversions.hpp"

namespace multicue::ros1 {
namespace {

double MsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

std::string StampText(const ros::Time& t) { return fmt::format("{}.{:09d}", t.sec, t.nsec); }

}  // namespace

PerceptionNode::PerceptionNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh), pnh_(pnh) {
    // The configuration: ~config_file (JSON), then ~config (the same keys as ROS parameters).
    CoreOptions options;
    pnh_.param<std::string>("config_file", options.config_file, "");
    if (pnh_.hasParam("config")) {
        XmlRpc::XmlRpcValue value;
        pnh_.getParam("config", value);
        // A struct of parameters (rosparam, launch files), or JSON text (`_config:=...` on the
        // command line, where roscpp keeps the value as a string).
        options.config_json = value.getType() == XmlRpc::XmlRpcValue::TypeString
                                  ? static_cast<std::string>(value)
                                  : ParamToJson(value);
        options.config_source = pnh_.resolveName("config") + " (ROS parameters)";
    }
    pnh_.param("threads", options.threads, 0);
    pnh_.param<std::string>("database", options.database, "");
    core_ = std::make_unique<NodeCore>(options);

    labels_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("labelled_cloud", 1);
    markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("markers", 1);
    result_pub_ = pnh_.advertise<std_msgs::String>("result", 1);
    stats_pub_ = pnh_.advertise<std_msgs::String>("stats", 1, true);
    task_srv_ = pnh_.advertiseService("run_task", &PerceptionNode::OnTask, this);

    bool use_images = false;
    pnh_.param("use_images", use_images, false);
    // Queue size 1 everywhere: the newest message wins (see Offer for the node's own slot).
    const auto hints = ros::TransportHints().tcpNoDelay();
    if (use_images) {
        depth_sub_ = nh_.subscribe("depth/image", 1, &PerceptionNode::OnDepth, this, hints);
        colour_sub_ = nh_.subscribe("rgb/image", 1, &PerceptionNode::OnColour, this, hints);
        info_sub_ = nh_.subscribe("depth/camera_info", 1, &PerceptionNode::OnCameraInfo, this);
    } else {
        cloud_sub_ = nh_.subscribe("points", 1, &PerceptionNode::OnCloud, this, hints);
    }
    double period = 5.0;
    pnh_.param("stats_period", period, 5.0);
    stats_time_ = ros::WallTime::now();
    stats_timer_ = nh_.createWallTimer(ros::WallDuration(period > 0 ? period : 5.0),
                                       &PerceptionNode::OnStatsTimer, this);
    worker_ = std::thread([this] { Worker(); });
    ROS_INFO(
        "multicue_node: listening on %s, publishing on %s/{labelled_cloud,markers,result}",
        use_images ? nh_.resolveName("depth/image").c_str() : nh_.resolveName("points").c_str(),
        pnh_.getNamespace().c_str());
}

PerceptionNode::~PerceptionNode() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    if (worker_.joinable()) worker_.join();
}

void PerceptionNode::OnCloud(const sensor_msgs::PointCloud2ConstPtr& msg) {
    Pending p;
    p.cloud = msg;
    p.received = ros::Time::now();
    Offer(std::move(p));
}

void PerceptionNode::OnColour(const sensor_msgs::ImageConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    last_colour_ = msg;
}

void PerceptionNode::OnCameraInfo(const sensor_msgs::CameraInfoConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    last_info_ = *msg;
}

void PerceptionNode::OnDepth(const sensor_msgs::ImageConstPtr& msg) {
    Pending p;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!last_info_) {
            ROS_WARN_THROTTLE(5.0, "multicue_node: depth image without camera_info yet; skipped");
            return;
        }
        p.info = *last_info_;
        // A colour image of the same size taken within 50 ms is the depth image's colour.
        if (last_colour_ && last_colour_->width == msg->width &&
            last_colour_->height == msg->height &&
            std::abs((last_colour_->header.stamp - msg->header.stamp).toSec()) < 0.05) {
            p.colour = last_colour_;
        }
    }
    p.depth = msg;
    p.received = ros::Time::now();
    Offer(std::move(p));
}

void PerceptionNode::Offer(Pending frame) {
    ++received_;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (pending_) ++dropped_;  // the waiting frame is replaced, never queued
        pending_ = std::move(frame);
    }
    wake_.notify_one();
}

void PerceptionNode::Worker() {
    while (true) {
        Pending frame;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [this] { return stop_ || pending_.has_value(); });
            if (stop_) return;
            frame = std::move(*pending_);
            pending_.reset();
        }
        try {
            Process(frame);
        } catch (const std::exception& e) {
            ++failed_;
            ROS_WARN("multicue_node: frame skipped: %s", e.what());
        }
    }
}

void PerceptionNode::Process(const Pending& frame) {
    const auto start = std::chrono::steady_clock::now();
    const std_msgs::Header header = frame.cloud ? frame.cloud->header : frame.depth->header;
    const std::string name =
        fmt::format("{} {} at {}", frame.cloud ? cloud_sub_.getTopic() : depth_sub_.getTopic(),
                    header.frame_id, StampText(header.stamp));
    const FrameOutput out =
        frame.cloud ? core_->Perceive(FromRosMsg(*frame.cloud), name)
                    : core_->PerceiveDepth(
                          DepthFrameFromRos(*frame.depth, frame.info, frame.colour.get()), name);
    auto labels = ToRosMsg(out.labels);
    labels.header = header;
    labels_pub_.publish(labels);
    markers_pub_.publish(MarkersFromOutput(out, header));
    // result.json with the message's stamp and frame.
    auto json = nlohmann::json::parse(out.result_json);
    json["message"] = {
        {"stamp", StampText(header.stamp)}, {"frame_id", header.frame_id}, {"seq", header.seq}};
    std_msgs::String text;
    text.data = json.dump();
    result_pub_.publish(text);
    {
        std::lock_guard<std::mutex> lock(mutex_);
        last_latency_ms_ = (ros::Time::now() - frame.received).toSec() * 1000.0;
        last_pipeline_ms_ = MsSince(start);
    }
    ++processed_;
}

bool PerceptionNode::OnTask(multicue::RunTask::Request& request,
                            multicue::RunTask::Response& response) {
    try {
        response.result = core_->RunTask(request.task);
        response.ok = true;
    } catch (const std::exception& e) {
        response.ok = false;
        response.result = e.what();
        ROS_WARN("multicue_node: run_task failed: %s", e.what());
    }
    return true;
}

void PerceptionNode::OnStatsTimer(const ros::WallTimerEvent& /*event*/) {
    const ros::WallTime now = ros::WallTime::now();
    const double dt = (now - stats_time_).toSec();
    const std::uint64_t received = received_, processed = processed_;
    const double in_hz = dt > 0 ? double(received - stats_received_) / dt : 0.0;
    const double out_hz = dt > 0 ? double(processed - stats_processed_) / dt : 0.0;
    stats_time_ = now;
    stats_received_ = received;
    stats_processed_ = processed;
    double latency = 0, pipeline = 0;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        latency = last_latency_ms_;
        pipeline = last_pipeline_ms_;
    }
    nlohmann::json stats = {
        {"received", received},     {"processed", processed}, {"dropped", dropped_.load()},
        {"failed", failed_.load()}, {"in_hz", in_hz},         {"out_hz", out_hz},
        {"latency_ms", latency},    {"frame_ms", pipeline}};
    std_msgs::String text;
    text.data = stats.dump();
    stats_pub_.publish(text);
    if (received > 0) {
        ROS_INFO(
            "multicue_node: in %.1f Hz, out %.1f Hz; %lu received, %lu perceived, %lu "
            "dropped, %lu failed; last frame %.0f ms (%.0f ms after it arrived)",
            in_hz, out_hz, static_cast<unsigned long>(received),
            static_cast<unsigned long>(processed), static_cast<unsigned long>(dropped_.load()),
            static_cast<unsigned long>(failed_.load()), pipeline, latency);
    }
}

}  // namespace multicue::ros1
