// Keyword options of a Python function, mapped onto the core's Options
// fields: one table per function lists each keyword (named as the field),
// how it is checked and converted, and its default, read from a
// default-constructed Options struct so that the defaults have one source.
#pragma once

#include <climits>
#include <cmath>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "python/src/arrays.h"

namespace meshmend::python {

// What option values are checked against (index options need the mesh).
struct Bounds {
  Bounds(std::size_t vertexCount = 0, std::size_t faceCount = 0,
         std::vector<std::size_t> perMesh = {})
      : vertices(vertexCount), faces(faceCount), layer_vertices(std::move(perMesh)) {}
  std::size_t vertices, faces;              // of the mesh (the first one when there are several)
  std::vector<std::size_t> layer_vertices;  // of each mesh, when there are several
};

namespace detail {

inline bool isBool(py::handle v) {
  return PyBool_Check(v.ptr()) ||
         py::str(py::type::of(v).attr("__name__")).cast<std::string>() == "bool_";  // numpy.bool_
}
inline bool isInteger(py::handle v) {
  return !isBool(v) && PyIndex_Check(v.ptr());
}
inline bool isReal(py::handle v) {
  return !isBool(v) &&
         (PyFloat_Check(v.ptr()) || PyIndex_Check(v.ptr()) || py::hasattr(v, "__float__")) &&
         !PyComplex_Check(v.ptr());
}
inline std::string typeName(py::handle v) {
  return py::str(py::type::of(v).attr("__name__")).cast<std::string>();
}

template <class T>
T convert(py::handle v, const std::string& name) {
  if constexpr (std::is_same_v<T, bool>) {
    if (!isBool(v)) throw py::type_error(name + " must be True or False, not " + typeName(v));
    return PyObject_IsTrue(v.ptr()) == 1;
  } else if constexpr (std::is_integral_v<T>) {
    if (!isInteger(v)) throw py::type_error(name + " must be an integer, not " + typeName(v));
    const long long x = py::int_(py::reinterpret_borrow<py::object>(v)).cast<long long>();
    if (std::is_unsigned_v<T> && x < 0)
      throw InvalidInputError(name + " must be 0 or more (got " + std::to_string(x) + ")");
    if (x > static_cast<long long>(INT_MAX) || x < static_cast<long long>(INT_MIN))
      throw InvalidInputError(name + " is out of range (got " + std::to_string(x) + ")");
    return T(x);
  } else if constexpr (std::is_floating_point_v<T>) {
    if (!isReal(v)) throw py::type_error(name + " must be a number, not " + typeName(v));
    const double x = py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>();
    if (!std::isfinite(x))
      throw InvalidInputError(name + " must be a finite number (got " + std::to_string(x) + ")");
    return T(x);
  } else {
    static_assert(std::is_same_v<T, bool>, "no conversion for this option type");
  }
}

}  // namespace detail

template <class Call>
class OptionTable {
 public:
  using Setter = std::function<void(Call&, py::handle, const Bounds&)>;

  // A keyword whose value is the field `access(call)` (bool, integer or double).
  template <class Access>
  OptionTable& add(const char* name, Access access, const char* doc) {
    using T = std::remove_reference_t<decltype(access(std::declval<Call&>()))>;
    Call defaults;
    entries_.push_back({name, doc, py::cast(access(defaults)),
                        [access, name](Call& call, py::handle v, const Bounds&) {
                          access(call) = detail::convert<T>(v, name);
                        }});
    return *this;
  }

  // A keyword naming one of `choices` (strings) for an enum field.
  template <class Access, class Enum>
  OptionTable& addChoice(const char* name, Access access,
                         std::vector<std::pair<const char*, Enum>> choices, const char* doc) {
    Call defaults;
    py::object defaultName = py::none();
    for (const auto& [text, value] : choices)
      if (value == access(defaults)) defaultName = py::str(text);
    entries_.push_back(
        {name, doc, defaultName, [access, name, choices](Call& call, py::handle v, const Bounds&) {
           std::string known;
           if (py::isinstance<py::str>(v)) {
             const std::string text = v.cast<std::string>();
             for (const auto& [choice, value] : choices)
               if (text == choice) {
                 access(call) = value;
                 return;
               }
           }
           for (const auto& c : choices)
             known += (known.empty() ? "'" : ", '") + std::string(c.first) + "'";
           throw InvalidInputError(std::string(name) + " must be one of " + known + " (got " +
                                   py::repr(v).cast<std::string>() + ")");
         }});
    return *this;
  }

  // A keyword with its own conversion (index lists, masks) and default.
  OptionTable& addCustom(const char* name, py::object defaultValue, Setter setter,
                         const char* doc) {
    entries_.push_back({name, doc, std::move(defaultValue), std::move(setter)});
    return *this;
  }

  // The options given as keywords, on top of the defaults. Unknown keywords
  // are a TypeError listing the known ones; None means "the default".
  Call parse(const std::string& function, const py::kwargs& kwargs, const Bounds& bounds) const {
    Call call;
    for (const auto& [key, value] : kwargs) {
      const std::string name = py::str(key).cast<std::string>();
      const Entry* entry = find(name);
      if (!entry) {
        std::string known;
        for (const Entry& e : entries_) known += (known.empty() ? "" : ", ") + e.name;
        throw py::type_error(function + "() got an unexpected keyword argument '" + name +
                             "'; its options are: " + known + ", progress");
      }
      if (!value.is_none()) entry->set(call, value, bounds);
    }
    return call;
  }

  // [(name, default, doc)], for the Python layer's signatures and help.
  py::list describe() const {
    py::list out;
    for (const Entry& e : entries_) out.append(py::make_tuple(e.name, e.default_value, e.doc));
    return out;
  }

 private:
  struct Entry {
    std::string name, doc;
    py::object default_value;
    Setter set;
  };
  const Entry* find(const std::string& name) const {
    for (const Entry& e : entries_)
      if (e.name == name) return &e;
    return nullptr;
  }
  std::vector<Entry> entries_;
};

// The option tables of every function, exported as _core.OPTIONS.
inline void registerOptions(py::module_& m, const char* function, py::list described) {
  if (!py::hasattr(m, "OPTIONS")) m.attr("OPTIONS") = py::dict();
  m.attr("OPTIONS")[function] = std::move(described);
}

}  // namespace meshmend::python
