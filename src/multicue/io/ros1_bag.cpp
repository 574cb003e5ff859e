#include "multicue/io/ros1_bag.hpp"

#include <bzlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string_view>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/bag_internal.hpp"

// ROS 1 bags (format 2.0) read here, without librosbag: Debian's librosbag takes every length
// and offset in the file as it is (a damaged bag made it allocate gigabytes or read past its
// buffers). A bag is a sequence of records, each a header (fields `name=value`, each preceded by
// its length) and a data block, both preceded by their length:
//   op 0x03 bag header (index_pos, conn_count, chunk_count)
//   op 0x05 chunk (compression none, lz4 or bz2; size) whose data holds connection and message
//           records
//   op 0x07 connection (conn, topic; its data is a header with type, md5sum, ...)
//   op 0x02 message data (conn, time; its data is the serialised message)
//   op 0x04 index data, op 0x06 chunk info (message counts per connection)
// Connections and chunk infos are repeated after index_pos, which is where the topics and their
// message counts are read from; messages are then read chunk after chunk, in file order.

namespace multicue::io {
namespace {

namespace fs = std::filesystem;

constexpr std::uint8_t kOpMessageData = 0x02;
constexpr std::uint8_t kOpBagHeader = 0x03;
constexpr std::uint8_t kOpChunk = 0x05;
constexpr std::uint8_t kOpChunkInfo = 0x06;
constexpr std::uint8_t kOpConnection = 0x07;
constexpr std::uint64_t kMaxHeader = 1 << 20;  // record headers are a few hundred bytes

std::uint32_t U32(const std::uint8_t* p) {
    return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
           std::uint32_t{p[3]} << 24;
}

std::uint64_t U64(const std::uint8_t* p) { return U32(p) | std::uint64_t{U32(p + 4)} << 32; }

/// The fields of a record header.
class Fields {
  public:
    Fields(std::span<const std::uint8_t> bytes, const std::function<void(std::string)>& fail) {
        std::size_t f = 0;
        while (f < bytes.size()) {
            if (bytes.size() - f < 4) fail("header field length cut off");
            const std::uint32_t len = U32(bytes.data() + f);
            f += 4;
            if (len > bytes.size() - f) fail("header field beyond its header");
            const std::string_view field(reinterpret_cast<const char*>(bytes.data() + f), len);
            const auto eq = field.find('=');
            if (eq == std::string_view::npos) fail("header field without '='");
            values_[std::string(field.substr(0, eq))] = field.substr(eq + 1);
            f += len;
        }
    }
    std::optional<std::string_view> Get(const std::string& name) const {
        const auto it = values_.find(name);
        if (it == values_.end()) return std::nullopt;
        return it->second;
    }

  private:
    std::map<std::string, std::string_view, std::less<>> values_;
};

class Ros1Bag : public BagReader {
  public:
    Ros1Bag(const fs::path& path, const std::vector<std::string>& selected)
        : name_(path.string()), selected_(selected.begin(), selected.end()) {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) throw IoError(name_ + ": no such file");
        in_.open(path, std::ios::binary);
        if (!in_) throw IoError(name_ + ": cannot open");
        size_ = fs::file_size(path, ec);
        const std::string magic = "#ROSBAG V2.0\n";
        std::string head(magic.size(), '\0');
        if (!in_.read(head.data(), static_cast<std::streamsize>(head.size())) || head != magic) {
            throw FormatError(
                fmt::format("{}: not a ROS 1 bag of format 2.0 (no '#ROSBAG V2.0' line)", name_));
        }
        pos_ = magic.size();
        ReadRecord();
        if (Op() != kOpBagHeader) Fail(pos_, "the first record is no bag header");
        const auto index_pos = Field64("index_pos");
        if (index_pos == 0) {
            throw FormatError(fmt::format(
                "{}: the bag has no index (recording interrupted?); `rosbag reindex` repairs it",
                name_));
        }
        if (index_pos < pos_ || index_pos > size_) Fail(pos_, "index_pos outside the file");
        messages_end_ = index_pos;
        const std::uint64_t first = pos_;
        ReadIndex(index_pos);
        Seek(first);
    }

