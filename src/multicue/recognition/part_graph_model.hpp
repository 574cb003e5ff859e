#pragma once
/// \file Categorisation in clutter by part-graph hashing (thesis sections 5.1.2, 5.1.3 and 5.3;
/// Figures 5.5, 5.6, 5.14, 5.16). See docs/part-graph.md.
///
/// Descriptor of a part: GRSD- (features/grsd.hpp, 21 raw transition counts) of the 2.5 cm voxels
/// the part owns in one voxel map computed over all given parts (a voxel belongs to the part with
/// most points in it, ties to the lower part index; neighbours owned by other parts count as
/// empty), followed by the part's point moments (count, first and second order sums), a histogram
/// of its normals' elevation against the up direction (|n . up| in 6 bins) and the counts of its
/// points by the minimum radius of their RSD voxel (curved / mildly curved / planar). The
/// descriptor of a group of parts is the plain sum of its parts' descriptors, so it is computed
/// once per part and summed per subgraph. For the k-NN the GRSD- sum is normalised to unit sum and
/// square-rooted (the Euclidean distance of two such vectors is then exactly the
/// Jeffries-Matusita distance sqrt(2 (1 - sum sqrt(p_i q_i))) of the histograms), the summed
/// moments give the covariance of the group's points, whose three extents (weighted) are
/// appended, and the two count blocks are mapped like the GRSD- block, each with its own weight;
/// a k-d tree finds the nearest ones.
///
/// Model: a two-level hash table, number of parts -> sorted degree sequence -> the stored
/// subgraph descriptors with their categories (one k-d tree per bucket). Recognition grows every
/// subgraph of up to max_parts parts, looks up its bucket (an unseen degree sequence falls back
/// to the bucket of the same size whose sequence is nearest in L1, ties to the lower key), takes
/// the category frequencies of the k nearest stored descriptors, and adds them to each of its
/// parts with weight confidence / size^size_exponent (confidence = the largest frequency).

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "multicue/core/point_cloud.hpp"
#include "multicue/core/progress.hpp"
#include "multicue/core/types.hpp"
#include "multicue/features/feature_common.hpp"
#include "multicue/features/rsd.hpp"
#include "multicue/ml/knn.hpp"
#include "multicue/recognition/category_distribution.hpp"
#include "multicue/recognition/category_stacker.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/recognition/part_graph.hpp"

