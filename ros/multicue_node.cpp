// multicue_node: the perceive pipeline as a ROS 1 node (perception_node.hpp, docs/ros.md).

#include <ros/ros.h>

#include <exception>
#include <memory>

#include "perception_node.hpp"

int main(int argc, char** argv) {
    ros::init(argc, argv, "multicue_node");
    ros::NodeHandle nh;
    ros::NodeHandle pnh("~");
    std::unique_ptr<multicue::ros1::PerceptionNode> node;
    try {
        node = std::make_unique<multicue::ros1::PerceptionNode>(nh, pnh);
    } catch (const std::exception& e) {
        ROS_FATAL("multicue_node: %s", e.what());
        return 2;
    }
    // Two threads: a task service call never holds up the frame callbacks.
    ros::AsyncSpinner spinner(2);
    spinner.start();
    ros::waitForShutdown();
    return 0;
}