    const std::vector<BagTopic>& Topics() const override { return topics_; }

    bool Next(BagMessage& message) override {
        while (true) {
            if (chunk_pos_ < chunk_.size()) {
                if (NextInChunk(message)) return true;
                continue;
            }
            if (pos_ >= messages_end_) return false;
            ReadRecord();
            if (Op() == kOpChunk) {
                LoadChunk();
            } else if (Op() == kOpMessageData) {
                if (TakeMessage(Fields(header_, failer(record_)), data_, message)) return true;
            }
        }
    }

  private:
    [[noreturn]] void Fail(std::uint64_t at, const std::string& what) const {
        throw FormatError(
            fmt::format("{}: record at byte {}: {} (truncated or corrupt bag)", name_, at, what));
    }
    std::function<void(std::string)> failer(std::uint64_t at) const {
        return [this, at](const std::string& what) { Fail(at, what); };
    }

    void Seek(std::uint64_t pos) {
        in_.clear();
        in_.seekg(static_cast<std::streamoff>(pos));
        pos_ = pos;
    }

    // Reads the record at pos_ into header_ and data_ (lengths checked against the file).
    void ReadRecord() {
        record_ = pos_;
        std::uint8_t len[4];
        const auto read = [&](void* to, std::uint64_t n, const char* what) {
            if (n > size_ - pos_ ||
                !in_.read(static_cast<char*>(to), static_cast<std::streamsize>(n))) {
                Fail(record_, what);
            }
            pos_ += n;
        };
        read(len, 4, "header length cut off");
        const std::uint64_t header_len = U32(len);
        if (header_len > kMaxHeader) Fail(record_, fmt::format("header of {} bytes", header_len));
        if (header_len > size_ - pos_) Fail(record_, "header longer than the file");
        header_.resize(header_len);
        read(header_.data(), header_len, "header longer than the file");
        read(len, 4, "data length cut off");
        const std::uint64_t data_len = U32(len);
        if (data_len > size_ - pos_) Fail(record_, "data longer than the file");  // before resize
        data_.resize(data_len);
        read(data_.data(), data_len, "data longer than the file");
        fields_.emplace(header_, failer(record_));
    }

    std::uint8_t Op() const {
        const auto op = fields_->Get("op");
        if (!op || op->size() != 1) Fail(record_, "no op field");
        return static_cast<std::uint8_t>((*op)[0]);
    }
    std::uint64_t Field64(const char* name) const { return FieldInt(*fields_, name, 8, record_); }
    std::uint64_t FieldInt(const Fields& f, const char* name, std::size_t bytes,
                           std::uint64_t at) const {
        const auto v = f.Get(name);
        if (!v || v->size() != bytes) Fail(at, fmt::format("no {}-byte field '{}'", bytes, name));
        const auto* p = reinterpret_cast<const std::uint8_t*>(v->data());
        return bytes == 8 ? U64(p) : U32(p);
    }

    // Connections and message counts from the index section.
    void ReadIndex(std::uint64_t index_pos) {
        Seek(index_pos);
        std::map<std::uint32_t, std::uint64_t> counts;
        while (pos_ < size_) {
            ReadRecord();
            if (Op() == kOpConnection) {
                AddConnection();
            } else if (Op() == kOpChunkInfo) {
                const auto n = FieldInt(*fields_, "count", 4, record_);
                if (n * 8 > data_.size()) Fail(record_, "chunk info counts beyond its data");
                for (std::uint64_t k = 0; k < n; ++k) {
                    counts[U32(data_.data() + 8 * k)] += U32(data_.data() + 8 * k + 4);
                }
            }
        }
        for (const auto& [conn, n] : counts) {
            const auto it = connections_.find(conn);
            if (it == connections_.end()) continue;
            for (auto& t : topics_) {
                if (t.name == it->second) t.messages += n;
            }
        }
    }

    void AddConnection() {
        const auto conn = static_cast<std::uint32_t>(FieldInt(*fields_, "conn", 4, record_));
        const auto topic = fields_->Get("topic");
        if (!topic) Fail(record_, "connection without topic");
        const Fields details(data_, failer(record_));
        const auto type = details.Get("type");
        if (!type) Fail(record_, "connection without type");
        connections_[conn] = std::string(*topic);
        if (FindTopic(std::string(*topic)) == nullptr) {
            topics_.push_back({std::string(*topic), std::string(*type), "ros1", 0});
        }
    }

