// read() and write() of point clouds; the file extension picks PCD or PLY.

#include <filesystem>
#include <string>

#include <pybind11/pybind11.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "multicue/io/point_cloud_io.hpp"

namespace py = pybind11;

namespace multicue::python {

void BindIo(py::module_& m) {
    m.def(
        "read",
        [](const std::filesystem::path& path) {
            py::gil_scoped_release release;
            return io::ReadPointCloud(path);
        },
        py::arg("path"),
        "Reads a .pcd (ascii, binary, binary_compressed) or .ply point cloud.\n\n"
        "Raises IoError when the file cannot be read, FormatError when it is malformed.");
    m.def(
        "write",
        [](const std::filesystem::path& path, const PointCloud& cloud,
           const std::string& encoding) {
            const io::Encoding e = io::ParseEncoding(encoding);
            py::gil_scoped_release release;
            io::WritePointCloud(path, cloud, e);
        },
        py::arg("path"), py::arg("cloud"), py::arg("encoding") = "binary",
        "Writes a .pcd or .ply point cloud atomically. encoding: 'ascii', 'binary' or\n"
        "'compressed' (PCD binary_compressed; PLY writes binary little endian).");
}

}  // namespace multicue::python
