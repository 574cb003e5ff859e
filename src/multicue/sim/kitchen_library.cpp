#include "multicue/sim/kitchen_library.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/sim/kitchen_procedural.hpp"

namespace multicue::sim {

const std::vector<std::string>& KitchenModelKinds() {
    static const std::vector<std::string> kinds = {
        "cupboard",   "wall_cupboard", "tall_cupboard", "sink_cupboard", "drawer_unit",
        "dishwasher", "fridge",        "oven",          "microwave",     "table"};
    return kinds;
}

const std::vector<std::string>& ContainerTypes() {
    static const std::vector<std::string> types = {"cupboard", "drawer_unit", "oven", "dishwasher",
                                                   "fridge",   "microwave",   "table"};
    return types;
}

std::string ContainerTypeOfKind(const std::string& kind) {
    if (kind == "wall_cupboard" || kind == "tall_cupboard" || kind == "sink_cupboard") {
        return "cupboard";
    }
    return kind;
}

std::string ContainerTypeOfModel(const ArticulatedModel& model) {
    const std::string type = ContainerTypeOfKind(model.kind);
    if (type != "cupboard") return type;
    int drawers = 0;
    for (const ArticulatedJoint& j : model.joints) {
        if (!j.Movable()) continue;
        if (j.type != io::UrdfJointType::kPrismatic) return type;
        ++drawers;
    }
    return drawers > 0 ? "drawer_unit" : type;
}

std::vector<KitchenModelEntry> ReadKitchenLibrary(const std::filesystem::path& root) {
    const std::filesystem::path labels = root / "labels.csv";
    std::ifstream in(labels);
    if (!in) throw IoError(fmt::format("{}: cannot open the kitchen library", labels.string()));
    std::string line;
    if (!std::getline(in, line)) throw FormatError(fmt::format("{}: empty file", labels.string()));
    const auto header = SplitCsvLine(line);
    auto column = [&](const std::string& name) {
        const auto it = std::find(header.begin(), header.end(), name);
        if (it == header.end()) {
            throw FormatError(fmt::format("{}: no column '{}'", labels.string(), name));
        }
        return static_cast<std::size_t>(it - header.begin());
    };
    const std::size_t c_folder = column("folder"), c_kind = column("kind"),
                      c_scale = column("scale_to_m");
    const auto& kinds = KitchenModelKinds();
    std::vector<KitchenModelEntry> out;
    int number = 1;
    while (std::getline(in, line)) {
        ++number;
        if (line.empty() || line == "\r") continue;
        const auto f = SplitCsvLine(line);
        if (f.size() < header.size()) {
            throw FormatError(fmt::format("{}:{}: {} fields, expected {}", labels.string(), number,
                                          f.size(), header.size()));
        }
        KitchenModelEntry e;
        e.id = f[c_folder];
        e.folder = root / e.id;
        e.kind = f[c_kind];
        if (std::find(kinds.begin(), kinds.end(), e.kind) == kinds.end()) {
            throw FormatError(
                fmt::format("{}:{}: unknown kind '{}'", labels.string(), number, e.kind));
        }
        try {
            e.scale_to_m = std::stof(f[c_scale]);
        } catch (const std::exception&) {
            e.scale_to_m = -1.0f;
        }
        if (!(e.scale_to_m > 0.0f) || !std::isfinite(e.scale_to_m)) {
            throw FormatError(
                fmt::format("{}:{}: bad scale_to_m '{}'", labels.string(), number, f[c_scale]));
        }
        std::error_code ec;
        if (!std::filesystem::is_regular_file(e.folder / "mobility.urdf", ec)) {
            throw FormatError(fmt::format("{}:{}: {} has no mobility.urdf", labels.string(), number,
                                          e.folder.string()));
        }
        out.push_back(std::move(e));
    }
    return out;
}

std::vector<MeshSplit> KitchenSplitOf(const std::vector<KitchenModelEntry>& library) {
    auto annotation = [](const KitchenModelEntry& e) {
        return std::filesystem::path(e.id).filename().string();
    };
    std::map<std::string, std::vector<std::pair<std::uint64_t, std::string>>> by_kind;
    for (const auto& e : library) {
        by_kind[e.kind].emplace_back(MeshNameHash(annotation(e)), annotation(e));
    }
    std::map<std::pair<std::string, std::string>, MeshSplit> half;
    for (auto& [kind, ids] : by_kind) {
        std::sort(ids.begin(), ids.end());
        ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
        for (std::size_t r = 0; r < ids.size(); ++r) {
            half[{kind, ids[r].second}] = r % 2 == 0 ? MeshSplit::kTune : MeshSplit::kTest;
        }
    }
    // An id listed under several kinds is one model: it must never be a test model in one kind
    // and a training model in another.
    std::map<std::string, std::set<std::string>> kinds_of_id;
    for (const auto& e : library) kinds_of_id[annotation(e)].insert(e.kind);
    std::vector<MeshSplit> out;
    out.reserve(library.size());
    for (const auto& e : library) {
        MeshSplit s = half.at({e.kind, annotation(e)});
        if (kinds_of_id[annotation(e)].size() > 1) s = MeshSplit::kTune;
        out.push_back(s);
    }
    return out;
}

std::vector<KitchenModelEntry> SelectKitchenSplit(const std::vector<KitchenModelEntry>& library,
                                                  MeshSplit split) {
    if (split == MeshSplit::kAll) return library;
    const auto halves = KitchenSplitOf(library);
    std::vector<KitchenModelEntry> out;
    for (std::size_t i = 0; i < library.size(); ++i) {
        if (halves[i] == split) out.push_back(library[i]);
    }
    return out;
}

std::shared_ptr<const ArticulatedModel> KitchenModelCache::Get(const KitchenModelEntry& entry) {
    const std::string key = entry.procedural ? entry.id : entry.folder.string();
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        const auto it = models_.find(key);
        if (it != models_.end()) return it->second;
    }
    ArticulatedModel model =
        entry.procedural
            ? MakeProceduralUnit(entry.kind, entry.procedural_seed)
            : LoadArticulatedModel(entry.folder, ArticulatedLoadParams{.scale = entry.scale_to_m});
    model.kind = entry.kind;
    auto shared = std::make_shared<const ArticulatedModel>(std::move(model));
    const std::lock_guard<std::mutex> lock(mutex_);
    return models_.emplace(key, std::move(shared)).first->second;
}

}  // namespace multicue::sim
