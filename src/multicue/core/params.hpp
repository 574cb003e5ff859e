#pragma once
/// \file Building blocks of parameter trees: optional steps of a pipeline, and validation that
/// names the node of the tree a bad value is in.

#include <string>
#include <utility>

#include "multicue/core/exceptions.hpp"

namespace multicue {

/// The parameters of an optional step with its on/off switch: every field of P plus `enabled`.
/// A pipeline holds `Switchable<RotationalFitParams> rotational` where its configuration has
/// `"rotational": {"enabled": true, ...}`; the step's own function still takes a `const P&`.
template <typename P>
struct Switchable : P {
    bool enabled = true;  ///< run the step

    /// The step's own parameters, with their defaults changed by `set(P&)`.
    template <typename Fn>
    static Switchable With(Fn&& set) {
        Switchable s;
        set(static_cast<P&>(s));
        return s;
    }
};

/// A bad parameter inside a node of a parameter tree: what() is "path: detail", the path being
/// the node's key path in the configuration (`models.concentric: distance must be >= 0`).
class ParameterError : public InvalidArgument {
  public:
    ParameterError(std::string path, std::string detail)
        : InvalidArgument(path + ": " + detail),
          path_(std::move(path)),
          detail_(std::move(detail)) {}
    const std::string& path() const { return path_; }
    const std::string& detail() const { return detail_; }

  private:
    std::string path_;
    std::string detail_;
};

/// Runs `validate()` (a node's checks) and rethrows an InvalidArgument as a ParameterError whose
/// path starts with `node`; nested calls build the whole path.
template <typename Fn>
void ValidateNode(const std::string& node, Fn&& validate) {
    try {
        validate();
    } catch (const ParameterError& e) {
        throw ParameterError(node + "." + e.path(), e.detail());
    } catch (const InvalidArgument& e) {
        throw ParameterError(node, e.what());
    }
}

}  // namespace multicue
