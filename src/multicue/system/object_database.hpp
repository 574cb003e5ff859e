#pragma once
/// \file The object model database of the perception system (thesis section 3.2): every object the
/// robot knows, each with the views it was learnt from (one descriptor per examination method, the
/// geometric category with its distribution, appearance, model parameters and an optional mesh),
/// and where and when it was last seen.
///
/// Storage is one SQLite file. Writes happen in transactions, so a crash or a killed process loses
/// nothing that was committed; the journal is in write-ahead mode, so readers (another process with
/// `multicue db list`, say) work while a writer learns. The schema carries a version
/// (`PRAGMA user_version`): older files are migrated on open, newer ones are refused.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace multicue {

/// One view of an object: what the examination methods saw in one frame.
struct ObjectView {
    std::int64_t id = 0;         ///< assigned by the database
    std::int64_t object_id = 0;  ///< the object this view belongs to
    double time = 0.0;           ///< seconds (frame time or wall clock)
    std::string frame;           ///< where the view came from (file name, frame index)
    std::string category;        ///< geometric category at the time ("" = unknown)
    std::map<std::string, double> category_probabilities;
    /// Descriptor per examination method or feature ("grsd-", "vfh", "colour", ...).
    std::map<std::string, std::vector<float>> descriptors;
    nlohmann::json model = nlohmann::json::object();     ///< model parameters (box, cylinder, ...)
    std::string mesh_ply;                                ///< optional mesh as PLY bytes
    Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();  ///< object pose in the map frame
};

/// One object with its identity and the place it was last seen.
struct ObjectRecord {
    std::int64_t id = 0;  ///< assigned by the database
    std::string name;     ///< user-given or generated ("object-7")
    std::string category;
    double created = 0.0;
    double last_seen = 0.0;
    Eigen::Matrix4d last_pose = Eigen::Matrix4d::Identity();
    std::size_t num_views = 0;  ///< filled by reads
};

/// How to open a database file.
enum class DatabaseMode {
    kReadOnly,       ///< the file must exist
    kReadWrite,      ///< the file must exist; migrated to the current schema if older
    kCreateOrWrite,  ///< created (empty, current schema) when missing
};

class ObjectDatabase {
  public:
    /// The schema this build writes. Version history is documented in docs/object-database.md.
    static constexpr int kSchemaVersion = 2;

    /// Opens (or creates) a database. Throws IoError if the file cannot be opened or is not an
    /// SQLite database, FormatError if its schema is newer than kSchemaVersion or not ours.
    static ObjectDatabase Open(const std::filesystem::path& path, DatabaseMode mode);

    ObjectDatabase(ObjectDatabase&&) noexcept;
    ObjectDatabase& operator=(ObjectDatabase&&) noexcept;
    ~ObjectDatabase();

    int schema_version() const;
    const std::filesystem::path& path() const;

    /// Adds an object and returns its id. An empty name becomes "object-<id>".
    std::int64_t AddObject(ObjectRecord object);
    /// Adds a view to an existing object (DataError if there is none) and updates the object's last
    /// pose and time when the view is newer. Returns the view's id.
    std::int64_t AddView(ObjectView view);
    /// Adds a new object together with its first view in one transaction; returns the object's id.
    std::int64_t AddObjectWithView(ObjectRecord object, ObjectView view);
    /// Records that an object was seen at `pose` at `time` without learning a view (ignored when
    /// an equal or newer sighting is stored). DataError if there is no such object.
    void UpdateLastSeen(std::int64_t id, double time, const Eigen::Matrix4d& pose);
    /// Renames or recategorises an object.
    void UpdateObject(const ObjectRecord& object);
    /// Removes an object and its views. Returns false if there was none.
    bool RemoveObject(std::int64_t id);

    std::vector<ObjectRecord> ListObjects() const;
    std::optional<ObjectRecord> GetObject(std::int64_t id) const;
    std::vector<ObjectView> GetViews(std::int64_t object_id) const;
    /// Objects last seen within `radius` of `position` (identity by position, section 3.2.4),
    /// nearest first.
    std::vector<ObjectRecord> ObjectsNear(const Eigen::Vector3d& position, double radius) const;

    /// The whole database as JSON (objects with their views; meshes base64-encoded).
    nlohmann::json Export() const;
    /// Adds every object of an export (new ids) in one transaction; nothing is added on an error.
    /// Returns the number of objects imported.
    std::size_t Import(const nlohmann::json& data);

    /// Runs `body` in one transaction: committed if it returns, rolled back if it throws.
    template <typename Body>
    void Transaction(Body&& body) {
        Begin();
        try {
            body();
        } catch (...) {
            Rollback();
            throw;
        }
        Commit();
    }

  private:
    struct Impl;
    explicit ObjectDatabase(std::unique_ptr<Impl> impl);
    void Begin();
    void Commit();
    void Rollback();
    std::int64_t InsertObject(ObjectRecord& object);
    std::int64_t InsertView(ObjectView& view);

    std::unique_ptr<Impl> impl_;
};

}  // namespace multicue
