#include "registration_json.hpp"

#include <cmath>

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"

namespace multicue::cli {

nlohmann::json TransformJson(const Eigen::Isometry3d& T) {
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) {
        rows.push_back({T(r, 0), T(r, 1), T(r, 2), T(r, 3)});
    }
    return rows;
}

Eigen::Isometry3d CheckedTransform(const Eigen::Matrix4d& M, const std::string& what) {
    if (!M.allFinite()) throw InvalidArgument(what + ": the transform is not finite");
    if ((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9) {
        throw InvalidArgument(what + ": the last row of the transform must be 0 0 0 1");
    }
    const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
    if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 ||
        R.determinant() < 0.0) {
        throw InvalidArgument(what + ": the rotation part is not a rotation matrix");
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
    T.translation() = M.topRightCorner<3, 1>();
    return T;
}

Eigen::Isometry3d TransformFromJson(const nlohmann::json& rows) {
    if (!rows.is_array() || rows.size() != 4) throw FormatError("the transform is not 4x4");
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r) {
        if (!rows[r].is_array() || rows[r].size() != 4)
            throw FormatError("the transform is not 4x4");
        for (int c = 0; c < 4; ++c) M(r, c) = rows[r][c].get<double>();
    }
    try {
        return CheckedTransform(M, "transform");
    } catch (const InvalidArgument& e) {
        throw FormatError(e.what());
    }
}

nlohmann::ordered_json RegistrationJson(const RegistrationResult& r) {
    nlohmann::ordered_json j;
    j["format"] = "multicue.registration/1";
    j["T_target_source"] = TransformJson(r.T_target_source);
    j["converged"] = r.converged;
    j["status"] = RegistrationStatusName(r.status);
    j["reason"] = r.reason;
    j["iterations"] = r.iterations;
    j["correspondences"] = r.correspondences;
    j["inlier_rmse"] = r.inlier_rmse;
    j["fitness"] = r.fitness;
    j["overlap"] = r.overlap;
    j["condition"] = r.constraints.condition;
    j["free_space_violation"] = r.free_space_violation;
    nlohmann::json info = nlohmann::json::array();
    for (int a = 0; a < 6; ++a) {
        nlohmann::json row = nlohmann::json::array();
        for (int b = 0; b < 6; ++b) row.push_back(r.constraints.information(a, b));
        info.push_back(std::move(row));
    }
    j["information"] = std::move(info);
    j["time_ms"] = r.time_ms;
    return j;
}

float ParseFloatOption(const std::string& text, const std::string& option) {
    std::size_t used = 0;
    float v = 0.0f;
    try {
        v = std::stof(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != text.size() || text.empty() || !std::isfinite(v)) {
        throw InvalidArgument(fmt::format("{} must be a number, got '{}'", option, text));
    }
    return v;
}

}  // namespace multicue::cli
