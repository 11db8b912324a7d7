// meshmend._core: the MeshMend core on NumPy arrays. The package meshmend
// (python/meshmend/__init__.py) is the interface users call; this module
// validates the arrays, runs the core without the GIL and turns the core's
// typed errors into Python exceptions carrying the core's messages.
#include <pybind11/pybind11.h>

#include "common/base/errors.h"
#include "common/base/parallel.h"
#include "python/src/bindings.h"

namespace py = pybind11;

namespace {

// A new exception class meshmend.<name> deriving from `bases` (a tuple).
py::object newException(py::module_& m, const char* name, py::tuple bases, const char* doc) {
  const std::string qualified = std::string("meshmend.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (!type) throw py::error_already_set();
  py::object cls = py::reinterpret_steal<py::object>(type);
  m.attr(name) = cls;
  return cls;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "The MeshMend geometry core on NumPy arrays (use the package meshmend).";

  // Leaked on purpose: the translator may run until the interpreter exits.
  static py::object* error = new py::object(
      newException(m, "Error", py::make_tuple(py::reinterpret_borrow<py::object>(PyExc_Exception)),
                   "Base of every error MeshMend raises on purpose."));
  static py::object* invalidInput = new py::object(newException(
      m, "InvalidInputError",
      py::make_tuple(*error, py::reinterpret_borrow<py::object>(PyExc_ValueError)),
      "The input violates a precondition: bad arrays, empty mesh, non-finite coordinates, an "
      "index out of range, a bad option."));
  static py::object* topology = new py::object(newException(
      m, "TopologyError",
      py::make_tuple(*error, py::reinterpret_borrow<py::object>(PyExc_ValueError)),
      "The mesh's topology does not allow the operation (non-manifold, open where a closed mesh "
      "is needed, inconsistently oriented, ...)."));
  static py::object* cancelled = new py::object(
      newException(m, "CancelledError", py::make_tuple(*error),
                   "The progress callback returned False: the operation stopped, the input "
                   "arrays are unchanged."));

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const meshmend::InvalidInputError& e) {
      PyErr_SetString(invalidInput->ptr(), e.what());
    } catch (const meshmend::TopologyError& e) {
      PyErr_SetString(topology->ptr(), e.what());
    } catch (const meshmend::CancelledError& e) {
      PyErr_SetString(cancelled->ptr(), e.what());
    } catch (const meshmend::Error& e) {
      PyErr_SetString(error->ptr(), e.what());
    }
  });

  m.def(
      "set_threads",
      [](long count) {
        if (count < 0)
          throw meshmend::InvalidInputError("set_threads: the count must be 0 or more");
        meshmend::setThreadCount(unsigned(count));
      },
      py::arg("count"),
      "Sets how many threads MeshMend uses from now on (0: back to MESHMEND_THREADS or the "
      "CPUs).");
  m.def("threads", &meshmend::workerCount, "How many threads MeshMend uses.");
  meshmend::python::bindIntersect(m);
  meshmend::python::bindRepair(m);
  meshmend::python::bindClearance(m);
  meshmend::python::bindPatches(m);
}
