// Runs a study: see qdmr/study/study.hpp.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "file/atomic_file.hpp"
#include "file/folder_lock.hpp"
#include "check/canonical_hash.hpp"
#include "qdmr/check/compare.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/progress.hpp"
#include "qdmr/core/version.hpp"
#include "qdmr/load/load.hpp"
#include "qdmr/plan/plan.hpp"
#include "qdmr/reference/reference_memo.hpp"
#include "qdmr/render/render.hpp"
#include "qdmr/study/study.hpp"
#include "qdmr/write/write.hpp"
#include "scene/reader.hpp"
#include "study/results.hpp"

namespace qdmr {
namespace {

using Clock = std::chrono::steady_clock;

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.starts_with("model name")) return line.substr(line.find(':') + 2);
  return "unknown";
}

RenderOptions with_threads(int threads, std::shared_ptr<ReferenceMemo> memo = nullptr) {
  RenderOptions options;
  options.threads = threads;
  options.reference_memo = std::move(memo);
  return options;
}

double number_or(const nlohmann::json& v, double fallback) { return v.is_number() ? v.get<double>() : fallback; }

// A relative cost estimate of a configuration, for balancing shards: iteration caps and step counts multiply,
// techniques weigh by their typical cost, grazing views cost more.
double estimated_cost(const StudySpec& spec, const StudyConfig& config) {
  static const std::map<std::string, double> technique{{"normal", 1}, {"pom", 2}, {"csm", 2}, {"rcsm", 2},
                                                       {"relief", 3}, {"qdm", 3}, {"qdmhb", 4}};
  double cost = 1;
  for (std::size_t i = 0; i < spec.axes.size(); ++i) {
    const StudyAxis& axis = spec.axes[i];
    const nlohmann::json& v = config.values[i];
    if (v.is_null()) continue;
    if (axis.kind == StudyAxis::Kind::Elevation) cost *= 1 + std::min(10.0, 1 / std::sin(number_or(v, 45) * 0.0174533));
    if (axis.kind != StudyAxis::Kind::Set) continue;
    if (v.is_string() && technique.count(v.get<std::string>())) cost *= technique.at(v.get<std::string>());
    const std::string& p = axis.pointer;
    if (v.is_number() && (p.ends_with("iterations") || p.ends_with("steps") || p.ends_with("samples")))
      cost *= 1 + std::max(0.0, v.get<double>()) / 16;
  }
  return cost;
}

// The baseline configuration of `config`: its values with the spec's baseline values put in.
StudyConfig baseline_config(const StudySpec& spec, const StudyConfig& config) {
  StudyConfig base = config;
  for (std::size_t i = 0; i < spec.axes.size(); ++i) {
    const auto it = spec.baseline.find(spec.axes[i].name);
    if (it != spec.baseline.end()) base.values[i] = it->second;
  }
  return base;
}

// The base scene's document, read once; each configuration is its overrides applied in memory, loaded on the
// configuration's threads (0: every core).
class SceneSource {
public:
  SceneSource(const std::filesystem::path& file, int threads)
      : file_(file), document_(scene_detail::parse_json_file(file, InputKind::Scene)), threads_(threads) {}
  SceneDesc load(const std::vector<SceneOverride>& overrides) const {
    return load_scene_json(document_, file_, file_.parent_path(), overrides, 0, threads_);
  }

private:
  std::filesystem::path file_;
  nlohmann::json document_;
  int threads_;
};

// One configuration's row: everything deterministic from a frame without AOVs (timing) and one with the error
// AOVs, against the baseline's colour. The untimed frames remember the exact reference's hits: a configuration's
// error AOVs and reference image trace the same rays, and so do configurations that differ only in sampling.
class Measurer {
public:
  Measurer(const StudySpec& spec, const SceneSource& source, int threads)
      : spec_(spec), source_(source), write_{.threads = threads}, timing_(with_threads(threads)),
        measuring_(with_threads(threads, std::make_shared<ReferenceMemo>())), baseline_renderer_(with_threads(threads)) {}

