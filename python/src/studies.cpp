// Studies and checks for the Python module: qdmr._qdmr.run_study / merge_studies / study_rows / study_size /
// run_checks, which qdmr.study and qdmr.check (python/qdmr) wrap.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <filesystem>
#include <string>
#include <vector>

#include "common.hpp"
#include "file/input_file.hpp"
#include "qdmr/check/check.hpp"
#include "qdmr/check/manifest.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/study/spec.hpp"
#include "qdmr/study/study.hpp"
#include "study/results.hpp"

namespace qdmr::python {
namespace {

// A spec from a file (str or os.PathLike) or a dict (relative paths against base_dir, default the current folder).
StudySpec spec_arg(py::handle spec, py::handle base_dir, const char* fn) {
  if (PyDict_Check(spec.ptr())) {
    const nlohmann::json document = from_python(spec, fn, "spec");
    const std::filesystem::path base =
        base_dir.is_none() ? std::filesystem::current_path() : std::filesystem::path(path_arg(base_dir, fn, "base_dir"));
    py::gil_scoped_release release;
    return read_study_spec_json(document, "<spec dict>", std::filesystem::absolute(base));
  }
  if (!PyUnicode_Check(spec.ptr()) && !PyObject_HasAttrString(spec.ptr(), "__fspath__"))
    type_error(fn, "spec", "a path (str or os.PathLike) or a dict", spec);
  const std::string path = path_arg(spec, fn, "spec");
  if (const std::string reason = non_regular_reason(path); !reason.empty()) throw InputFailure(path + ": " + reason);
  py::gil_scoped_release release;
  return read_study_spec(path);
}

int threads_arg(py::handle threads, const char* fn) {
  if (threads.is_none()) return 0;
  const int n = int_arg(threads, fn, "threads");
  if (n < 1 || n > limits::kMaxThreads)
    throw BadValue(std::string(fn) + "(): threads must be from 1 to " + std::to_string(limits::kMaxThreads) + " (or None)");
  return n;
}

py::dict run_study_arg(py::handle spec_value, py::handle out_value, py::handle resume, py::handle threads,
                       py::handle jobs, py::handle shard, py::handle force, py::handle base_dir) {
  const char* fn = "study.run";
  const StudySpec spec = spec_arg(spec_value, base_dir, fn);
  const std::filesystem::path out = path_arg(out_value, fn, "out");
  StudyOptions options;
  options.resume = bool_arg(resume, fn, "resume");
  options.force = bool_arg(force, fn, "force");
  options.threads = threads_arg(threads, fn);
  options.jobs = int_arg(jobs, fn, "jobs");
  if (options.jobs < 1 || options.jobs > 64) throw BadValue("study.run(): jobs must be from 1 to 64");
  if (!shard.is_none()) {
    if (!PyTuple_Check(shard.ptr()) || PyTuple_Size(shard.ptr()) != 2) type_error(fn, "shard", "a tuple (I, N)", shard);
    options.shard.index = int_arg(PyTuple_GetItem(shard.ptr(), 0), fn, "shard[0]");
    options.shard.count = int_arg(PyTuple_GetItem(shard.ptr(), 1), fn, "shard[1]");
    if (options.shard.count < 1 || options.shard.index < 1 || options.shard.index > options.shard.count)
      throw BadValue("study.run(): shard must be (I, N) with 1 <= I <= N");
  }
  InterruptWatch watch;  // Ctrl-C: the run stops after the configuration being drawn; its rows stay valid
  const bool watching = watch.active();
  options.stop_requested = [watching] { return watching && InterruptWatch::requested(); };
  StudyRun run;
  {
    py::gil_scoped_release release;
    run = run_study(spec, out, options);
  }
  if (run.stopped) raise_interrupt();
  py::dict result;
  result["total"] = run.total;
  result["rendered"] = run.rendered;
  result["resumed"] = run.resumed;
  result["asset_builds"] = run.asset_builds;
  result["seconds"] = run.seconds;
  return result;
}

std::vector<py::dict> run_checks_arg(py::handle manifest_value, py::handle update, py::handle jobs, py::handle threads,
                                     py::handle diff_dir) {
  const char* fn = "check.run";
  const std::string file = path_arg(manifest_value, fn, "manifest");
  if (const std::string reason = non_regular_reason(file); !reason.empty()) throw InputFailure(file + ": " + reason);
  CheckOptions options;
  options.update = bool_arg(update, fn, "update");
  options.jobs = int_arg(jobs, fn, "jobs");
  if (options.jobs < 1 || options.jobs > 64) throw BadValue("check.run(): jobs must be from 1 to 64");
  if (!threads.is_none()) {
    options.threads = int_arg(threads, fn, "threads");
    if (options.threads < 1 || options.threads > limits::kMaxThreads)
      throw BadValue("check.run(): threads must be from 1 to " + std::to_string(limits::kMaxThreads) + " (or None)");
  }
  options.diff_dir = path_arg(diff_dir, fn, "diff_dir");
  CheckRun run;
  {
    py::gil_scoped_release release;
    const Manifest manifest = read_manifest(file);
    run = run_checks(manifest, options);
  }
  std::vector<py::dict> results;
  for (const CheckResult& r : run.results) {
    py::dict d;
    d["name"] = r.name;
    d["status"] = check_status_name(r.status);
    d["passed"] = r.status == CheckStatus::Passed || r.status == CheckStatus::Skipped || r.status == CheckStatus::Updated;
    d["lines"] = r.lines;
    py::dict hashes;
    for (const OutputResult& o : r.outputs) hashes[py::str(o.output)] = o.hash;
    d["hashes"] = hashes;
    d["diff_folder"] = r.diff_folder.empty() ? py::object(py::none()) : py::object(py::str(r.diff_folder.string()));
    d["prepare_ms"] = r.prepare_ms;
    d["draw_ms"] = r.draw_ms;
    d["seconds"] = r.seconds;
    results.push_back(std::move(d));
  }
  return results;
}

// The results folder of a study spread over workers (qdmr/_dask.py): the caller holds it (and its lock) while the
// workers' rows come in; close() writes the results and lets the folder go.
class StudyFolderHandle {
public:
  StudyFolderHandle(py::handle spec_value, py::handle out_value, py::handle resume, py::handle force,
                    py::handle threads, py::handle base_dir) {
    const char* fn = "study.run";
    const StudySpec spec = spec_arg(spec_value, base_dir, fn);
    const std::filesystem::path out = path_arg(out_value, fn, "out");
    StudyFolderInfo info;
    info.configurations = expand_study(spec, bool_arg(force, fn, "force")).size();
    info.resume = bool_arg(resume, fn, "resume");
    info.threads = threads_arg(threads, fn);
    info.isa = isa_name(resolve_isa(Isa::Auto));
    hash_ = spec.hash;
    configurations_ = info.configurations;
    py::gil_scoped_release release;
    folder_ = std::make_unique<StudyFolder>(spec, out, info);
  }

