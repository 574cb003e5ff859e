#pragma once
/// \file The perception executive (thesis sections 3.1 and 3.2): regions of interest with class
/// distributions ("hypotheses") are the common input and output of every examination method; the
/// executive chooses and chains methods according to a task, identifies what it sees against the
/// object model database, and learns new objects and new views of known ones.
///
/// Methods declare what they require and provide (capabilities such as "hypotheses", "category",
/// "descriptor:colour", "identity"); the executive orders them so that every requirement is met
/// before a method runs. Identification merges the evidence of several descriptors either in
/// parallel (product of per-descriptor identity distributions, section 3.3) or hierarchically
/// (each descriptor removes candidate identities before the next, section 3.2.2).

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/types.hpp"
#include "multicue/system/object_database.hpp"
#include "multicue/system/perceive.hpp"

namespace multicue {

/// A region of interest and what the methods found out about it.
struct Hypothesis {
    int id = 0;       ///< 1-based within the frame (the perceive object id)
    Indices indices;  ///< the frame's points of the region
    Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< centroid in the world frame [m]
    Eigen::Vector3f extents = Eigen::Vector3f::Zero();   ///< sorted bounding-box extents [m]
    std::map<std::string, double> categories;            ///< geometric category distribution
    std::map<std::string, std::vector<float>> descriptors;
    /// Identity: distribution over database objects (by id); empty until identified.
    std::map<std::int64_t, double> identities;
    std::int64_t object_id = 0;  ///< the identified (or newly learnt) object, 0 = none
    bool novel = false;          ///< no known object matched; a new one was (or would be) learnt
    bool by_position = false;    ///< identified because a known object was last seen here
    std::vector<std::string> provenance;  ///< methods that examined the hypothesis, in order
    nlohmann::json model = nlohmann::json::object();  ///< model parameters when fitted

    std::string Category() const;  ///< most probable category, "" if none
};

/// One sensor frame with its pose in the world (map) frame.
struct Frame {
    PointCloud cloud;  ///< in the sensor frame
    Eigen::Isometry3d T_world_sensor = Eigen::Isometry3d::Identity();
    double time = 0.0;  ///< [s]
    std::string name;   ///< file name or index, stored with learnt views
};

/// What the robot's planner asks for (section 6.1).
struct Task {
    enum class Kind {
        kEnumerate,  ///< find and identify everything in the region; learn what is new
        kFind,       ///< find one object (by database name or id): active search
        kModel,      ///< find and model objects of a category or one object
    };
    Kind kind = Kind::kEnumerate;
    std::string target;  ///< kFind: object name or id; kModel: category or object name
    std::optional<Eigen::AlignedBox3d> region;  ///< world-frame region of interest
    std::vector<std::string> possible_objects;  ///< restrict identities to these names
    bool learn = true;                          ///< learn novel objects and new views
};

/// Parses "enumerate", "find" or "model"; throws InvalidArgument otherwise.
Task::Kind ParseTaskKind(const std::string& name);

struct ExecutiveParams {
    PerceiveParams perceive{};
    /// Identity by position: a hypothesis within this distance of where a known object was last
    /// seen is that object (section 3.2.4) [m].
    double same_place_radius = 0.05;
    /// A descriptor match closer than this (mean normalised distance in [0, 1]) is a known object;
    /// farther means novel.
    double novelty_distance = 0.35;
    /// Merge descriptor evidence in parallel (product of distributions) instead of hierarchically.
    bool parallel_merge = true;
    /// Learn a new view of a known object when its nearest stored view is at least this far
    /// (same normalised distance): the view adds information (section 3.2.4).
    double new_view_distance = 0.08;
    /// Active search looks first within this distance of where the sought object was last seen
    /// (horizontally, all heights), then in the whole frame [m].
    double search_margin = 0.25;
    int colour_bins = 8;  ///< per channel of the colour descriptor
};

/// Everything a method may read while examining a frame.
struct ExaminationContext {
    const Frame& frame;
    const Task& task;
    const ExecutiveParams& params;
    const ObjectDatabase* database = nullptr;  ///< may be null (nothing known yet)
    const PerceiveModels* models = nullptr;    ///< the categoriser's models (null: none)
    std::optional<PerceiveResult> perceive;    ///< set by the segmentation method
};

/// One examination method (section 3.1.2).
class ExaminationMethod {
  public:
    virtual ~ExaminationMethod() = default;
    virtual std::string Name() const = 0;
    virtual std::vector<std::string> Requires() const = 0;
    virtual std::vector<std::string> Provides() const = 0;
    /// Refines the hypotheses (may add or drop some).
    virtual void Examine(ExaminationContext& context, std::vector<Hypothesis>& hypotheses) = 0;
};

/// Table-top segmentation with geometric categories and primitive models (provides
/// "hypotheses", "category", "model").
std::unique_ptr<ExaminationMethod> MakeSegmentationMethod();
/// Colour histogram per hypothesis ("descriptor:colour").
std::unique_ptr<ExaminationMethod> MakeColourDescriptorMethod();
/// Size and geometric category as a descriptor ("descriptor:shape").
std::unique_ptr<ExaminationMethod> MakeShapeDescriptorMethod();
/// Identification against the database (requires hypotheses and descriptors; provides
/// "identity").
std::unique_ptr<ExaminationMethod> MakeIdentificationMethod();

/// Per-frame outcome.
struct FrameReport {
    std::string frame;
    double time = 0.0;
    std::vector<Hypothesis> hypotheses;
    std::vector<std::string> methods;  ///< in the order they ran
    std::vector<std::pair<std::string, double>> timings_ms;
    std::size_t learnt_objects = 0;  ///< new objects added to the database
    std::size_t learnt_views = 0;    ///< new views of known objects
    /// kFind: the hypothesis that is the sought object, if seen.
    std::optional<std::size_t> found;
};

/// Distance between two descriptors of the same kind, normalised to [0, 1] (chi-square for
/// histograms, relative difference for the shape descriptor).
double DescriptorDistance(const std::string& kind, const std::vector<float>& a,
                          const std::vector<float>& b);

class PerceptionExecutive {
  public:
    /// `database` may be null: nothing is identified or learnt then. `models` are the learned
    /// models of the segmentation method's categoriser (params.perceive.category); checked here.
    PerceptionExecutive(ObjectDatabase* database, ExecutiveParams params = {},
                        PerceiveModels models = {});

    /// Adds a method (the four standard ones are there from the start).
    void AddMethod(std::unique_ptr<ExaminationMethod> method);

    /// The methods a task needs, in an order that meets every requirement. Throws InvalidArgument
    /// if a requirement cannot be met.
    std::vector<std::string> Plan(const Task& task) const;

    /// Examines one frame for a task; learns into the database when the task says so.
    FrameReport Run(const Frame& frame, const Task& task);

  private:
    ObjectDatabase* database_;
    ExecutiveParams params_;
    PerceiveModels models_;
    std::vector<std::unique_ptr<ExaminationMethod>> methods_;
};

}  // namespace multicue
