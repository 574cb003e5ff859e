// `multicue db init|list|show|export|import`: the object model database.

#include <cstdio>
#include <memory>
#include <ostream>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/json_text.hpp"
#include "multicue/system/object_database.hpp"

namespace multicue::cli {
namespace {

std::string PositionText(const Eigen::Matrix4d& pose) {
    return fmt::format("{:.3f} {:.3f} {:.3f}", pose(0, 3), pose(1, 3), pose(2, 3));
}

void PrintObjects(const ObjectDatabase& db, bool json) {
    const auto objects = db.ListObjects();
    if (json) {
        nlohmann::ordered_json list = nlohmann::ordered_json::array();
        for (const auto& o : objects) {
            list.push_back(
                {{"id", o.id},
                 {"name", o.name},
                 {"category", o.category},
                 {"views", o.num_views},
                 {"last_seen", o.last_seen},
                 {"position", {o.last_pose(0, 3), o.last_pose(1, 3), o.last_pose(2, 3)}}});
        }
        std::printf("%s\n", list.dump().c_str());
        return;
    }
    std::printf("%-6s %-20s %-10s %5s %10s  %s\n", "id", "name", "category", "views", "last_seen",
                "position [m]");
    for (const auto& o : objects) {
        std::printf("%-6lld %-20s %-10s %5zu %10.2f  %s\n", static_cast<long long>(o.id),
                    o.name.c_str(), o.category.empty() ? "-" : o.category.c_str(), o.num_views,
                    o.last_seen, PositionText(o.last_pose).c_str());
    }
    std::printf("%zu objects\n", objects.size());
}

void ShowObject(const ObjectDatabase& db, std::int64_t id) {
    const auto object = db.GetObject(id);
    if (!object) throw DataError(fmt::format("{}: no object with id {}", db.path().string(), id));
    std::printf("object %lld: %s\n  category:  %s\n  created:   %.2f\n  last seen: %.2f at %s\n",
                static_cast<long long>(object->id), object->name.c_str(),
                object->category.empty() ? "-" : object->category.c_str(), object->created,
                object->last_seen, PositionText(object->last_pose).c_str());
    for (const auto& v : db.GetViews(id)) {
        std::string descriptors;
        for (const auto& [method, values] : v.descriptors) {
            descriptors += fmt::format(" {}[{}]", method, values.size());
        }
        std::printf("  view %lld: t=%.2f frame=%s category=%s model=%s%s%s\n",
                    static_cast<long long>(v.id), v.time, v.frame.empty() ? "-" : v.frame.c_str(),
                    v.category.empty() ? "-" : v.category.c_str(),
                    v.model.empty() ? "-" : v.model.value("type", std::string("?")).c_str(),
                    descriptors.empty() ? "" : (" descriptors:" + descriptors).c_str(),
                    v.mesh_ply.empty() ? "" : " mesh");
    }
}

}  // namespace

void AddDbCommand(CLI::App& app, const GlobalOptions&) {
    auto* db = app.add_subcommand("db",
                                  "object model database (SQLite): init, list, show, export, "
                                  "import");
    db->require_subcommand(1);

    auto path = std::make_shared<std::string>();
    auto* init = db->add_subcommand("init", "create a database (or migrate an older one)");
    init->add_option("DB", *path, "database file (.db)")->required();
    init->callback([path] {
        const auto database = ObjectDatabase::Open(*path, DatabaseMode::kCreateOrWrite);
        std::printf("%s: schema version %d, %zu objects\n", path->c_str(),
                    database.schema_version(), database.ListObjects().size());
    });

    auto json = std::make_shared<bool>(false);
    auto* list = db->add_subcommand("list", "list the objects");
    list->add_option("DB", *path, "database file")->required();
    list->add_flag("--json", *json, "print JSON");
    list->callback([path, json] {
        PrintObjects(ObjectDatabase::Open(*path, DatabaseMode::kReadOnly), *json);
    });

    auto id = std::make_shared<std::int64_t>(0);
    auto* show = db->add_subcommand("show", "show one object with its views");
    show->add_option("DB", *path, "database file")->required();
    show->add_option("ID", *id, "object id")->required();
    show->callback(
        [path, id] { ShowObject(ObjectDatabase::Open(*path, DatabaseMode::kReadOnly), *id); });

    auto file = std::make_shared<std::string>();
    auto* exp = db->add_subcommand("export", "write every object and view as JSON");
    exp->add_option("DB", *path, "database file")->required();
    exp->add_option("--out", *file, "JSON file (default: standard output)");
    exp->callback([path, file] {
        const std::string text =
            ObjectDatabase::Open(*path, DatabaseMode::kReadOnly).Export().dump(1) + "\n";
        if (file->empty()) {
            std::fwrite(text.data(), 1, text.size(), stdout);
        } else {
            io::WriteFileAtomically(*file, [&](std::ostream& out) { out << text; });
        }
    });

    auto* imp = db->add_subcommand("import", "add the objects of a JSON export (all or none)");
    imp->add_option("DB", *path, "database file (created when missing)")->required();
    imp->add_option("FILE", *file, "JSON export")->required();
    imp->callback([path, file] {
        const nlohmann::json data = io::ReadJsonFile(*file);
        auto database = ObjectDatabase::Open(*path, DatabaseMode::kCreateOrWrite);
        std::printf("%s: imported %zu objects\n", path->c_str(), database.Import(data));
    });
}

}  // namespace multicue::cli
