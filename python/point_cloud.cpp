// multicue.PointCloud. PointCloud keeps one std::vector per field; the point and normal vectors
// hold Eigen::Vector3f, three packed floats (12 bytes, no padding), so NumPy sees them as (N, 3)
// float32 arrays with strides (12, 4) without a copy. Every view keeps its cloud alive; a view is
// invalidated only by replacing the field it looks at (assigning a different number of points).

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "multicue/core/exceptions.hpp"
#include "multicue/core/point_cloud.hpp"

namespace py = pybind11;

namespace multicue::python {
namespace {

static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "Vector3f must be 3 packed floats");
static_assert(sizeof(Color) == 4, "Color must be 4 packed bytes");

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

/// A view of `count` rows of `cols` values of type T at `data`, owned by `owner`.
template <typename T>
py::array View(T* data, std::size_t count, std::size_t cols, py::handle owner) {
    const auto rows = static_cast<py::ssize_t>(count);
    if (cols == 1) {
        return py::array_t<T>({rows}, {static_cast<py::ssize_t>(sizeof(T))}, data, owner);
    }
    const auto c = static_cast<py::ssize_t>(cols);
    return py::array_t<T>(
        {rows, c}, {c * static_cast<py::ssize_t>(sizeof(T)), static_cast<py::ssize_t>(sizeof(T))},
        data, owner);
}

/// The shape of `obj` as NumPy sees it, "(4, 2)", or its type name when it is no array.
std::string Shape(const py::object& obj) {
    const py::array a = py::array::ensure(obj);
    if (!a || a.ndim() == 0) return "a " + std::string(py::str(py::type::of(obj).attr("__name__")));
    std::string s = "(";
    for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

/// The rows of an (N, 3) array as points; InvalidArgument naming `what` otherwise.
std::vector<Eigen::Vector3f> ToVectors(const py::object& any, const char* what) {
    const FloatArray a = FloatArray::ensure(any);
    if (!a || a.ndim() != 2 || a.shape(1) != 3) {
        throw InvalidArgument(
            fmt::format("{} must be an array of shape (N, 3), got {}", what, Shape(any)));
    }
    std::vector<Eigen::Vector3f> out(static_cast<std::size_t>(a.shape(0)));
    if (!out.empty()) std::memcpy(out.front().data(), a.data(), out.size() * 3 * sizeof(float));
    return out;
}

/// A 1-D array of `n` values of type T; InvalidArgument naming `what` otherwise.
template <typename T>
std::vector<T> ToValues(const py::object& any, std::size_t n, const char* what) {
    const auto a = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(any);
    if (!a || a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n) {
        throw InvalidArgument(
            fmt::format("{} must be an array of shape ({},), got {}", what, n, Shape(any)));
    }
    return std::vector<T>(a.data(), a.data() + n);
}

std::vector<Color> ToColors(const py::object& any, std::size_t n) {
    const auto a =
        py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(any);
    if (!a || a.ndim() != 2 || static_cast<std::size_t>(a.shape(0)) != n ||
        (a.shape(1) != 3 && a.shape(1) != 4)) {
        throw InvalidArgument(fmt::format(
            "colors must be a uint8 array of shape ({}, 3) or ({}, 4), got {}", n, n, Shape(any)));
    }
    std::vector<Color> out(n);
    const auto cols = static_cast<std::size_t>(a.shape(1));
    const std::uint8_t* p = a.data();
    for (std::size_t i = 0; i < n; ++i, p += cols) {
        out[i] = Color{p[0], p[1], p[2], cols == 4 ? p[3] : std::uint8_t{255}};
    }
    return out;
}

void CheckRows(const PointCloud& c, std::size_t n, const char* what) {
    if (n != c.size()) {
        throw InvalidArgument(
            fmt::format("{} has {} rows but the cloud has {} points", what, n, c.size()));
    }
}

/// Sets the points; a new count makes the cloud unorganized and requires no other fields.
void SetPoints(PointCloud& c, const py::object& a) {
    auto points = ToVectors(a, "points");
    if (points.size() == c.size()) {
        std::copy(points.begin(), points.end(), c.points.begin());  // views stay valid
        return;
    }
    const bool other_fields = c.HasNormals() || c.HasColors() || c.HasCurvature() ||
                              c.HasLabels() || c.HasIntensity() || c.HasConfidence() ||
                              !c.extra_fields.empty();
    if (other_fields) {
        throw InvalidArgument(
            fmt::format("points: {} rows for a cloud of {} points with other fields; make a new "
                        "PointCloud to change the number of points",
                        points.size(), c.size()));
    }
    c.points = std::move(points);
    c.SetUnorganized();
}

/// A scalar field (curvature, labels, ...) as a property: a view, None when absent; assigning an
/// array of size() values copies it, assigning None removes the field.
template <typename T>
void ScalarField(py::class_<PointCloud>& cls, const char* name, std::vector<T> PointCloud::*field,
                 const char* doc) {
    cls.def_property(
        name,
        [field](py::object self) -> py::object {
            auto& c = self.cast<PointCloud&>();
            auto& v = c.*field;
            if (v.empty()) return py::none();
            return View(v.data(), v.size(), 1, self);
        },
        [field, name](PointCloud& c, py::object value) {
            if (value.is_none()) {
                (c.*field).clear();
                return;
            }
            auto values = ToValues<T>(value, c.size(), name);
            if ((c.*field).size() == values.size()) {
                std::copy(values.begin(), values.end(), (c.*field).begin());
            } else {
                c.*field = std::move(values);
            }
        },
        doc);
}

py::array_t<float> ToNumpyCopy(const PointCloud& c) {
    py::array_t<float> out({static_cast<py::ssize_t>(c.size()), py::ssize_t{3}});
    if (!c.empty()) std::memcpy(out.mutable_data(), c.points.data(), c.size() * 12);
    return out;
}

/// An extra field as a NumPy array (copy), shape (N,) or (N, count).
py::array ExtraFieldArray(const ExtraField& e, std::size_t n) {
    const auto make = [&](auto tag) -> py::array {
        using T = decltype(tag);
        std::vector<py::ssize_t> shape = {static_cast<py::ssize_t>(n)};
        if (e.count != 1) shape.push_back(static_cast<py::ssize_t>(e.count));
        py::array_t<T> out(shape);
        if (!e.data.empty()) std::memcpy(out.mutable_data(), e.data.data(), e.data.size());
        return out;
    };
    switch (e.type) {
        case 'F':
            if (e.size == 4) return make(float{});
            if (e.size == 8) return make(double{});
            break;
        case 'I':
            if (e.size == 1) return make(std::int8_t{});
            if (e.size == 2) return make(std::int16_t{});
            if (e.size == 4) return make(std::int32_t{});
            if (e.size == 8) return make(std::int64_t{});
            break;
        case 'U':
            if (e.size == 1) return make(std::uint8_t{});
            if (e.size == 2) return make(std::uint16_t{});
            if (e.size == 4) return make(std::uint32_t{});
            if (e.size == 8) return make(std::uint64_t{});
            break;
        default:
            break;
    }
    throw DataError(fmt::format("extra field '{}' has unsupported type {} {}", e.name, e.type,
                                static_cast<int>(e.size)));
}

}  // namespace

void BindPointCloud(py::module_& m) {
    py::class_<PointCloud> cls(m, "PointCloud", R"(A point cloud: one array per field.

`points` is always there; every other field is None or has one row per point. Organized clouds
(RGB-D frames) have height > 1 and width * height points; their invalid points are NaN.
The field properties return NumPy views of the C++ storage (no copy): writing into them changes
the cloud. Assigning an array copies it in.)");
    cls.def(py::init<>(), "An empty cloud.")
        .def(py::init([](const py::object& points, const py::object& normals,
                         const py::object& colors, const py::object& labels) {
                 PointCloud c(ToVectors(points, "points"));
                 if (!normals.is_none()) {
                     c.normals = ToVectors(normals, "normals");
                     CheckRows(c, c.normals.size(), "normals");
                 }
                 if (!colors.is_none()) c.colors = ToColors(colors, c.size());
                 if (!labels.is_none()) {
                     c.labels = ToValues<std::uint32_t>(labels, c.size(), "labels");
                 }
                 return c;
             }),
             py::arg("points"), py::arg("normals") = py::none(), py::arg("colors") = py::none(),
             py::arg("labels") = py::none(),
             "An unorganized cloud of a copy of `points` (N, 3), and optionally normals (N, 3), "
             "colors (N, 3|4) uint8 and labels (N,) uint32.")
        .def("__len__", &PointCloud::size)
        .def("__repr__",
             [](const PointCloud& c) {
                 std::string fields = "points";
                 if (c.HasNormals()) fields += ", normals";
                 if (c.HasColors()) fields += ", colors";
                 if (c.HasCurvature()) fields += ", curvature";
                 if (c.HasLabels()) fields += ", labels";
                 if (c.HasIntensity()) fields += ", intensity";
                 if (c.HasConfidence()) fields += ", confidence";
                 for (const auto& e : c.extra_fields) fields += ", " + e.name;
                 return fmt::format("<multicue.PointCloud {} points ({}x{}): {}>", c.size(),
                                    c.width, c.height, fields);
             })
        .def_property_readonly(
            "width", [](const PointCloud& c) { return c.width; },
            "Columns when organized, else the number of points.")
        .def_property_readonly(
            "height", [](const PointCloud& c) { return c.height; }, "Rows when organized, else 1.")
        .def_property_readonly("is_organized", &PointCloud::IsOrganized,
                               "True for an image-shaped cloud (height > 1).")
        .def(
            "set_organized",
            [](PointCloud& c, std::uint32_t width, std::uint32_t height) {
                if (std::size_t{width} * height != c.size()) {
                    throw InvalidArgument(
                        fmt::format("width * height must be the number of points ({}), got {} x {}",
                                    c.size(), width, height));
                }
                c.width = width;
                c.height = height;
            },
            py::arg("width"), py::arg("height"),
            "Gives the cloud an image layout of width x height points (row-major).")
        .def_property(
            "points",
            [](py::object self) {
                auto& c = self.cast<PointCloud&>();
                return View(c.points.empty() ? nullptr : c.points.front().data(), c.size(), 3,
                            self);
            },
            &SetPoints,
            "(N, 3) float32 view of the coordinates [m], strides (12, 4). Assigning N rows "
            "copies them in place; another count is allowed only without other fields.")
        .def_property(
            "normals",
            [](py::object self) -> py::object {
                auto& c = self.cast<PointCloud&>();
                if (!c.HasNormals()) return py::none();
                return View(c.normals.front().data(), c.normals.size(), 3, self);
            },
            [](PointCloud& c, py::object value) {
                if (value.is_none()) {
                    c.normals.clear();
                    return;
                }
                auto normals = ToVectors(value, "normals");
                CheckRows(c, normals.size(), "normals");
                c.normals = std::move(normals);
            },
            "(N, 3) float32 view of the unit normals (NaN where undefined), or None.")
        .def_property(
            "colors",
            [](py::object self) -> py::object {
                auto& c = self.cast<PointCloud&>();
                if (!c.HasColors()) return py::none();
                return View(&c.colors.front().r, c.colors.size(), 4, self);
            },
            [](PointCloud& c, py::object value) {
                if (value.is_none()) {
                    c.colors.clear();
                    return;
                }
                c.colors = ToColors(value, c.size());
            },
            "(N, 4) uint8 view of r, g, b, a, or None. Assign (N, 3) or (N, 4).");
    ScalarField(cls, "curvature", &PointCloud::curvature,
                "(N,) float32 view of the surface variation, or None.");
    ScalarField(cls, "labels", &PointCloud::labels,
                "(N,) uint32 view of the labels (PCD field `label`), or None.");
    ScalarField(cls, "intensity", &PointCloud::intensity,
                "(N,) float32 view of the intensity, or None.");
    ScalarField(cls, "confidence", &PointCloud::confidence,
                "(N,) float32 view of the confidence, or None.");
    cls.def_property_readonly(
           "extra_field_names",
           [](const PointCloud& c) {
               std::vector<std::string> names;
               for (const auto& e : c.extra_fields) names.push_back(e.name);
               return names;
           },
           "Names of the fields multicue has no vector for (as read from the file).")
        .def(
            "extra_field",
            [](const PointCloud& c, const std::string& name) {
                const ExtraField* e = c.FindExtraField(name);
                if (e == nullptr) {
                    throw py::key_error(fmt::format("no extra field '{}'", name));
                }
                return ExtraFieldArray(*e, c.size());
            },
            py::arg("name"), "A copy of an extra field: shape (N,) or (N, count), its file's type.")
        .def_property(
            "sensor_origin",
            [](const PointCloud& c) { return py::array_t<float>(3, c.sensor_origin.data()); },
            [](PointCloud& c, const py::object& a) {
                const auto v = ToValues<float>(a, 3, "sensor_origin");
                c.sensor_origin = Eigen::Vector3f(v[0], v[1], v[2]);
            },
            "Sensor position (3,) in the cloud's frame (PCD VIEWPOINT), a copy.")
        .def_property(
            "sensor_orientation",
            [](const PointCloud& c) {
                const auto& q = c.sensor_orientation;
                const float wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
                return py::array_t<float>(4, wxyz);
            },
            [](PointCloud& c, const py::object& a) {
                const auto v = ToValues<float>(a, 4, "sensor_orientation");
                c.sensor_orientation = Eigen::Quaternionf(v[0], v[1], v[2], v[3]).normalized();
            },
            "Sensor orientation as a quaternion (w, x, y, z), a copy.")
        .def(
            "to_numpy", [](const PointCloud& c) { return ToNumpyCopy(c); },
            "A copy of the points as an (N, 3) float32 array that owns its data.")
        .def(
            "copy", [](const PointCloud& c) { return PointCloud(c); },
            "A deep copy of the cloud (all fields).")
        .def("count_finite", &PointCloud::CountFinite, "Points with three finite coordinates.")
        .def("validate", &PointCloud::Validate,
             "Raises DataError if a field's length differs from the number of points.");
}

}  // namespace multicue::python
