#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/system/object_database.hpp"
#include "test_util.hpp"

namespace multicue {
namespace {

ObjectView MakeView(double time, float seed, const Eigen::Vector3d& position) {
    ObjectView v;
    v.time = time;
    v.frame = "frame-" + std::to_string(static_cast<int>(time));
    v.category = "cylinder";
    v.category_probabilities = {{"cylinder", 0.75}, {"box", 0.25}};
    v.descriptors["grsd-"] = {seed, seed + 1.0f, 0.0f, 2.5f};
    v.descriptors["colour"] = {0.5f, 0.25f};
    v.model = {{"type", "cylinder"}, {"radius", 0.04}};
    v.mesh_ply = std::string("ply\nformat binary_little_endian 1.0\n\0\x01\xff", 38);
    v.pose.block<3, 1>(0, 3) = position;
    return v;
}

ObjectRecord NewObject() {
    ObjectRecord o;
    o.created = 0.5;
    return o;
}

void RunSql(const std::filesystem::path& path, const char* sql) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    char* message = nullptr;
    const int rc = sqlite3_exec(db, sql, nullptr, nullptr, &message);
    const std::string text = message != nullptr ? message : "";
    sqlite3_free(message);
    sqlite3_close(db);
    ASSERT_EQ(rc, SQLITE_OK) << text;
}

TEST(ObjectDatabase, StoresObjectsWithViewsAndReadsThemBackAfterReopening) {
    test::TempDir dir;
    const auto path = dir / "objects.db";
    std::int64_t id = 0;
    {
        auto db = ObjectDatabase::Open(path, DatabaseMode::kCreateOrWrite);
        EXPECT_EQ(db.schema_version(), ObjectDatabase::kSchemaVersion);
        ObjectRecord o;
        o.category = "cylinder";
        o.created = 1.0;
        id = db.AddObjectWithView(o, MakeView(1.0, 3.0f, {0.1, 0.2, 0.7}));
        db.AddView([&] {
            auto v = MakeView(5.0, 4.0f, {0.1, 0.25, 0.7});
            v.object_id = id;
            return v;
        }());
    }
    auto db = ObjectDatabase::Open(path, DatabaseMode::kReadOnly);
    const auto objects = db.ListObjects();
    ASSERT_EQ(objects.size(), 1u);
    EXPECT_EQ(objects[0].name, "object-" + std::to_string(id));
    EXPECT_EQ(objects[0].num_views, 2u);
    EXPECT_DOUBLE_EQ(objects[0].last_seen, 5.0);
    EXPECT_DOUBLE_EQ(objects[0].last_pose(1, 3), 0.25);
    const auto views = db.GetViews(id);
    ASSERT_EQ(views.size(), 2u);
    const auto expected = MakeView(1.0, 3.0f, {0.1, 0.2, 0.7});
    EXPECT_EQ(views[0].descriptors, expected.descriptors);
    EXPECT_EQ(views[0].category_probabilities, expected.category_probabilities);
    EXPECT_EQ(views[0].model, expected.model);
    EXPECT_EQ(views[0].mesh_ply, expected.mesh_ply);
    EXPECT_TRUE(views[0].pose.isApprox(expected.pose));
}

TEST(ObjectDatabase, FindsObjectsByPositionNearestFirst) {
    test::TempDir dir;
    auto db = ObjectDatabase::Open(dir / "o.db", DatabaseMode::kCreateOrWrite);
    const auto a = db.AddObjectWithView(NewObject(), MakeView(1, 0, {0.0, 0.0, 1.0}));
    const auto b = db.AddObjectWithView(NewObject(), MakeView(1, 0, {0.03, 0.0, 1.0}));
    db.AddObjectWithView(NewObject(), MakeView(1, 0, {0.5, 0.0, 1.0}));
    const auto near = db.ObjectsNear({0.025, 0.0, 1.0}, 0.05);
    ASSERT_EQ(near.size(), 2u);
    EXPECT_EQ(near[0].id, b);
    EXPECT_EQ(near[1].id, a);
}

TEST(ObjectDatabase, AFailedWriteChangesNothing) {
    test::TempDir dir;
    auto db = ObjectDatabase::Open(dir / "o.db", DatabaseMode::kCreateOrWrite);
    ObjectView orphan = MakeView(1, 0, {0, 0, 0});
    orphan.object_id = 42;
    EXPECT_THROW(db.AddView(orphan), DataError);
    auto bad = MakeView(1, 0, {0, 0, 0});
    bad.descriptors["vfh"] = {1.0f, std::numeric_limits<float>::quiet_NaN()};
    EXPECT_THROW(db.AddObjectWithView(NewObject(), bad), DataError);
    EXPECT_TRUE(db.ListObjects().empty());
}

TEST(ObjectDatabase, ExportImportRoundTripAndAtomicImport) {
    test::TempDir dir;
    auto db = ObjectDatabase::Open(dir / "a.db", DatabaseMode::kCreateOrWrite);
    ObjectRecord named;
    named.name = "red mug";
    named.category = "cylinder";
    db.AddObjectWithView(named, MakeView(2, 1, {0.2, 0.1, 0.9}));
    const auto exported = db.Export();

    auto other = ObjectDatabase::Open(dir / "b.db", DatabaseMode::kCreateOrWrite);
    EXPECT_EQ(other.Import(exported), 1u);
    EXPECT_EQ(other.Export(), exported);

    auto broken = exported;
    broken["objects"].push_back({{"name", "x"}, {"last_pose", {1, 2, 3}}});
    EXPECT_THROW(other.Import(broken), FormatError);
    EXPECT_EQ(other.ListObjects().size(), 1u);  // the valid first object was rolled back too
    EXPECT_THROW(other.Import(nlohmann::json{{"objects", 1}}), FormatError);
}

TEST(ObjectDatabase, RefusesNewerSchemasForeignFilesAndMissingFiles) {
    test::TempDir dir;
    const auto path = dir / "o.db";
    ObjectDatabase::Open(path, DatabaseMode::kCreateOrWrite);
    RunSql(path, "PRAGMA user_version=99");
    try {
        ObjectDatabase::Open(path, DatabaseMode::kReadWrite);
        FAIL() << "a newer schema was accepted";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("newer"), std::string::npos) << e.what();
    }

