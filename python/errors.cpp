// multicue's exceptions as Python exceptions. Each class also derives from the built-in exception
// a Python caller would expect: InvalidArgument and DataError are ValueErrors, IoError an OSError.

#include <exception>

#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "multicue/core/exceptions.hpp"

namespace py = pybind11;

namespace multicue::python {
namespace {

// The classes live as long as the interpreter: the translator holds plain references to them,
// never released (a static py::object would be released after the interpreter is gone).
PyObject* error = nullptr;
PyObject* invalid_argument = nullptr;
PyObject* io_error = nullptr;
PyObject* format_error = nullptr;
PyObject* data_error = nullptr;

PyObject* MakeClass(py::module_& m, const char* name, py::tuple bases, const char* doc) {
    py::dict attrs;
    attrs["__doc__"] = doc;
    attrs["__module__"] = "multicue";
    py::object cls = py::module_::import("builtins").attr("type")(name, bases, attrs);
    m.attr(name) = cls;
    return cls.release().ptr();
}

py::handle H(PyObject* p) { return py::handle(p); }

}  // namespace

void BindErrors(py::module_& m) {
    const py::object value_error = py::reinterpret_borrow<py::object>(PyExc_ValueError);
    const py::object os_error = py::reinterpret_borrow<py::object>(PyExc_OSError);
    const py::object exception = py::reinterpret_borrow<py::object>(PyExc_Exception);
    error = MakeClass(m, "Error", py::make_tuple(exception), "Base of every multicue error.");
    invalid_argument = MakeClass(m, "InvalidArgument", py::make_tuple(H(error), value_error),
                                 "A parameter or argument is out of its domain.");
    io_error = MakeClass(m, "IoError", py::make_tuple(H(error), os_error),
                         "A file could not be opened, read or written.");
    format_error = MakeClass(m, "FormatError", py::make_tuple(H(io_error)),
                             "A file was readable but its content is malformed.");
    data_error = MakeClass(m, "DataError", py::make_tuple(H(error), value_error),
                           "Input data violates a precondition (no valid points, sizes differ).");
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const FormatError& e) {
            PyErr_SetString(format_error, e.what());
        } catch (const IoError& e) {
            PyErr_SetString(io_error, e.what());
        } catch (const InvalidArgument& e) {
            PyErr_SetString(invalid_argument, e.what());
        } catch (const DataError& e) {
            PyErr_SetString(data_error, e.what());
        } catch (const Error& e) {
            PyErr_SetString(error, e.what());
        }
    });
}

}  // namespace multicue::python