  // The colour of the baseline configuration for `config`: its values with the spec's baseline values put in
  // (the other axes stay, so each row is compared at its own angle, depth, ...). Rendered once per distinct one.
  const Image& baseline_for(const StudyConfig& config, const std::array<double, 9>& camera) {
    const StudyConfig base = baseline_config(spec_, config);
    const std::string key = nlohmann::json(base.values).dump();
    auto found = baselines_.find(key);
    if (found != baselines_.end()) return found->second;
    baseline_renderer_.set_scene(source_.load(study_overrides(spec_, base, camera)), {});
    const Frame& frame = baseline_renderer_.draw();
    Image image(frame.width, frame.height, 3);
    std::copy(frame.color.begin(), frame.color.end(), image.texels.begin());
    return baselines_.emplace(key, std::move(image)).first->second;
  }

  const Renderer& renderer() const { return timing_; }
  std::size_t asset_builds() const { return asset_builds_; }  // configurations whose timed scene built anything

  StudyRow measure(const StudyConfig& config, const SceneDesc& scene, const std::filesystem::path& images,
                   const std::array<double, 9>& camera) {
    StudyRow row;
    row["index"] = config.index;
    nlohmann::ordered_json values = nlohmann::ordered_json::object();
    for (std::size_t i = 0; i < spec_.axes.size(); ++i) values[spec_.axes[i].name] = config.values[i];
    row["config"] = values;
    nlohmann::ordered_json det = nlohmann::ordered_json::object(), timing = nlohmann::ordered_json::object();

    // Timed frames never record texture fetches: the cache is measured on its own frame below.
    SceneDesc timed = scene;
    timed.texture_cache.enabled = false;
    timing_.set_scene(timed, {});
    std::vector<double> draws;
    double prepare_ms = 0;
    for (int f = 0; f < spec_.warmup + spec_.frames; ++f) {
      const Frame& frame = timing_.draw();
      if (f == 0) {
        prepare_ms = frame.stats.plan_ms + frame.stats.prepare_ms;
        if (frame.stats.items_built > 0) ++asset_builds_;
      }
      if (f >= spec_.warmup) draws.push_back(frame.stats.draw_ms());
    }
    const Frame& frame = timing_.frame();
    const RenderStats& s = frame.stats;
    det["hash"] = canonical_hash(frame.width, frame.height, 3, frame.color);
    std::uint64_t nonfinite = 0;
    for (float v : frame.color) nonfinite += std::isfinite(v) ? 0 : 1;
    det["nonfinite"] = nonfinite;
    det["pixels_shaded"] = s.pixels_shaded;
    if (spec_.wants(StudyMetric::Iterations)) {
      det["iterations_mean"] = s.iterations_mean;
      det["iterations_p99"] = s.iterations_p99;
      det["iterations_max"] = s.iterations_max;
      det["lane_utilisation"] = s.lane_utilisation;
    }
    if (spec_.wants(StudyMetric::ImageDiff) && !spec_.baseline.empty()) {
      Image color(frame.width, frame.height, 3);
      std::copy(frame.color.begin(), frame.color.end(), color.texels.begin());
      Tolerance t;
      t.max_abs = spec_.diff_threshold;
      const Comparison c = compare_images(color, baseline_for(config, camera), t);
      det["diff_rmse"] = c.rmse;
      det["diff_max"] = std::isfinite(c.max_abs) ? nlohmann::json(c.max_abs) : nlohmann::json("inf");
      det["diff_pixels"] = c.pixels_over;
    }
    if (keeps("image")) write_frame(frame, images / (std::to_string(config.index) + ".png"), write_);
    if (spec_.wants(StudyMetric::Time)) {
      std::vector<double> sorted = draws;
      std::sort(sorted.begin(), sorted.end());
      timing["draw_ms_median"] = sorted[sorted.size() / 2];
      timing["draw_ms_min"] = sorted.front();
      timing["prepare_ms"] = prepare_ms;
    }

    const bool cache = spec_.wants(StudyMetric::Cache) || scene.texture_cache.enabled || keeps("cache_misses");
    if (spec_.wants(StudyMetric::Error) || !keep_aovs().empty() || cache) measure_frame(config, scene, cache, images, det);
    if (keeps("reference")) write_reference(config, scene, images);
    row["deterministic"] = det;
    row["timing"] = timing;
    return row;
  }

private:
  bool keeps(const char* what) const { return std::find(spec_.keep.begin(), spec_.keep.end(), what) != spec_.keep.end(); }

