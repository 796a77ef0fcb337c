// The Python module `errfield`: NumPy in, NumPy out, over the library's public API (docs/python.md).
// errfield's C++ exceptions become Python exceptions of the same names and messages:
//   errfield.Error (RuntimeError)          base of them all
//   errfield.ArgumentError (Error, ValueError)
//   errfield.InputError (Error, ValueError) with .file, .row, .column as the C++ InputError
//   errfield.OutsideGridError (InputError)
//   errfield.ResourceError (Error)

#include <pybind11/pybind11.h>

#include "errfield/error.hpp"
#include "errfield/grid_idw.hpp"
#include "python/arrays.hpp"
#include "python/bindings.hpp"

namespace py = pybind11;

namespace {

// Created once at import and kept for the life of the interpreter (exception types are never
// unloaded, so holding raw references is safe and avoids destructor order issues at exit).
PyObject* g_error = nullptr;
PyObject* g_argument_error = nullptr;
PyObject* g_input_error = nullptr;
PyObject* g_outside_grid_error = nullptr;
PyObject* g_resource_error = nullptr;

PyObject* new_exception(py::module_& m, const char* name, const char* doc, std::initializer_list<PyObject*> bases) {
  py::tuple b(bases.size());
  std::size_t i = 0;
  for (PyObject* base : bases) b[i++] = py::reinterpret_borrow<py::object>(base);
  const std::string qualified = std::string("errfield.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, b.ptr(), nullptr);
  if (!type) throw py::error_already_set();
  m.add_object(name, py::reinterpret_borrow<py::object>(type));
  return type;
}

void raise_input_error(PyObject* type, const errfield::InputError& e) {
  py::object instance = py::reinterpret_borrow<py::object>(type)(e.what());
  instance.attr("file") = e.file().empty() ? py::object(py::none()) : py::object(py::str(e.file()));
  instance.attr("row") = e.row() == 0 ? py::object(py::none()) : py::object(py::int_(e.row()));
  instance.attr("column") = e.column().empty() ? py::object(py::none()) : py::object(py::str(e.column()));
  PyErr_SetObject(type, instance.ptr());
}

}  // namespace

PYBIND11_MODULE(errfield, m) {
  m.doc() =
      "errfield: geostatistics of error fields and robot kinematics (C++ engine, NumPy interface).\n\n"
      "Units follow the data: coordinates in mm (task space) or deg (joint space), values in mm,\n"
      "semivariances and variances in mm^2. Every array argument is checked: a wrong shape or a\n"
      "non-finite number raises errfield.ArgumentError (a ValueError) naming the argument, a wrong\n"
      "dtype raises TypeError. See docs/python.md.";
  m.attr("__version__") = ERRFIELD_VERSION;

  g_error = new_exception(m, "Error", "Base of every exception errfield raises.", {PyExc_RuntimeError});
  g_argument_error = new_exception(m, "ArgumentError",
                                   "An argument or option is out of its domain; the message names it.",
                                   {g_error, PyExc_ValueError});
  g_input_error = new_exception(m, "InputError",
                                "Data (samples, a file) are unusable. .file, .row (1-based, header = 1) and "
                                ".column say where when known, else None.",
                                {g_error, PyExc_ValueError});
  g_outside_grid_error = new_exception(m, "OutsideGridError", "A target lies outside the grid (GridIdw, clamp=False).",
                                       {g_input_error});
  g_resource_error = new_exception(m, "ResourceError",
                                   "The job would exceed a resource budget (memory); the message names a cheaper way.",
                                   {g_error});

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const errfield::OutsideGridError& e) {
      raise_input_error(g_outside_grid_error, e);
    } catch (const errfield::InputError& e) {
      raise_input_error(g_input_error, e);
    } catch (const errfield::ArgumentError& e) {
      PyErr_SetString(g_argument_error, e.what());
    } catch (const errfield::ResourceError& e) {
      PyErr_SetString(g_resource_error, e.what());
    } catch (const errfield::Error& e) {
      PyErr_SetString(g_error, e.what());
    }
  });

  m.def("_input_copies", &errfield::python::input_copies,
        "Array arguments copied so far (conversions of non-float64 or non-C-ordered arrays, and copies into\n"
        "column-major storage): for tests that an argument was read in place.");
  errfield::python::bind_variogram(m);
  errfield::python::bind_interpolation(m);
  errfield::python::bind_cokriging(m);
  errfield::python::bind_robot(m);
  errfield::python::bind_calibration(m);
  errfield::python::bind_pipeline(m);
}
