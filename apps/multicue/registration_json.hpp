#pragma once
// JSON of registration results and transforms, shared by `register`, `map` and `perceive
// --manifest` (format "multicue.registration/1", docs/registration.md).

#include <string>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "multicue/registration/registration_result.hpp"

namespace multicue::cli {

/// A 4x4 matrix as rows.
nlohmann::json TransformJson(const Eigen::Isometry3d& T);
inline nlohmann::json TransformJson(const Eigen::Isometry3f& T) {
    return TransformJson(T.cast<double>());
}
/// The inverse of TransformJson; throws FormatError unless it is a finite rigid 4x4 matrix.
Eigen::Isometry3d TransformFromJson(const nlohmann::json& rows);
/// `M` as a rigid transform: throws InvalidArgument (naming `what`) unless it is finite with an
/// orthonormal rotation (to 1e-3) and a last row 0 0 0 1; the rotation is re-orthonormalised.
Eigen::Isometry3d CheckedTransform(const Eigen::Matrix4d& M, const std::string& what);

/// Every field of a result: format, T_target_source, converged, status, reason, iterations,
/// correspondences, inlier_rmse, fitness, overlap, condition, free_space_violation, information
/// (6x6), time_ms.
nlohmann::ordered_json RegistrationJson(const RegistrationResult& r);

/// A float option ("0.0014"); throws InvalidArgument naming the option otherwise.
float ParseFloatOption(const std::string& text, const std::string& option);

}  // namespace multicue::cli
