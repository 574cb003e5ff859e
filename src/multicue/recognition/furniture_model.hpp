#pragma once
/// \file The trained furniture model (thesis section 4.2.3): a common vocabulary of parts (k-means
/// words over the part features, min-max normalised on the training parts), the shape model of
/// every training view (the vector d = p - s from each part's centre of mass s to the object's
/// centre p), the furniture classes with their widths and detection thresholds, and the CAD
/// models that verify detections (section 4.2.4.3), as dense point clouds with normals and as
/// meshes. One versioned file holds it all (docs/furniture.md, "Model file").
///
/// Shape vectors are kept in the part's bearing frame: rotated by minus the yaw under which the
/// sensor saw the part. A part of a scene seen under another bearing votes with the vector
/// turned back by its own bearing, so a chair's back seen face-on votes for a centre in front of
/// it whatever the chair's yaw in the room; the training views, taken from all around the
/// piece, supply the vectors of every side.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/triangle_mesh.hpp"
#include "multicue/features/feature_common.hpp"
#include "multicue/recognition/furniture_parts.hpp"

namespace multicue::ml {
class Classifier;
}  // namespace multicue::ml

namespace multicue {

/// Which part features the vocabulary uses (section 4.2.5: the full set against a reduced one).
enum class FurnitureFeatureSet {
    kFull,     ///< all 24 values
    kReduced,  ///< without features 4, 7 and 8 of section 4.2.3.1 (columns 3-8 and 13-22)
};
/// "full", "reduced"; and back (InvalidArgument naming the choices).
const char* FurnitureFeatureSetName(FurnitureFeatureSet set);
FurnitureFeatureSet ParseFurnitureFeatureSet(std::string_view name);
/// Columns of part_stats.hpp's 24 values a set uses, ascending.
std::vector<int> FurnitureFeatureColumns(FurnitureFeatureSet set);

/// How a part activates the vocabulary (section 4.2.5: the vocabulary against nearest neighbour).
enum class FurnitureActivation {
    kWords,        ///< the `activations` nearest words, weighted by Eq. (4.3)
    kNearestPart,  ///< only the nearest training part votes, with its own shape vector
};
/// "words", "nearest-part"; and back (InvalidArgument naming the choices).
const char* FurnitureActivationName(FurnitureActivation activation);
FurnitureActivation ParseFurnitureActivation(std::string_view name);

/// A furniture class.
struct FurnitureClass {
    std::string name;        ///< table, chair, cabinet, sideboard
    float width = 0.5f;      ///< median footprint width of its training pieces [m]
    float length = 0.5f;     ///< median footprint length [m]
    float height = 0.8f;     ///< median height [m]
    float threshold = 1.0f;  ///< V(o, x) a hypothesis needs (Eq. 4.5, section 4.2.4.2)
};

/// A CAD model for fitting, in the canonical frame of sim/furniture_models.hpp (z up, resting on
/// z = 0, footprint centred on the origin, front along +x).
struct FurnitureCad {
    std::string id;
    int cls = 0;        ///< index into FurnitureModel::classes()
    PointCloud cloud;   ///< outer surface points with outward normals [m]
    TriangleMesh mesh;  ///< for display (models.ply)
    Eigen::Vector3f extent = Eigen::Vector3f::Zero();  ///< box size [m]
};

/// One training part: its 24 features, class, training piece and view, and shape vector.
struct FurnitureTrainingPart {
    FeatureVector features;  ///< the 24 values of part_stats.hpp, unnormalised
    int cls = 0;             ///< class index
    int piece = 0;           ///< training piece
    int view = 0;            ///< training view of the piece
    Eigen::Vector3f offset = Eigen::Vector3f::Zero();  ///< d = p - s, part frame [m]
    float centre_z = 0.0f;  ///< height of p, the piece's centre, above the floor [m]
};

struct FurnitureVocabularyParams {
    std::size_t words = 40;            ///< k of k-means (thesis: 40), >= 1
    std::size_t max_iterations = 100;  ///< k-means iterations at most, >= 1
    std::uint32_t seed = 1;            ///< k-means++ seeding
    FurnitureFeatureSet features = FurnitureFeatureSet::kFull;
    int num_threads = 0;  ///< 0 = all cores; never changes the result
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

class FurnitureModel {
  public:
    /// Format version of the model file this build writes. Version 2 added the learned
    /// verifier; version 1 files (no verifier) are still read.
    static constexpr std::uint32_t kFormatVersion = 2;

