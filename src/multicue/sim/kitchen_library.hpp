#pragma once
/// \file The kitchen model library (PartNet-Mobility folders listed in a labels.csv, see the data
/// README) and its held-out split: kitchen maps are trained and tuned on kitchens built from the
/// "tune" half of the models and evaluated on kitchens built from the "test" half only.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "multicue/sim/articulated.hpp"
#include "multicue/sim/mesh_split.hpp"

namespace multicue::sim {

/// One line of the kitchen library's labels.csv.
struct KitchenModelEntry {
    std::filesystem::path folder;  ///< the model's folder
    std::string id;                ///< "CabinetLower/45213"
    std::string kind;  ///< cupboard, wall_cupboard, tall_cupboard, sink_cupboard, drawer_unit,
                       ///< dishwasher, fridge, oven, microwave or table
    float scale_to_m = 1.0f;  ///< file units -> metres
    /// Made by MakeProceduralUnit(kind, procedural_seed) instead of loaded (folder empty); see
    /// kitchen_procedural.hpp
    bool procedural = false;
    std::uint64_t procedural_seed = 0;
};

/// The kinds of labels.csv, in this order.
const std::vector<std::string>& KitchenModelKinds();

/// The container type of a kind (thesis section 4.1.3): cupboard (also wall, tall and sink
/// cupboards), drawer_unit, oven, dishwasher, fridge, microwave, table.
std::string ContainerTypeOfKind(const std::string& kind);

/// The container type of a model: its kind's, except that a cupboard whose moving fronts are all
/// drawers is a drawer unit. Every drawer unit of the library is such a unit, and two of its
/// "cupboards" (MiniFridgeBase/45261 and 45746, stacks of drawers) are too.
std::string ContainerTypeOfModel(const ArticulatedModel& model);

/// The container types, in a fixed order: cupboard, drawer_unit, oven, dishwasher, fridge,
/// microwave, table.
const std::vector<std::string>& ContainerTypes();

/// Reads ROOT/labels.csv (columns found by header name: folder, kind, scale_to_m). Throws IoError
/// if it is missing and FormatError naming the line for a missing folder, an unknown kind, a bad
/// scale or a malformed line.
std::vector<KitchenModelEntry> ReadKitchenLibrary(const std::filesystem::path& root);

/// The half of every entry: within each kind the models are ordered by MeshNameHash of their
/// annotation id (the folder's last component) and alternate tune, test, tune, ... A model id that
/// appears under two kinds (PartNet-Mobility lists some models twice) gets the tune half in both,
/// so no test model was ever seen in training.
std::vector<MeshSplit> KitchenSplitOf(const std::vector<KitchenModelEntry>& library);

/// The entries of one half (all for kAll), in library order.
std::vector<KitchenModelEntry> SelectKitchenSplit(const std::vector<KitchenModelEntry>& library,
                                                  MeshSplit split);

/// Loads models once and shares them (loading a model reads dozens of OBJ files). Thread-safe.
class KitchenModelCache {
  public:
    /// The model of `entry`, loaded on first use. Throws as LoadArticulatedModel.
    std::shared_ptr<const ArticulatedModel> Get(const KitchenModelEntry& entry);

  private:
    std::mutex mutex_;
    std::map<std::string, std::shared_ptr<const ArticulatedModel>> models_;
};

}  // namespace multicue::sim
