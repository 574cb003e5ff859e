#include "multicue/io/ros1_bag.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <fmt/format.h>

#include <cstdint>
#include <fstream>
#include <string_view>

#include "multicue/core/exceptions.hpp"

namespace multicue::io {
namespace {

namespace fs = std::filesystem;

std::uint32_t LittleEndian32(const char* p) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(p[i]);
    return v;
}

// librosbag takes the lengths in a bag as they are and allocates what they claim (a damaged
// length asks for gigabytes). The top-level records of a version 2.0 bag are walked here first,
// reading only their headers: every header and data length must fit in the rest of the file,
// every header field in its header, and a chunk may not claim more than 256 times its stored
// bytes once decompressed.
void CheckRecordLengths(const fs::path& path, const std::string& name) {
    std::ifstream in(path, std::ios::binary);
    const std::uint64_t file_size = fs::file_size(path);
    const std::string magic = "#ROSBAG V2.0\n";
    std::string head(magic.size(), '\0');
    if (!in.read(head.data(), static_cast<std::streamsize>(head.size())) || head != magic) {
        throw FormatError(
            fmt::format("{}: not a ROS 1 bag of format 2.0 (no '#ROSBAG V2.0' line)", name));
    }
    const auto fail = [&](std::uint64_t at, const std::string& what) {
        throw FormatError(
            fmt::format("{}: record at byte {}: {} (truncated or corrupt bag)", name, at, what));
    };
    constexpr std::uint64_t kMaxHeader = 1 << 20;  // record headers are a few hundred bytes
    std::uint64_t pos = magic.size();
    std::string header;
    char length[4];
    while (pos < file_size) {
        const std::uint64_t record = pos;
        if (file_size - pos < 4 || !in.read(length, 4)) fail(record, "header length cut off");
        const std::uint64_t header_len = LittleEndian32(length);
        pos += 4;
        if (header_len > file_size - pos) fail(record, "header longer than the file");
        if (header_len > kMaxHeader) fail(record, fmt::format("header of {} bytes", header_len));
        header.resize(header_len);
        if (!in.read(header.data(), static_cast<std::streamsize>(header_len))) {
            fail(record, "header cut off");
        }
        pos += header_len;
        std::string_view compression;
        std::uint64_t size = 0;
        bool has_size = false;
        for (std::size_t f = 0; f < header.size();) {
            if (header.size() - f < 4) fail(record, "header field length cut off");
            const std::uint64_t field_len = LittleEndian32(header.data() + f);
            f += 4;
            if (field_len > header.size() - f) fail(record, "header field beyond its header");
            const std::string_view field(header.data() + f, field_len);
            if (field.starts_with("compression=")) compression = field.substr(12);
            if (field.starts_with("size=") && field.size() == 9) {
                size = LittleEndian32(field.data() + 5);
                has_size = true;
            }
            f += field_len;
        }
        if (file_size - pos < 4 || !in.read(length, 4)) fail(record, "data length cut off");
        const std::uint64_t data_len = LittleEndian32(length);
        pos += 4;
        if (data_len > file_size - pos) fail(record, "data longer than the file");
        if (has_size && !compression.empty() && size > 256 * data_len + 65536) {
            fail(record,
                 fmt::format("a chunk of {} bytes claims {} bytes decompressed", data_len, size));
        }
        pos += data_len;
        in.seekg(static_cast<std::streamoff>(pos));
    }
}

class Ros1Bag : public BagReader {
  public:
    Ros1Bag(const fs::path& path, const std::vector<std::string>& selected) : name_(path.string()) {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) throw IoError(name_ + ": no such file");
        CheckRecordLengths(path, name_);
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
        } catch (const ros::Exception& e) {
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
