#include "multicue/io/bag.hpp"

#include <algorithm>
#include <cstring>
#include <set>

#include <fmt/format.h>

#ifdef MULTICUE_HAVE_ZSTD
#include <zstd.h>
#endif
#ifdef MULTICUE_HAVE_LZ4
#include <lz4frame.h>
#endif

#include "multicue/core/exceptions.hpp"
#include "multicue/io/bag_internal.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/ros_messages.hpp"

namespace multicue::io {
namespace {

namespace fs = std::filesystem;

/// The storage files of a bag folder, in name order (split bags: name_0, name_1, ...).
std::vector<fs::path> StorageFiles(const fs::path& dir) {
    std::vector<fs::path> files;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
        const std::string ext = LowerExtension(entry.path());
        if (entry.is_regular_file() && (ext == "db3" || ext == "mcap"))
            files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    return files;
}

/// The files of a split bag one after the other.
class ChainedBag : public BagReader {
  public:
    explicit ChainedBag(std::vector<std::unique_ptr<BagReader>> parts) : parts_(std::move(parts)) {
        for (const auto& part : parts_) {
            for (const auto& t : part->Topics()) {
                auto it = std::find_if(topics_.begin(), topics_.end(),
                                       [&](const BagTopic& o) { return o.name == t.name; });
                if (it == topics_.end()) {
                    topics_.push_back(t);
                } else {
                    it->messages += t.messages;
                }
            }
        }
    }
    const std::vector<BagTopic>& Topics() const override { return topics_; }
    bool Next(BagMessage& message) override {
        while (current_ < parts_.size()) {
            if (parts_[current_]->Next(message)) return true;
            ++current_;
        }
        return false;
    }

  private:
    std::vector<std::unique_ptr<BagReader>> parts_;
    std::vector<BagTopic> topics_;
    std::size_t current_ = 0;
};

std::unique_ptr<BagReader> OpenStorageFile(const fs::path& path,
                                           const std::vector<std::string>& topics) {
    const std::string ext = LowerExtension(path);
    if (ext == "db3") return detail::OpenSqliteBag(path, topics);
    if (ext == "mcap") return detail::OpenMcapBag(path, topics);
    throw IoError(fmt::format("{}: not a ROS 2 bag (expected a .db3 or .mcap file or a bag folder)",
                              path.string()));
}

}  // namespace

const BagTopic* BagReader::FindTopic(const std::string& name) const {
    for (const auto& t : Topics()) {
        if (t.name == name) return &t;
    }
    return nullptr;
}

std::uint64_t BagReader::CountMessages(const std::vector<std::string>& topics) const {
    std::uint64_t n = 0;
    for (const auto& t : Topics()) {
        if (topics.empty() || std::find(topics.begin(), topics.end(), t.name) != topics.end())
            n += t.messages;
    }
    return n;
}

std::string BagReader::DescribeTopics() const {
    std::string s;
    for (const auto& t : Topics()) {
        s += fmt::format("{}{} ({}, {} messages)", s.empty() ? "" : ", ", t.name, t.type,
                         t.messages);
    }
    return s.empty() ? "no topics" : s;
}

std::unique_ptr<BagReader> OpenRos2Bag(const fs::path& path,
                                       const std::vector<std::string>& topics) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        const auto files = StorageFiles(path);
        if (files.empty()) {
            throw IoError(fmt::format("{}: a folder without .db3 or .mcap files (not a ROS 2 bag)",
                                      path.string()));
        }
        if (files.size() == 1) return OpenStorageFile(files.front(), topics);
        std::vector<std::unique_ptr<BagReader>> parts;
        for (const auto& f : files) parts.push_back(OpenStorageFile(f, topics));
        return std::make_unique<ChainedBag>(std::move(parts));
    }
    if (!fs::exists(path, ec)) throw IoError(fmt::format("{}: no such file", path.string()));
    return OpenStorageFile(path, topics);
}

bool IsRos2BagPath(const fs::path& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) return !StorageFiles(path).empty();
    const std::string ext = LowerExtension(path);
    return ext == "db3" || ext == "mcap";
}