    void LoadChunk() {
        const auto compression = fields_->Get("compression");
        if (!compression) Fail(record_, "chunk without compression field");
        const std::uint64_t size = FieldInt(*fields_, "size", 4, record_);
        if (size > 256 * std::uint64_t{data_.size()} + 65536) {
            Fail(record_, fmt::format("a chunk of {} bytes claims {} bytes decompressed",
                                      data_.size(), size));
        }
        const std::string source = fmt::format("{}: chunk at byte {}", name_, record_);
        if (*compression == "none") {
            if (size != data_.size()) Fail(record_, "chunk size differs from its data");
            chunk_.swap(data_);  // data_ is refilled by the next record
        } else if (*compression == "lz4") {
            chunk_ = detail::Decompress("lz4", data_, size, source);
        } else if (*compression == "bz2") {
            chunk_.resize(size);
            auto got = static_cast<unsigned int>(size);
            const int rc = BZ2_bzBuffToBuffDecompress(
                reinterpret_cast<char*>(chunk_.data()), &got, reinterpret_cast<char*>(data_.data()),
                static_cast<unsigned int>(data_.size()), 0, 0);
            if (rc != BZ_OK || got != size) throw FormatError(source + ": corrupt bz2 data");
        } else {
            Fail(record_, fmt::format("unknown compression '{}'", *compression));
        }
        chunk_record_ = record_;
        chunk_pos_ = 0;
    }

    // The next message of a selected topic in the current chunk; false at its end.
    bool NextInChunk(BagMessage& message) {
        while (chunk_pos_ < chunk_.size()) {
            const auto take = [&](std::size_t n) {
                if (n > chunk_.size() - chunk_pos_) {
                    Fail(chunk_record_, "a record in the chunk runs past its end");
                }
                const std::span<const std::uint8_t> s(chunk_.data() + chunk_pos_, n);
                chunk_pos_ += n;
                return s;
            };
            const auto header = take(U32(take(4).data()));
            const auto data = take(U32(take(4).data()));
            const Fields f(header, failer(chunk_record_));
            const auto op = f.Get("op");
            if (!op || op->size() != 1) Fail(chunk_record_, "a record in the chunk has no op");
            if (static_cast<std::uint8_t>((*op)[0]) == kOpMessageData &&
                TakeMessage(f, data, message)) {
                return true;
            }
        }
        return false;
    }

    bool TakeMessage(const Fields& f, std::span<const std::uint8_t> data, BagMessage& message) {
        const auto conn = static_cast<std::uint32_t>(FieldInt(f, "conn", 4, record_));
        const auto it = connections_.find(conn);
        if (it == connections_.end()) {
            Fail(record_, fmt::format("a message of connection {}, which the index lacks", conn));
        }
        if (!selected_.empty() &&
            std::find(selected_.begin(), selected_.end(), it->second) == selected_.end()) {
            return false;
        }
        const std::uint64_t time = FieldInt(f, "time", 8, record_);
        message.topic = it->second;
        message.log_time_ns =
            static_cast<std::int64_t>((time & 0xffffffffu) * 1000000000ull + (time >> 32));
        message.data.assign(data.begin(), data.end());
        return true;
    }

    std::string name_;
    std::vector<std::string> selected_;
    std::ifstream in_;
    std::uint64_t size_ = 0, pos_ = 0, record_ = 0, messages_end_ = 0;
    std::vector<std::uint8_t> header_, data_;
    std::optional<Fields> fields_;
    std::vector<std::uint8_t> chunk_;
    std::size_t chunk_pos_ = 0;
    std::uint64_t chunk_record_ = 0;
    std::map<std::uint32_t, std::string> connections_;
    std::vector<BagTopic> topics_;
};

}  // namespace

std::unique_ptr<BagReader> OpenRos1Bag(const fs::path& path,
                                       const std::vector<std::string>& topics) {
    return std::make_unique<Ros1Bag>(path, topics);
}

}  // namespace multicue::io
