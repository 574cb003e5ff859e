#include "multicue/sim/mesh_split.hpp"

#include <algorithm>
#include <map>
#include <tuple>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::sim {

std::string_view MeshSplitName(MeshSplit split) {
    switch (split) {
        case MeshSplit::kTune:
            return "tune";
        case MeshSplit::kTest:
            return "test";
        case MeshSplit::kAll:
            break;
    }
    return "all";
}

MeshSplit ParseMeshSplit(std::string_view name) {
    for (const MeshSplit s : {MeshSplit::kAll, MeshSplit::kTune, MeshSplit::kTest}) {
        if (name == MeshSplitName(s)) return s;
    }
    throw InvalidArgument(fmt::format("mesh split must be all, tune or test, got '{}'", name));
}

std::uint64_t MeshNameHash(std::string_view file_name) {
    std::uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a offset basis and prime (64 bit)
    for (const char c : file_name) {
        h ^= static_cast<unsigned char>(c);
        h *= 0x100000001b3ull;
    }
    return h;
}

std::vector<MeshSplit> MeshSplitOf(const std::vector<MeshEntry>& library) {
    // Distinct file names per category, ordered by hash: a file's rank there decides its half.
    std::map<std::string, std::vector<std::pair<std::uint64_t, std::string>>> by_category;
    for (const auto& e : library) {
        const std::string name = e.file.filename().string();
        by_category[e.category].emplace_back(MeshNameHash(name), name);
    }
    std::map<std::pair<std::string, std::string>, MeshSplit> half;
    for (auto& [category, names] : by_category) {
        std::sort(names.begin(), names.end());
        names.erase(std::unique(names.begin(), names.end()), names.end());
        for (std::size_t r = 0; r < names.size(); ++r) {
            half[{category, names[r].second}] = r % 2 == 0 ? MeshSplit::kTune : MeshSplit::kTest;
        }
    }
    std::vector<MeshSplit> out;
    out.reserve(library.size());
    for (const auto& e : library) out.push_back(half.at({e.category, e.file.filename().string()}));
    return out;
}

std::vector<MeshEntry> SelectMeshSplit(const std::vector<MeshEntry>& library, MeshSplit split) {
    if (split == MeshSplit::kAll) return library;
    const auto halves = MeshSplitOf(library);
    std::vector<MeshEntry> out;
    for (std::size_t i = 0; i < library.size(); ++i) {
        if (halves[i] == split) out.push_back(library[i]);
    }
    return out;
}

}  // namespace multicue::sim