  StudyFolder& folder() {
    if (!folder_) throw BadValue("StudyFolder: closed");
    return *folder_;
  }
  const std::string& spec_hash() const { return hash_; }
  std::size_t configurations() const { return configurations_; }
  void close() {
    if (!folder_) return;
    py::gil_scoped_release release;
    folder_->finish();
    folder_.reset();
  }

private:
  std::string hash_;
  std::size_t configurations_ = 0;
  std::unique_ptr<StudyFolder> folder_;
};

}  // namespace

void bind_studies(py::module_& m) {
  m.def("run_study", &run_study_arg, py::arg("spec"), py::arg("out"), py::kw_only(), py::arg("resume") = true,
        py::arg("threads") = py::none(), py::arg("jobs") = 1, py::arg("shard") = py::none(), py::arg("force") = false,
        py::arg("base_dir") = py::none(), "One process's study run (qdmr.study.run wraps it).");
  py::class_<StudyMeasurer>(m, "StudyMeasurer",
                            "One process's persistent renderers for a spec's configurations (a Dask worker keeps one).")
      .def(py::init([](py::handle spec, py::handle threads, py::handle force, py::handle base_dir) {
             const StudySpec s = spec_arg(spec, base_dir, "study.run");
             const int n = threads_arg(threads, "study.run");
             const bool f = bool_arg(force, "study.run", "force");
             py::gil_scoped_release release;
             return std::make_unique<StudyMeasurer>(s, n, f);
           }),
           py::arg("spec"), py::kw_only(), py::arg("threads") = py::none(), py::arg("force") = false,
           py::arg("base_dir") = py::none())
      .def("measure", [](StudyMeasurer& measurer, std::size_t index, py::handle out) {
             const std::filesystem::path folder = path_arg(out, "study.run", "out");
             std::string row;
             {
               py::gil_scoped_release release;
               row = measurer.measure(index, folder).dump();
             }
             return row;
           }, py::arg("index"), py::arg("out"),
           "Configuration `index`'s row as JSON text (kept files into out/images).")
      .def("reuse_order", &StudyMeasurer::reuse_order, py::arg("pending"),
           "`pending` grouped by the asset sets their plans build, the order that re-prepares least.")
      .def("share_groups", &StudyMeasurer::share_groups, py::arg("pending"), py::call_guard<py::gil_scoped_release>(),
           "`pending` in groups that share the exact reference and the heights it is traced on, each in reuse order.")
      .def("estimated_cost", &StudyMeasurer::estimated_cost, py::arg("index"),
           "A relative estimate of what configuration `index` costs to draw.")
      .def_property_readonly("spec_hash", &StudyMeasurer::spec_hash)
      .def_property_readonly("asset_builds", &StudyMeasurer::asset_builds);
  py::class_<StudyFolderHandle>(m, "StudyFolder", "A study's results folder, locked while a run writes it.")
      .def(py::init<py::handle, py::handle, py::handle, py::handle, py::handle, py::handle>(), py::arg("spec"),
           py::arg("out"), py::kw_only(), py::arg("resume") = true, py::arg("force") = false,
           py::arg("threads") = py::none(), py::arg("base_dir") = py::none())
      .def_property_readonly("done", [](StudyFolderHandle& h) {
             const std::set<std::size_t>& done = h.folder().done();
             return std::vector<std::size_t>(done.begin(), done.end());
           }, "Indices that have a row, ascending.")
      .def_property_readonly("resumed", [](StudyFolderHandle& h) { return h.folder().resumed(); })
      .def_property_readonly("spec_hash", &StudyFolderHandle::spec_hash)
      .def_property_readonly("configurations", &StudyFolderHandle::configurations)
      .def("append", [](StudyFolderHandle& h, const std::string& row) {
             StudyFolder& folder = h.folder();
             py::gil_scoped_release release;
             folder.append(StudyRow::parse(row));
           }, py::arg("row"), "Appends a row (JSON text, as StudyMeasurer.measure returns it).")
      .def("close", &StudyFolderHandle::close, "Writes results.json, results.csv and pareto.csv; unlocks the folder.");
  m.def("study_size", [](py::handle spec, py::handle force, py::handle base_dir) {
    const StudySpec s = spec_arg(spec, base_dir, "study.run");
    return expand_study(s, bool_arg(force, "study.run", "force")).size();
  }, py::arg("spec"), py::arg("force") = false, py::arg("base_dir") = py::none(),
        "The number of configurations of a spec (SceneError for a bad spec, before anything renders).");
  m.def("merge_studies", [](const std::vector<std::string>& folders, py::handle out) {
    const std::string target = path_arg(out, "study.merge", "out");
    std::vector<std::filesystem::path> paths(folders.begin(), folders.end());
    py::gil_scoped_release release;
    merge_studies(paths, target);
  }, py::arg("folders"), py::arg("out"), "`qdmr study merge`.");
  m.def("study_rows", [](py::handle folder) {
    const std::filesystem::path dir = path_arg(folder, "study.load", "folder");
    const std::filesystem::path file = dir / "rows.jsonl";
    if (const std::string reason = non_regular_reason(file); !reason.empty())
      throw InputFailure(file.string() + ": " + reason + " (not a study results folder)");
    std::vector<StudyRow> rows;
    {
      py::gil_scoped_release release;
      rows = read_study_rows(file);
    }
    py::list out;
    for (const StudyRow& r : rows) out.append(to_python(r));
    return out;
  }, py::arg("folder"), "The rows of a results folder (rows.jsonl), in the order written.");
  m.def("run_checks", &run_checks_arg, py::arg("manifest"), py::kw_only(), py::arg("update") = false,
        py::arg("jobs") = 1, py::arg("threads") = py::none(), py::arg("diff_dir") = "qdmr-check-failures",
        "`qdmr check MANIFEST` in process (qdmr.check.run wraps it).");
}

}  // namespace qdmr::python