  std::vector<Aov> keep_aovs() const {
    std::vector<Aov> aovs;
    for (const std::string& k : spec_.keep)
      if (const std::optional<Aov> aov = parse_aov(k)) aovs.push_back(*aov);
    return aovs;
  }

  // The configuration's image at the exact reference's hits (every displaced material with exact_hits).
  void write_reference(const StudyConfig& config, SceneDesc scene, const std::filesystem::path& images) {
    for (MaterialDesc& material : scene.materials) material.technique.exact_hits = true;
    measuring_.set_scene(scene, {});
    write_frame(measuring_.draw(), images / (std::to_string(config.index) + ".reference.png"), write_);
  }

  // One untimed frame for what is not time: the error AOVs, the kept AOVs and the texture cache.
  void measure_frame(const StudyConfig& config, SceneDesc scene, bool cache, const std::filesystem::path& images,
                     nlohmann::ordered_json& det) {
    std::vector<Aov> aovs;
    if (spec_.wants(StudyMetric::Error)) aovs = {Aov::Depth, Aov::ErrorTexels, Aov::Missed};
    for (Aov a : keep_aovs())
      if (std::find(aovs.begin(), aovs.end(), a) == aovs.end()) aovs.push_back(a);
    scene.texture_cache.enabled = cache;
    measuring_.set_scene(scene, aovs);
    const Frame& frame = measuring_.draw();
    for (Aov a : keep_aovs())
      write_aov(frame, a, images / (std::to_string(config.index) + "." + aov_name(a) + ".exr"), write_);
    if (cache) {
      const TextureCacheStats& c = frame.stats.texture_cache;
      det["cache_accesses_per_pixel"] = c.accesses_per_pixel;
      det["cache_miss_ratio"] = c.miss_ratio;
      det["cache_misses_per_pixel"] = c.misses_per_pixel;
      det["cache_bytes_per_pixel"] = c.bytes_per_pixel;
      det["cache_footprint_bytes"] = c.footprint_bytes;
    }
    if (!spec_.wants(StudyMetric::Error)) return;
    const auto plane = [&](Aov a) -> const PixelBuffer& {
      for (const AovImage& image : frame.aovs)
        if (image.aov == a) return image.pixels;
      throw Error("study", "AOV not rendered");
    };
    const PixelBuffer &depth = plane(Aov::Depth), &error = plane(Aov::ErrorTexels), &missed = plane(Aov::Missed);
    std::vector<float> errors;
    double sum = 0, missed_sum = 0;
    std::uint64_t nonfinite = 0;
    for (std::size_t p = 0; p < depth.size(); ++p) {
      if (!(depth[p] > 0)) continue;  // not covered
      if (!std::isfinite(error[p])) {
        ++nonfinite;
        continue;
      }
      errors.push_back(error[p]);
      sum += error[p];
      missed_sum += missed[p];
    }
    det["covered_pixels"] = errors.size();
    det["error_nonfinite"] = nonfinite;
    if (errors.empty()) return;
    const std::size_t k = std::min(errors.size() - 1, std::size_t(std::ceil(0.99 * double(errors.size()))) - 1);
    std::nth_element(errors.begin(), errors.begin() + std::ptrdiff_t(k), errors.end());
    det["error_mean"] = sum / double(errors.size());
    det["error_p99"] = errors[k];
    det["error_max"] = *std::max_element(errors.begin(), errors.end());
    det["missed_fraction"] = missed_sum / double(errors.size());
  }

  const StudySpec& spec_;
  const SceneSource& source_;
  WriteOptions write_;  // the kept images written on the configuration's threads, as it is drawn
  Renderer timing_, measuring_, baseline_renderer_;
  std::size_t asset_builds_ = 0;
  std::map<std::string, Image> baselines_;
};

std::array<double, 9> base_camera(const StudySpec& spec, const SceneSource& source) {
  const SceneDesc base = source.load(spec.overrides);
  const CameraDesc& c = base.camera;
  return {c.position.x, c.position.y, c.position.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y, c.up.z};
}

