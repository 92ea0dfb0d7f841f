// The Python module qdmr._qdmr: scenes, the Renderer with frames as numpy arrays, image files, and the shared
// helpers of common.hpp. docs/python.md describes the API; qdmr/__init__.pyi has its signatures.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <signal.h>

#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common.hpp"
#include "file/input_file.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/core/version.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/texture/image.hpp"
#include "qdmr/write/write.hpp"

namespace qdmr::python {

// --- arguments and JSON ----------------------------------------------------------------------------------------

std::string type_name(py::handle value) { return Py_TYPE(value.ptr())->tp_name; }

void type_error(const char* function, const std::string& parameter, const char* expected, py::handle got) {
  throw py::type_error(std::string(function) + "(): " + parameter + " must be " + expected + ", not " +
                       type_name(got));
}

std::string path_arg(py::handle value, const char* function, const char* parameter) {
  if (PyUnicode_Check(value.ptr())) return value.cast<std::string>();
  if (!PyObject_HasAttrString(value.ptr(), "__fspath__")) type_error(function, parameter, "a str or os.PathLike", value);
  py::object path = py::reinterpret_steal<py::object>(PyOS_FSPath(value.ptr()));
  if (!path) throw py::error_already_set();
  if (!PyUnicode_Check(path.ptr())) type_error(function, parameter, "a str or os.PathLike of str", value);
  return path.cast<std::string>();
}

std::string str_arg(py::handle value, const char* function, const char* parameter) {
  if (!PyUnicode_Check(value.ptr())) type_error(function, parameter, "a str", value);
  return value.cast<std::string>();
}

int int_arg(py::handle value, const char* function, const char* parameter) {
  if (PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr())) type_error(function, parameter, "an int", value);
  const long long v = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr())).cast<long long>();
  if (v < -(1LL << 30) || v > (1LL << 30))
    throw BadValue(std::string(function) + "(): " + parameter + " is out of range: " + std::to_string(v));
  return int(v);
}

bool bool_arg(py::handle value, const char* function, const char* parameter) {
  if (!PyBool_Check(value.ptr())) type_error(function, parameter, "a bool", value);
  return value.ptr() == Py_True;
}

nlohmann::json from_python(py::handle value, const char* function, const std::string& parameter) {
  PyObject* o = value.ptr();
  if (o == Py_None) return nullptr;
  if (PyBool_Check(o)) return o == Py_True;
  if (PyLong_Check(o)) {
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(o, &overflow);
    if (overflow == 0) return v;
    if (overflow > 0) {
      const unsigned long long u = PyLong_AsUnsignedLongLong(o);
      if (!PyErr_Occurred()) return u;
      PyErr_Clear();
    }
    throw BadValue(std::string(function) + "(): " + parameter + ": integer out of range");
  }
  if (PyFloat_Check(o)) return PyFloat_AsDouble(o);
  if (PyUnicode_Check(o)) return value.cast<std::string>();
  if (PyDict_Check(o)) {
    nlohmann::json object = nlohmann::json::object();
    for (const auto& [key, item] : py::reinterpret_borrow<py::dict>(value)) {
      if (!PyUnicode_Check(key.ptr())) type_error(function, parameter + " key", "a str", key);
      const std::string name = key.cast<std::string>();
      object[name] = from_python(item, function, parameter + "/" + name);
    }
    return object;
  }
  if (PyList_Check(o) || PyTuple_Check(o)) {
    nlohmann::json array = nlohmann::json::array();
    std::size_t i = 0;
    for (const auto& item : py::reinterpret_borrow<py::sequence>(value))
      array.push_back(from_python(item, function, parameter + "/" + std::to_string(i++)));
    return array;
  }
  if (PyObject_HasAttrString(o, "__fspath__")) return path_arg(value, function, parameter.c_str());
  // numpy scalars: integers have __index__, floating point numbers __float__.
  if (PyIndex_Check(o)) return from_python(py::reinterpret_steal<py::object>(PyNumber_Index(o)), function, parameter);
  if (PyObject_HasAttrString(o, "__float__") && !PyComplex_Check(o)) return py::float_(py::reinterpret_borrow<py::object>(value)).cast<double>();
  type_error(function, parameter, "JSON-like (dict, list, str, int, float, bool or None)", value);
}

