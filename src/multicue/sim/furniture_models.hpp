#pragma once
/// \file Furniture for the furniture detector (thesis section 4.2): the library of web models
/// (the merged PartNet-Mobility OBJ files of meshes/furniture/ and the tables, cupboards and
/// drawer units of the kitchen library, loaded through their URDF), its held-out split, and
/// procedural furniture built from boards (chairs, tables, cabinets, sideboards of random size
/// and style).
///
/// Every piece is returned in one canonical frame: z up, resting on z = 0, the bounding box of
/// its footprint centred on x = y = 0, and its front facing +x (the seat side of a chair, the
/// doors and drawers of a cabinet or sideboard, a long side of a table). Yaw errors of fitted
/// models are measured in this frame.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/sim/mesh.hpp"
#include "multicue/sim/mesh_split.hpp"
#include "multicue/sim/rng.hpp"

namespace multicue::sim {

/// One piece of furniture in the canonical frame.
struct FurniturePiece {
    std::shared_ptr<const PartMesh> mesh;  ///< [m], canonical frame
    std::string category;                  ///< table, chair, cabinet or sideboard
    std::string id;      ///< "table__22339", "DiningTable/23782" or "procedural/chair/<seed>"
    std::string source;  ///< "furniture", "kitchen" or "procedural"
    float scale = 1.0f;  ///< file units -> metres (1 for procedural pieces)
};

/// One model of the furniture library.
struct FurnitureEntry {
    std::filesystem::path path;  ///< OBJ file (furniture) or model folder (kitchen)
    std::string category;        ///< table, chair, cabinet or sideboard
    std::string id;              ///< file stem (furniture) or "Category/annotation" (kitchen)
    std::string model_id;        ///< PartNet-Mobility annotation id: the key of the split
    std::string source;          ///< "furniture" or "kitchen"
    float scale_to_m = 1.0f;     ///< file units -> metres
};

/// The library: FURNITURE/labels.csv (categories table, chair, cabinet, sideboard) and, when
/// `kitchen` is not empty, the kitchen library's tables (kind table -> table), cupboards and sink
/// cupboards (-> cabinet) and drawer units (-> sideboard: long, low storage furniture). A kitchen
/// model whose annotation id is already in the furniture folder is the same model and is left
/// out. Either folder may be empty (not both). Throws as ReadMeshLibrary / ReadKitchenLibrary.
std::vector<FurnitureEntry> ReadFurnitureLibrary(const std::filesystem::path& furniture,
                                                 const std::filesystem::path& kitchen);

/// The half of every entry: within each category the entries are ordered by MeshNameHash of
/// their annotation id (ties by id) and alternate tune, test, tune, ... (the tune half takes the
/// odd one out), as MeshSplitOf does for the table-top library.
std::vector<MeshSplit> FurnitureSplitOf(const std::vector<FurnitureEntry>& library);
/// The entries of one half (all for kAll), in library order.
std::vector<FurnitureEntry> SelectFurnitureSplit(const std::vector<FurnitureEntry>& library,
                                                 MeshSplit split);

/// Loads an entry into the canonical frame: kitchen models closed (doors and drawers shut) with
/// their materials' colours and laser reflectance; furniture OBJ files turned so that their
/// front faces +x, the front found from the named parts (a chair's back lies behind its seat;
/// doors, drawers and handles are on a cabinet's front, its back panel behind). Throws IoError /
/// FormatError / DataError naming the file.
FurniturePiece LoadFurniturePiece(const FurnitureEntry& entry);

/// Width used by the detector's true-positive test: the smaller side of the footprint's
/// axis-aligned bounding box in the canonical frame [m].
float FurnitureWidth(const PartMesh& mesh);

/// A random procedural piece of `category` (table, chair, cabinet or sideboard) made of boards,
/// with parts named as in the library (seat, chair_back, leg, tabletop, door, drawer, handle,
/// ...). Styles: chairs on four legs (board or slatted backs, some with arms) or on a pedestal
/// with a star base; tables on four legs (with or without an apron), desks on side panels, round
/// tables on a column; cabinets and sideboards with doors, drawers or open shelves on a plinth or
/// legs. Throws InvalidArgument for another category.
FurniturePiece MakeProceduralFurniture(const std::string& category, StreamRng& rng);

/// Adds an axis-aligned board of size `extents` centred at `center`, rotated by `R` about its
/// centre, as part `part` of `mesh`.
void AddBoard(PartMesh& mesh, const Eigen::Vector3f& extents, const Eigen::Vector3f& center,
              const std::string& part, const Eigen::Matrix3f& R = Eigen::Matrix3f::Identity());

}  // namespace multicue::sim
