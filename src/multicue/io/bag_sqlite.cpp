// rosbag2's SQLite storage: table `topics` (id, name, type, serialization_format, ...) and table
// `messages` (id, topic_id, timestamp [ns], data: the serialised message).

#include <sqlite3.h>

#include <map>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/bag_internal.hpp"

namespace multicue::io::detail {
namespace {

namespace fs = std::filesystem;

class SqliteBag : public BagReader {
  public:
    SqliteBag(const fs::path& path, const std::vector<std::string>& selected)
        : name_(path.string()) {
        if (sqlite3_open_v2(name_.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
            const std::string why = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
            Close();
            throw IoError(fmt::format("{}: cannot open ({})", name_, why));
        }
        try {
            ReadTopics(selected);
            Prepare();
        } catch (...) {
            Close();
            throw;
        }
    }
    ~SqliteBag() override { Close(); }
    SqliteBag(const SqliteBag&) = delete;
    SqliteBag& operator=(const SqliteBag&) = delete;

    const std::vector<BagTopic>& Topics() const override { return topics_; }

    bool Next(BagMessage& message) override {
        if (done_) return false;
        const int rc = sqlite3_step(messages_);
        if (rc == SQLITE_DONE) {
            done_ = true;
            return false;
        }
        if (rc != SQLITE_ROW) Fail("reading messages");
        const sqlite3_int64 topic_id = sqlite3_column_int64(messages_, 0);
        const auto topic = topic_names_.find(topic_id);
        if (topic == topic_names_.end()) {
            throw FormatError(
                fmt::format("{}: a message names topic id {}, which the topics table "
                            "does not have (corrupt bag?)",
                            name_, topic_id));
        }
        message.topic = topic->second;
        message.log_time_ns = sqlite3_column_int64(messages_, 1);
        const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(messages_, 2));
        const int bytes = sqlite3_column_bytes(messages_, 2);
        message.data.assign(blob, blob + (blob != nullptr ? bytes : 0));
        DecompressIfZstd(message.data, fmt::format("{}: message at {} ns on {}", name_,
                                                   message.log_time_ns, message.topic));
        return true;
    }

  private:
    [[noreturn]] void Fail(const std::string& what) const {
        throw FormatError(fmt::format("{}: {}: {} (not a rosbag2 SQLite file, or truncated?)",
                                      name_, what, sqlite3_errmsg(db_)));
    }

    void ReadTopics(const std::vector<std::string>& selected) {
        sqlite3_stmt* st = nullptr;
        if (sqlite3_prepare_v2(db_, "SELECT id, name, type, serialization_format FROM topics", -1,
                               &st, nullptr) != SQLITE_OK) {
            Fail("reading the topics table");
        }
        std::map<sqlite3_int64, std::size_t> index;
        int rc;
        while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
            const auto text = [&](int col) {
                const auto* t = sqlite3_column_text(st, col);
                return t != nullptr ? std::string(reinterpret_cast<const char*>(t)) : "";
            };
            const sqlite3_int64 id = sqlite3_column_int64(st, 0);
            index[id] = topics_.size();
            topics_.push_back({text(1), text(2), text(3), 0});
            topic_names_[id] = text(1);
        }
        sqlite3_finalize(st);
        if (rc != SQLITE_DONE) Fail("reading the topics table");

        if (sqlite3_prepare_v2(db_, "SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id", -1,
                               &st, nullptr) != SQLITE_OK) {
            Fail("counting messages");
        }
        while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
            const auto it = index.find(sqlite3_column_int64(st, 0));
            if (it != index.end())
                topics_[it->second].messages =
                    static_cast<std::uint64_t>(sqlite3_column_int64(st, 1));
        }
        sqlite3_finalize(st);
        if (rc != SQLITE_DONE) Fail("counting messages");
        for (const auto& [id, name] : topic_names_) {
            for (const auto& s : selected) {
                if (s == name) selected_ids_.push_back(id);
            }
        }
        filter_ = !selected.empty();
    }

    void Prepare() {
        std::string sql = "SELECT topic_id, timestamp, data FROM messages";
        if (filter_) {
            sql += " WHERE topic_id IN (";
            for (std::size_t k = 0; k < selected_ids_.size(); ++k)
                sql += fmt::format("{}{}", k == 0 ? "" : ",", selected_ids_[k]);
            sql += ")";
        }
        sql += " ORDER BY timestamp, id";
        if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &messages_, nullptr) != SQLITE_OK) {
            Fail("reading the messages table");
        }
    }

    void Close() {
        if (messages_ != nullptr) sqlite3_finalize(messages_);
        messages_ = nullptr;
        if (db_ != nullptr) sqlite3_close(db_);
        db_ = nullptr;
    }

    std::string name_;
    sqlite3* db_ = nullptr;
    sqlite3_stmt* messages_ = nullptr;
    std::vector<BagTopic> topics_;
    std::map<sqlite3_int64, std::string> topic_names_;
    std::vector<sqlite3_int64> selected_ids_;
    bool filter_ = false;
    bool done_ = false;
};

}  // namespace

std::unique_ptr<BagReader> OpenSqliteBag(const fs::path& path,
                                         const std::vector<std::string>& topics) {
    return std::make_unique<SqliteBag>(path, topics);
}

}  // namespace multicue::io::detail
