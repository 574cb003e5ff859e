#include "multicue/system/object_database.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string_view>
#include <utility>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

constexpr std::string_view kApplicationTag = "multicue-object-database";
constexpr int kBusyTimeoutMs = 10000;

// Schema of version 1; later versions are reached by the migrations below, so a new file and a
// migrated old file are the same database.
constexpr const char* kSchemaV1 = R"sql(
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE objects (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT NOT NULL,
    category TEXT NOT NULL DEFAULT '',
    created REAL NOT NULL,
    last_seen REAL NOT NULL,
    last_pose BLOB NOT NULL
);
CREATE TABLE views (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    object_id INTEGER NOT NULL REFERENCES objects(id) ON DELETE CASCADE,
    time REAL NOT NULL,
    frame TEXT NOT NULL DEFAULT '',
    category TEXT NOT NULL DEFAULT '',
    model TEXT NOT NULL DEFAULT '{}',
    mesh BLOB,
    pose BLOB NOT NULL
);
CREATE INDEX views_by_object ON views(object_id);
CREATE TABLE descriptors (
    view_id INTEGER NOT NULL REFERENCES views(id) ON DELETE CASCADE,
    method TEXT NOT NULL,
    data BLOB NOT NULL,
    PRIMARY KEY (view_id, method)
);
)sql";

// Version 2: category distributions per view.
constexpr const char* kMigrationV1ToV2 = R"sql(
ALTER TABLE views ADD COLUMN category_probabilities TEXT NOT NULL DEFAULT '{}';
)sql";

// SQLite's message, with the system's reason when the operating system refused (a full disk, a
// file size limit, no permission).
std::string Describe(sqlite3* db) {
    if (db == nullptr) return "out of memory";
    std::string text = sqlite3_errmsg(db);
    if (const int e = sqlite3_system_errno(db); e != 0) {
        text += " (";
        text += std::strerror(e);
        text += ")";
    }
    return text;
}

class Statement {
  public:
    Statement(sqlite3* db, const char* sql, const std::filesystem::path& path) : db_(db) {
        if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) {
            throw IoError("object database " + path.string() + ": " + Describe(db));
        }
        path_ = path.string();
    }
    ~Statement() { sqlite3_finalize(stmt_); }
    Statement(const Statement&) = delete;
    Statement& operator=(const Statement&) = delete;

    Statement& Bind(int i, std::int64_t v) {
        Check(sqlite3_bind_int64(stmt_, i, v));
        return *this;
    }
    Statement& Bind(int i, double v) {
        Check(sqlite3_bind_double(stmt_, i, v));
        return *this;
    }
    Statement& Bind(int i, const std::string& v) {
        Check(sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
        return *this;
    }
    Statement& BindBlob(int i, const void* data, std::size_t bytes) {
        Check(sqlite3_bind_blob(stmt_, i, bytes == 0 ? "" : data, static_cast<int>(bytes),
                                SQLITE_TRANSIENT));
        return *this;
    }
    Statement& BindNull(int i) {
        Check(sqlite3_bind_null(stmt_, i));
        return *this;
    }
    /// Steps once; true while a row is available.
    bool Step() {
        const int rc = sqlite3_step(stmt_);
        if (rc == SQLITE_ROW) return true;
        if (rc == SQLITE_DONE) return false;
        throw IoError("object database " + path_ + ": " + Describe(db_));
    }
    std::int64_t Int(int col) const { return sqlite3_column_int64(stmt_, col); }
    double Real(int col) const { return sqlite3_column_double(stmt_, col); }
    std::string Text(int col) const {
        const auto* text = sqlite3_column_text(stmt_, col);
        return text != nullptr ? std::string(reinterpret_cast<const char*>(text)) : std::string();
    }
    std::string Blob(int col) const {
        const void* data = sqlite3_column_blob(stmt_, col);
        const int bytes = sqlite3_column_bytes(stmt_, col);
        return data != nullptr ? std::string(static_cast<const char*>(data), bytes) : std::string();
    }
    bool IsNull(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }

  private:
    void Check(int rc) const {
        if (rc != SQLITE_OK) throw IoError("object database " + path_ + ": " + Describe(db_));
    }
    sqlite3* db_ = nullptr;
    sqlite3_stmt* stmt_ = nullptr;
    std::string path_;
};

