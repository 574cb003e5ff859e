// Incremental learning of a new object, after thesis section 3.2.4 and Table 3.3.
//
// Known objects are learnt from one view each. Then a table with those objects and one unknown
// object is seen from viewpoints around it; identification uses the database's views only
// (identity by position off), before and after a pass in which the executive learns the novel
// object and new views of every object by continuous observation at the same place.
//
//   build/eval/executive_sequence [VIEWS]

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>

#include <fmt/format.h>
#include <unistd.h>

#include "driver_options.hpp"
#include "executive_common.hpp"

namespace {

using namespace multicue;

/// The ground-truth object (mOSD label / 10 - 1) most of a hypothesis's points belong to, 0 if
/// none.
int TrueObject(const Frame& frame, const Hypothesis& h) {
    std::map<int, int> votes;
    for (auto i : h.indices) {
        const auto label = frame.cloud.labels[i];
        if (label >= 20) ++votes[static_cast<int>(label / 10) - 1];
    }
    int best = 0, count = 0;
    for (const auto& [object, n] : votes) {
        if (n > count) {
            best = object;
            count = n;
        }
    }
    return best;
}

struct Tally {
    int views = 0, known = 0, failures = 0, unknown = 0, correct = 0;
};

Tally Evaluate(ObjectDatabase& db, const sim::TableTopScene& scene, int num_views,
               const std::map<int, std::int64_t>& identity) {
    ExecutiveParams params;
    params.same_place_radius = 0.0;  // identify from the stored views alone
    PerceptionExecutive executive(&db, params);
    Task task;
    task.learn = false;
    Tally t;
    for (int v = 0; v < num_views; ++v) {
        const float angle =
            -0.7f + 1.4f * static_cast<float>(v) / static_cast<float>(num_views - 1);
        const Frame frame = bench::ViewOfScene(scene, angle, 100.0 + v, 1000 + v);
        for (const auto& h : executive.Run(frame, task).hypotheses) {
            const int gt = TrueObject(frame, h);
            if (gt == 0) continue;
            ++t.views;
            const auto it = identity.find(gt);
            if (it == identity.end()) {
                ++t.unknown;  // an object the database does not hold yet
                continue;
            }
            ++t.known;
            if (h.object_id == it->second) {
                ++t.correct;
            } else {
                ++t.failures;
            }
        }
    }
    return t;
}

void PrintRow(const char* name, const Tally& t) {
    const double with = t.views > 0 ? 100.0 * t.correct / t.views : 0.0;
    const double without = t.known > 0 ? 100.0 * t.correct / t.known : 0.0;
    std::printf("| %-6s | %5d/%-5d | %8d | %8d | %6.1f%% / %5.1f%% |\n", name, t.views, t.known,
                t.failures, t.unknown, with, without);
}

}  // namespace

int main(int argc, char** argv) {
    int num_views = 12;
    CLI::App app{
        "executive_sequence: identification of known objects and learning of a new one over a "
        "sequence of views (thesis Table 3.3)"};
    app.add_option("VIEWS", num_views, "views in the sequence")
        ->capture_default_str()
        ->check(CLI::Range(2, 100000));
    if (auto code =
            eval::ParseDriverOptions(app, "executive_sequence", [&] { app.parse(argc, argv); }))
        return *code;
    const auto path = std::filesystem::temp_directory_path() /
                      ("multicue-executive-sequence-" + std::to_string(::getpid()) + ".db");
    std::filesystem::remove(path);
    std::map<int, std::int64_t> identity;  // ground-truth object -> database id
    {
        auto db = ObjectDatabase::Open(path, DatabaseMode::kCreateOrWrite);
        // 1. The known objects, one view each.
        auto scene = sim::MakeDemoScene();
        {
            PerceptionExecutive executive(&db);
            const Frame frame = bench::ViewOfScene(scene, 0.0f, 1.0, 1);
            for (const auto& h : executive.Run(frame, Task{}).hypotheses) {
                if (const int gt = TrueObject(frame, h); gt > 0) identity[gt] = h.object_id;
            }
        }
        // 2. Scene 1: the known objects and an unknown one.
        scene.cylinders.push_back({{-0.42f, -0.24f}, 0.03f, 0.17f, {240, 130, 20, 255}});
        const int unknown_gt = static_cast<int>(scene.boxes.size() + scene.cylinders.size());
        const Tally before = Evaluate(db, scene, num_views, identity);

        // 3. Continuous observation: the executive learns the new object and new views.
        std::size_t learnt_objects = 0, learnt_views = 0;
        {
            PerceptionExecutive executive(&db);
            std::map<std::int64_t, int> unknown_votes;
            for (int v = 0; v < 8; ++v) {
                const float angle = -0.8f + 1.6f * static_cast<float>(v) / 7.0f;
                const Frame frame = bench::ViewOfScene(scene, angle, 10.0 + v, 500 + v);
                const auto report = executive.Run(frame, Task{});
                learnt_objects += report.learnt_objects;
                learnt_views += report.learnt_views;
                for (const auto& h : report.hypotheses) {
                    if (TrueObject(frame, h) == unknown_gt) ++unknown_votes[h.object_id];
                }
            }
            int best = 0;
            for (const auto& [id, n] : unknown_votes) {
                if (n > best) {
                    best = n;
                    identity[unknown_gt] = id;
                }
            }
        }
        const Tally after = Evaluate(db, scene, num_views, identity);

        std::printf(
            "Scene 1 (%zu known objects + 1 unknown, %d viewpoints; identity from stored "
            "views only)\n\n",
            identity.size() - 1, num_views);
        std::printf(
            "| run    | views/known | failures | unknown | success (with / no unknowns) |\n");
        std::printf(
            "|--------|-------------|----------|---------|------------------------------|\n");
        PrintRow("before", before);
        PrintRow("after", after);
        std::printf("\nlearning pass: %zu new objects, %zu new views; database: %zu objects\n",
                    learnt_objects, learnt_views, db.ListObjects().size());
    }
    std::error_code ec;
    for (const char* suffix : {"", "-wal", "-shm"})
        std::filesystem::remove(path.string() + suffix, ec);
    return 0;
}