    const auto foreign = dir / "foreign.db";
    RunSql(foreign, "CREATE TABLE things(x)");
    EXPECT_THROW(ObjectDatabase::Open(foreign, DatabaseMode::kReadWrite), FormatError);

    const auto text = dir / "notes.txt";
    std::ofstream(text) << "this is not a database, it is a text file of some length.........";
    EXPECT_THROW(ObjectDatabase::Open(text, DatabaseMode::kReadWrite), IoError);
    EXPECT_THROW(ObjectDatabase::Open(dir / "missing.db", DatabaseMode::kReadOnly), IoError);
    EXPECT_FALSE(std::filesystem::exists(dir / "missing.db"));
}

TEST(ObjectDatabase, MigratesVersionOneFiles) {
    test::TempDir dir;
    const auto path = dir / "old.db";
    ObjectDatabase::Open(path, DatabaseMode::kCreateOrWrite)
        .AddObjectWithView(NewObject(), MakeView(1, 0, {0.0, 0.0, 0.0}));
    // Turn the file back into the first schema.
    RunSql(path, "ALTER TABLE views DROP COLUMN category_probabilities; PRAGMA user_version=1");
    EXPECT_THROW(ObjectDatabase::Open(path, DatabaseMode::kReadOnly), FormatError);
    auto db = ObjectDatabase::Open(path, DatabaseMode::kReadWrite);
    EXPECT_EQ(db.schema_version(), 2);
    const auto views = db.GetViews(db.ListObjects().at(0).id);
    ASSERT_EQ(views.size(), 1u);
    EXPECT_TRUE(views[0].category_probabilities.empty());
    EXPECT_EQ(views[0].descriptors.size(), 2u);
}

TEST(ObjectDatabase, AReaderWorksWhileAWriterHoldsATransaction) {
    test::TempDir dir;
    const auto path = dir / "o.db";
    auto writer = ObjectDatabase::Open(path, DatabaseMode::kCreateOrWrite);
    writer.AddObjectWithView(NewObject(), MakeView(1, 0, {0.0, 0.0, 0.0}));

    std::mutex mutex;
    std::condition_variable cv;
    bool written = false;
    bool read = false;
    std::size_t seen_by_reader = 0;
    std::thread reader([&] {
        std::unique_lock<std::mutex> lock(mutex);
        cv.wait(lock, [&] { return written; });
        auto db = ObjectDatabase::Open(path, DatabaseMode::kReadOnly);
        seen_by_reader = db.ListObjects().size();
        read = true;
        cv.notify_all();
    });
    writer.Transaction([&] {
        writer.AddObjectWithView(NewObject(), MakeView(2, 0, {0.0, 0.0, 0.0}));
        std::unique_lock<std::mutex> lock(mutex);
        written = true;
        cv.notify_all();
        cv.wait(lock, [&] { return read; });
    });
    reader.join();
    EXPECT_EQ(seen_by_reader, 1u);  // the committed state, not the open transaction
    EXPECT_EQ(writer.ListObjects().size(), 2u);
}

TEST(ObjectDatabase, AKilledWriterLosesNothingCommitted) {
    test::TempDir dir;
    const auto path = dir / "o.db";
    ObjectDatabase::Open(path, DatabaseMode::kCreateOrWrite);
    int fds[2];
    ASSERT_EQ(pipe(fds), 0);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        close(fds[0]);
        try {
            auto db = ObjectDatabase::Open(path, DatabaseMode::kReadWrite);
            for (int i = 0;; ++i) {
                db.AddObjectWithView(NewObject(), MakeView(i, static_cast<float>(i), {0, 0, 1}));
                const char byte = 1;  // one byte per committed object
                if (write(fds[1], &byte, 1) != 1) _exit(3);
            }
        } catch (...) {
            _exit(2);
        }
    }
    close(fds[1]);
    std::size_t committed = 0;
    char byte = 0;
    while (committed < 25 && read(fds[0], &byte, 1) == 1) ++committed;
    kill(child, SIGKILL);
    int status = 0;
    waitpid(child, &status, 0);
    while (read(fds[0], &byte, 1) == 1) ++committed;  // commits reported before the kill
    close(fds[0]);
    ASSERT_EQ(committed >= 25, true);

    auto db = ObjectDatabase::Open(path, DatabaseMode::kReadWrite);
    const auto objects = db.ListObjects();
    EXPECT_GE(objects.size(), committed);
    for (const auto& o : objects) EXPECT_EQ(o.num_views, 1u);
}

}  // namespace
}  // namespace multicue
