// MCAP (https://mcap.dev/spec): the magic "\x89MCAP0\r\n", then records (opcode uint8, length
// uint64, content), little endian. Schemas (0x03) name the message types, channels (0x04) the
// topics, messages (0x05) carry the serialised bytes; chunks (0x06) hold records, compressed with
// zstd or lz4. The summary section after DataEnd (0x0F) repeats schemas and channels and has the
// statistics (0x0B) with per-channel message counts; the footer (0x02) points at it.

#include <cstring>
#include <deque>
#include <fstream>
#include <map>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/bag_internal.hpp"

namespace multicue::io::detail {
namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};
enum Op : std::uint8_t {
    kFooter = 0x02,
    kSchema = 0x03,
    kChannel = 0x04,
    kMessage = 0x05,
    kChunk = 0x06,
    kStatistics = 0x0B,
    kDataEnd = 0x0F,
};

/// Reads the fields of one record's content.
class Fields {
  public:
    Fields(std::span<const std::uint8_t> bytes, const std::string& where)
        : bytes_(bytes), where_(where) {}
    const std::uint8_t* Take(std::size_t n) {
        if (n > bytes_.size() - pos_) {
            throw FormatError(fmt::format("{}: record field runs past its record", where_));
        }
        const std::uint8_t* p = bytes_.data() + pos_;
        pos_ += n;
        return p;
    }
    template <typename T>
    T Number() {
        T v;
        std::memcpy(&v, Take(sizeof(T)), sizeof(T));
        return v;
    }
    std::string String() {
        const auto n = Number<std::uint32_t>();
        const auto* p = Take(n);
        return std::string(reinterpret_cast<const char*>(p), n);
    }
    std::span<const std::uint8_t> Rest() {
        auto rest = bytes_.subspan(pos_);
        pos_ = bytes_.size();
        return rest;
    }
    std::span<const std::uint8_t> Bytes(std::uint64_t n) {
        const auto* p = Take(n);
        return {p, static_cast<std::size_t>(n)};
    }

  private:
    std::span<const std::uint8_t> bytes_;
    const std::string& where_;
    std::size_t pos_ = 0;
};

class McapBag : public BagReader {
  public:
    McapBag(const fs::path& path, const std::vector<std::string>& selected)
        : name_(path.string()), selected_(selected) {
        in_.open(path, std::ios::binary);
        if (!in_) throw IoError(fmt::format("{}: cannot open", name_));
        in_.seekg(0, std::ios::end);
        size_ = static_cast<std::uint64_t>(in_.tellg());
        in_.seekg(0);
        char magic[8] = {};
        in_.read(magic, 8);
        if (!in_ || std::memcmp(magic, kMagic, 8) != 0) {
            throw FormatError(fmt::format("{}: not an MCAP file (no MCAP magic)", name_));
        }
        if (!ReadSummary()) Prescan();
        in_.clear();
        in_.seekg(8);
        pos_ = 8;
    }

    const std::vector<BagTopic>& Topics() const override { return topics_; }

    bool Next(BagMessage& message) override {
        while (true) {
            if (!pending_.empty()) {
                message = std::move(pending_.front());
                pending_.pop_front();
                return true;
            }
            if (done_) return false;
            std::uint8_t op = 0;
            std::vector<std::uint8_t> content;
            if (!ReadRecord(op, content)) {
                done_ = true;
                throw FormatError(fmt::format(
                    "{}: truncated: ends at byte {} inside the data section (no footer)", name_,
                    size_));
            }
            if (op == kDataEnd || op == kFooter) {
                done_ = true;
                continue;
            }
            Handle(op, content, true);
        }
    }

  private:
    /// The next record at pos_; false when the file ends before it does.
    bool ReadRecord(std::uint8_t& op, std::vector<std::uint8_t>& content) {
        if (pos_ + 9 > size_) return false;
        char head[9];
        in_.seekg(static_cast<std::streamoff>(pos_));
        in_.read(head, 9);
        std::uint64_t length = 0;
        op = static_cast<std::uint8_t>(head[0]);
        std::memcpy(&length, head + 1, 8);
        if (length > size_ - pos_ - 9) return false;
        content.resize(length);
        in_.read(reinterpret_cast<char*>(content.data()), static_cast<std::streamsize>(length));
        if (!in_) return false;
        pos_ += 9 + length;
        return true;
    }

    /// Schemas, channels and statistics from the summary section; false if there is none.
    bool ReadSummary() {
        constexpr std::uint64_t kFooterRecord = 1 + 8 + 8 + 8 + 4;
        if (size_ < 8 + kFooterRecord + 8) return false;
        pos_ = size_ - 8 - kFooterRecord;
        std::uint8_t op = 0;
        std::vector<std::uint8_t> content;
        if (!ReadRecord(op, content) || op != kFooter) return false;
        char magic[8] = {};
        in_.read(magic, 8);
        if (!in_ || std::memcmp(magic, kMagic, 8) != 0) return false;
        Fields footer(content, name_);
        const auto summary_start = footer.Number<std::uint64_t>();
        if (summary_start == 0 || summary_start >= size_) return false;
        pos_ = summary_start;
        bool counted = false;
        while (ReadRecord(op, content) && op != kFooter) {
            if (op == kStatistics) {
                ReadStatistics(content);
                counted = true;
            } else if (op == kSchema || op == kChannel) {
                Handle(op, content, false);
            }
        }
        return counted;
    }

