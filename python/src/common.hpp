#pragma once
// What both translation units of the Python module share: JSON to and from Python objects, argument checks that
// raise TypeError naming the parameter, qdmr's exceptions as Python ones, and Ctrl-C during long calls.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>  // in every translation unit alike (pybind11: the same conversions everywhere)

#include <cstdint>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace qdmr::python {

namespace py = pybind11;

// A JSON value as Python objects (dicts, lists, str, int, float, bool, None).
template <class Json>
py::object to_python(const Json& j) {
  using T = nlohmann::json::value_t;
  switch (j.type()) {
    case T::boolean: return py::bool_(j.template get<bool>());
    case T::number_integer: return py::int_(j.template get<std::int64_t>());
    case T::number_unsigned: return py::int_(j.template get<std::uint64_t>());
    case T::number_float: return py::float_(j.template get<double>());
    case T::string: return py::str(j.template get_ref<const std::string&>());
    case T::array: {
      py::list list;
      for (const auto& e : j) list.append(to_python(e));
      return list;
    }
    case T::object: {
      py::dict dict;
      for (const auto& [key, value] : j.items()) dict[py::str(key)] = to_python(value);
      return dict;
    }
    default: return py::none();
  }
}

// Python objects (dict with str keys, list, tuple, str, os.PathLike, int, float, bool, None, numpy scalars) as
// JSON. TypeError naming `function`'s `parameter` (and where inside it) for anything else.
nlohmann::json from_python(py::handle value, const char* function, const std::string& parameter);

[[noreturn]] void type_error(const char* function, const std::string& parameter, const char* expected,
                             py::handle got);
std::string path_arg(py::handle value, const char* function, const char* parameter);  // str or os.PathLike
std::string str_arg(py::handle value, const char* function, const char* parameter);
int int_arg(py::handle value, const char* function, const char* parameter);  // int (not bool)
bool bool_arg(py::handle value, const char* function, const char* parameter);

// A file could not be read or written: raised as qdmr.InputError (an OSError).
struct InputFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// A value given to a function is out of range: raised as ValueError.
struct BadValue : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Thrown from inside a draw when Ctrl-C was pressed: raised as KeyboardInterrupt (the Python handler runs).
struct Interrupted {};

// While alive on the Python main thread (constructed with the GIL held), Ctrl-C also sets a flag long C++ work
// polls between tiles or configurations; Python's own handler still records the signal. Elsewhere inactive:
// Python delivers signals to its main thread only.
class InterruptWatch {
public:
  InterruptWatch();
  ~InterruptWatch();
  InterruptWatch(const InterruptWatch&) = delete;
  InterruptWatch& operator=(const InterruptWatch&) = delete;
  bool active() const { return active_; }
  static bool requested();

private:
  bool active_ = false;
};

// After C++ work stopped for Ctrl-C (GIL held): runs Python's signal handlers and throws what they raised
// (KeyboardInterrupt by default), or KeyboardInterrupt.
[[noreturn]] void raise_interrupt();

void bind_studies(py::module_& m);  // studies.cpp

}  // namespace qdmr::python
