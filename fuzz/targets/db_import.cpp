// `multicue db import`: a JSON export added to a fresh database (in memory), then exported again.

#include "fuzz_target.hpp"
#include "multicue/io/json_text.hpp"
#include "multicue/system/object_database.hpp"

MULTICUE_FUZZ_TARGET(db_import) {
    using namespace multicue;
    const auto path = fuzz::WriteInput(fuzz::Bytes(data, size), "export.json");
    fuzz::AllowTypedErrors([&] {
        const nlohmann::json j = io::ReadJsonFile(path);
        auto db = ObjectDatabase::Open(":memory:", DatabaseMode::kCreateOrWrite);
        db.Import(j);
        db.Export().dump();
    });
}