nlohmann::ordered_json make_header(const StudySpec& spec, std::size_t configurations, StudyShard shard, int threads,
                                   const char* isa) {
  nlohmann::ordered_json header;
  header["spec_hash"] = spec.hash;
  header["spec"] = nlohmann::ordered_json::parse(spec.document.dump());
  header["spec_file"] = spec.file.string();
  header["qdmr_version"] = version();
  header["bits_version"] = kBitsVersion;
  header["configurations"] = configurations;
  header["shard"] = {shard.index, shard.count};
  std::vector<std::string> axes;
  for (const StudyAxis& a : spec.axes) axes.push_back(a.name);
  header["axes"] = axes;
  header["group_by"] = spec.group_axis;
  header["machine"] = {{"cpu", cpu_model()}, {"isa", isa}, {"threads", threads},
                       {"cores", std::thread::hardware_concurrency()}};
  return header;
}

// Appends one line with one write(): a killed process leaves whole lines (and a crash of the machine at most one
// torn last line, which --resume drops). A write that fails part way (a full disk) is cut off again, so the file
// keeps whole lines. No fsync: it would cost more than drawing a small configuration. Only the holder of the
// folder's lock appends.
void append_line(const std::filesystem::path& file, const std::string& line) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw FileError(file.string(), std::string("cannot open for appending: ") + std::strerror(errno));
  struct stat before{};
  const bool sized = ::fstat(fd, &before) == 0;
  const std::string text = line + "\n";
  const ssize_t written = ::write(fd, text.data(), text.size());
  const int error = errno;
  if (written != ssize_t(text.size()) && written > 0 && sized) static_cast<void>(::ftruncate(fd, before.st_size));
  ::close(fd);
  if (written != ssize_t(text.size()))
    throw FileError(file.string(), std::string("cannot append a row: ") +
                                   (written < 0 ? std::strerror(error) : "short write (disk full?)"));
}

// The rows an earlier run left in `file` (none when it does not exist: a run killed before its first row), with a
// torn last line (a killed write) cut off the file, so that appending continues after the last whole row.
std::vector<StudyRow> rows_to_resume(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return {};
  std::uint64_t valid = 0;
  std::vector<StudyRow> rows = read_study_rows(file, &valid);
  if (std::filesystem::file_size(file, ec) != valid || ec) {
    std::filesystem::resize_file(file, valid, ec);
    if (ec) throw FileError(file.string(), "cannot cut its half-written last row: " + ec.message());
  }
  return rows;
}

// The configurations in the order that re-prepares least: grouped by what their plan builds (the items of the
// timed frame's plan: textures, meshes, derived data by content key), groups in the order of their first
// configuration, indices ascending within a group. A renderer keeps the last scene's items, so each asset set is
// then built once per renderer instead of at every change of an axis that alters it.
std::vector<std::size_t> order_for_reuse(const StudySpec& spec, const std::vector<StudyConfig>& configs,
                                         const std::vector<std::size_t>& pending, const SceneSource& source,
                                         const std::array<double, 9>& camera) {
  std::map<std::string, std::size_t> group_of;  // asset set -> its group's rank
  std::vector<std::pair<std::size_t, std::size_t>> ranked;  // (group, index)
  for (std::size_t index : pending) {
    const FramePlan plan = plan_frame(source.load(study_overrides(spec, configs[index], camera)));
    std::vector<std::string> items = plan.items();
    std::sort(items.begin(), items.end());
    std::string set;
    for (const std::string& item : items) set += item + "\n";
    const auto found = group_of.emplace(set, group_of.size()).first;
    ranked.emplace_back(found->second, index);
  }
  std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::size_t> order;
  for (const auto& [group, index] : ranked) order.push_back(index);
  return order;
}

