#pragma once
// Conversions between multicue's feature matrices and OpenCV's, and OpenCV models as strings.
// Internal to the ml module.

#include <string>

#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/ml/dataset.hpp"

namespace multicue::ml::detail {

/// A CV_32F copy of `x` (rows x cols).
inline cv::Mat ToMat(const FeaturesRef& x) {
    cv::Mat m(static_cast<int>(x.rows()), static_cast<int>(x.cols()), CV_32F);
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
        for (Eigen::Index c = 0; c < x.cols(); ++c) {
            m.at<float>(static_cast<int>(r), static_cast<int>(c)) = x(r, c);
        }
    }
    return m;
}

/// An OpenCV model in OpenCV's own YAML form (kept inside multicue's model container).
inline std::string ModelToString(const cv::Ptr<cv::ml::StatModel>& model) {
    cv::FileStorage fs(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    fs << "model"
       << "{";
    model->write(fs);
    fs << "}";
    return fs.releaseAndGetString();
}

/// "" when `model` is a classification tree model (boosting, random forest) over
/// `num_features` ordered features whose indices, class labels and thresholds are all in range;
/// otherwise the problem (opencv_model_check.cpp).
std::string TreesProblem(const cv::FileNode& model, std::size_t num_features,
                         std::size_t num_classes);
/// The same for a multi-layer perceptron with num_features inputs and num_classes outputs.
std::string MlpProblem(const cv::FileNode& model, std::size_t num_features,
                       std::size_t num_classes);

/// Reads an OpenCV model from its YAML form after `problem(node)` found nothing wrong with it:
/// OpenCV's readers trust their input (TreesProblem, MlpProblem).
template <typename T, typename Problem>
cv::Ptr<T> ModelFromString(const std::string& text, const std::string& what, Problem&& problem) {
    try {
        cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
        if (const std::string p = problem(fs["model"]); !p.empty()) {
            throw FormatError(what + ": embedded OpenCV model is damaged: " + p);
        }
        cv::Ptr<T> model = T::create();
        model->read(fs["model"]);
        if (!model->isTrained()) throw FormatError(what + ": embedded OpenCV model is empty");
        return model;
    } catch (const cv::Exception& e) {
        throw FormatError(what + ": embedded OpenCV model unreadable: " + e.msg);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        // OpenCV's YAML parser lets standard exceptions through on some malformed text (an
        // empty key gives std::length_error).
        throw FormatError(what + ": embedded OpenCV model unreadable: " + e.what());
    }
}

}  // namespace multicue::ml::detail
