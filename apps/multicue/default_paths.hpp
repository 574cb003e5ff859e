#pragma once
// The shared mesh libraries the CLI uses when no folder is given (beside the source tree). The
// values are written by CMake into one generated source file (default_paths.cpp in the build
// folder), so that no other compile command carries an absolute path.

namespace multicue::cli {

/// Furniture library (labels.csv) for `simulate furniture`, `map furniture`, `train furniture`.
const char* DefaultFurnitureDir();
/// Kitchen library (URDF kitchens, tables, cupboards).
const char* DefaultKitchenDir();

}  // namespace multicue::cli