// What one measurer computes once for every configuration with the same key, beyond the timed frame's asset set:
// the exact reference (the ReferenceMemo remembers hits by field content, ray and depth) is traced on the fields
// of the error frame's plan (layer 0's stored heights, a blend's combined surface), from the camera, at the frame's
// size; those fields' heights are built once per renderer. The depth is left out: configurations that differ only
// in it still share the heights.
std::string share_key(const StudySpec& spec, const StudyConfig& config, const SceneSource& source,
                      const std::array<double, 9>& camera) {
  PlanOptions options;
  options.aovs = {Aov::ErrorTexels};
  const FramePlan plan = plan_frame(source.load(study_overrides(spec, config, camera)), options);
  std::set<std::string> fields;
  for (const DerivedPlan& d : plan.derived) {
    if (d.kind == DerivedKind::CombinedSurface) fields.insert(d.key);
    if (d.kind != DerivedKind::HeightField) continue;
    // Level 0 of the heights and the address mode: the field's content, whichever mip chain its texture has.
    const std::string& heights = plan.textures[std::size_t(d.texture)].key;
    fields.insert("field " + heights.substr(0, heights.rfind("|mip")) + d.key.substr(d.key.rfind("|address=")));
  }
  const CameraDesc& c = plan.scene.camera;
  std::ostringstream key;
  key << std::hexfloat << plan.width << "x" << plan.height << " camera " << c.position.x << "," << c.position.y << ","
      << c.position.z << " " << c.target.x << "," << c.target.y << "," << c.target.z << " " << c.up.x << "," << c.up.y
      << "," << c.up.z << " " << c.fov_y_deg;
  for (const std::string& field : fields) key << "\n" << field;
  return key.str();
}

}  // namespace

