#include "python/src/arrays.h"

#include <climits>
#include <cmath>
#include <memory>

namespace meshmend::python {

namespace {

// `value` as a NumPy array (lists and tuples converted), or an error naming it.
py::array asArray(py::handle value, const std::string& name, const char* expected) {
  if (value.is_none()) throw InvalidInputError(name + " is None: pass " + expected);
  try {
    return py::module_::import("numpy").attr("asarray")(value);
  } catch (py::error_already_set& e) {
    throw InvalidInputError(name + " is not " + expected + " (" + e.what() + ")");
  }
}

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtypeText(const py::array& a) {
  return py::str(a.dtype()).cast<std::string>();
}

// An (n, 3) array with dtype kind in `kinds`; throws naming the argument otherwise.
py::array rowsOfThree(py::handle value, const std::string& name, const std::string& kinds,
                      const char* expected, const char* fix) {
  py::array a = asArray(value, name, expected);
  const char kind = a.dtype().kind();
  if (kinds.find(kind) == std::string::npos)
    throw InvalidInputError(name + " has dtype " + dtypeText(a) + ": it must be " + expected + fix);
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw InvalidInputError(name + " has shape " + shapeText(a) + ": it must be " + expected +
                            ", one row per element");
  return a;
}

}  // namespace

void readArrays(Mesh& mesh, py::handle vertices, py::handle faces, const MeshArgument& names,
                int layer, Coordinates coordinates) {
  const std::string& vn = names.vertices_name;
  const std::string& fn = names.faces_name;
  const py::array va =
      rowsOfThree(vertices, vn, "fiu", "an (n, 3) array of real coordinates", " (float, or int)");
  const py::array fa =
      rowsOfThree(faces, fn, "iu", "an (m, 3) array of integer vertex indices",
                  "; if they are whole numbers stored as floats, pass faces.astype(int)");
  const std::size_t n = std::size_t(va.shape(0)), m = std::size_t(fa.shape(0));
  if (n == 0) throw InvalidInputError(vn + " is empty: the mesh needs vertices and faces");
  if (m == 0) throw InvalidInputError(fn + " is empty: the mesh needs at least one triangle");
  if (n > std::size_t(INT_MAX) || m > std::size_t(INT_MAX))
    throw InvalidInputError("the mesh is too large: at most " + std::to_string(INT_MAX) +
                            " vertices and faces");

  using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
  using Indices = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  const Doubles v = Doubles::ensure(va);
  const Indices f = Indices::ensure(fa);
  if (!v || !f) throw InvalidInputError(vn + " and " + fn + " could not be read as numbers");

  std::vector<Point3> points(n);
  const double* p = v.data();
  for (std::size_t i = 0; i < n; ++i) {
    points[i] = Point3(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    if (coordinates == Coordinates::kFinite && !isFinite(points[i]))
      throw InvalidInputError(vn + ": vertex " + std::to_string(i) +
                              " has a non-finite coordinate (NaN or infinity): fix or remove it");
  }
  std::vector<Triangle> triangles(m);
  const std::int64_t* t = f.data();
  // Unsigned arrays above 2^63 became negative in the conversion: still out of range.
  for (std::size_t i = 0; i < m; ++i)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t index = t[3 * i + k];
      if (index < 0 || std::uint64_t(index) >= n)
        throw InvalidInputError(fn + ": face " + std::to_string(i) + " refers to vertex " +
                                std::to_string(index) + ", but " + vn + " has " +
                                std::to_string(n) + " rows (indices 0 to " + std::to_string(n - 1) +
                                ")");
      triangles[i][k] = int(index);
    }
  buildMesh(mesh, points, triangles, layer);
}

std::vector<Mesh> meshesFrom(py::handle meshes, std::size_t minimum) {
  if (!py::isinstance<py::sequence>(meshes) || py::isinstance<py::str>(meshes))
    throw InvalidInputError("meshes must be a sequence of (vertices, faces) pairs");
  const py::sequence list = py::reinterpret_borrow<py::sequence>(meshes);
  if (list.size() < minimum)
    throw InvalidInputError("meshes holds " + std::to_string(list.size()) + " meshes: at least " +
                            std::to_string(minimum) + " are needed");
  std::vector<Mesh> out(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    const py::object item = list[i];
    if (!py::isinstance<py::sequence>(item) || py::len(item) != 2)
      throw InvalidInputError("meshes[" + std::to_string(i) + "] must be a (vertices, faces) pair");
    const std::string k = std::to_string(i + 1);
    const py::sequence pair = py::reinterpret_borrow<py::sequence>(item);
    readArrays(out[i], pair[0], pair[1], {"vertices" + k, "faces" + k}, int(i));
  }
  return out;
}

py::array_t<double> verticesOf(const Mesh& mesh) {
  if (mesh.vn != int(mesh.vert.size()))
    throw std::logic_error("meshmend: a core result has deleted vertices");
  py::array_t<double> out({py::ssize_t(mesh.vert.size()), py::ssize_t(3)});
  double* p = out.mutable_data();
  for (const Vertex& v : mesh.vert)
    for (int k = 0; k < 3; ++k) *p++ = v.cP()[k];
  return out;
}

py::array_t<std::int32_t> facesOf(const Mesh& mesh) {
  if (mesh.fn != int(mesh.face.size()))
    throw std::logic_error("meshmend: a core result has deleted faces");
  py::array_t<std::int32_t> out({py::ssize_t(mesh.face.size()), py::ssize_t(3)});
  std::int32_t* p = out.mutable_data();
  for (const Face& f : mesh.face)
    for (int k = 0; k < 3; ++k) *p++ = std::int32_t(vcg::tri::Index(mesh, f.cV(k)));
  return out;
}

py::tuple meshTuple(const Mesh& mesh) {
  return py::make_tuple(verticesOf(mesh), facesOf(mesh));
}

py::array_t<std::int32_t> intArray(const std::vector<int>& values) {
  py::array_t<std::int32_t> out(py::ssize_t(values.size()));
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}

py::list stringList(const std::vector<std::string>& values) {
  py::list out;
  for (const std::string& v : values) out.append(v);
  return out;
}

py::array_t<std::int32_t> pairArray(const std::vector<std::array<int, 2>>& pairs) {
  py::array_t<std::int32_t> out({py::ssize_t(pairs.size()), py::ssize_t(2)});
  std::int32_t* p = out.mutable_data();
  for (const auto& e : pairs) *p++ = e[0], *p++ = e[1];
  return out;
}

py::array_t<std::int32_t> faceLayers(Mesh& mesh) {
  FaceOriginHandle origin = faceOrigins(mesh);
  std::vector<int> layers(mesh.face.size());
  for (std::size_t f = 0; f < layers.size(); ++f) layers[f] = origin[f].layer;
  return intArray(layers);
}

py::array_t<std::int32_t> faceOriginsOf(Mesh& mesh) {
  FaceOriginHandle origin = faceOrigins(mesh);
  std::vector<int> faces(mesh.face.size());
  for (std::size_t f = 0; f < faces.size(); ++f) faces[f] = origin[f].face;
  return intArray(faces);
}

namespace {

// Indices of `element`s ("vertex", "face") in [0, count).
std::vector<int> elementIndices(py::handle value, const std::string& name, std::size_t count,
                                const std::string& element, const std::string& plural) {
  const std::string what = "a sequence of " + element + " indices";
  const py::array a = asArray(value, name, what.c_str());
  const char kind = a.dtype().kind();
  // An empty list comes out of NumPy as float64: it is still an empty list of indices.
  if (a.ndim() != 1 || (a.size() > 0 && kind != 'i' && kind != 'u'))
    throw InvalidInputError(name + " must be a 1-D sequence of integer " + element +
                            " indices (got shape " + shapeText(a) + ", dtype " + dtypeText(a) +
                            ")");
  using Indices = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  const Indices indices = Indices::ensure(a);
  std::vector<int> out;
  out.reserve(std::size_t(a.size()));
  for (py::ssize_t i = 0; i < a.size(); ++i) {
    const std::int64_t v = indices.data()[i];
    if (v < 0 || std::uint64_t(v) >= count)
      throw InvalidInputError(name + "[" + std::to_string(i) + "] is " + element + " " +
                              std::to_string(v) + ", but the mesh has " + std::to_string(count) +
                              " " + plural + " (indices 0 to " + std::to_string(count - 1) + ")");
    out.push_back(int(v));
  }
  return out;
}

std::vector<bool> elementMask(py::handle value, const std::string& name, std::size_t count,
                              const std::string& element, const std::string& plural) {
  const std::string what = "a boolean mask or " + element + " indices";
  const py::array a = asArray(value, name, what.c_str());
  if (a.dtype().kind() != 'b') {
    std::vector<bool> mask(count, false);
    for (int v : elementIndices(a, name, count, element, plural)) mask[std::size_t(v)] = true;
    return mask;
  }
  if (a.ndim() != 1 || std::size_t(a.size()) != count)
    throw InvalidInputError(name + " is a boolean mask of shape " + shapeText(a) +
                            ": it needs one flag per " + element + " (" + std::to_string(count) +
                            ",)");
  using Flags = py::array_t<bool, py::array::c_style | py::array::forcecast>;
  const Flags flags = Flags::ensure(a);
  return std::vector<bool>(flags.data(), flags.data() + flags.size());
}

}  // namespace

std::vector<int> vertexIndices(py::handle value, const std::string& name, std::size_t vertexCount) {
  return elementIndices(value, name, vertexCount, "vertex", "vertices");
}

std::vector<bool> vertexMask(py::handle value, const std::string& name, std::size_t vertexCount) {
  return elementMask(value, name, vertexCount, "vertex", "vertices");
}

std::vector<bool> faceMask(py::handle value, const std::string& name, std::size_t faceCount) {
  return elementMask(value, name, faceCount, "face", "faces");
}

py::dict dictOf(const JsonObject& report) {
  return py::module_::import("json").attr("loads")(report.str()).cast<py::dict>();
}

// ---------------------------------------------------------------- CoreCall

struct CoreCall::State {
  py::object callback;
  std::optional<py::error_already_set> error;  // raised in a progress call
  bool declined = false;                       // the callback returned False
};

CoreCall::CoreCall(py::object callback) : state_(std::make_shared<State>()) {
  if (!callback.is_none() && !PyCallable_Check(callback.ptr()))
    throw py::type_error("progress must be a callable progress(percent, stage), or None");
  state_->callback = std::move(callback);
}

Progress CoreCall::progress() {
  std::shared_ptr<State> state = state_;
  return [state](int percent, const char* stage) {
    py::gil_scoped_acquire gil;
    if (state->error || state->declined) return false;
    if (PyErr_CheckSignals() != 0) {  // Ctrl-C: KeyboardInterrupt is pending
      state->error.emplace();
      return false;
    }
    if (state->callback.is_none()) return true;
    try {
      const py::object answer = state->callback(percent, stage);
      if (answer.ptr() == Py_False) {
        state->declined = true;
        return false;
      }
    } catch (py::error_already_set& e) {
      state->error.emplace(std::move(e));
      return false;
    }
    return true;
  };
}

void CoreCall::raisePending() {
  if (state_->error) {
    py::error_already_set error = std::move(*state_->error);
    state_->error.reset();
    throw error;
  }
}

py::object takeProgress(py::kwargs& kwargs) {
  if (!kwargs.contains("progress")) return py::none();
  py::object callback = kwargs["progress"];
  PyDict_DelItemString(kwargs.ptr(), "progress");
  return callback;
}

}  // namespace meshmend::python
