#pragma once
// Bird's-eye pictures of a scored room for furniture_eval --draw: the scans' points (grey), the
// true pieces (outlined in their class colour, distractors in grey), the hypotheses (circles,
// radius growing with the score) and the fitted models (footprints; rejected ones thin and
// labelled with the reason's first letter), the head positions (black).

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "multicue/mapping/furniture_detection.hpp"
#include "multicue/sim/objects.hpp"
#include "multicue/training/furniture_training.hpp"

namespace multicue::eval {

inline cv::Scalar ClassColour(const std::string& c) {
    if (c == "table") return {40, 40, 220};
    if (c == "chair") return {220, 120, 30};
    if (c == "cabinet") return {40, 170, 40};
    if (c == "sideboard") return {180, 40, 180};
    return {120, 120, 120};
}

inline void DrawRoom(const std::string& path, const training::ScannedFurnitureRoom& r,
                     const FurnitureScene& scene, const FurnitureDetectionResult& det,
                     const FurnitureModel& model) {
    const float ppm = 90.0f, margin = 0.5f;
    const Eigen::Vector2f half = r.room.size / 2 + Eigen::Vector2f::Constant(margin);
    cv::Mat img(static_cast<int>(2 * half.y() * ppm), static_cast<int>(2 * half.x() * ppm), CV_8UC3,
                cv::Scalar(255, 255, 255));
    auto px = [&](const Eigen::Vector2f& p) {
        return cv::Point(static_cast<int>((p.x() + half.x()) * ppm),
                         static_cast<int>((half.y() - p.y()) * ppm));
    };
    const float max_extent = 1.25f * model.max_part_extent(),
                max_top = model.max_object_height() + 0.15f;
    for (const auto& v : scene.views) {
        for (const auto& part : v.parts) {
            const bool wall = part.extent > max_extent || part.top > max_top;
            for (Index i : part.indices) {
                cv::circle(img, px(v.cloud.points[i].head<2>()), 0,
                           wall ? cv::Scalar(150, 150, 255) : cv::Scalar(150, 150, 150), -1);
            }
        }
    }
    auto poly = [&](const std::vector<Eigen::Vector2f>& pts, cv::Scalar c, int w) {
        std::vector<cv::Point> q;
        for (const auto& p : pts) q.push_back(px(p));
        cv::polylines(img, q, true, c, w, cv::LINE_AA);
    };
    for (const auto& o : r.room.scene.objects) {
        if (o.label < sim::ObjectLabel(1)) continue;
        std::vector<Eigen::Vector2f> pts;
        for (const auto& v : o.mesh->mesh.vertices) pts.push_back((o.T_world_object * v).head<2>());
        const std::string c = o.category > 0 ? sim::CategoryNames()[o.category] : "none";
        std::vector<cv::Point> q;
        for (const auto& p : sim::ConvexHull2D(pts)) q.push_back(px(p));
        const cv::Scalar col = ClassColour(c);
        cv::Mat layer = img.clone();
        cv::fillConvexPoly(layer, q, col);
        cv::addWeighted(layer, 0.25, img, 0.75, 0.0, img);
    }
    auto draw_det = [&](const FurnitureDetection& d, bool accepted) {
        const cv::Scalar col = ClassColour(d.category);
        if (d.fitted) {
            const auto& cad = model.cads()[static_cast<std::size_t>(d.fit.cad)];
            std::vector<Eigen::Vector2f> pts;
            for (std::size_t i = 0; i < cad.cloud.size(); i += 7)
                pts.push_back((d.fit.ModelToWorld() * cad.cloud.points[i]).head<2>());
            if (accepted) poly(sim::ConvexHull2D(pts), col, 2);
        }
        const int rad = static_cast<int>(3 + 4 * std::min(d.score, 3.0f));
        if (accepted || d.score >= 1.0f)
            cv::circle(img, px(d.hypothesis.centre), rad, col, accepted ? 2 : 1, cv::LINE_AA);
        if (!accepted && d.score < 1.0f) return;
        if (!accepted) {
            cv::putText(img, d.rejection.substr(0, 1), px(d.hypothesis.centre) + cv::Point(rad, 0),
                        cv::FONT_HERSHEY_SIMPLEX, 0.4, col, 1);
        }
    };
    for (const auto& d : det.rejected) draw_det(d, false);
    for (const auto& d : det.detections) draw_det(d, true);
    for (const auto& T : r.T_world_sensor) {
        cv::circle(img, px(T.translation().head<2>()), 5, cv::Scalar(0, 0, 0), -1);
    }
    cv::imwrite(path, img);
}

}  // namespace multicue::eval