std::string PoseBlob(const Eigen::Matrix4d& pose) {
    std::string bytes(sizeof(double) * 16, '\0');
    std::memcpy(bytes.data(), pose.data(), bytes.size());
    return bytes;
}

Eigen::Matrix4d PoseFromBlob(const std::string& bytes, const std::string& where) {
    if (bytes.size() != sizeof(double) * 16) {
        throw FormatError("object database: " + where + " holds a pose of " +
                          std::to_string(bytes.size()) + " bytes (expected 128)");
    }
    Eigen::Matrix4d pose;
    std::memcpy(pose.data(), bytes.data(), bytes.size());
    return pose;
}

std::vector<double> PoseList(const Eigen::Matrix4d& pose) {
    // Row-major in files people read.
    std::vector<double> values;
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) values.push_back(pose(r, c));
    }
    return values;
}

Eigen::Matrix4d PoseFromJson(const nlohmann::json& value, const std::string& where) {
    if (!value.is_array() || value.size() != 16) {
        throw FormatError("object database import: " + where + " must be 16 numbers (row-major)");
    }
    Eigen::Matrix4d pose;
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
            const auto& v = value[static_cast<std::size_t>(r * 4 + c)];
            if (!v.is_number())
                throw FormatError("object database import: " + where + " not numeric");
            pose(r, c) = v.get<double>();
        }
    }
    return pose;
}

constexpr char kBase64Alphabet[] =
    "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

std::string EncodeBase64(const std::string& bytes) {
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const auto a = static_cast<unsigned char>(bytes[i]);
        const auto b = static_cast<unsigned char>(bytes[i + 1]);
        const auto c = static_cast<unsigned char>(bytes[i + 2]);
        out += kBase64Alphabet[a >> 2];
        out += kBase64Alphabet[((a & 3) << 4) | (b >> 4)];
        out += kBase64Alphabet[((b & 15) << 2) | (c >> 6)];
        out += kBase64Alphabet[c & 63];
    }
    if (i < bytes.size()) {
        const auto a = static_cast<unsigned char>(bytes[i]);
        const bool two = i + 1 < bytes.size();
        const auto b = two ? static_cast<unsigned char>(bytes[i + 1]) : 0;
        out += kBase64Alphabet[a >> 2];
        out += kBase64Alphabet[((a & 3) << 4) | (b >> 4)];
        out += two ? kBase64Alphabet[(b & 15) << 2] : '=';
        out += '=';
    }
    return out;
}

std::string DecodeBase64(const std::string& text, const std::string& where) {
    auto value = [&](char c) -> int {
        const char* p = std::strchr(kBase64Alphabet, c);
        if (c == '\0' || p == nullptr) {
            throw FormatError("object database import: " + where + " is not base64");
        }
        return static_cast<int>(p - kBase64Alphabet);
    };
    if (text.size() % 4 != 0)
        throw FormatError("object database import: " + where + " is not base64");
    std::string out;
    for (std::size_t i = 0; i < text.size(); i += 4) {
        const int a = value(text[i]);
        const int b = value(text[i + 1]);
        out += static_cast<char>((a << 2) | (b >> 4));
        if (text[i + 2] == '=') break;
        const int c = value(text[i + 2]);
        out += static_cast<char>(((b & 15) << 4) | (c >> 2));
        if (text[i + 3] == '=') break;
        const int d = value(text[i + 3]);
        out += static_cast<char>(((c & 3) << 6) | d);
    }
    return out;
}

}  // namespace