// --- exceptions ------------------------------------------------------------------------------------------------

namespace {

PyObject* scene_error = nullptr;  // qdmr.SceneError(ValueError)
PyObject* input_error = nullptr;  // qdmr.InputError(OSError)

}  // namespace

void raise_interrupt() {
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  PyErr_SetNone(PyExc_KeyboardInterrupt);  // a Python handler ran and raised nothing: stopping is still an interrupt
  throw py::error_already_set();
}

// --- Ctrl-C ----------------------------------------------------------------------------------------------------

namespace {

std::atomic<bool> interrupt_flag{false};
struct sigaction previous_sigint;
unsigned long main_thread_ident = 0;

extern "C" void on_sigint(int signal, siginfo_t* info, void* context) {
  interrupt_flag.store(true);
  // Chain to Python's handler, which records the signal for PyErr_CheckSignals.
  if (previous_sigint.sa_flags & SA_SIGINFO)
    previous_sigint.sa_sigaction(signal, info, context);
  else if (previous_sigint.sa_handler != SIG_DFL && previous_sigint.sa_handler != SIG_IGN)
    previous_sigint.sa_handler(signal);
}

}  // namespace

InterruptWatch::InterruptWatch() {
  if (PyThread_get_thread_ident() != main_thread_ident) return;
  struct sigaction current {};
  if (sigaction(SIGINT, nullptr, &current) != 0) return;
  // SIGINT ignored or left to the system (Python started that way): nothing to watch.
  if (!(current.sa_flags & SA_SIGINFO) && (current.sa_handler == SIG_DFL || current.sa_handler == SIG_IGN)) return;
  previous_sigint = current;
  interrupt_flag.store(false);
  struct sigaction mine {};
  mine.sa_sigaction = on_sigint;
  mine.sa_flags = SA_SIGINFO | (current.sa_flags & SA_ONSTACK);
  sigemptyset(&mine.sa_mask);
  active_ = sigaction(SIGINT, &mine, nullptr) == 0;
}

InterruptWatch::~InterruptWatch() {
  if (active_) sigaction(SIGINT, &previous_sigint, nullptr);
}

bool InterruptWatch::requested() { return interrupt_flag.load(std::memory_order_relaxed); }

