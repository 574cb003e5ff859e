#pragma once
// ROS 2 bags written the way rosbag2 writes them, for the bag reader's tests: a bag folder with
// metadata.yaml and an SQLite .db3 file (rosbag2's schema version 4 tables), or an MCAP file
// (uncompressed chunks, summary with statistics, as the mcap storage plugin writes).

#include <sqlite3.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace multicue::test {

struct Ros2BagMessage {
    std::string topic;
    std::int64_t timestamp_ns = 0;
    std::vector<std::uint8_t> data;  // CDR with its encapsulation header
};

struct Ros2BagTopic {
    std::string name;
    std::string type;
};

/// Writes DIR/metadata.yaml and DIR/<name>.db3.
inline void WriteRos2SqliteBag(const std::filesystem::path& dir, const std::string& name,
                               const std::vector<Ros2BagTopic>& topics,
                               const std::vector<Ros2BagMessage>& messages) {
    std::filesystem::create_directories(dir);
    const auto file = dir / (name + ".db3");
    std::filesystem::remove(file);
    sqlite3* db = nullptr;
    if (sqlite3_open(file.c_str(), &db) != SQLITE_OK) throw std::runtime_error("sqlite open");
    const auto exec = [&](const std::string& sql) {
        char* err = nullptr;
        if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
            const std::string what = err != nullptr ? err : "?";
            sqlite3_free(err);
            throw std::runtime_error(what);
        }
    };
    exec("PRAGMA journal_mode=MEMORY;");
    exec("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);");
    exec("INSERT INTO schema VALUES(4, 'humble');");
    exec(
        "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,"
        "metadata TEXT NOT NULL);");
    exec(
        "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
        "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL,"
        "type_description_hash TEXT NOT NULL);");
    exec(
        "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
        "timestamp INTEGER NOT NULL, data BLOB NOT NULL);");
    exec("CREATE INDEX timestamp_idx ON messages (timestamp ASC);");
    std::map<std::string, int> ids;
    for (const auto& t : topics) {
        ids[t.name] = static_cast<int>(ids.size()) + 1;
        exec("INSERT INTO topics VALUES(" + std::to_string(ids[t.name]) + ", '" + t.name + "', '" +
             t.type + "', 'cdr', '', '');");
    }
    sqlite3_stmt* st = nullptr;
    sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?,?,?)", -1, &st,
                       nullptr);
    exec("BEGIN;");
    for (const auto& m : messages) {
        sqlite3_bind_int(st, 1, ids.at(m.topic));
        sqlite3_bind_int64(st, 2, m.timestamp_ns);
        sqlite3_bind_blob(st, 3, m.data.data(), static_cast<int>(m.data.size()), SQLITE_TRANSIENT);
        if (sqlite3_step(st) != SQLITE_DONE) throw std::runtime_error("sqlite insert");
        sqlite3_reset(st);
    }
    exec("COMMIT;");
    sqlite3_finalize(st);
    sqlite3_close(db);
    std::ofstream yaml(dir / "metadata.yaml");
    yaml << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
         << "  relative_file_paths:\n    - " << name << ".db3\n  message_count: " << messages.size()
         << "\n";
}