namespace multicue {

/// Columns of the GRSD- block of a part descriptor.
inline constexpr int kPartGrsdSize = 21;
/// Columns of the moment block: point count, sums of x, y, z and of xx, xy, xz, yy, yz, zz (point
/// coordinates relative to the mean of all parts given to ComputePartDescriptors, in a frame whose
/// z axis is the up direction).
inline constexpr int kPartMomentSize = 10;
/// Columns of the elevation block: counts of the part's points whose |normal . up| falls in each
/// of 6 equal bins of [0, 1] (0: horizontal normal, a vertical surface; 1: a horizontal surface).
inline constexpr int kPartElevationSize = 6;
/// Columns of the curvature block: counts of the part's points whose RSD voxel has r_min below
/// 3 cm, in [3 cm, 10 cm), and at least 10 cm (curved / mildly curved / planar); points in a voxel
/// without RSD count nowhere.
inline constexpr int kPartRsdSize = 3;
/// First column of each block of a raw part descriptor.
inline constexpr int kPartMomentOffset = kPartGrsdSize;
inline constexpr int kPartElevationOffset = kPartMomentOffset + kPartMomentSize;
inline constexpr int kPartRsdOffset = kPartElevationOffset + kPartElevationSize;
/// Dimensions of a raw part descriptor (GRSD- counts, moments, elevation counts, curvature
/// counts); every column is additive.
inline constexpr int kPartDescriptorSize = kPartRsdOffset + kPartRsdSize;
/// Dimensions of a stored (mapped) descriptor: square-rooted unit-sum GRSD- times grsd_weight,
/// then the three extents of the group's points (sqrt(12 lambda) of their covariance,
/// descending) times size_weight and the extent's own factor, then the square-rooted unit-sum
/// elevation and curvature counts times their weights.
inline constexpr int kPartMappedSize = kPartGrsdSize + 3 + kPartElevationSize + kPartRsdSize;
/// Version of the model file format (docs/part-graph.md). 2: moment block and extents. 3:
/// elevation and curvature blocks, block weights. 4: whole-object rows. 5: the RSD angle
/// quantile.
inline constexpr std::uint32_t kPartGraphModelVersion = 6;

struct PartDescriptorParams {
    /// GRSD- voxel map settings: 2.5 cm voxels; the RSD takes the 80th percentile angle of each
    /// distance bin as its largest (RsdParams::angle_quantile), so that the normal noise of a
    /// real Kinect does not turn planes into curved surfaces (docs/part-graph.md).
    VoxelRsdParams voxels = {.voxel_size = 0.025f, .rsd = {.angle_quantile = 0.8f}};
    /// Weight of the extents in the k-NN distance [1/m], >= 0 (0: no size).
    /// A 5 cm difference in an extent then counts as much as a Jeffries-Matusita distance of
    /// 0.05 * size_weight.
    float size_weight = 32.0f;
    /// Factors of the largest, middle and smallest extent (each times size_weight), >= 0.
    std::array<float, 3> extent_weights = {1.0f, 1.0f, 1.0f};
    float grsd_weight = 1.0f;       ///< weight of the GRSD- block, >= 0
    float elevation_weight = 1.0f;  ///< weight of the elevation block, >= 0 (0: unused)
    float rsd_weight = 0.5f;        ///< weight of the curvature block, >= 0 (0: unused)
    /// Extents against up instead of principal extents: the larger and smaller extent of the
    /// points projected on the support plane, then the extent along up (each sqrt(12 variance)).
    bool upright_extents = false;
};

/// One row per part (parts x kPartDescriptorSize): GRSD- raw counts from a voxel map over the
/// union of the parts' points, the point moments, the elevation counts against `up` and the
/// curvature counts. `up` is the support plane's normal in the cloud's frame (its sign does not
/// matter); a zero vector means unknown and falls back to the camera's -y axis (up in an image
/// of a level camera). `cloud` needs normals. Parts without a voxel of their own get a zero
/// GRSD- block. Throws InvalidArgument for an index out of range or a non-finite `up`, DataError
/// without normals (unless nothing is given).
FeatureMatrix ComputePartDescriptors(const PointCloud& cloud, const std::vector<Indices>& parts,
                                     const PartDescriptorParams& params = {},
                                     const Eigen::Vector3f& up = Eigen::Vector3f::Zero());

/// Sum of the descriptor rows of `vertices`.
Eigen::Matrix<float, 1, kPartDescriptorSize> SubgraphDescriptor(
    const FeatureMatrix& descriptors, std::span<const std::uint32_t> vertices);

struct PartGraphTrainParams {
    std::size_t max_parts = 8;  ///< largest subgraph stored (thesis: 8), [1, 15]
    /// Stored subgraphs per object and size at most (a uniform sample of the enumerated ones).
    std::size_t max_per_size = 200;
    /// Enumeration stops after this many subgraphs per object (roots in random order).
    std::size_t max_visited = 100000;
    std::uint64_t seed = 1;  ///< sampling seed
};

struct PartGraphRecognitionParams {
    std::size_t max_parts = 4;   ///< largest subgraph grown in a scene (Figure 5.14 a), [1, 15]
    std::size_t k = 5;           ///< neighbours voting per subgraph, >= 1
    float size_exponent = 1.0f;  ///< vote weight confidence / size^size_exponent, >= 0
    bool confidence_weighted = true;  ///< weight votes by their largest frequency
    /// Divide each neighbour's vote by its category's share of the stored rows (so categories
    /// with few stored subgraphs, e.g. flat objects of few parts, are not outvoted).
    bool balanced = true;
    /// Weight each neighbour's vote by 1 / (distance + distance_offset) (distance in the stored
    /// descriptor space); off: every neighbour counts once.
    bool distance_weighted = false;
    float distance_offset = 0.05f;       ///< > 0
    std::size_t max_subgraphs = 200000;  ///< enumeration cap per scene
    /// With part groups (objects): only subgraphs inside one group vote; adjacency between parts
    /// of different groups is ignored.
    bool within_groups = true;
    /// With part groups: every connected component of a group's parts (of at most the model's
    /// train_max_parts parts) also votes as one subgraph, with weight group_weight times its
    /// confidence on each of its parts (a single part's own vote has weight confidence), >= 0.
    float group_weight = 0.0f;
    /// Prior weight of each category (indexed by Category, kNone ignored), multiplied into every
    /// part's accumulated votes before they are normalised: the scenes' category frequencies
    /// relative to the balanced training votes, each >= 0 and finite, at least one > 0.
    std::array<float, kNumCategories> category_priors = UniformCategoryPriors();
    /// Throws InvalidArgument naming the first out-of-range field.
    void Validate() const;
    /// Its parameters once each: configuration key (the field's name), field, meaning. A
    /// visitor reads or records them (io::ConfigSection::operator(); ReadPerceiveParams).
    template <typename V>
    void VisitParams(V& v) {
        v("max_parts", max_parts, "largest group of parts classified in a scene");
        v("k", k, "neighbours voting per group");
        v("balanced", balanced, "divide votes by the category's share of the model's rows");
        v("within_groups", within_groups, "only groups of parts inside one perceived object vote");
        v("group_weight", group_weight, "weight of each whole object's own vote (0: none)");
        auto priors = v.Section("category_priors");
        for (std::size_t c = 1; c < kNumCategories; ++c) {
            priors(std::string(kCategoryNames[c]), category_priors[c],
                   "prior weight of this category's part-graph votes (>= 0)");
        }
    }
};

/// Per-part and per-group category distributions (indexed by Category; kNone stays 0 unless a
/// part received no vote, which then gets kNone with probability 1).
struct PartGraphResult {
    std::vector<std::array<float, kNumCategories>> part_probabilities;
    std::vector<Category> part_categories;
    std::size_t subgraphs = 0;  ///< subgraphs classified
    std::size_t fallbacks = 0;  ///< of which through a nearest bucket
};

class PartGraphModel {
  public:
    struct Bucket {
        std::vector<float> rows;           ///< mapped descriptors, kPartMappedSize per row
        std::vector<std::uint8_t> labels;  ///< Category per row
        ml::KdTreeNd tree;                 ///< over `rows` (Build)
    };