namespace {

// --- scenes ----------------------------------------------------------------------------------------------------

struct Scene {
  SceneDesc desc;
};

std::vector<SceneOverride> overrides_arg(py::handle value, const char* function) {
  std::vector<SceneOverride> overrides;
  if (value.is_none()) return overrides;
  if (PyDict_Check(value.ptr())) {
    for (const auto& [key, item] : py::reinterpret_borrow<py::dict>(value)) {
      if (!PyUnicode_Check(key.ptr())) type_error(function, "overrides key", "a str (a JSON pointer)", key);
      const std::string pointer = key.cast<std::string>();
      overrides.push_back({pointer, from_python(item, function, "overrides['" + pointer + "']").dump()});
    }
    return overrides;
  }
  if (PyList_Check(value.ptr()) || PyTuple_Check(value.ptr())) {
    for (const auto& item : py::reinterpret_borrow<py::sequence>(value))
      overrides.push_back(parse_override(str_arg(item, function, "overrides item")));  // "POINTER=VALUE", as --set
    return overrides;
  }
  type_error(function, "overrides", "a dict of JSON pointers and values or a list of 'POINTER=VALUE' strings", value);
}

Scene load_scene_arg(py::handle scene, py::handle overrides, py::handle base_dir, py::handle threads_value) {
  const char* fn = "load_scene";
  const std::vector<SceneOverride> sets = overrides_arg(overrides, fn);
  int threads = 0;  // every core
  if (!threads_value.is_none()) {
    threads = int_arg(threads_value, fn, "threads");
    if (threads < 1 || threads > limits::kMaxThreads)
      throw BadValue("load_scene(): threads must be from 1 to " + std::to_string(limits::kMaxThreads) +
                     " (or None for every core), got " + std::to_string(threads));
  }
  if (PyDict_Check(scene.ptr())) {
    const nlohmann::json document = from_python(scene, fn, "scene");
    const std::filesystem::path base =
        base_dir.is_none() ? std::filesystem::current_path() : std::filesystem::path(path_arg(base_dir, fn, "base_dir"));
    py::gil_scoped_release release;
    return Scene{load_scene_json(document, "<scene dict>", std::filesystem::absolute(base), sets, 0, threads)};
  }
  if (!PyUnicode_Check(scene.ptr()) && !PyObject_HasAttrString(scene.ptr(), "__fspath__"))
    type_error(fn, "scene", "a path (str or os.PathLike) or a dict", scene);
  const std::string path = path_arg(scene, fn, "scene");
  if (const std::string reason = non_regular_reason(path); !reason.empty()) throw InputFailure(path + ": " + reason);
  py::gil_scoped_release release;
  return Scene{load_scene(path, sets, 0, threads)};
}

const Scene& scene_arg(py::handle value, const char* function) {
  if (!py::isinstance<Scene>(value)) type_error(function, "scene", "a qdmr.Scene (from qdmr.load_scene)", value);
  return value.cast<const Scene&>();
}

std::vector<Aov> aovs_arg(py::handle value, const char* function) {
  std::vector<Aov> aovs;
  if (value.is_none()) return aovs;
  if (PyUnicode_Check(value.ptr()) || !PySequence_Check(value.ptr()))
    type_error(function, "aovs", "a list of AOV names", value);
  for (const auto& item : py::reinterpret_borrow<py::sequence>(value)) {
    const std::string name = str_arg(item, function, "aovs item");
    const std::optional<Aov> aov = parse_aov(name);
    if (!aov) {
      std::string valid;
      for (const std::string& n : aov_names()) valid += (valid.empty() ? "" : ", ") + n;
      throw BadValue(std::string(function) + "(): aovs: unknown AOV '" + name + "' (valid: " + valid + ")");
    }
    for (Aov seen : aovs)
      if (seen == *aov) throw BadValue(std::string(function) + "(): aovs: AOV '" + name + "' given twice");
    aovs.push_back(*aov);
  }
  return aovs;
}

// --- frames ----------------------------------------------------------------------------------------------------

// A renderer's spare frame: a frame nobody refers to any more comes back here, and the next draw draws into its
// buffers instead of allocating (and first-touching) new ones.
struct FrameRecycler {
  std::mutex lock;
  std::optional<Frame> spare;
};

using SharedFrame = std::shared_ptr<const Frame>;

SharedFrame share_frame(Frame frame, const std::shared_ptr<FrameRecycler>& recycler) {
  std::weak_ptr<FrameRecycler> weak = recycler;
  return SharedFrame(new Frame(std::move(frame)), [weak](const Frame* f) {
    std::unique_ptr<Frame> owned(const_cast<Frame*>(f));
    if (const std::shared_ptr<FrameRecycler> r = weak.lock()) {
      const std::lock_guard<std::mutex> guard(r->lock);
      if (!r->spare) r->spare = std::move(*owned);
    }
  });
}

// A read-only numpy view of `pixels` that keeps the whole frame alive: (H, W) for one channel, else (H, W, C).
py::array plane_array(const SharedFrame& frame, const PixelBuffer& pixels, int channels) {
  auto* owner = new SharedFrame(frame);
  py::capsule base(owner, [](void* p) { delete static_cast<SharedFrame*>(p); });
  const py::ssize_t h = frame->height, w = frame->width, c = channels, f = sizeof(float);
  py::array array = channels == 1
                        ? py::array(py::dtype::of<float>(), {h, w}, {w * f, f}, pixels.data(), base)
                        : py::array(py::dtype::of<float>(), {h, w, c}, {w * c * f, c * f, f}, pixels.data(), base);
  py::detail::array_proxy(array.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return array;
}

struct PyFrame {
  SharedFrame frame;

  py::array color() const { return plane_array(frame, frame->color, 3); }
  py::dict aovs() const {
    py::dict out;
    for (const AovImage& a : frame->aovs) out[py::str(aov_name(a.aov))] = plane_array(frame, a.pixels, a.channels);
    return out;
  }
  py::array get(const std::string& name) const {
    if (name == "color") return color();
    for (const AovImage& a : frame->aovs)
      if (aov_name(a.aov) == name) return plane_array(frame, a.pixels, a.channels);
    std::string have = "color";
    for (const AovImage& a : frame->aovs) have += ", " + aov_name(a.aov);
    throw py::key_error("'" + name + "': this frame has " + have);
  }
  py::object stats() const { return to_python(frame->stats.to_json()); }
};

// --- the renderer ----------------------------------------------------------------------------------------------

class PyRenderer {
public:
  PyRenderer(py::handle threads, py::handle isa, py::handle tile, py::handle aovs, py::handle max_memory_mib) {
    const char* fn = "Renderer";
    RenderOptions options;
    if (!threads.is_none()) {
      options.threads = int_arg(threads, fn, "threads");
      if (options.threads < 1 || options.threads > limits::kMaxThreads)
        throw BadValue("Renderer(): threads must be from 1 to " + std::to_string(limits::kMaxThreads) + " (or None for every core), got " + std::to_string(options.threads));
    }
    options.tile_size = int_arg(tile, fn, "tile");
    const std::string isa_text = str_arg(isa, fn, "isa");
    const std::optional<Isa> parsed = parse_isa(isa_text);
    if (!parsed) throw BadValue("Renderer(): isa: unknown ISA '" + isa_text + "' (valid: auto, sse4.2, avx2, avx512)");
    options.isa = *parsed;
    options.aovs = aovs_arg(aovs, fn);
    default_aovs_ = options.aovs;
    if (!max_memory_mib.is_none()) {
      const int mib = int_arg(max_memory_mib, fn, "max_memory_mib");
      if (mib < 1) throw BadValue("Renderer(): max_memory_mib must be at least 1, got " + std::to_string(mib));
      options.max_memory_bytes = std::uint64_t(mib) << 20;
    }
    // Ctrl-C: a draw on the main thread stops at the next reported tile (every tile up to 100 tiles a frame,
    // every hundredth of them beyond).
    options.progress = [watching = &watching_](const char* stage, double fraction) {
      if (stage[0] == 'r' && fraction < 1.0 && watching->load(std::memory_order_relaxed) && InterruptWatch::requested())
        throw Interrupted{};
    };
    try {
      renderer_ = std::make_unique<Renderer>(options);
    } catch (const Error& e) {
      std::string_view message = e.what();  // "--threads: ...": the command's flags are this call's parameters
      if (message.starts_with("--")) message.remove_prefix(2);
      throw BadValue("Renderer(): " + std::string(message));
    }
  }

  void set_scene(py::handle scene_value, py::handle aovs) {
    const Scene& scene = scene_arg(scene_value, "Renderer.set_scene");
    const std::vector<Aov> list = aovs.is_none() ? default_aovs_ : aovs_arg(aovs, "Renderer.set_scene");
    Busy busy(*this, "set_scene");
    py::gil_scoped_release release;
    renderer_->set_scene(scene.desc, list);
    has_scene_ = true;
  }

  void set_frame(py::handle frame) {
    const int n = int_arg(frame, "Renderer.set_frame", "frame");
    Busy busy(*this, "set_frame");
    if (!has_scene_) throw std::runtime_error("Renderer.set_frame(): no scene (call set_scene first)");
    py::gil_scoped_release release;
    try {
      renderer_->set_frame(n);
    } catch (const Error& e) {
      throw BadValue(std::string("Renderer.set_frame(): ") + e.what());
    }
  }

  // A height field for layer `layer` of `material`, (H, W), row 0 at the top (as images and frames are): row 0 of
  // the texture (v = 0) is the array's last row.
  void update_layer(py::handle material, py::handle layer, py::handle height) {
    const char* fn = "Renderer.update_layer";
    const std::string name = str_arg(material, fn, "material");
    const int index = int_arg(layer, fn, "layer");
    using Floats = py::array_t<float, py::array::c_style | py::array::forcecast>;
    if (!py::isinstance<py::array>(height)) type_error(fn, "height", "a numpy array of shape (H, W)", height);
    Floats values = Floats::ensure(height);
    if (!values) {
      PyErr_Clear();
      type_error(fn, "height", "a numpy array of numbers", height);
    }
    if (values.ndim() != 2 || values.shape(0) < 1 || values.shape(1) < 1 || values.shape(0) > limits::kMaxTextureSide ||
        values.shape(1) > limits::kMaxTextureSide)
      throw BadValue("Renderer.update_layer(): height must have the shape (H, W), 1 to " +
                     std::to_string(limits::kMaxTextureSide) + " a side");
    Busy busy(*this, "update_layer");
    if (!has_scene_) throw std::runtime_error("Renderer.update_layer(): no scene (call set_scene first)");
    const int h = int(values.shape(0)), w = int(values.shape(1));
    Image image(w, h, 1);
    const float* data = values.data();
    for (int y = 0; y < h; ++y)
      std::copy(data + std::size_t(h - 1 - y) * std::size_t(w), data + std::size_t(h - y) * std::size_t(w), &image.at(0, y, 0));
    py::gil_scoped_release release;
    try {
      renderer_->update_height(name, index, std::move(image));
    } catch (const Error& e) {
      std::string_view message = e.what();  // "update_height: ...": the C++ call's name
      if (message.starts_with("update_height: ")) message.remove_prefix(15);
      throw BadValue("Renderer.update_layer(): " + std::string(message));
    }
  }

  PyFrame draw() {
    Busy busy(*this, "draw");
    if (!has_scene_) throw std::runtime_error("Renderer.draw(): no scene (call set_scene first)");
    last_.reset();  // unless the caller keeps it, the last frame becomes the spare one
    InterruptWatch watch;
    watching_ = watch.active();
    struct Unwatch {
      std::atomic<bool>& flag;
      ~Unwatch() { flag = false; }
    } unwatch{watching_};
    SharedFrame frame;
    try {
      py::gil_scoped_release release;
      {
        std::optional<Frame> spare;
        {
          const std::lock_guard<std::mutex> guard(recycler_->lock);
          spare.swap(recycler_->spare);
        }
        if (spare) renderer_->recycle_frame(std::move(*spare));
      }
      renderer_->draw();
      frame = share_frame(renderer_->take_frame(), recycler_);
    } catch (const Interrupted&) {
      raise_interrupt();
    }
    last_ = frame;
    return PyFrame{frame};
  }

  py::object plan() const {
    if (!has_scene_) throw std::runtime_error("Renderer.plan: no scene (call set_scene first)");
    return to_python(renderer_->plan().to_json());
  }
  py::object stats() const { return last_ ? to_python(last_->stats.to_json()) : py::none(); }
  std::string isa() const { return isa_name(renderer_->isa()); }
  int threads() const { return renderer_->threads(); }

private:
  // One call at a time: a Renderer is not thread-safe (one per thread), and the GIL is released while it works.
  struct Busy {
    std::unique_lock<std::mutex> hold;
    Busy(PyRenderer& r, const char* what) : hold(r.busy_, std::try_to_lock) {
      if (!hold) throw std::runtime_error(std::string("Renderer.") + what + "(): the renderer is busy in another thread (use one Renderer per thread)");
    }
  };
  std::unique_ptr<Renderer> renderer_;
  std::shared_ptr<FrameRecycler> recycler_ = std::make_shared<FrameRecycler>();
  std::mutex busy_;
  std::atomic<bool> watching_{false};
  SharedFrame last_;
  std::vector<Aov> default_aovs_;
  bool has_scene_ = false;  // a failed set_scene keeps the previous scene (qdmr::Renderer::set_scene)
};

// --- image files -----------------------------------------------------------------------------------------------

py::array read_image_arg(py::handle path_value) {
  const std::string path = path_arg(path_value, "read_image", "path");
  auto image = std::make_unique<Image>();
  {
    py::gil_scoped_release release;
    try {
      *image = read_image(path, path);
    } catch (const Error& e) {
      throw InputFailure(e.what());
    }
  }
  // Files are read bottom-up (row 0 at v = 0); the array shows them top row first, as frames are: a view with a
  // negative row stride, no copy.
  const py::ssize_t h = image->height, w = image->width, c = image->channels, f = sizeof(float);
  const float* top = image->texels.data() + std::size_t(h - 1) * std::size_t(w * c);
  Image* owned = image.release();
  py::capsule base(owned, [](void* p) { delete static_cast<Image*>(p); });
  if (c == 1) return py::array(py::dtype::of<float>(), {h, w}, {-w * f, f}, top, base);
  return py::array(py::dtype::of<float>(), {h, w, c}, {-w * c * f, c * f, f}, top, base);
}

void write_image_arg(py::handle image, py::handle path_value, py::handle srgb_value, py::handle threads) {
  const char* fn = "write_image";
  const std::string path = path_arg(path_value, fn, "path");
  WriteOptions write;
  if (!threads.is_none()) {
    write.threads = int_arg(threads, fn, "threads");
    if (write.threads < 1 || write.threads > limits::kMaxThreads)
      throw BadValue("write_image(): threads must be from 1 to " + std::to_string(limits::kMaxThreads) +
                     " (or None for every core), got " + std::to_string(write.threads));
  }
  using Floats = py::array_t<float, py::array::c_style | py::array::forcecast>;
  if (!py::isinstance<py::array>(image) && !PyList_Check(image.ptr()))
    type_error(fn, "image", "a numpy array of shape (H, W) or (H, W, C)", image);
  Floats pixels = Floats::ensure(image);
  if (!pixels) {
    PyErr_Clear();
    type_error(fn, "image", "a numpy array of numbers", image);
  }
  const int dims = int(pixels.ndim());
  const int channels = dims == 3 ? int(pixels.shape(2)) : 1;
  if ((dims != 2 && dims != 3) || channels < 1 || channels > 4)
    throw BadValue("write_image(): image must have the shape (H, W) or (H, W, C) with C from 1 to 4");
  const int height = int(pixels.shape(0)), width = int(pixels.shape(1));
  if (width < 1 || height < 1 || width > limits::kMaxImageSide || height > limits::kMaxImageSide)
    throw BadValue("write_image(): image must be 1 to " + std::to_string(limits::kMaxImageSide) + " pixels a side");
  const bool srgb = srgb_value.is_none() ? channels == 3 : bool_arg(srgb_value, fn, "srgb");
  const std::span<const float> values(pixels.data(), pixels.size());
  py::gil_scoped_release release;
  try {
    write_image(path, width, height, channels, values, srgb, write);
  } catch (const Error& e) {
    throw InputFailure(e.what());
  }
}

}  // namespace
}  // namespace qdmr::python

