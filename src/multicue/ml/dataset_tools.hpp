#pragma once
/// \file Dataset tools (section 3.1.4): concatenation of features and of datasets, selecting and
/// dropping columns or feature blocks, relabelling and flattening of hierarchical labels, row
/// subsets, and turning classifier confidences into a dataset (for stacking, section 3.3.4).

#include <map>
#include <string>
#include <vector>

#include "multicue/ml/dataset.hpp"

namespace multicue::ml {

/// Rows `indices` of `data`, in that order (class names kept).
Dataset SelectRows(const Dataset& data, const std::vector<std::size_t>& indices);

/// Columns `columns` of `data`, in that order; blocks are rebuilt from the selected columns
/// (consecutive columns of one block stay one block).
Dataset SelectColumns(const Dataset& data, const std::vector<std::size_t>& columns);
/// Only the named blocks, in the order given. InvalidArgument names an unknown block.
Dataset SelectBlocks(const Dataset& data, const std::vector<std::string>& blocks);
/// Everything except the named blocks.
Dataset DropBlocks(const Dataset& data, const std::vector<std::string>& blocks);
/// Everything except the columns `columns`.
Dataset DropColumns(const Dataset& data, const std::vector<std::size_t>& columns);

/// Column-wise concatenation: joins rows with equal row ids; the result has the rows of `a`
/// (in a's order) with b's columns appended. Rows of `a` without a partner in `b` are dropped
/// when `drop_unmatched`, otherwise they are a DataError. Labels and groups of joined rows must
/// agree (DataError). Block names must be distinct (InvalidArgument).
Dataset ConcatColumns(const Dataset& a, const Dataset& b, bool drop_unmatched = false);

/// Row-wise concatenation: the rows of `b` after those of `a`. Columns must have the same names
/// and blocks (InvalidArgument otherwise); classes are merged by name. When row ids collide,
/// b's rows get new ids after a's largest (`renumber`), else a DataError.
Dataset ConcatRows(const Dataset& a, const Dataset& b, bool renumber = true);

/// Renames classes: every label path found in `mapping` becomes the mapped path (several old
/// classes may merge into one); unmapped classes stay. Unused classes are removed.
Dataset Relabel(const Dataset& data, const std::map<std::string, std::string>& mapping);
/// Cuts every label path to its first `depth` components ("cylinder/mug" -> "cylinder").
Dataset FlattenLabels(const Dataset& data, std::size_t depth);
/// Removes classes no row uses and renumbers the labels (order of first class id kept).
Dataset CompactClasses(const Dataset& data);

/// Maps `data`'s labels onto `class_names` (by name). A label missing from `class_names` is a
/// DataError naming it (e.g. a test label never seen in training); unlabelled rows stay kNoLabel.
std::vector<int> MapLabels(const Dataset& data, const std::vector<std::string>& class_names);

/// A dataset with the per-class confidences of a classifier as features: block `block`, columns
/// named after the classes; labels, groups, views, row ids and sources are those of `rows_of`.
Dataset ConfidencesToDataset(const FeatureMatrix& confidences,
                             const std::vector<std::string>& class_names, const Dataset& rows_of,
                             const std::string& block);

}  // namespace multicue::ml