/// Writes an MCAP file: header, one chunk per message group, data end, summary, footer.
class McapWriter {
  public:
    std::vector<std::uint8_t> Build(const std::vector<Ros2BagTopic>& topics,
                                    const std::vector<Ros2BagMessage>& messages,
                                    bool with_summary = true) {
        out_ = {};
        Raw("\x89MCAP0\r\n", 8);
        Record(0x01, [&](Buf& b) {
            b.Str("ros2");
            b.Str("multicue test");
        });
        std::map<std::string, std::uint16_t> channel;
        for (const auto& t : topics) {
            const auto id = static_cast<std::uint16_t>(channel.size() + 1);
            channel[t.name] = id;
        }
        const auto schemas_and_channels = [&]() {
            for (const auto& t : topics) {
                const auto id = channel[t.name];
                Record(0x03, [&](Buf& b) {
                    b.U16(id);
                    b.Str(t.type);
                    b.Str("ros2msg");
                    b.Str("");
                });
                Record(0x04, [&](Buf& b) {
                    b.U16(id);
                    b.U16(id);
                    b.Str(t.name);
                    b.Str("cdr");
                    b.U32(0);
                });
            }
        };
        schemas_and_channels();
        std::map<std::uint16_t, std::uint64_t> counts;
        std::uint32_t seq = 0;
        for (const auto& m : messages) {
            Buf inner;
            inner.U8(0x05);
            Buf msg;
            msg.U16(channel.at(m.topic));
            msg.U32(seq++);
            msg.U64(static_cast<std::uint64_t>(m.timestamp_ns));
            msg.U64(static_cast<std::uint64_t>(m.timestamp_ns));
            msg.bytes.insert(msg.bytes.end(), m.data.begin(), m.data.end());
            inner.U64(msg.bytes.size());
            inner.bytes.insert(inner.bytes.end(), msg.bytes.begin(), msg.bytes.end());
            ++counts[channel.at(m.topic)];
            Record(0x06, [&](Buf& b) {
                b.U64(static_cast<std::uint64_t>(m.timestamp_ns));
                b.U64(static_cast<std::uint64_t>(m.timestamp_ns));
                b.U64(inner.bytes.size());
                b.U32(0);
                b.Str("");
                b.U64(inner.bytes.size());
                b.bytes.insert(b.bytes.end(), inner.bytes.begin(), inner.bytes.end());
            });
        }
        Record(0x0F, [&](Buf& b) { b.U32(0); });
        std::uint64_t summary_start = 0;
        if (with_summary) {
            summary_start = out_.size();
            schemas_and_channels();
            Record(0x0B, [&](Buf& b) {
                b.U64(messages.size());
                b.U16(static_cast<std::uint16_t>(topics.size()));
                b.U32(static_cast<std::uint32_t>(topics.size()));
                b.U32(0);
                b.U32(0);
                b.U32(static_cast<std::uint32_t>(messages.size()));
                b.U64(0);
                b.U64(0);
                b.U32(static_cast<std::uint32_t>(counts.size() * 10));
                for (const auto& [id, n] : counts) {
                    b.U16(id);
                    b.U64(n);
                }
            });
        }
        Record(0x02, [&](Buf& b) {
            b.U64(summary_start);
            b.U64(0);
            b.U32(0);
        });
        Raw("\x89MCAP0\r\n", 8);
        return out_;
    }

  private:
    struct Buf {
        std::vector<std::uint8_t> bytes;
        template <typename T>
        void Num(T v) {
            const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
            bytes.insert(bytes.end(), p, p + sizeof(T));
        }
        void U8(std::uint8_t v) { bytes.push_back(v); }
        void U16(std::uint16_t v) { Num(v); }
        void U32(std::uint32_t v) { Num(v); }
        void U64(std::uint64_t v) { Num(v); }
        void Str(const std::string& s) {
            U32(static_cast<std::uint32_t>(s.size()));
            bytes.insert(bytes.end(), s.begin(), s.end());
        }
    };
    template <typename Fn>
    void Record(std::uint8_t op, Fn&& fill) {
        Buf b;
        fill(b);
        out_.push_back(op);
        const std::uint64_t n = b.bytes.size();
        const auto* p = reinterpret_cast<const std::uint8_t*>(&n);
        out_.insert(out_.end(), p, p + 8);
        out_.insert(out_.end(), b.bytes.begin(), b.bytes.end());
    }
    void Raw(const char* s, std::size_t n) {
        for (std::size_t k = 0; k < n; ++k) out_.push_back(static_cast<std::uint8_t>(s[k]));
    }

    std::vector<std::uint8_t> out_;
};

inline void WriteBytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& b) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

}  // namespace multicue::test