using namespace qdmr::python;

PYBIND11_MODULE(_qdmr, m) {
  m.doc() = "qdmr's renderer, images, studies and checks (the package qdmr re-exports them; docs/python.md)";
  main_thread_ident = py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();

  scene_error = PyErr_NewExceptionWithDoc(
      "qdmr.SceneError", "A scene, study spec, manifest or override is invalid; the message names the file and the field.",
      PyExc_ValueError, nullptr);
  input_error = PyErr_NewExceptionWithDoc(
      "qdmr.InputError", "A file cannot be read or written; the message names the file.", PyExc_OSError, nullptr);
  m.add_object("SceneError", py::handle(scene_error));
  m.add_object("InputError", py::handle(input_error));
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputFailure& e) {
      PyErr_SetString(input_error, e.what());
    } catch (const BadValue& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const qdmr::Error& e) {  // its kind: a file as a whole (InputError), or a value (SceneError)
      PyErr_SetString(e.kind() == qdmr::Error::Kind::File ? input_error : scene_error, e.what());
    } catch (const Interrupted&) {
      try {
        raise_interrupt();
      } catch (py::error_already_set& raised) {
        raised.restore();
      }
    }
  });

  m.attr("__version__") = qdmr::version();
  m.attr("bits_version") = qdmr::kBitsVersion;
  m.def("aov_names", &qdmr::aov_names, "The AOV names a Renderer draws besides colour.");
  m.def("isas", [] {
    std::vector<std::string> names;
    for (qdmr::Isa isa : qdmr::usable_isas()) names.push_back(qdmr::isa_name(isa));
    return names;
  }, "The draw kernels this CPU runs, best first (every one draws the same bits).");

  py::class_<Scene>(m, "Scene", "A loaded, validated scene (load_scene); give it to Renderer.set_scene.")
      .def_property_readonly("width", [](const Scene& s) { return s.desc.output.width; }, "Output width in pixels.")
      .def_property_readonly("height", [](const Scene& s) { return s.desc.output.height; }, "Output height in pixels.")
      .def_property_readonly("file", [](const Scene& s) { return s.desc.file.string(); }, "The scene file, or '<scene dict>'.")
      .def_property_readonly("materials", [](const Scene& s) {
        std::vector<std::string> names;
        for (const auto& material : s.desc.materials) names.push_back(material.name);
        return names;
      }, "The material names.")
      .def("__repr__", [](const Scene& s) {
        return "<qdmr.Scene " + s.desc.file.string() + " " + std::to_string(s.desc.output.width) + "x" +
               std::to_string(s.desc.output.height) + ">";
      });

  m.def("load_scene", &load_scene_arg, py::arg("scene"), py::arg("overrides") = py::none(), py::kw_only(),
        py::arg("base_dir") = py::none(), py::arg("threads") = py::none(),
        "load_scene(scene, overrides=None, *, base_dir=None, threads=None) -> Scene\n\n"
        "Reads a scene file (str or os.PathLike), a glTF asset (.gltf, .glb) or a scene dict, applies the overrides\n"
        "first (a dict of JSON pointers and values, or a list of 'POINTER=VALUE' strings: `qdmr render --set`),\n"
        "validates it and reads its meshes. Relative paths of a dict resolve against base_dir (default: the current\n"
        "folder). threads: at most that many threads for the load's parallel parts (a glTF mesh's reads, its\n"
        "MikkTSpace tangents), as `qdmr render --threads`; None: every core. The same Scene for any count.\n"
        "Raises SceneError naming the file and the field, InputError for a file that cannot be read.");

  m.def("plan", [](py::handle scene, py::handle aovs) {
    const qdmr::PlanOptions options{aovs_arg(aovs, "plan")};
    return to_python(qdmr::plan_frame(scene_arg(scene, "plan").desc, options).to_json());
  }, py::arg("scene"), py::arg("aovs") = py::none(),
        "plan(scene, aovs=None) -> dict\n\nWhat the scene requires (programs, textures, derived data, memory): "
        "`qdmr plan --json`.");

  py::class_<PyFrame>(m, "Frame",
                      "One drawn frame. Its arrays are read-only views of the frame's memory, which lives as long as\n"
                      "the frame or any of its arrays (after the next draw and after the renderer is gone too).")
      .def_property_readonly("color", &PyFrame::color, "Linear RGB, float32 (H, W, 3), row 0 at the top: the EXR's values.")
      .def_property_readonly("aovs", &PyFrame::aovs, "The AOVs drawn: name -> float32 (H, W) or (H, W, C).")
      .def_property_readonly("stats", &PyFrame::stats, "Timings and counters (`qdmr render --stats`).")
      .def_property_readonly("width", [](const PyFrame& f) { return f.frame->width; })
      .def_property_readonly("height", [](const PyFrame& f) { return f.frame->height; })
      .def("__getitem__", &PyFrame::get, py::arg("name"), "'color' or an AOV name -> its array.")
      .def("__repr__", [](const PyFrame& f) {
        std::string aovs;
        for (const qdmr::AovImage& a : f.frame->aovs) aovs.append(" ").append(qdmr::aov_name(a.aov));
        return "<qdmr.Frame " + std::to_string(f.frame->width) + "x" + std::to_string(f.frame->height) + " color" + aovs + ">";
      });

  py::class_<PyRenderer>(m, "Renderer",
                         "Renderer(threads=None, isa='auto', tile=64, aovs=None, max_memory_mib=None)\n\n"
                         "Prepares a scene once and draws it many times (qdmr::Renderer). threads: worker threads\n"
                         "(None: every core); isa: 'auto', 'sse4.2', 'avx2' or 'avx512' (the same bits on each); tile:\n"
                         "pixels, a multiple of 8; aovs: the default AOVs of set_scene. The GIL is released while it\n"
                         "prepares and draws: renderers in different threads run at once. One call at a time each.")
      .def(py::init<py::handle, py::handle, py::handle, py::handle, py::handle>(),
           py::kw_only(), py::arg("threads") = py::none(), py::arg("isa") = "auto", py::arg("tile") = 64,
           py::arg("aovs") = py::none(), py::arg("max_memory_mib") = py::none())
      .def("set_scene", &PyRenderer::set_scene, py::arg("scene"), py::arg("aovs") = py::none(),
           "set_scene(scene, aovs=None)\n\nPlans the scene with these AOVs (None: the renderer's) and prepares what\n"
           "the previous scene did not already have: a new camera, size or lighting builds nothing.")
      .def("set_frame", &PyRenderer::set_frame, py::arg("frame"),
           "set_frame(frame)\n\nThe current scene at frame `frame` of its animation: only the plan's dynamic items\n"
           "(made from time-dependent textures) are rebuilt.")
      .def("update_layer", &PyRenderer::update_layer, py::arg("material"), py::arg("layer"), py::kw_only(),
           py::arg("height"),
           "update_layer(material, layer, *, height)\n\nNew heights for a layer, drawn from the next draw on: a float\n"
           "(H, W) array in [0, 1], row 0 at the top. Its mip chain, max-quadtree, normals from_height and AO maps\n"
           "are rebuilt, nothing else (qdmr::Renderer::update_height).")
      .def("draw", &PyRenderer::draw,
           "draw() -> Frame\n\nDraws the current scene. Ctrl-C stops it at the next tile (KeyboardInterrupt; no frame).")
      .def_property_readonly("plan", &PyRenderer::plan, "The current scene's plan as a dict (`qdmr plan --json`).")
      .def_property_readonly("stats", &PyRenderer::stats, "The last frame's stats as a dict, or None before the first draw.")
      .def_property_readonly("isa", &PyRenderer::isa, "The draw kernel in use.")
      .def_property_readonly("threads", &PyRenderer::threads, "The worker threads.");

  m.def("read_image", &read_image_arg, py::arg("path"),
        "read_image(path) -> numpy.ndarray\n\nAn image file as float32 (H, W) or (H, W, C), row 0 at the top; PNG and\n"
        "TIFF codes normalised to [0, 1], EXR floats as stored. Raises InputError naming the file.");
  m.def("write_image", &write_image_arg, py::arg("image"), py::arg("path"), py::kw_only(), py::arg("srgb") = py::none(),
        py::arg("threads") = py::none(),
        "write_image(image, path, *, srgb=None, threads=None)\n\nWrites float (H, W) or (H, W, C) pixels (C from 1 to 4, row 0 at the\n"
        "top) with qdmr's writers, through a temporary file and a rename: EXR as 32-bit floats, PNG 8-bit and TIFF\n"
        "16-bit codes, sRGB-encoded when srgb (default: for 3 channels, as a frame's colour). A frame's colour\n"
        "written to .exr gives the same bytes as `qdmr render -o x.exr`. threads: at most that many threads\n"
        "encode and compress (1: the calling thread alone), None for every core; the same bytes on any count.\n"
        "Raises InputError naming the file.");

  bind_studies(m);
}
