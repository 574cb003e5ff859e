#pragma once
/// \file Global Radius-based Surface Descriptors (thesis section 2.5.2): GRSD with free space
/// found by ray casting, and the additive GRSD- ("GRSD minus").
///
/// Both start from RSD per voxel (ComputeVoxelRsd: 2.5 cm voxels, one surface type per occupied
/// voxel) and count transitions between classes c in {edge 0, plane 1, cylinder 2, sphere 3,
/// rim 4, empty 5}. A 6 x 6 count matrix T is folded into 21 bins, the upper triangle with the
/// diagonal: bin(i, j) for i <= j in the order (0,0) (0,1) .. (0,5) (1,1) .. (1,5) .. (5,5), holds
/// T(i, j) + T(j, i) (PCL's GRSDSignature21 layout; a count on the diagonal appears twice).
/// Bins are raw counts, not normalised: the thesis sums the histograms "instead of computing
/// their distribution", and only raw counts can be additive.
///
/// GRSD- (Kanezaki et al., 2011c): for every occupied voxel a of the set and each of its 26
/// neighbour cells b, T(type(a), class(b)) += 1, where class(b) is type(b) if b is an occupied
/// voxel of the same set and 5 (empty) otherwise. Every voxel contributes 26 counts to T, so the
/// bins sum to 26 V + (same-type neighbour pairs, counted from both sides); bin (5,5) is always 0
/// (20 informative dimensions, as Table 2.2 counts them). Voxels with an undefined type (no
/// finite normal near them) are treated as empty. This is PCL's GRSDEstimation construction.
///
/// Additivity. For two voxel sets A and B without common voxels, with labels taken from one
/// voxel map (VoxelRsdResult of the scene or object they belong to):
///     H(A u B) = H(A) + H(B) + sum over 26-adjacent pairs (a in A, b in B) of
///                [ 2 w e(type a, type b) - e(type a, 5) - e(type b, 5) ]
/// with e(i, j) the unit vector of bin(i, j) and w = 2 for equal types, else 1: in A u B the
/// two voxels see each other instead of empty space. So the descriptor of a union of parts is
/// the sum of the parts' descriptors up to the voxels on their shared boundary, and the
/// correction is exactly computable (GrsdMinusBoundaryCorrection); parts that do not touch
/// (no 26-adjacent voxels) add exactly.
///
/// GRSD (ray cast): free space is found by casting a ray from the viewpoint to every point of the
/// cluster through a voxel grid over the cluster's voxels grown by one cell on each side (a 3D
/// DDA, Amanatides and Woo): cells the rays cross before reaching their point's voxel are free;
/// cells never crossed and not occupied are unknown (occluded). Then the line between the centres
/// of every pair of occupied voxels is walked with the same DDA, and every step between two
/// consecutive known cells (unknown cells are stepped over) counts once in bin(class before,
/// class after), same-class steps included (free-free steps count in bin (5,5)). Cost: one ray
/// per point plus one line per voxel pair, O(V^2 L) for V voxels and lines of L cells.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "multicue/features/rsd.hpp"

namespace multicue {

inline constexpr int kGrsdSize = 21;

/// Index of bin(i, j) (order of i and j does not matter) in the 21-bin layout; classes 0-5.
int GrsdBin(int class_a, int class_b);

struct GrsdParams {
    VoxelRsdParams voxels = {};  ///< voxel size, RSD settings (incl. num_threads), thresholds
    /// Viewpoint for the ray casting of GRSD [m]; default: the cloud's sensor_origin.
    std::optional<Eigen::Vector3f> viewpoint = std::nullopt;
};

/// GRSD- of the voxels `subset` (indices into `voxels`) of a voxel map.
/// Throws InvalidArgument on an out-of-range or repeated voxel index.
FeatureVector GrsdMinusOfVoxels(const VoxelRsdResult& voxels,
                                std::span<const std::uint32_t> subset);

/// The exact difference H(A u B) - H(A) - H(B) for disjoint voxel sets A and B (see above).
FeatureVector GrsdMinusBoundaryCorrection(const VoxelRsdResult& voxels,
                                          std::span<const std::uint32_t> a,
                                          std::span<const std::uint32_t> b);

/// GRSD- of a whole cluster (with normals): builds the k-d tree and the voxel map of the cluster
/// and counts all its voxels. Throws InvalidArgument without normals or on bad parameters; an
/// empty cluster gives zeros.
FeatureVector ComputeGrsdMinus(const PointCloud& cluster, const GrsdParams& params = {});

/// GRSD of a whole cluster with free space by ray casting. Same errors as ComputeGrsdMinus, and
/// InvalidArgument if the viewpoint is not finite.
FeatureVector ComputeGrsd(const PointCloud& cluster, const GrsdParams& params = {});

/// Ray-cast GRSD from a ready voxel map; `cloud` provides the points the rays go to.
FeatureVector GrsdOfVoxels(const PointCloud& cloud, const VoxelRsdResult& voxels,
                           const Eigen::Vector3f& viewpoint);

}  // namespace multicue
