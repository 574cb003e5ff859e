#pragma once
// Pieces of the Python module `multicue` (module.cpp), one function per part of the API.

#include <pybind11/pybind11.h>

namespace multicue::python {

/// multicue.Error and its subclasses, and the translation of multicue's C++ exceptions to them.
void BindErrors(pybind11::module_& m);
/// multicue.PointCloud with NumPy views of its fields.
void BindPointCloud(pybind11::module_& m);
/// read / write of PCD and PLY files.
void BindIo(pybind11::module_& m);
/// Filters, normals and segmentation.
void BindAlgorithms(pybind11::module_& m);
/// perceive(cloud, config) and the default configuration.
void BindPerceive(pybind11::module_& m);

}  // namespace multicue::python
