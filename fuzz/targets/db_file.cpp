// An object database file (SQLite) of unknown origin opened read-only and read through.

#include <filesystem>
#include <system_error>

#include "fuzz_target.hpp"
#include "multicue/system/object_database.hpp"

MULTICUE_FUZZ_TARGET(db_file) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "objects.db");
    // SQLite's journal files of the previous input would otherwise be read with this one.
    std::error_code ec;
    for (const char* suffix : {"-wal", "-shm", "-journal"}) {
        std::filesystem::remove(path.string() + suffix, ec);
    }
    fuzz::AllowTypedErrors([&] {
        const auto db = ObjectDatabase::Open(path, DatabaseMode::kReadOnly);
        for (const auto& o : db.ListObjects()) db.GetViews(o.id);
        db.ObjectsNear(Eigen::Vector3d::Zero(), 1.0);
        db.Export().dump();
    });
}
