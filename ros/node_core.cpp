#include "node_core.hpp"

#include <mutex>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/config.hpp"
#include "multicue/io/depth_image.hpp"
#include "multicue/io/point_cloud2.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/system/executive.hpp"
#include "multicue/system/executive_json.hpp"
#include "multicue/system/object_database.hpp"
#include "multicue/system/perceive_output.hpp"
#include "multicue/training/part_graph_training.hpp"

namespace multicue::ros1 {

struct NodeCore::Impl {
    PerceiveParams params;
    PerceiveModels models;
    std::optional<ObjectDatabase> database;
    std::unique_ptr<PerceptionExecutive> executive;
    std::mutex executive_mutex;
    std::mutex frame_mutex;
    std::shared_ptr<const PointCloud> last_cloud;
    std::string last_name;

    FrameOutput Run(PointCloud cloud, const std::string& name) {
        if (!cloud.HasFinite()) {
            throw DataError(fmt::format("{}: no finite point among {}", name, cloud.size()));
        }
        const PerceiveResult result = multicue::Perceive(cloud, params, models);
        FrameOutput out;
        out.objects = result.objects.size();
        out.labels = io::ToPointCloud2(PerceiveLabelsCloud(cloud, result));
        out.result_json = PerceiveResultJson(name, result).dump();
        const TriangleMesh mesh = PerceiveModelsMesh(result);
        for (const auto& t : mesh.triangles) {
            for (int k = 0; k < 3; ++k) {
                const auto v = static_cast<std::size_t>(t[k]);
                for (int d = 0; d < 3; ++d) out.triangles.push_back(mesh.vertices[v][d]);
                const Color c = mesh.HasVertexColors() ? mesh.vertex_colors[v] : Color{};
                out.triangle_rgb.insert(out.triangle_rgb.end(),
                                        {c.r / 255.0f, c.g / 255.0f, c.b / 255.0f});
            }
        }
        for (const auto& o : result.objects) {
            TextMarker m;
            m.id = o.id;
            for (int d = 0; d < 3; ++d) m.position[d] = o.centroid[d];
            m.text = fmt::format("{} {} {:.2f}", o.id, CategoryName(o.category.category),
                                 o.category.confidence);
            const Color c = ObjectColor(o.id);
            m.rgb[0] = c.r / 255.0f, m.rgb[1] = c.g / 255.0f, m.rgb[2] = c.b / 255.0f;
            out.texts.push_back(std::move(m));
        }
        auto shared = std::make_shared<const PointCloud>(std::move(cloud));
        std::lock_guard<std::mutex> lock(frame_mutex);
        last_cloud = std::move(shared);
        last_name = name;
        return out;
    }
};

NodeCore::NodeCore(const CoreOptions& options) : impl_(std::make_unique<Impl>()) {
    auto& params = impl_->params;
    if (!options.config_file.empty()) {
        auto config = io::ConfigSection::Load(options.config_file);
        ReadPerceiveParams(config, params);
        config.CheckAllUsed();
    }
    if (!options.config_json.empty()) {
        auto config = io::ConfigSection::Parse(options.config_json, options.config_source);
        ReadPerceiveParams(config, params);
        config.CheckAllUsed();
    }
    if (options.threads != 0) params.num_threads = options.threads;
    params.Validate();
    impl_->models = training::LoadPerceiveModels(params);
    if (!options.database.empty())
        impl_->database = ObjectDatabase::Open(options.database, DatabaseMode::kCreateOrWrite);
    ExecutiveParams executive;
    executive.perceive = params;
    impl_->executive = std::make_unique<PerceptionExecutive>(
        impl_->database ? &*impl_->database : nullptr, executive, impl_->models);
}

NodeCore::~NodeCore() = default;

FrameOutput NodeCore::Perceive(const io::PointCloud2Message& message, const std::string& name) {
    return impl_->Run(io::FromPointCloud2(message, name), name);
}

FrameOutput NodeCore::PerceiveDepth(const DepthFrame& frame, const std::string& name) {
    io::DepthImage depth{frame.width, frame.height, frame.depth};
    std::vector<Color> colors;
    if (!frame.rgb.empty()) {
        if (frame.rgb.size() != 3 * frame.depth.size()) {
            throw InvalidArgument(
                fmt::format("{}: colour image size differs from the depth's", name));
        }
        colors.resize(frame.depth.size());
        for (std::size_t i = 0; i < colors.size(); ++i)
            colors[i] = Color{frame.rgb[3 * i], frame.rgb[3 * i + 1], frame.rgb[3 * i + 2], 255};
    }
    return impl_->Run(io::DepthToCloud(depth, {frame.fx, frame.fy, frame.cx, frame.cy}, colors),
                      name);
}

std::string NodeCore::RunTask(const std::string& task_json) {
    nlohmann::json spec;
    try {
        spec = task_json.empty() ? nlohmann::json::object() : nlohmann::json::parse(task_json);
    } catch (const nlohmann::json::exception& e) {
        throw InvalidArgument(std::string("run_task: malformed JSON (") + e.what() + ")");
    }
    if (!spec.is_object()) throw InvalidArgument("run_task: the task must be a JSON object");
    const Task task = TaskFromJson(spec, "run_task");
    Frame frame;
    {
        std::lock_guard<std::mutex> lock(impl_->frame_mutex);
        if (!impl_->last_cloud) throw DataError("run_task: no frame perceived yet");
        frame.cloud = *impl_->last_cloud;
        frame.name = impl_->last_name;
    }
    std::lock_guard<std::mutex> lock(impl_->executive_mutex);
    const FrameReport report = impl_->executive->Run(frame, task);
    const ObjectDatabase* db = impl_->database ? &*impl_->database : nullptr;
    return FrameReportJson(report, task, db).dump();
}

}  // namespace multicue::ros1