    /// Without a summary: one pass over the file for the topics and their message counts.
    void Prescan() {
        pos_ = 8;
        counting_ = true;
        std::uint8_t op = 0;
        std::vector<std::uint8_t> content;
        while (ReadRecord(op, content) && op != kDataEnd && op != kFooter)
            Handle(op, content, false);
        counting_ = false;
    }

    void ReadStatistics(std::span<const std::uint8_t> content) {
        Fields f(content, name_);
        f.Take(8 + 2 + 4 + 4 + 4 + 4 + 8 + 8);
        const auto bytes = f.Number<std::uint32_t>();
        Fields map(f.Bytes(bytes), name_);
        for (std::uint32_t k = 0; k < bytes / 10; ++k) {
            const auto channel = map.Number<std::uint16_t>();
            const auto count = map.Number<std::uint64_t>();
            if (const auto it = channels_.find(channel); it != channels_.end())
                topics_[it->second].messages += count;
            else
                early_counts_[channel] += count;
        }
    }

    /// One record: schema, channel or message (deliver: queue it), or a chunk of them.
    void Handle(std::uint8_t op, std::span<const std::uint8_t> content, bool deliver) {
        const std::string where = fmt::format("{}: record 0x{:02x}", name_, op);
        Fields f(content, where);
        if (op == kSchema) {
            const auto id = f.Number<std::uint16_t>();
            schemas_[id] = f.String();
        } else if (op == kChannel) {
            const auto id = f.Number<std::uint16_t>();
            const auto schema = f.Number<std::uint16_t>();
            const std::string topic = f.String();
            const std::string encoding = f.String();
            if (channels_.count(id) != 0) return;
            const auto it = schemas_.find(schema);
            channels_[id] = topics_.size();
            topics_.push_back({topic, it != schemas_.end() ? it->second : "", encoding, 0});
            if (const auto c = early_counts_.find(id); c != early_counts_.end())
                topics_.back().messages = c->second;
        } else if (op == kMessage) {
            const auto channel = f.Number<std::uint16_t>();
            f.Number<std::uint32_t>();  // sequence
            const auto log_time = f.Number<std::uint64_t>();
            f.Number<std::uint64_t>();  // publish time
            const auto it = channels_.find(channel);
            if (it == channels_.end()) {
                throw FormatError(fmt::format("{}: message on unknown channel {}", name_, channel));
            }
            const BagTopic& topic = topics_[it->second];
            if (counting_) ++topics_[it->second].messages;
            if (!deliver || !Selected(topic.name)) return;
            const auto data = f.Rest();
            BagMessage m;
            m.topic = topic.name;
            m.log_time_ns = static_cast<std::int64_t>(log_time);
            m.data.assign(data.begin(), data.end());
            pending_.push_back(std::move(m));
        } else if (op == kChunk) {
            f.Number<std::uint64_t>();  // start time
            f.Number<std::uint64_t>();  // end time
            const auto uncompressed = f.Number<std::uint64_t>();
            f.Number<std::uint32_t>();  // crc
            const std::string compression = f.String();
            const auto bytes = f.Number<std::uint64_t>();
            const auto records = Decompress(compression, f.Bytes(bytes), uncompressed, where);
            std::size_t p = 0;
            while (p < records.size()) {
                if (records.size() - p < 9) throw FormatError(where + ": truncated chunk");
                std::uint64_t length = 0;
                std::memcpy(&length, records.data() + p + 1, 8);
                if (length > records.size() - p - 9) throw FormatError(where + ": truncated chunk");
                Handle(records[p], std::span(records).subspan(p + 9, length), deliver);
                p += 9 + length;
            }
        }
    }

    bool Selected(const std::string& topic) const {
        if (selected_.empty()) return true;
        for (const auto& s : selected_) {
            if (s == topic) return true;
        }
        return false;
    }

    std::string name_;
    std::vector<std::string> selected_;
    std::ifstream in_;
    std::uint64_t size_ = 0;
    std::uint64_t pos_ = 0;
    std::map<std::uint16_t, std::string> schemas_;
    std::map<std::uint16_t, std::size_t> channels_;  // channel id -> index into topics_
    std::map<std::uint16_t, std::uint64_t> early_counts_;
    std::vector<BagTopic> topics_;
    std::deque<BagMessage> pending_;
    bool counting_ = false;
    bool done_ = false;
};

}  // namespace

std::unique_ptr<BagReader> OpenMcapBag(const fs::path& path,
                                       const std::vector<std::string>& topics) {
    return std::make_unique<McapBag>(path, topics);
}

}  // namespace multicue::io::detail