    FurnitureModel() = default;

    /// Builds the vocabulary: min-max normalisation of the used columns over `parts`, k-means
    /// into min(words, parts) words, the elements of every word and their class counts. Throws
    /// InvalidArgument for no parts, no classes, a part or CAD model of an unknown class, a part
    /// feature vector that is not 24 long, or bad parameters; DataError for non-finite features.
    static FurnitureModel Train(std::vector<FurnitureTrainingPart> parts,
                                std::vector<FurnitureClass> classes, std::vector<FurnitureCad> cads,
                                const FurniturePartParams& part_params,
                                const FurnitureVocabularyParams& params);

    /// The activation of a part with 24 `features`: for kWords the `activations` nearest words
    /// with p(A_i | f) of Eq. (4.3) (inverse Euclidean distance, normalised over them), nearest
    /// first; for kNearestPart the single nearest training part with weight 1. Throws
    /// InvalidArgument before training, for a wrong length or activations == 0; DataError for
    /// non-finite features.
    std::vector<std::pair<int, float>> Activate(std::span<const float> features,
                                                FurnitureActivation mode,
                                                std::size_t activations) const;

    /// Training parts (indices into parts()) assigned to word `w`.
    const std::vector<int>& WordElements(int w) const {
        return word_elements_.at(static_cast<std::size_t>(w));
    }
    /// #(A_w, o) of Eq. (4.4): elements of word w of class o.
    float WordClassCount(int w, int cls) const;

    bool trained() const { return words_.rows() > 0; }
    std::size_t num_words() const { return static_cast<std::size_t>(words_.rows()); }
    const std::vector<FurnitureTrainingPart>& parts() const { return parts_; }
    const std::vector<FurnitureClass>& classes() const { return classes_; }
    std::vector<FurnitureClass>& classes() { return classes_; }
    const std::vector<FurnitureCad>& cads() const { return cads_; }
    const FurniturePartParams& part_params() const { return part_params_; }
    const FurnitureVocabularyParams& vocabulary_params() const { return vocabulary_params_; }
    /// Index of a class by name; -1 if absent.
    int ClassIndex(std::string_view name) const;
    /// Longest part and tallest piece seen in training [m]: longer or higher scene parts (walls)
    /// belong to no furniture.
    float max_part_extent() const { return max_part_extent_; }
    float max_object_height() const { return max_object_height_; }

    /// The learned verifier of fitted detections (mapping/furniture_detection.hpp, "learned
    /// verification"): a classifier of the rows FurnitureVerifierFeatures gives, with the classes
    /// "right" and "wrong"; null when the model has none.
    const ml::Classifier* verifier() const { return verifier_.get(); }
    /// Sets (or, with null, removes) the verifier. Throws InvalidArgument for an unfitted
    /// classifier or one without the classes "right" and "wrong".
    void SetVerifier(std::shared_ptr<const ml::Classifier> verifier);

    /// Writes the model atomically (ml/serialization.hpp container, magic MCFURNIT). Throws
    /// IoError when the file cannot be written.
    void Save(const std::filesystem::path& path) const;
    /// Reads a model; FormatError naming the file for another format, another version, a
    /// truncated or corrupt file or inconsistent contents.
    static FurnitureModel Load(const std::filesystem::path& path);

  private:
    void Normalize(std::span<const float> in, float* out) const;
    std::vector<FurnitureTrainingPart> parts_;
    std::vector<FurnitureClass> classes_;
    std::vector<FurnitureCad> cads_;
    FurniturePartParams part_params_;
    FurnitureVocabularyParams vocabulary_params_;
    std::vector<int> columns_;        ///< used feature columns
    std::vector<float> lo_, scale_;   ///< min-max normalisation per used column
    FeatureMatrix words_;             ///< k x columns, normalised space
    FeatureMatrix normalized_parts_;  ///< parts x columns (nearest-part activation)
    std::vector<std::vector<int>> word_elements_;
    std::vector<std::vector<float>> word_class_counts_;  ///< word x class
    float max_part_extent_ = 0.0f;
    float max_object_height_ = 0.0f;
    void Derive();  ///< normalisation, limits and normalised parts from the training parts
    void Index();   ///< word elements and counts from the parts' words
    std::vector<int> part_words_;  ///< word of every training part
    std::shared_ptr<const ml::Classifier> verifier_;
};

}  // namespace multicue
