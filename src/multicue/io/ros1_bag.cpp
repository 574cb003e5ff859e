#include "multicue/io/ros1_bag.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::io {
namespace {

namespace fs = std::filesystem;

class Ros1Bag : public BagReader {
  public:
    Ros1Bag(const fs::path& path, const std::vector<std::string>& selected) : name_(path.string()) {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) throw IoError(name_ + ": no such file");
        try {
            bag_.open(name_, rosbag::bagmode::Read);
            rosbag::View all(bag_);
            for (const rosbag::ConnectionInfo* c : all.getConnections()) {
                if (FindTopic(c->topic) != nullptr) continue;
                rosbag::View one(bag_, rosbag::TopicQuery(c->topic));
                topics_.push_back({c->topic, c->datatype, "ros1", one.size()});
            }
            view_ = selected.empty()
                        ? std::make_unique<rosbag::View>(bag_)
                        : std::make_unique<rosbag::View>(bag_, rosbag::TopicQuery(selected));
            it_ = view_->begin();
        } catch (const rosbag::BagException& e) {
            throw FormatError(fmt::format("{}: not a readable ROS 1 bag ({})", name_, e.what()));
        }
    }

    const std::vector<BagTopic>& Topics() const override { return topics_; }

    bool Next(BagMessage& message) override {
        try {
            if (it_ == view_->end()) return false;
            const rosbag::MessageInstance& m = *it_;
            message.topic = m.getTopic();
            message.log_time_ns = static_cast<std::int64_t>(m.getTime().toNSec());
            message.data.resize(m.size());
            ros::serialization::OStream stream(message.data.data(),
                                               static_cast<std::uint32_t>(message.data.size()));
            m.write(stream);
            ++it_;
            return true;
        } catch (const rosbag::BagException& e) {
            throw FormatError(fmt::format("{}: reading a message failed ({})", name_, e.what()));
        } catch (const ros::Exception& e) {
            throw FormatError(fmt::format("{}: reading a message failed ({})", name_, e.what()));
        }
    }

  private:
    std::string name_;
    rosbag::Bag bag_;
    std::vector<BagTopic> topics_;
    std::unique_ptr<rosbag::View> view_;
    rosbag::View::iterator it_;
};

}  // namespace

std::unique_ptr<BagReader> OpenRos1Bag(const fs::path& path,
                                       const std::vector<std::string>& topics) {
    return std::make_unique<Ros1Bag>(path, topics);
}

}  // namespace multicue::io