std::vector<std::size_t> shard_configurations(const StudySpec& spec, const std::vector<StudyConfig>& configs,
                                              StudyShard shard) {
  // Longest first onto the least loaded shard (ties: the lower index), deterministic.
  std::vector<std::pair<double, std::size_t>> by_cost;
  for (const StudyConfig& c : configs) by_cost.emplace_back(estimated_cost(spec, c), c.index);
  std::stable_sort(by_cost.begin(), by_cost.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<double> load(std::size_t(shard.count), 0.0);
  std::vector<std::size_t> mine;
  for (const auto& [cost, index] : by_cost) {
    const std::size_t target = std::size_t(std::min_element(load.begin(), load.end()) - load.begin());
    load[target] += cost;
    if (int(target) + 1 == shard.index) mine.push_back(index);
  }
  std::sort(mine.begin(), mine.end());
  return mine;
}

struct StudyMeasurer::State {
  State(const StudySpec& s, int threads, bool force)
      : spec(s), configs(expand_study(spec, force)), source(spec.scene, threads), camera(base_camera(spec, source)),
        measurer(spec, source, threads) {}
  StudySpec spec;
  std::vector<StudyConfig> configs;
  SceneSource source;
  std::array<double, 9> camera;
  Measurer measurer;  // refers to spec and source above
};

StudyMeasurer::StudyMeasurer(const StudySpec& spec, int threads, bool force)
    : state_(std::make_unique<State>(spec, threads, force)) {}
StudyMeasurer::~StudyMeasurer() = default;

std::size_t StudyMeasurer::configurations() const { return state_->configs.size(); }
const std::string& StudyMeasurer::spec_hash() const { return state_->spec.hash; }
std::size_t StudyMeasurer::asset_builds() const { return state_->measurer.asset_builds(); }
int StudyMeasurer::threads() const { return state_->measurer.renderer().threads(); }
const char* StudyMeasurer::isa() const { return isa_name(state_->measurer.renderer().isa()); }

StudyRow StudyMeasurer::measure(std::size_t index, const std::filesystem::path& out) {
  State& s = *state_;
  if (index >= s.configs.size())
    throw Error("study", "configuration " + std::to_string(index) + " does not exist (the spec has " +
                             std::to_string(s.configs.size()) + ")");
  const StudyConfig& config = s.configs[index];
  const SceneDesc scene = s.source.load(study_overrides(s.spec, config, s.camera));
  try {
    return s.measurer.measure(config, scene, out / "images", s.camera);
  } catch (const Error& e) {
    throw e.within(study_label(s.spec, config));
  }
}

std::vector<std::vector<std::size_t>> StudyMeasurer::share_groups(const std::vector<std::size_t>& pending) const {
  const State& s = *state_;
  for (std::size_t index : pending)
    if (index >= s.configs.size())
      throw Error("study", "configuration " + std::to_string(index) + " does not exist (the spec has " +
                               std::to_string(s.configs.size()) + ")");
  const std::vector<std::size_t> order = reuse_order(pending);
  std::map<std::string, std::size_t> group_of;
  std::vector<std::vector<std::size_t>> groups;
  for (std::size_t index : order) {
    std::string key;
    try {
      key = share_key(s.spec, s.configs[index], s.source, s.camera);
    } catch (const Error&) {
      // A configuration that cannot be planned shares nothing: its own error is reported when it is drawn.
      key = "unplanned " + std::to_string(index);
    }
    const auto found = group_of.emplace(key, groups.size()).first;
    if (found->second == groups.size()) groups.emplace_back();
    groups[found->second].push_back(index);
  }
  return groups;
}

double StudyMeasurer::estimated_cost(std::size_t index) const {
  const State& s = *state_;
  if (index >= s.configs.size())
    throw Error("study", "configuration " + std::to_string(index) + " does not exist (the spec has " +
                             std::to_string(s.configs.size()) + ")");
  return qdmr::estimated_cost(s.spec, s.configs[index]);
}

std::vector<std::size_t> StudyMeasurer::reuse_order(const std::vector<std::size_t>& pending) const {
  try {
    return order_for_reuse(state_->spec, state_->configs, pending, state_->source, state_->camera);
  } catch (const Error&) {
    // A configuration that cannot be planned keeps the index order: its own error is reported when it is drawn.
    return pending;
  }
}

struct StudyFolder::State {
  State(const std::filesystem::path& folder, bool made) : out(folder), created(made), lock(folder, "study", made) {}
  std::filesystem::path out;
  bool created;
  FolderLock lock;  // two runs on one folder would interleave their rows
  nlohmann::ordered_json header;
  std::vector<StudyRow> rows;
  std::set<std::size_t> done;
  std::size_t resumed = 0;
  double earlier_seconds = 0;  // the wall time of the earlier runs of a resumed study
  Clock::time_point start = Clock::now(), last_write = Clock::now();

  nlohmann::ordered_json results_header() const {
    nlohmann::ordered_json h = header;
    h["run"] = {{"wall_seconds", earlier_seconds + std::chrono::duration<double>(Clock::now() - start).count()},
                {"shards", 1}};
    return h;
  }
};

StudyFolder::StudyFolder(const StudySpec& spec, const std::filesystem::path& out, const StudyFolderInfo& info)
    : state_([&] {
        std::error_code made;
        const bool created = std::filesystem::create_directories(out, made);
        if (made) throw FileError(out.string(), "cannot create the results folder: " + made.message());
        return std::make_unique<State>(out, created);
      }()) {
  State& s = *state_;
  s.header = make_header(spec, info.configurations, info.shard, info.threads, info.isa.c_str());
  s.header["machine"]["jobs"] = info.jobs;
  const std::filesystem::path rows_file = out / "rows.jsonl", header_file = out / "study.json";
  if (std::filesystem::exists(rows_file) || std::filesystem::exists(header_file)) {
    if (!info.resume)
      throw Error(out.string(), "holds the results of a study already: add --resume to continue it, or choose another -o");
    nlohmann::ordered_json old;
    try {
      old = nlohmann::ordered_json::parse(std::ifstream(header_file));
    } catch (const nlohmann::json::exception&) {
      throw FileError(header_file.string(), "unreadable: cannot resume (remove the folder to start again)");
    }
    if (old.value("spec_hash", "") != spec.hash)
      throw Error(out.string(), "holds results of another spec (" + old.value("spec_hash", std::string("?")) + ", this one is " +
                                    spec.hash + "): --resume continues the same spec only");
    if (old["shard"] != s.header["shard"])
      throw Error(out.string(), "holds shard " + old["shard"].dump() + ", not " + s.header["shard"].dump());
    s.rows = rows_to_resume(rows_file);
  }
  write_text_file(header_file, s.header.dump(2) + "\n");
  if (!spec.keep.empty()) std::filesystem::create_directories(out / "images");
  for (const StudyRow& r : s.rows) s.done.insert(r["index"].get<std::size_t>());
  s.resumed = s.done.size();
  if (!s.rows.empty()) {
    try {
      s.earlier_seconds = nlohmann::json::parse(std::ifstream(out / "results.json"))["run"].value("wall_seconds", 0.0);
    } catch (const nlohmann::json::exception&) {
    }
  }
}

StudyFolder::~StudyFolder() = default;

const std::set<std::size_t>& StudyFolder::done() const { return state_->done; }
std::size_t StudyFolder::resumed() const { return state_->resumed; }

void StudyFolder::append(StudyRow row) {
  State& s = *state_;
  const std::size_t index = row["index"].get<std::size_t>();
  if (s.done.count(index)) throw Error(s.out.string(), "configuration " + std::to_string(index) + " has a row already");
  append_line(s.out / "rows.jsonl", row.dump());
  s.done.insert(index);
  s.rows.push_back(std::move(row));
  if (Clock::now() - s.last_write > std::chrono::seconds(2)) {
    write_study_results(s.results_header(), s.rows, s.out);
    s.last_write = Clock::now();
  }
}

void StudyFolder::finish() { write_study_results(state_->results_header(), state_->rows, state_->out); }

StudyRun run_study(const StudySpec& spec, const std::filesystem::path& out, const StudyOptions& options) {
  const auto start = Clock::now();
  if (options.shard.count < 1 || options.shard.index < 1 || options.shard.index > options.shard.count)
    throw Error("--shard", "expected I/N with 1 <= I <= N");
  const std::vector<StudyConfig> configs = expand_study(spec, options.force);
  const std::vector<std::size_t> mine = shard_configurations(spec, configs, options.shard);

  // --jobs: that many configurations at once, each measured by its own renderers with threads / jobs workers
  // (every core / jobs by default). Rows are the same; the timing columns then include the contention.
  const int jobs = std::max(1, options.jobs);
  int threads_per_job = options.threads;
  if (jobs > 1 && threads_per_job == 0)
    threads_per_job = std::max(1, int(std::thread::hardware_concurrency()) / jobs);
  std::vector<std::unique_ptr<StudyMeasurer>> measurers;
  for (int j = 0; j < jobs; ++j)
    measurers.push_back(std::make_unique<StudyMeasurer>(spec, threads_per_job, options.force));
  StudyFolderInfo info;
  info.configurations = configs.size();
  info.shard = options.shard;
  info.resume = options.resume;
  info.threads = measurers[0]->threads();
  info.isa = measurers[0]->isa();
  info.jobs = jobs;
  StudyFolder folder(spec, out, info);

  StudyRun run;
  run.total = mine.size();
  run.resumed = folder.resumed();
  std::size_t finished = folder.resumed();
  // Workers take the next pending configuration in order; everything shared (rows, files, progress) is updated
  // under the lock, the drawing is not. The first error stops every worker and is thrown after they finish.
  std::vector<std::size_t> pending;
  for (std::size_t index : mine)
    if (!folder.done().count(index)) pending.push_back(index);
  pending = measurers[0]->reuse_order(pending);
  std::mutex lock;
  std::size_t next = 0;
  std::exception_ptr failure;
  const auto work = [&](StudyMeasurer& measurer) {
    for (;;) {
      std::size_t index = 0;
      {
        const std::lock_guard<std::mutex> guard(lock);
        if (failure || run.stopped || next == pending.size()) return;
        if (options.stop_requested && options.stop_requested()) {
          run.stopped = true;
          return;
        }
        index = pending[next++];
      }
      try {
        StudyRow row = measurer.measure(index, out);
        const std::lock_guard<std::mutex> guard(lock);
        folder.append(std::move(row));
        ++run.rendered;
        ++finished;
        if (options.progress) options.progress(finished, mine.size(), study_label(spec, configs[index]));
      } catch (const Interrupted&) {  // a long bake stopped by Ctrl-C: the rows so far are the result
        const std::lock_guard<std::mutex> guard(lock);
        run.stopped = true;
        return;
      } catch (...) {
        const std::lock_guard<std::mutex> guard(lock);
        if (!failure) failure = std::current_exception();
        return;
      }
    }
  };
  if (jobs == 1) {
    work(*measurers[0]);
  } else {
    std::vector<std::thread> workers;
    for (auto& m : measurers) workers.emplace_back(work, std::ref(*m));
    for (std::thread& w : workers) w.join();
  }
  if (failure) std::rethrow_exception(failure);
  for (const auto& m : measurers) run.asset_builds += m->asset_builds();
  folder.finish();
  run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return run;
}

void merge_studies(const std::vector<std::filesystem::path>& shards, const std::filesystem::path& out) {
  if (shards.empty()) throw Error("study merge", "no shard folders given");
  nlohmann::ordered_json header;
  std::map<int, std::filesystem::path> seen;
  std::vector<StudyRow> rows;
  int count = 0;
  double wall_seconds = 0, longest_shard = 0;
  for (const std::filesystem::path& folder : shards) {
    const std::filesystem::path file = folder / "study.json";
    nlohmann::ordered_json h;
    try {
      h = nlohmann::ordered_json::parse(std::ifstream(file));
    } catch (const nlohmann::json::exception&) {
      throw FileError(file.string(), "missing or unreadable: not a study folder");
    }
    if (header.is_null()) {
      header = h;
      count = h["shard"][1].get<int>();
    } else if (h["spec_hash"] != header["spec_hash"]) {
      throw Error(folder.string(), "is a shard of another spec (" + h["spec_hash"].get<std::string>() + ", not " +
                                       header["spec_hash"].get<std::string>() + ")");
    }
    const int index = h["shard"][0].get<int>();
    if (h["shard"][1].get<int>() != count)
      throw Error(folder.string(), "is shard " + std::to_string(index) + " of " + h["shard"][1].dump() + ", the others are of " + std::to_string(count));
    if (seen.count(index)) throw Error(folder.string(), "is shard " + std::to_string(index) + " again (also " + seen[index].string() + ")");
    seen[index] = folder;
    for (StudyRow& r : read_study_rows(folder / "rows.jsonl")) rows.push_back(std::move(r));
    try {
      const nlohmann::json run = nlohmann::json::parse(std::ifstream(folder / "results.json"))["run"];
      wall_seconds += run.value("wall_seconds", 0.0);
      longest_shard = std::max(longest_shard, run.value("wall_seconds", 0.0));
    } catch (const nlohmann::json::exception&) {
    }
  }
  for (int i = 1; i <= count; ++i)
    if (!seen.count(i)) throw Error("study merge", "shard " + std::to_string(i) + " of " + std::to_string(count) + " is missing");
  const std::size_t total = header["configurations"].get<std::size_t>();
  std::vector<int> present(total, 0);
  for (const StudyRow& r : rows) {
    const std::size_t index = r["index"].get<std::size_t>();
    if (index >= total || present[index]++) throw Error("study merge", "configuration " + std::to_string(index) + " is in two shards");
  }
  std::size_t missing = 0;
  for (int p : present) missing += p == 0 ? 1 : 0;
  if (missing) throw Error("study merge", std::to_string(missing) + " configuration(s) have no row: resume the unfinished shards first");
  header["shard"] = {1, 1};
  std::error_code made;
  const bool created = std::filesystem::create_directories(out, made);
  if (made) throw FileError(out.string(), "cannot create the merged folder: " + made.message());
  const FolderLock lock_folder(out, "study merge", created);
  write_text_file(out / "study.json", header.dump(2) + "\n");
  std::sort(rows.begin(), rows.end(),
            [](const StudyRow& a, const StudyRow& b) { return a["index"].get<std::size_t>() < b["index"].get<std::size_t>(); });
  std::string lines;
  for (const StudyRow& r : rows) lines += r.dump() + "\n";
  write_text_file(out / "rows.jsonl", lines);
  // The kept files of every shard (named by configuration index, so they never collide): hard links where the
  // folders share a file system, copies elsewhere.
  for (const std::filesystem::path& folder : shards) {
    std::error_code error;
    if (!std::filesystem::is_directory(folder / "images", error)) continue;
    std::filesystem::create_directories(out / "images");
    for (const auto& entry : std::filesystem::directory_iterator(folder / "images")) {
      const std::filesystem::path target = out / "images" / entry.path().filename();
      std::filesystem::remove(target, error);
      std::filesystem::create_hard_link(entry.path(), target, error);
      if (error) copy_file_atomically(entry.path(), target);
    }
  }
  header["run"] = {{"wall_seconds", wall_seconds}, {"shards", count}, {"longest_shard_seconds", longest_shard}};
  write_study_results(header, rows, out);
}

}  // namespace qdmr
