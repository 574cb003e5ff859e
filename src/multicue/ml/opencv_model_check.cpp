// Checks of the OpenCV models inside classifier files, made before OpenCV reads them: OpenCV's
// readers take indices, sizes and category subsets from the file as they are (a split's variable
// index, a leaf's class index, a categorical subset, layer sizes), so a damaged or crafted file
// would make them, or the predictions after them, read and write out of bounds. multicue's models
// have num_features ordered inputs and a categorical response; anything else is refused.

#include <cmath>
#include <string>

#include "multicue/ml/opencv_util.hpp"

namespace multicue::ml::detail {
namespace {

bool IsInt(const cv::FileNode& n) { return n.isInt(); }
bool IsFinite(const cv::FileNode& n) {
    return (n.isInt() || n.isReal()) && std::isfinite(static_cast<double>(n));
}

// A sequence of `size` numbers (any size when size < 0), each satisfying `ok`.
template <typename Ok>
bool Sequence(const cv::FileNode& n, long long size, Ok ok) {
    if (!n.isSeq() || (size >= 0 && static_cast<long long>(n.size()) != size)) return false;
    for (const auto& item : n) {
        if (!ok(item)) return false;
    }
    return true;
}

bool IntEquals(const cv::FileNode& n, long long v) {
    return n.isInt() && static_cast<long long>(static_cast<int>(n)) == v;
}

std::string CheckSplit(const cv::FileNode& s, int num_features) {
    if (!s.isMap()) return "a split is not a map";
    const cv::FileNode var = s["var"];
    if (!var.isInt() || static_cast<int>(var) < 0 || static_cast<int>(var) >= num_features) {
        return "a split's variable is not one of the features";
    }
    if (!s["in"].empty() || !s["not_in"].empty()) return "a categorical split on a numeric feature";
    const cv::FileNode le = s["le"], gt = s["gt"];
    if (le.empty() == gt.empty() || !IsFinite(le.empty() ? gt : le)) {
        return "a split has no finite threshold";
    }
    return "";
}

std::string CheckNode(const cv::FileNode& node, int num_features, int num_labels) {
    if (!node.isMap()) return "a tree node is not a map";
    if (!IsFinite(node["value"])) return "a tree node has no finite value";
    const cv::FileNode cls = node["norm_class_idx"];
    if (!cls.empty() &&
        (!cls.isInt() || static_cast<int>(cls) < 0 || static_cast<int>(cls) >= num_labels)) {
        return "a tree node's class index is out of range";
    }
    const cv::FileNode splits = node["splits"];
    if (splits.empty()) return "";
    if (!splits.isSeq()) return "a tree node's splits are not a list";
    for (const auto& s : splits) {
        if (auto p = CheckSplit(s, num_features); !p.empty()) return p;
    }
    return "";
}

}  // namespace

std::string TreesProblem(const cv::FileNode& m, std::size_t num_features, std::size_t num_classes) {
    if (!m.isMap()) return "no model";
    const auto n = static_cast<long long>(num_features);
    if (!IntEquals(m["format"], 3) || !IntEquals(m["is_classifier"], 1)) {
        return "not a classification tree model of format 3";
    }
    if (!IntEquals(m["var_count"], n) || !IntEquals(m["var_all"], n + 1) ||
        !IntEquals(m["ord_var_count"], n) || !IntEquals(m["cat_var_count"], 1)) {
        return "the variable counts do not match the model's features";
    }
    const cv::FileNode var_idx = m["var_idx"];
    if (!var_idx.empty()) {
        long long expected = 0;
        if (!Sequence(var_idx, n,
                      [&](const cv::FileNode& v) { return IntEquals(v, expected++); })) {
            return "var_idx is not the list of the features";
        }
    }
    long long k = 0;
    if (!Sequence(m["var_type"], n + 1,
                  [&](const cv::FileNode& v) { return IntEquals(v, k++ < n ? 0 : 1); })) {
        return "var_type must mark every feature ordered and the response categorical";
    }
    // cat_ofs and cat_map describe categorical variables: with every feature ordered, they are
    // never read by a prediction.
    const cv::FileNode missing = m["missing_subst"];
    if (!missing.empty() && !Sequence(missing, -1, IsFinite)) return "bad missing_subst";
    if (!missing.empty() && static_cast<long long>(missing.size()) < n)
        return "short missing_subst";
    // Boosting is one binary model per class (labels 0 and 1); forests use the class indices.
    const long long max_label = std::max<long long>(static_cast<long long>(num_classes), 2);
    long long last = -1;
    const cv::FileNode labels = m["class_labels"];
    if (!Sequence(labels, -1,
                  [&](const cv::FileNode& v) {
                      const bool ok =
                          IsInt(v) && static_cast<int>(v) > last && static_cast<int>(v) < max_label;
                      last = ok ? static_cast<int>(v) : last;
                      return ok;
                  }) ||
        labels.size() < 1) {
        return "class_labels are not ascending class indices";
    }
    const cv::FileNode trees = m["trees"];
    if (!trees.isSeq() || trees.size() == 0) return "no trees";
    if (!m["ntrees"].empty() && !IntEquals(m["ntrees"], static_cast<long long>(trees.size()))) {
        return "ntrees does not match the trees";
    }
    for (const auto& tree : trees) {
        const cv::FileNode nodes = tree.isMap() ? tree["nodes"] : cv::FileNode();
        if (!nodes.isSeq() || nodes.size() == 0) return "a tree has no nodes";
        for (const auto& node : nodes) {
            if (auto p = CheckNode(node, static_cast<int>(n), static_cast<int>(labels.size()));
                !p.empty()) {
                return p;
            }
        }
    }
    return "";
}

std::string MlpProblem(const cv::FileNode& m, std::size_t num_features, std::size_t num_classes) {
    if (!m.isMap()) return "no model";
    if (!IntEquals(m["format"], 3)) return "not an MLP of format 3";
    const cv::FileNode sizes = m["layer_sizes"];
    if (!Sequence(sizes, -1, IsInt) || sizes.size() < 2) return "bad layer_sizes";
    std::vector<long long> s;
    for (const auto& v : sizes) s.push_back(static_cast<int>(v));
    if (s.front() != static_cast<long long>(num_features) ||
        s.back() != static_cast<long long>(num_classes)) {
        return "layer sizes do not match the model's features and classes";
    }
    for (long long v : s) {
        if (v < 1) return "a layer has no neurons";
    }
    // The weights must all be in the file: OpenCV allocates them from layer_sizes first.
    const cv::FileNode weights = m["weights"];
    if (!weights.isSeq() || weights.size() != s.size() - 1)
        return "weights do not match the layers";
    std::size_t i = 1;
    for (const auto& w : weights) {
        if (!Sequence(w, (s[i - 1] + 1) * s[i], IsFinite)) {
            return "a weight matrix does not match its layers";
        }
        ++i;
    }
    if (!Sequence(m["input_scale"], 2 * s.front(), IsFinite) ||
        !Sequence(m["output_scale"], 2 * s.back(), IsFinite) ||
        !Sequence(m["inv_output_scale"], 2 * s.back(), IsFinite)) {
        return "input or output scales do not match the layers";
    }
    return "";
}

}  // namespace multicue::ml::detail