    PartDescriptorParams descriptor_params;  ///< used for training; recognition must use the same
    PartGraphParams graph_params;            ///< adjacency of parts
    std::size_t train_max_parts = 8;

    /// Adds every connected subgraph (sampled, see PartGraphTrainParams) of one labelled object.
    /// `category` must not be kNone. Returns the number of rows added.
    std::size_t AddObject(const FeatureMatrix& descriptors, const PartGraph& graph,
                          Category category, const PartGraphTrainParams& params);
    /// Builds the search structures; call after the last AddObject (Load calls it).
    void Build();

    /// Category frequencies of the k nearest stored descriptors for one subgraph key (raw
    /// descriptor, kPartDescriptorSize values); sets `fallback` when the key was not stored.
    /// With `balanced`, votes are divided by their category's share of the rows (then
    /// renormalised). With distance_offset > 0, each vote is also weighted by
    /// 1 / (distance + distance_offset). All zero if no bucket of that size exists.
    std::array<float, kNumCategories> Classify(std::uint64_t key, const float* descriptor,
                                               std::size_t k, bool* fallback = nullptr,
                                               bool balanced = false,
                                               float distance_offset = 0.0f) const;
    /// The stored form of a raw descriptor (kPartMappedSize values into `out`).
    void MapDescriptor(const float* raw, float* out) const;