PointCloud2Message DecodePointCloud2(const BagTopic& topic, std::span<const std::uint8_t> data,
                                     const std::string& source) {
    if (!IsPointCloud2Type(topic.type)) {
        throw FormatError(fmt::format("{}: topic {} carries {}, not sensor_msgs PointCloud2",
                                      source, topic.name, topic.type));
    }
    if (topic.serialization == "cdr") return DecodePointCloud2Cdr(data, source);
    if (topic.serialization == "ros1") return DecodePointCloud2Ros1(data, source);
    throw FormatError(fmt::format("{}: topic {} is serialised as '{}' (cdr or ros1 expected)",
                                  source, topic.name, topic.serialization));
}

namespace detail {

void DecompressIfZstd(std::vector<std::uint8_t>& data, const std::string& source) {
    static constexpr std::uint8_t kMagic[4] = {0x28, 0xb5, 0x2f, 0xfd};
    if (data.size() < 4 || std::memcmp(data.data(), kMagic, 4) != 0) return;
#ifdef MULTICUE_HAVE_ZSTD
    const unsigned long long size = ZSTD_getFrameContentSize(data.data(), data.size());
    if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN) {
        throw FormatError(fmt::format("{}: zstd-compressed message without its size", source));
    }
    data = Decompress("zstd", data, size, source);
#else
    throw FormatError(fmt::format(
        "{}: the message is zstd-compressed and this build has no zstd (libzstd-dev)", source));
#endif
}

std::vector<std::uint8_t> Decompress(const std::string& compression,
                                     std::span<const std::uint8_t> data, std::uint64_t size,
                                     const std::string& source) {
    if (compression.empty()) return {data.begin(), data.end()};
    if (size > (std::uint64_t{1} << 34)) {
        throw FormatError(fmt::format("{}: implausible uncompressed size {}", source, size));
    }
    // The output grows with what the data really decompresses to (a megabyte at a time, up to
    // the claimed size): a damaged size field costs nothing until the data backs it.
    std::vector<std::uint8_t> out;
    const auto grow = [&]() {
        const std::size_t old = out.size();
        out.resize(old + static_cast<std::size_t>(std::min<std::uint64_t>(size - old, 1 << 20)));
        return old;
    };
    if (compression == "zstd") {
#ifdef MULTICUE_HAVE_ZSTD
        ZSTD_DStream* ds = ZSTD_createDStream();
        if (ds == nullptr) throw FormatError(source + ": cannot create a zstd context");
        ZSTD_inBuffer in{data.data(), data.size(), 0};
        std::size_t ret = ZSTD_initDStream(ds);
        std::size_t produced = 0;
        while (!ZSTD_isError(ret) && produced < size) {
            const std::size_t old = grow();
            ZSTD_outBuffer ob{out.data() + old, out.size() - old, 0};
            ret = ZSTD_decompressStream(ds, &ob, &in);
            produced = old + ob.pos;
            out.resize(produced);
            if (ret == 0 || (ob.pos == 0 && in.pos == in.size)) break;
        }
        ZSTD_freeDStream(ds);
        if (ZSTD_isError(ret) || produced != size) {
            throw FormatError(fmt::format("{}: corrupt zstd data ({})", source,
                                          ZSTD_isError(ret) ? ZSTD_getErrorName(ret) : "size"));
        }
        return out;
#endif
    } else if (compression == "lz4") {
#ifdef MULTICUE_HAVE_LZ4
        LZ4F_dctx* ctx = nullptr;
        if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) {
            throw FormatError(source + ": cannot create an lz4 context");
        }
        std::size_t in_pos = 0, produced = 0, ret = 1;
        while (ret != 0 && produced < size) {
            const std::size_t old = grow();
            std::size_t in_size = data.size() - in_pos, out_size = out.size() - old;
            ret = LZ4F_decompress(ctx, out.data() + old, &out_size, data.data() + in_pos, &in_size,
                                  nullptr);
            produced = old + (LZ4F_isError(ret) ? 0 : out_size);
            out.resize(produced);
            if (LZ4F_isError(ret)) break;
            in_pos += in_size;
            if (in_size == 0 && out_size == 0) break;
        }
        LZ4F_freeDecompressionContext(ctx);
        if (LZ4F_isError(ret) || produced != size) {
            throw FormatError(fmt::format("{}: corrupt lz4 data", source));
        }
        return out;
#endif
    }
    throw FormatError(
        fmt::format("{}: '{}' compression is not supported by this build", source, compression));
}

}  // namespace detail
}  // namespace multicue::io
