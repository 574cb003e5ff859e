// perceive(): the pipeline of `multicue perceive` on a cloud in memory. The configuration is the
// parameter file's JSON object as a dict; the result is result.json's object as a dict (made by
// the same function the CLI uses) and labels.pcd's per-point fields as arrays.

#include <cstdint>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "multicue/io/config.hpp"
#include "multicue/recognition/geometric_category.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_output.hpp"
#include "multicue/system/perceive_report.hpp"
#include "multicue/training/part_graph_training.hpp"

namespace py = pybind11;

namespace multicue::python {
namespace {

/// The parameters of a configuration dict (None: the defaults), checked as `multicue perceive
/// --config` checks a file; its "report" section is accepted and ignored.
PerceiveParams ReadParams(const py::object& config, int threads) {
    PerceiveParams params;
    if (!config.is_none()) {
        if (!py::isinstance<py::dict>(config)) {
            throw InvalidArgument("config must be a dict (the JSON object of a parameter file)");
        }
        const std::string text =
            py::module_::import("json").attr("dumps")(config).cast<std::string>();
        auto section = io::ConfigSection::Parse(text, "config");
        ReadPerceiveParams(section, params);
        ReportParams report;
        ReadReportParams(section, report);
        section.CheckAllUsed();
    }
    if (threads != 0) params.num_threads = threads;
    params.Validate();
    return params;
}

}  // namespace

void BindPerceive(py::module_& m) {
    py::list names;
    for (const auto& name : kCategoryNames) names.append(std::string(name));
    m.attr("CATEGORIES") = py::tuple(names);
    m.attr("RESULT_FORMAT") = "multicue.result/" + std::to_string(kPerceiveOutputFormatVersion);
    m.def(
        "perceive",
        [](const PointCloud& cloud, const py::object& config, int threads,
           const std::string& input) {
            const PerceiveParams params = ReadParams(config, threads);
            PerceiveResult result;
            std::string json;
            {
                py::gil_scoped_release release;
                const PerceiveModels models = training::LoadPerceiveModels(params);
                result = Perceive(cloud, params, models);
                json = PerceiveResultJson(input, result).dump();
            }
            py::object dict = py::module_::import("json").attr("loads")(json);
            const auto n = static_cast<py::ssize_t>(result.point_objects.size());
            py::array_t<std::uint32_t> objects(n, result.point_objects.data());
            py::array_t<std::uint8_t> categories(n, result.point_categories.data());
            return py::make_tuple(dict, objects, categories);
        },
        py::arg("cloud"), py::arg("config") = py::none(), py::kw_only(), py::arg("threads") = 0,
        py::arg("input") = "",
        R"(Runs the table-top pipeline of `multicue perceive` on `cloud`.

config: None for the defaults, or a dict shaped like a parameter file (`multicue config --dump`);
unknown keys and out-of-range values raise InvalidArgument naming the key.
threads: worker threads, 0 = the configuration's (all cores by default).
input: the name recorded as "input" in the result.

Returns (result, objects, categories): result is the dict that result.json holds (format
RESULT_FORMAT: support plane, objects with categories and models, timings), objects the per-point
object id (uint32, 0 = none; labels.pcd's `label` and `object`), categories the per-point index
into CATEGORIES (uint8; labels.pcd's `category`).)");
}

}  // namespace multicue::python