struct ObjectDatabase::Impl {
    sqlite3* db = nullptr;
    std::filesystem::path path;
    int version = 0;
    bool read_only = false;
    int depth = 0;  // nesting of Transaction()

    ~Impl() {
        if (db != nullptr) sqlite3_close_v2(db);
    }

    void Exec(const char* sql) const {
        char* message = nullptr;
        if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
            std::string text = message != nullptr ? message : Describe(db);
            if (const int e = sqlite3_system_errno(db); message != nullptr && e != 0) {
                text += " (";
                text += std::strerror(e);
                text += ")";
            }
            sqlite3_free(message);
            throw IoError("object database " + path.string() + ": " + text);
        }
    }

    int UserVersion() const {
        Statement s(db, "PRAGMA user_version", path);
        return s.Step() ? static_cast<int>(s.Int(0)) : 0;
    }

    bool HasTable(const char* name) const {
        Statement s(db, "SELECT 1 FROM sqlite_master WHERE type='table' AND name=?", path);
        s.Bind(1, std::string(name));
        return s.Step();
    }
};

ObjectDatabase::ObjectDatabase(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ObjectDatabase::ObjectDatabase(ObjectDatabase&&) noexcept = default;
ObjectDatabase& ObjectDatabase::operator=(ObjectDatabase&&) noexcept = default;
ObjectDatabase::~ObjectDatabase() = default;

ObjectDatabase ObjectDatabase::Open(const std::filesystem::path& path, DatabaseMode mode) {
    std::error_code ec;
    const bool exists = std::filesystem::exists(path, ec);
    if (!exists && mode != DatabaseMode::kCreateOrWrite) {
        throw IoError("object database " + path.string() +
                      " does not exist (create it with `multicue db init`)");
    }
    if (exists && std::filesystem::is_directory(path, ec)) {
        throw IoError("object database " + path.string() + " is a directory");
    }
    auto impl = std::make_unique<Impl>();
    impl->path = path;
    impl->read_only = mode == DatabaseMode::kReadOnly;
    const int flags =
        impl->read_only ? SQLITE_OPEN_READONLY : (SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
    if (sqlite3_open_v2(path.c_str(), &impl->db, flags | SQLITE_OPEN_FULLMUTEX, nullptr) !=
        SQLITE_OK) {
        throw IoError("cannot open object database " + path.string() + ": " + Describe(impl->db));
    }
    sqlite3_busy_timeout(impl->db, kBusyTimeoutMs);
    sqlite3_extended_result_codes(impl->db, 1);

    // Reading the header tells a non-database file apart ("file is not a database").
    int version = 0;
    try {
        version = impl->UserVersion();
    } catch (const IoError& e) {
        if ((sqlite3_errcode(impl->db) & 0xff) == SQLITE_NOTADB) {
            throw IoError("object database " + path.string() + " is not an SQLite database");
        }
        throw;
    }
    if (!impl->read_only) {
        impl->Exec("PRAGMA journal_mode=WAL");
        impl->Exec("PRAGMA synchronous=FULL");
    }
    impl->Exec("PRAGMA foreign_keys=ON");

    if (version > kSchemaVersion) {
        throw FormatError("object database " + path.string() + " has schema version " +
                          std::to_string(version) + ", newer than this multicue supports (" +
                          std::to_string(kSchemaVersion) + "); upgrade multicue to open it");
    }
    if (version == 0) {
        if (impl->HasTable("objects") || impl->HasTable("meta") || impl->HasTable("views")) {
            throw FormatError("object database " + path.string() +
                              " is an SQLite file of another application");
        }
        Statement any(impl->db, "SELECT count(*) FROM sqlite_master", path);
        if (any.Step() && any.Int(0) > 0) {
            throw FormatError("object database " + path.string() +
                              " is an SQLite file of another application");
        }
        if (impl->read_only) {
            throw FormatError("object database " + path.string() + " is empty (no schema)");
        }
        impl->Exec("BEGIN IMMEDIATE");
        try {
            impl->Exec(kSchemaV1);
            Statement tag(impl->db, "INSERT INTO meta(key, value) VALUES('application', ?)", path);
            tag.Bind(1, std::string(kApplicationTag));
            tag.Step();
            impl->Exec("PRAGMA user_version=1");
            impl->Exec("COMMIT");
        } catch (...) {
            sqlite3_exec(impl->db, "ROLLBACK", nullptr, nullptr, nullptr);
            throw;
        }
        version = 1;
    } else {
        bool ours = false;
        if (impl->HasTable("meta")) {
            Statement tag(impl->db, "SELECT value FROM meta WHERE key='application'", path);
            ours = tag.Step() && tag.Text(0) == kApplicationTag;
        }
        if (!ours) {
            throw FormatError("object database " + path.string() +
                              " is an SQLite file of another application");
        }
    }
    if (version < kSchemaVersion) {
        if (impl->read_only) {
            throw FormatError("object database " + path.string() + " has schema version " +
                              std::to_string(version) +
                              "; open it once for writing (e.g. `multicue db init`) to migrate");
        }
        impl->Exec("BEGIN IMMEDIATE");
        try {
            if (version < 2) impl->Exec(kMigrationV1ToV2);
            impl->Exec(("PRAGMA user_version=" + std::to_string(kSchemaVersion)).c_str());
            impl->Exec("COMMIT");
        } catch (...) {
            sqlite3_exec(impl->db, "ROLLBACK", nullptr, nullptr, nullptr);
            throw;
        }
        version = kSchemaVersion;
    }
    impl->version = version;
    return ObjectDatabase(std::move(impl));
}

int ObjectDatabase::schema_version() const { return impl_->version; }
const std::filesystem::path& ObjectDatabase::path() const { return impl_->path; }

void ObjectDatabase::Begin() {
    if (impl_->read_only) {
        throw InvalidArgument("object database " + impl_->path.string() + " is open read-only");
    }
    // The outermost level takes the write lock at once, so a transaction never fails half-way
    // because another writer got in first.
    impl_->Exec(impl_->depth == 0 ? "BEGIN IMMEDIATE" : "SAVEPOINT nested");
    ++impl_->depth;
}

void ObjectDatabase::Commit() {
    --impl_->depth;
    impl_->Exec(impl_->depth == 0 ? "COMMIT" : "RELEASE nested");
}

void ObjectDatabase::Rollback() {
    --impl_->depth;
    const char* sql = impl_->depth == 0 ? "ROLLBACK" : "ROLLBACK TO nested; RELEASE nested";
    sqlite3_exec(impl_->db, sql, nullptr, nullptr, nullptr);
}

std::int64_t ObjectDatabase::InsertObject(ObjectRecord& object) {
    Statement s(impl_->db,
                "INSERT INTO objects(name, category, created, last_seen, last_pose) "
                "VALUES(?, ?, ?, ?, ?)",
                impl_->path);
    const std::string pose = PoseBlob(object.last_pose);
    s.Bind(1, object.name).Bind(2, object.category).Bind(3, object.created);
    s.Bind(4, object.last_seen).BindBlob(5, pose.data(), pose.size());
    s.Step();
    object.id = sqlite3_last_insert_rowid(impl_->db);
    if (object.name.empty()) {
        object.name = "object-" + std::to_string(object.id);
        Statement rename(impl_->db, "UPDATE objects SET name=? WHERE id=?", impl_->path);
        rename.Bind(1, object.name).Bind(2, object.id);
        rename.Step();
    }
    return object.id;
}

std::int64_t ObjectDatabase::InsertView(ObjectView& view) {
    {
        Statement owner(impl_->db, "SELECT last_seen FROM objects WHERE id=?", impl_->path);
        owner.Bind(1, view.object_id);
        if (!owner.Step()) {
            throw DataError("object database: no object with id " + std::to_string(view.object_id));
        }
        if (view.time >= owner.Real(0)) {
            Statement seen(impl_->db, "UPDATE objects SET last_seen=?, last_pose=? WHERE id=?",
                           impl_->path);
            const std::string pose = PoseBlob(view.pose);
            seen.Bind(1, view.time).BindBlob(2, pose.data(), pose.size()).Bind(3, view.object_id);
            seen.Step();
        }
    }
    Statement s(impl_->db,
                "INSERT INTO views(object_id, time, frame, category, model, mesh, pose, "
                "category_probabilities) VALUES(?, ?, ?, ?, ?, ?, ?, ?)",
                impl_->path);
    const std::string pose = PoseBlob(view.pose);
    s.Bind(1, view.object_id).Bind(2, view.time).Bind(3, view.frame).Bind(4, view.category);
    s.Bind(5, view.model.dump());
    if (view.mesh_ply.empty()) {
        s.BindNull(6);
    } else {
        s.BindBlob(6, view.mesh_ply.data(), view.mesh_ply.size());
    }
    s.BindBlob(7, pose.data(), pose.size());
    s.Bind(8, nlohmann::json(view.category_probabilities).dump());
    s.Step();
    view.id = sqlite3_last_insert_rowid(impl_->db);
    for (const auto& [method, values] : view.descriptors) {
        for (float v : values) {
            if (!std::isfinite(v)) {
                throw DataError("object database: descriptor '" + method +
                                "' holds a non-finite value");
            }
        }
        Statement d(impl_->db, "INSERT INTO descriptors(view_id, method, data) VALUES(?, ?, ?)",
                    impl_->path);
        d.Bind(1, view.id)
            .Bind(2, method)
            .BindBlob(3, values.data(), values.size() * sizeof(float));
        d.Step();
    }
    return view.id;
}

std::int64_t ObjectDatabase::AddObject(ObjectRecord object) {
    std::int64_t id = 0;
    Transaction([&] { id = InsertObject(object); });
    return id;
}

std::int64_t ObjectDatabase::AddView(ObjectView view) {
    std::int64_t id = 0;
    Transaction([&] { id = InsertView(view); });
    return id;
}

std::int64_t ObjectDatabase::AddObjectWithView(ObjectRecord object, ObjectView view) {
    std::int64_t id = 0;
    Transaction([&] {
        id = InsertObject(object);
        view.object_id = id;
        InsertView(view);
    });
    return id;
}

void ObjectDatabase::UpdateLastSeen(std::int64_t id, double time, const Eigen::Matrix4d& pose) {
    Transaction([&] {
        Statement s(impl_->db,
                    "UPDATE objects SET last_seen=?, last_pose=? WHERE id=? AND last_seen<?",
                    impl_->path);
        const std::string blob = PoseBlob(pose);
        s.Bind(1, time).BindBlob(2, blob.data(), blob.size()).Bind(3, id).Bind(4, time);
        s.Step();
        if (sqlite3_changes(impl_->db) == 0 && !GetObject(id)) {
            throw DataError("object database: no object with id " + std::to_string(id));
        }
    });
}

void ObjectDatabase::UpdateObject(const ObjectRecord& object) {
    Transaction([&] {
        Statement s(impl_->db, "UPDATE objects SET name=?, category=? WHERE id=?", impl_->path);
        s.Bind(1, object.name).Bind(2, object.category).Bind(3, object.id);
        s.Step();
        if (sqlite3_changes(impl_->db) == 0) {
            throw DataError("object database: no object with id " + std::to_string(object.id));
        }
    });
}

bool ObjectDatabase::RemoveObject(std::int64_t id) {
    bool removed = false;
    Transaction([&] {
        Statement s(impl_->db, "DELETE FROM objects WHERE id=?", impl_->path);
        s.Bind(1, id);
        s.Step();
        removed = sqlite3_changes(impl_->db) > 0;
    });
    return removed;
}

namespace {
constexpr const char* kSelectObjects =
    "SELECT o.id, o.name, o.category, o.created, o.last_seen, o.last_pose, "
    "(SELECT count(*) FROM views v WHERE v.object_id = o.id) FROM objects o";

ObjectRecord ReadObjectRow(const Statement& s) {
    ObjectRecord o;
    o.id = s.Int(0);
    o.name = s.Text(1);
    o.category = s.Text(2);
    o.created = s.Real(3);
    o.last_seen = s.Real(4);
    o.last_pose = PoseFromBlob(s.Blob(5), "object " + std::to_string(o.id));
    o.num_views = static_cast<std::size_t>(s.Int(6));
    return o;
}
}  // namespace

std::vector<ObjectRecord> ObjectDatabase::ListObjects() const {
    Statement s(impl_->db, (std::string(kSelectObjects) + " ORDER BY o.id").c_str(), impl_->path);
    std::vector<ObjectRecord> objects;
    while (s.Step()) objects.push_back(ReadObjectRow(s));
    return objects;
}

std::optional<ObjectRecord> ObjectDatabase::GetObject(std::int64_t id) const {
    Statement s(impl_->db, (std::string(kSelectObjects) + " WHERE o.id=?").c_str(), impl_->path);
    s.Bind(1, id);
    if (!s.Step()) return std::nullopt;
    return ReadObjectRow(s);
}

std::vector<ObjectView> ObjectDatabase::GetViews(std::int64_t object_id) const {
    Statement s(impl_->db,
                "SELECT id, object_id, time, frame, category, model, mesh, pose, "
                "category_probabilities FROM views WHERE object_id=? ORDER BY time, id",
                impl_->path);
    s.Bind(1, object_id);
    std::vector<ObjectView> views;
    while (s.Step()) {
        ObjectView v;
        v.id = s.Int(0);
        v.object_id = s.Int(1);
        v.time = s.Real(2);
        v.frame = s.Text(3);
        v.category = s.Text(4);
        const std::string where = "view " + std::to_string(v.id);
        try {
            v.model = nlohmann::json::parse(s.Text(5));
            v.category_probabilities =
                nlohmann::json::parse(s.Text(8)).get<std::map<std::string, double>>();
        } catch (const nlohmann::json::exception&) {
            throw FormatError("object database: " + where + " holds malformed JSON");
        }
        if (!s.IsNull(6)) v.mesh_ply = s.Blob(6);
        v.pose = PoseFromBlob(s.Blob(7), where);
        views.push_back(std::move(v));
    }
    for (auto& v : views) {
        Statement d(impl_->db,
                    "SELECT method, data FROM descriptors WHERE view_id=? ORDER BY method",
                    impl_->path);
        d.Bind(1, v.id);
        while (d.Step()) {
            const std::string bytes = d.Blob(1);
            if (bytes.size() % sizeof(float) != 0) {
                throw FormatError("object database: view " + std::to_string(v.id) +
                                  " holds a truncated descriptor");
            }
            std::vector<float> values(bytes.size() / sizeof(float));
            if (!bytes.empty()) std::memcpy(values.data(), bytes.data(), bytes.size());
            v.descriptors[d.Text(0)] = std::move(values);
        }
    }
    return views;
}

std::vector<ObjectRecord> ObjectDatabase::ObjectsNear(const Eigen::Vector3d& position,
                                                      double radius) const {
    std::vector<std::pair<double, ObjectRecord>> near;
    for (auto& o : ListObjects()) {
        const double d = (o.last_pose.block<3, 1>(0, 3) - position).norm();
        if (d <= radius) near.emplace_back(d, std::move(o));
    }
    std::stable_sort(near.begin(), near.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<ObjectRecord> out;
    for (auto& [d, o] : near) out.push_back(std::move(o));
    return out;
}

nlohmann::json ObjectDatabase::Export() const {
    nlohmann::json objects = nlohmann::json::array();
    for (const auto& o : ListObjects()) {
        nlohmann::json views = nlohmann::json::array();
        for (const auto& v : GetViews(o.id)) {
            nlohmann::json view{{"time", v.time},
                                {"frame", v.frame},
                                {"category", v.category},
                                {"category_probabilities", v.category_probabilities},
                                {"descriptors", v.descriptors},
                                {"model", v.model},
                                {"pose", PoseList(v.pose)}};
            if (!v.mesh_ply.empty()) view["mesh_ply_base64"] = EncodeBase64(v.mesh_ply);
            views.push_back(std::move(view));
        }
        objects.push_back({{"name", o.name},
                           {"category", o.category},
                           {"created", o.created},
                           {"last_seen", o.last_seen},
                           {"last_pose", PoseList(o.last_pose)},
                           {"views", std::move(views)}});
    }
    nlohmann::json out{{"format", kApplicationTag},
                       {"schema_version", kSchemaVersion},
                       {"objects", std::move(objects)}};
    // Names, frames and categories come from the file as they are: text that is not UTF-8 (a
    // damaged file) cannot be written as JSON, and is said so here rather than by the caller's
    // dump.
    try {
        (void)out.dump();
    } catch (const nlohmann::json::type_error& e) {
        throw FormatError(std::string("object database export: the database holds text that is not "
                                      "UTF-8 (") +
                          e.what() + ")");
    }
    return out;
}

std::size_t ObjectDatabase::Import(const nlohmann::json& data) {
    if (!data.is_object() || !data.contains("format") || !data["format"].is_string() ||
        data["format"].get<std::string>() != kApplicationTag) {
        throw FormatError("object database import: not an export of a multicue object database");
    }
    if (!data.contains("schema_version") || !data["schema_version"].is_number_integer() ||
        data["schema_version"].get<int>() > kSchemaVersion) {
        throw FormatError("object database import: schema version missing or newer than " +
                          std::to_string(kSchemaVersion));
    }
    if (!data.contains("objects") || !data["objects"].is_array()) {
        throw FormatError("object database import: no 'objects' array");
    }
    std::size_t count = 0;
    Transaction([&] {
        for (const auto& item : data["objects"]) {
            const std::string where = "object " + std::to_string(count + 1);
            try {
                ObjectRecord o;
                o.name = item.at("name").get<std::string>();
                o.category = item.value("category", std::string());
                o.created = item.value("created", 0.0);
                o.last_seen = item.value("last_seen", 0.0);
                o.last_pose = PoseFromJson(item.at("last_pose"), where + " last_pose");
                InsertObject(o);
                for (const auto& jv : item.value("views", nlohmann::json::array())) {
                    ObjectView v;
                    v.object_id = o.id;
                    v.time = jv.value("time", 0.0);
                    v.frame = jv.value("frame", std::string());
                    v.category = jv.value("category", std::string());
                    v.category_probabilities =
                        jv.value("category_probabilities", std::map<std::string, double>());
                    v.descriptors =
                        jv.value("descriptors", std::map<std::string, std::vector<float>>());
                    v.model = jv.value("model", nlohmann::json::object());
                    v.pose = PoseFromJson(jv.at("pose"), where + " view pose");
                    if (jv.contains("mesh_ply_base64")) {
                        v.mesh_ply =
                            DecodeBase64(jv["mesh_ply_base64"].get<std::string>(), where + " mesh");
                    }
                    InsertView(v);
                }
            } catch (const nlohmann::json::exception& e) {
                throw FormatError("object database import: " + where + ": " + e.what());
            }
            ++count;
        }
    });
    return count;
}

}  // namespace multicue
