#pragma once
/// \file Meshes for the simulator: a triangle mesh with named parts, loaded from OBJ/PLY/STL/DAE/
/// glTF (through Assimp) or made procedurally, plus the mesh library read from a labels.csv.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/triangle_mesh.hpp"

namespace multicue::sim {

/// A triangle mesh in metres with named parts (OBJ groups, Assimp node/mesh names, or the parts of
/// a procedural object: "body", "handle", ...). Vertex colours are optional.
struct PartMesh {
    TriangleMesh mesh;
    std::vector<std::string> part_names;        ///< at least one when the mesh has triangles
    std::vector<std::uint32_t> triangle_parts;  ///< one per triangle, index into part_names
    std::string name;                           ///< file name or generator name
    /// Empty, or one laser reflectance in [0, 1] per vertex (the material's); without it the
    /// laser's intensity comes from the surface colour (RayCaster::HitReflectance).
    std::vector<float> vertex_reflectance;

    /// Axis-aligned bounds of the vertices (empty box for an empty mesh).
    Eigen::AlignedBox3f Bounds() const;
    /// Appends `other` as new parts (parts of equal name are merged).
    void AppendParts(const PartMesh& other);
    /// Throws DataError if the part table does not match the triangles.
    void Validate() const;
};

/// Limits that catch meshes in the wrong units.
struct MeshLoadParams {
    float scale = 1.0f;        ///< multiplies every coordinate (file units -> metres)
    float min_extent = 1e-3f;  ///< refuse meshes whose largest extent is below this [m]
    float max_extent = 10.0f;  ///< refuse meshes whose largest extent is above this [m]
};

/// Loads a mesh with Assimp (OBJ, PLY, STL, DAE, glTF/GLB and whatever else Assimp reads), keeping
/// the file's axes, scaled by params.scale. Node transforms are applied; every node or mesh name
/// becomes a part (meshes without a name get "part<i>"). Per-vertex colours are kept when every
/// mesh has them. Throws IoError (missing/unreadable), FormatError (Assimp cannot parse it) or
/// DataError (no triangles, non-finite vertices, largest extent outside [min_extent,
/// max_extent]); every message names the file.
PartMesh LoadMesh(const std::filesystem::path& path, const MeshLoadParams& params = {});

/// LoadMesh that logs a warning naming the file and returns nullopt on a bad mesh; with `strict`
/// it rethrows instead.
std::optional<PartMesh> TryLoadMesh(const std::filesystem::path& path, const MeshLoadParams& params,
                                    bool strict);

/// The fields of one CSV line (commas separate, double quotes quote, "" is a quote; CR dropped).
std::vector<std::string> SplitCsvLine(const std::string& line);

/// Category names; the ground-truth `category` field of simulated clouds is an index into this
/// list. 0..6 are the table-top categories of the perceive output contract (in its order),
/// 7..10 furniture for room scenes.
const std::vector<std::string>& CategoryNames();
/// Index of a category name; -1 if unknown.
int CategoryIndex(const std::string& name);
/// The six table-top object categories (sphere .. other).
const std::vector<std::string>& TabletopCategories();
/// The furniture categories (table, chair, cabinet, sideboard).
const std::vector<std::string>& FurnitureCategories();

/// One line of a mesh library's labels.csv.
struct MeshEntry {
    std::filesystem::path file;  ///< absolute or relative to the current directory
    std::string category;        ///< one of CategoryNames() (not "none")
    std::string source;          ///< "kit", "ocrtoc", ... (file prefix before "__" if no column)
    std::string object;          ///< object name (file stem if no column)
    float scale_to_m = 1.0f;     ///< file units -> metres
    /// True for meshes whose stored size is not their real size (source "kit": the Dex-Net copies
    /// are shrunk); such meshes get a random realistic size when scanned (RealisticExtentRange).
    bool rescale = false;
};

/// Reads FOLDER/labels.csv. Columns are found by header name; `file`, `category` are required,
/// `scale_to_m`, `source`, `object` optional; quoted fields may hold commas. Throws IoError if the
/// file is missing and FormatError naming the line for a missing mesh file, an unknown category
/// (one not in `categories`; default: every CategoryNames() entry but "none"), a bad scale or a
/// malformed line.
/// `labels` names another labels file (empty: FOLDER/labels.csv); its file names stay relative to
/// FOLDER.
std::vector<MeshEntry> ReadMeshLibrary(const std::filesystem::path& folder,
                                       const std::vector<std::string>& categories = {},
                                       const std::filesystem::path& labels = {});

/// Realistic range of the largest extent of an object of a category [m] (used to size shrunk
/// library meshes and procedural objects): sphere 0.06-0.25, box 0.08-0.25, flat 0.14-0.35,
/// cylinder 0.07-0.30, plate 0.16-0.30, other 0.10-0.30. Throws InvalidArgument for others.
std::pair<float, float> RealisticExtentRange(const std::string& category);

}  // namespace multicue::sim
