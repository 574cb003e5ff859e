#pragma once
/// \file Training of the furniture model (thesis section 4.2.2): every training piece (a half of
/// the furniture library and procedural furniture) stands on the floor and is scanned from
/// sensor positions around it (16 by default, 1.5-3 m away, the head 1.5 m high); the views are
/// cut into parts exactly as scenes are (recognition/furniture_parts.hpp), and the parts with
/// their shape vectors build the vocabulary. Every piece also becomes a CAD model for fitting:
/// points on its outer surface, found by casting parallel rays at it from 40 directions.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "multicue/core/progress.hpp"
#include "multicue/mapping/furniture_fit.hpp"
#include "multicue/ml/dataset.hpp"
#include "multicue/recognition/furniture_model.hpp"
#include "multicue/sim/furniture_models.hpp"
#include "multicue/sim/furniture_scenes.hpp"
#include "multicue/sim/sensors.hpp"

namespace multicue::training {

/// The simulated sensor of training views and rooms.
enum class FurnitureSensor {
    kLaser,   ///< tilting laser on a pan-tilt head (section 4.2.5)
    kKinect,  ///< RGB-D camera at the head, looking at the piece
};
/// "laser", "kinect"; and back (InvalidArgument naming the choices).
const char* FurnitureSensorName(FurnitureSensor sensor);
FurnitureSensor ParseFurnitureSensor(const std::string& name);

/// Class thresholds of V(o, x) used unless told otherwise (docs/furniture.md says where they
/// come from).
const std::map<std::string, float>& DefaultFurnitureThresholds();

struct FurnitureTrainingOptions {
    std::filesystem::path furniture;  ///< furniture folder with labels.csv; empty: none
    std::filesystem::path kitchen;    ///< kitchen library folder; empty: none
    sim::MeshSplit split = sim::MeshSplit::kTune;  ///< the library half trained on
    int procedural_per_class = 8;                  ///< procedural pieces per class, >= 0
    std::uint64_t seed = 1;                        ///< views, sensor noise and procedural pieces
    FurnitureSensor sensor = FurnitureSensor::kLaser;
    sim::FurnitureViewParams views{};  ///< 16 views at 1.5-3 m, 1.5 m high
    sim::LaserParams laser{.fov_deg = 120.0f};
    sim::KinectParams kinect{};
    FurniturePartParams parts{};
    FurnitureVocabularyParams vocabulary{};
    std::map<std::string, float> thresholds = DefaultFurnitureThresholds();
    float cad_spacing = 0.02f;  ///< spacing of the CAD models' points [m], > 0
    /// Learned verification (mapping/furniture_detection.hpp): the model's verifier is trained
    /// on the fits in this many simulated rooms of fresh procedural pieces, >= 0; 0: no verifier.
    /// 60 rooms ranked the validation rooms' fits better than 30 (eval/README.md)
    int verifier_rooms = 60;
    std::uint64_t verifier_seed = 5000;  ///< seed of the first verifier room (the next: + 1, ...)
    /// Rows from library pieces the fit has never seen: this many more verifier rooms furnished
    /// with the training library's pieces (no procedural ones where the library has the class).
    /// The library pieces are split in two halves (every other piece of a class by id); the
    /// rooms of one half are fitted by a stand-in model trained on the procedural pieces and the
    /// other half, so that every library piece is fitted as an unseen piece of the library would
    /// be, >= 0; 0: none. Nothing is added when the training pieces hold no library piece or no
    /// procedural one.
    int verifier_library_rooms = 30;  ///< 30 chosen on the library folds (eval/README.md)
    std::uint64_t verifier_library_seed = 6000;  ///< seed of the first of those rooms
    /// Label a verifier row by the centre of the piece's box (FurniturePieceCentre: the fitted
    /// model's box grown or shrunk to the scan's parts of the piece, as detection reports an
    /// accepted fit) instead of the fitted model's centre. Off: on the validation rooms and library
    /// folds it found one piece fewer (measured before the box could shrink; eval/README.md)
    bool verifier_piece_labels = false;
    /// Classifier of the verifier (ml::CreateClassifier spec)
    std::string verifier_spec = "rtrees:trees=200";
    /// CAD fitting in the verifier rooms: the parameters detection will use (the verifier learns
    /// what their fits look like)
    FurnitureFitParams verifier_fit{};
    /// CAD models finished per hypothesis in the verifier rooms (FurnitureDetectionParams::
    /// fit_models), >= 1. 1: the verifier learns from the best model's fits alone; with the other
    /// models' fits among its rows it ranked worse on the validation rooms and library folds
    /// (eval/README.md)
    int verifier_fit_models = 1;
    int num_threads = 0;  ///< 0 = all cores; never changes the model
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
};

/// The pieces trained on: the chosen half of the library (loaded; bad models are skipped with a
/// warning) and procedural_per_class procedural pieces of every class, procedural ids
/// "procedural/<class>/train<k>".
std::vector<sim::FurniturePiece> FurnitureTrainingPieces(const FurnitureTrainingOptions& options);

/// Outer surface points of a piece (canonical frame) with outward normals, `spacing` apart.
PointCloud FurnitureCadCloud(const sim::PartMesh& mesh, float spacing);

/// The training parts of one piece (class index `cls`, piece index `piece`) from its views.
std::vector<FurnitureTrainingPart> FurnitureTrainingParts(const sim::FurniturePiece& piece, int cls,
                                                          int piece_index,
                                                          const FurnitureTrainingOptions& options);

/// A scan of a scene from a head pose with the chosen sensor: the laser in the head frame, the
/// Kinect in its optical frame looking at `target`; `T_world_sensor` receives the sensor pose.
PointCloud ScanFurniture(const sim::RayCaster& caster, const Eigen::Isometry3f& head,
                         const Eigen::Vector3f& target, const FurnitureTrainingOptions& options,
                         std::uint64_t seed, Eigen::Isometry3f& T_world_sensor);

/// A furnished room scanned from `heads` head positions (RoomHeadPoses, 1.5 m high): the laser
/// sweeps its full field (270 degrees), the Kinect looks towards the room's centre.
struct ScannedFurnitureRoom {
    sim::FurnitureRoom room;
    std::vector<PointCloud> scans;  ///< in their sensor frames, with labels
    std::vector<Eigen::Isometry3f> T_world_sensor;
};
ScannedFurnitureRoom SimulateFurnitureRoom(const sim::FurnitureRoomParams& params,
                                           const sim::FurnitureSource& source, int heads,
                                           const FurnitureTrainingOptions& sensor,
                                           std::uint64_t seed);

/// Trains the model on `pieces` and, with verifier_rooms > 0, its verifier
/// (FurnitureTrainingSteps progress steps: one per piece, one per verifier room). Returns false,
/// leaving `out` untouched, when interrupted (InterruptRequested). Throws InvalidArgument for bad
/// options or no pieces, DataError when the views give no parts or the verifier rooms no right
/// and wrong fits.
bool TrainFurnitureModel(const std::vector<sim::FurniturePiece>& pieces,
                         const FurnitureTrainingOptions& options, FurnitureModel& out,
                         Progress* progress = nullptr);
std::size_t FurnitureTrainingSteps(const std::vector<sim::FurniturePiece>& pieces,
                                   const FurnitureTrainingOptions& options);

/// A classifier of options.verifier_spec (seeded with options.seed) fitted to `rows` of
/// CollectFurnitureVerifierRows. DataError when they hold no right or no wrong fit, or their
/// features are not the verifier's of `model`.
std::shared_ptr<const ml::Classifier> FitFurnitureVerifier(const FurnitureModel& model,
                                                           const ml::Dataset& rows,
                                                           const FurnitureTrainingOptions& options);

/// True for the pieces FurnitureTrainingPieces makes procedurally (ids "procedural/...").
bool IsProceduralFurniture(const sim::FurniturePiece& piece);

/// Pieces split for training on part of a library: the procedural ones, and the library ones in
/// two halves (within each class, ordered by id, every other piece; half 0 takes the odd one).
struct FurnitureLibraryHalves {
    std::vector<sim::FurniturePiece> procedural;
    std::array<std::vector<sim::FurniturePiece>, 2> library;
};
FurnitureLibraryHalves SplitFurnitureLibrary(const std::vector<sim::FurniturePiece>& pieces);

/// Progress steps of AppendFurnitureLibraryVerifierRows for `pieces`: the pieces of its two
/// stand-in models and its rooms (0 when it appends nothing).
std::size_t FurnitureLibraryVerifierSteps(const std::vector<sim::FurniturePiece>& pieces,
                                          const FurnitureTrainingOptions& options);

/// Appends to `rows` (CollectFurnitureVerifierRows of `model`) the rows of
/// options.verifier_library_rooms rooms furnished with the library pieces of `pieces` (see
/// FurnitureTrainingOptions::verifier_library_rooms): the rooms of each half of the library
/// fitted by a model trained on the procedural pieces of `pieces` and the other half. Appends
/// nothing when `pieces` hold no library or no procedural piece, or the option is 0. One
/// progress step per piece a stand-in trains on and per room; stops early when interrupted.
/// InvalidArgument when `rows` have other features than `model`'s verifier, DataError when the
/// procedural pieces lack a class of `model`.
void AppendFurnitureLibraryVerifierRows(ml::Dataset& rows, const FurnitureModel& model,
                                        const std::vector<sim::FurniturePiece>& pieces,
                                        const FurnitureTrainingOptions& options,
                                        Progress* progress = nullptr);

/// Rows of the verifier (FurnitureVerifierFeatureNames; labels "right" and "wrong"): every fit
/// of `model` to a hypothesis above its class threshold (default detection parameters with
/// options.verifier_fit, without the verifier; fits the coverage, free-space and wall tests reject
/// too, and those an overlapping fit displaces) in options.verifier_rooms rooms of fresh procedural
/// pieces (offices, seminar rooms and kitchens in turn, seeds from verifier_seed), each scanned
/// from 3 head positions, with the scans merged and each scan alone. A fit is right when a true
/// piece of its class stands within half its width of the fitted centre. One progress step per
/// room; stops early, with the rows so far, when interrupted.
ml::Dataset CollectFurnitureVerifierRows(const FurnitureModel& model,
                                         const FurnitureTrainingOptions& options,
                                         Progress* progress = nullptr);

}  // namespace multicue::training
