// The Python module `multicue`: a thin layer over the C++ library (python/multicue.pyi lists its
// API; docs/using-the-library.md shows it in use). No algorithm lives here.

#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "multicue/version.hpp"

PYBIND11_MODULE(multicue, m) {
    m.doc() =
        "multicue: multi-cue perception of table-top objects from 3D and RGB-D data.\n\n"
        "PointCloud holds one field per NumPy array; `points`, `normals`, `colors` and the scalar\n"
        "fields are views of the C++ storage (no copy). read()/write() handle PCD and PLY;\n"
        "voxel_grid, remove_non_finite, crop_box, statistical_outlier_removal,\n"
        "radius_outlier_removal, estimate_normals, find_support_plane and euclidean_clustering\n"
        "are the library's algorithms; perceive() runs the table-top pipeline of\n"
        "`multicue perceive` and returns what result.json and labels.pcd hold.";
    m.attr("__version__") = MULTICUE_VERSION_STRING;
    multicue::python::BindErrors(m);
    multicue::python::BindPointCloud(m);
    multicue::python::BindIo(m);
    multicue::python::BindAlgorithms(m);
    multicue::python::BindPerceive(m);
}
