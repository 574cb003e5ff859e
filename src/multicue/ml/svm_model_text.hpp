#pragma once
/// \file Checks libsvm model text before libsvm reads it. libsvm's reader (svm_load_model) trusts
/// its file: a missing value, a count that does not match or a short support-vector line makes it
/// read through a null pointer or past its arrays. The model text inside a classifier file comes
/// from the file, so it is checked against the format svm_save_model writes first.

#include <cstddef>
#include <string>
#include <string_view>

namespace multicue::ml {

/// "" when `text` is a complete C-SVC model as svm_save_model writes it (linear or RBF kernel, 2 to
/// `max_classes` classes, labels in [0, max_classes), support vectors over feature indices 1 to
/// `num_features`, every number finite); otherwise the first problem found.
std::string SvmModelTextProblem(std::string_view text, std::size_t num_features,
                                std::size_t max_classes);

}  // namespace multicue::ml