    /// Whole-object expert stored with the model (the whole-cluster baseline of Table 5.9, used
    /// as a third cue): one ComputeClusterDescriptor row per training object and its category.
    /// All rows must have the same length; an all-zero descriptor is skipped. Throws
    /// InvalidArgument for kNone, a length mismatch or non-finite values.
    void AddCluster(const Eigen::VectorXf& descriptor, Category category);
    /// Category frequencies of the k nearest stored cluster rows (Euclidean, ties by index); all
    /// zero when none are stored or `descriptor` is all zero or of another length.
    std::array<float, kNumCategories> ClassifyCluster(const Eigen::VectorXf& descriptor,
                                                      std::size_t k) const;
    std::size_t num_clusters() const { return cluster_labels_.size(); }
    /// ClusterDescriptorParams::size_weight the cluster rows were computed with (other
    /// parameters at their defaults) [1/m].
    float cluster_size_weight = 0.0f;
    /// Level-1 classifier over the rules, part-graph and whole-object experts (perceive's
    /// "stacked" categoriser); untrained unless the model was trained with stacker scenes.
    CategoryStacker stacker;

    std::size_t num_rows() const;
    std::size_t num_buckets() const { return buckets_.size(); }
    const std::map<std::uint64_t, Bucket>& buckets() const { return buckets_; }
    std::array<std::size_t, kNumCategories> rows_per_category() const;

    std::string Serialize() const;
    static PartGraphModel Deserialize(const std::string& bytes, const std::string& what);
    /// Atomic write.
    void Save(const std::filesystem::path& path) const;
    /// FormatError for a corrupt file or another version, IoError when unreadable.
    static PartGraphModel Load(const std::filesystem::path& path);

  private:
    std::uint64_t ResolveKey(std::uint64_t key, bool* fallback) const;
    std::map<std::uint64_t, Bucket> buckets_;
    std::map<std::size_t, std::vector<std::uint64_t>> keys_by_size_;
    std::array<float, kNumCategories> class_weight_{};  ///< 1 / share of rows (Build)
    bool built_ = false;
    std::size_t cluster_dims_ = 0;
    std::vector<float> cluster_rows_;
    std::vector<std::uint8_t> cluster_labels_;
};

/// Categorises parts: builds their graph (model.graph_params), descriptors
/// (model.descriptor_params, `up` as in ComputePartDescriptors), and votes with every connected
/// subgraph up to params.max_parts. Deterministic.
PartGraphResult RecognizeParts(const PartGraphModel& model, const PointCloud& cloud,
                               const std::vector<Indices>& parts,
                               const PartGraphRecognitionParams& params = {},
                               const Eigen::Vector3f& up = Eigen::Vector3f::Zero(),
                               std::span<const std::uint32_t> groups = {});
/// Same from a ready graph and descriptors. `groups` (empty, or one id per part) assigns the
/// parts to objects for PartGraphRecognitionParams::within_groups and group_weight; without
/// groups every connected subgraph of the whole graph votes.
PartGraphResult RecognizeParts(const PartGraphModel& model, const PartGraph& graph,
                               const FeatureMatrix& descriptors,
                               const PartGraphRecognitionParams& params = {},
                               std::span<const std::uint32_t> groups = {});

/// Distribution of a group of parts (an object): point-count weighted mean of the parts'
/// distributions (`part_ids` index into the result); kNone with probability 1 when empty.
std::array<float, kNumCategories> MergePartProbabilities(const PartGraphResult& result,
                                                         const std::vector<Indices>& parts,
                                                         const std::vector<std::size_t>& part_ids);

/// Multi-view accumulation (section 5.3, Figure 5.16): per-point category votes of registered
/// frames summed in a voxel grid (5 mm by default); each point then takes the category of its
/// voxel.
class VoxelVoteGrid {
  public:
    explicit VoxelVoteGrid(float voxel_size = 0.005f);
    /// Adds the votes of one frame: points in the common frame and one distribution per point
    /// (same length; non-finite points are skipped). InvalidArgument on a size mismatch.
    void Add(const std::vector<Eigen::Vector3f>& points,
             const std::vector<std::array<float, kNumCategories>>& votes);
    /// Accumulated distribution at a point (all zero where nothing voted).
    std::array<float, kNumCategories> Votes(const Eigen::Vector3f& point) const;
    Category CategoryAt(const Eigen::Vector3f& point) const;
    std::size_t size() const { return cells_.size(); }

  private:
    float voxel_;
    std::map<std::array<int, 3>, std::array<float, kNumCategories>> cells_;
};

}  // namespace multicue
