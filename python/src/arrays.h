// NumPy arrays in and out of the core: validation of what Python hands in
// (shapes, types, finite coordinates, indices in range) with messages that
// name the argument, conversion of core meshes and results back, and running
// core work with the GIL released (Ctrl-C and a progress callback cancel it).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "common/base/errors.h"
#include "common/base/json.h"
#include "common/base/mesh.h"
#include "common/base/progress.h"

namespace meshmend::python {

namespace py = pybind11;

// How a mesh's coordinates are checked: operations need finite ones;
// inspect() counts the others as a defect.
enum class Coordinates { kFinite, kAny };

// A mesh handed in from Python: vertices (n, 3) of real numbers, faces
// (m, 3) of integers in [0, n). `name` prefixes the messages ("the first
// mesh: ..."); the arrays are named as the caller's parameters.
struct MeshArgument {
  std::string vertices_name = "vertices", faces_name = "faces";
};

// Reads and checks a mesh into `mesh` (cleared first). Throws InvalidInputError (ValueError in
// Python) for an array that is not (n, 3), not numeric, empty, has a non-finite coordinate
// (kFinite) or a face index out of range; TypeError-like problems (faces of floats) are
// InvalidInputError too, with the fix named.
void readArrays(Mesh& mesh, py::handle vertices, py::handle faces, const MeshArgument& names,
                int layer = 0, Coordinates coordinates = Coordinates::kFinite);

// Several meshes: a sequence of (vertices, faces) pairs. Mesh i (from 0) is
// core layer i and its arrays are named vertices<i+1>, faces<i+1> in messages,
// as the parameters of the two-mesh functions are.
std::vector<Mesh> meshesFrom(py::handle meshes, std::size_t minimum = 1);

// The core mesh as arrays: vertices (n, 3) float64 and faces (m, 3) int32.
py::array_t<double> verticesOf(const Mesh& mesh);
py::array_t<std::int32_t> facesOf(const Mesh& mesh);
py::tuple meshTuple(const Mesh& mesh);  // (vertices, faces)

// 1-D int32 array of `values`; (k, 2) int32 array of index pairs.
py::array_t<std::int32_t> intArray(const std::vector<int>& values);
py::list stringList(const std::vector<std::string>& values);  // a list of str
py::array_t<std::int32_t> pairArray(const std::vector<std::array<int, 2>>& pairs);

// Per face of `mesh`: the input mesh (layer) it came from.
py::array_t<std::int32_t> faceLayers(Mesh& mesh);
// Per face of `mesh`: the input face it was cut from or copies, -1 for none.
py::array_t<std::int32_t> faceOriginsOf(Mesh& mesh);

// A 1-D sequence of vertex indices (list, tuple or integer array), each in
// [0, vertexCount). `name` is the option's name in messages.
std::vector<int> vertexIndices(py::handle value, const std::string& name, std::size_t vertexCount);
// One flag per vertex (a boolean array of length vertexCount), or vertex
// indices, as a mask.
std::vector<bool> vertexMask(py::handle value, const std::string& name, std::size_t vertexCount);
// The same per face.
std::vector<bool> faceMask(py::handle value, const std::string& name, std::size_t faceCount);

// A report (the JsonObject the plugins write to report_file) as a dict.
py::dict dictOf(const JsonObject& report);

// Runs core work with the GIL released. The core's progress callback
// (progress()) checks for Ctrl-C and calls the user's `callback(percent,
// stage)` if any; a KeyboardInterrupt, an exception in the callback, or the
// callback returning False stops the work, and the Python error (or
// meshmend.CancelledError) is raised.
class CoreCall {
 public:
  explicit CoreCall(py::object callback = py::none());
  Progress progress();

  template <class Work>
  auto operator()(Work&& work) -> decltype(work()) {
    try {
      py::gil_scoped_release release;
      return work();
    } catch (const CancelledError&) {
      raisePending();
      throw;
    }
  }

 private:
  void raisePending();
  struct State;
  std::shared_ptr<State> state_;
};

// The "progress" keyword, taken out of the options (None when absent).
py::object takeProgress(py::kwargs& kwargs);

}  // namespace meshmend::python
