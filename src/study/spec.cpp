#include "qdmr/study/spec.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "core/sha1.hpp"
#include "file/input_file.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "scene/reader.hpp"

namespace qdmr {
namespace {

using scene_detail::Object;
using scene_detail::Value;

// {"from": 1, "to": 89, "steps": 30, "scale": "log", "integer": false}: `steps` values from `from` to `to`.
std::vector<nlohmann::json> read_range(const Value& value) {
  const Object object(value, {"from", "to", "steps", "scale", "integer"});
  const double from = object.required("from").number(), to = object.required("to").number();
  const int steps = int(object.required("steps").integer(1, 100000));
  bool log = false;
  if (auto v = object.find("scale")) log = v->choice<bool>({{"linear", false}, {"log", true}});
  const bool integer = object.find("integer") ? object.find("integer")->boolean() : false;
  if (log) value.require(from > 0 && to > 0, "a log range needs from and to above 0");
  std::vector<nlohmann::json> values;
  for (int k = 0; k < steps; ++k) {
    const double t = steps == 1 ? 0.0 : double(k) / double(steps - 1);
    double v = log ? from * std::pow(to / from, t) : from + (to - from) * t;
    if (k == steps - 1) v = to;  // exact end points
    if (integer) {
      const auto i = static_cast<std::int64_t>(std::llround(v));
      if (values.empty() || values.back().get<std::int64_t>() != i) values.emplace_back(i);
    } else {
      values.emplace_back(v);
    }
  }
  return values;
}

StudyAxis read_axis(const Value& value) {
  const Object object(value, {"name", "path", "camera", "values", "range"});
  StudyAxis axis;
  const Value name = object.required("name");
  axis.name = name.string();
  name.require(!axis.name.empty() && axis.name.size() <= 64 &&
                   std::all_of(axis.name.begin(), axis.name.end(),
                               [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }),
               "an axis name is 1 to 64 letters, digits or '_' (it is a column name)");
  const auto path = object.find("path");
  const auto camera = object.find("camera");
  value.require(bool(path) != bool(camera), "an axis has either \"path\" (a --set JSON pointer) or \"camera\" "
                                            "(\"elevation\" or \"azimuth\", degrees)");
  if (path) {
    axis.pointer = path->string();
    try {
      parse_override(axis.pointer + "=0");
    } catch (const Error& e) {
      path->fail(e.what());
    }
  } else {
    axis.kind = camera->choice<StudyAxis::Kind>({{"elevation", StudyAxis::Kind::Elevation},
                                                 {"azimuth", StudyAxis::Kind::Azimuth}});
  }
  const auto values = object.find("values");
  const auto range = object.find("range");
  value.require(bool(values) != bool(range), "an axis has either \"values\" (a list) or \"range\"");
  if (values) {
    for (const Value& v : values->array()) {
      v.require(!v.json().is_null() && !v.json().is_object(), "a value is a number, string, boolean or array");
      if (axis.kind != StudyAxis::Kind::Set) v.number();
      axis.values.push_back(v.json());
    }
  } else {
    axis.values = read_range(*range);
  }
  (values ? *values : *range).require(!axis.values.empty(), "an axis needs at least one value");
  if (axis.kind == StudyAxis::Kind::Elevation)
    for (std::size_t i = 0; i < axis.values.size(); ++i)
      (values ? values->element(i) : *range).require(axis.values[i].get<double>() > 0 && axis.values[i].get<double>() <= 90,
                                                     "an elevation is above 0 and at most 90 degrees");
  return axis;
}

std::size_t axis_index(const StudySpec& spec, const Value& where, const std::string& name) {
  for (std::size_t i = 0; i < spec.axes.size(); ++i)
    if (spec.axes[i].name == name) return i;
  std::vector<std::string> names;
  for (const StudyAxis& a : spec.axes) names.push_back(a.name);
  where.fail("no axis named '" + scene_detail::shorten(name) + "'" + scene_detail::suggestion(name, names, "axes are"));
}

// An object of axis names and one value of each (a baseline, a budget's reference configuration).
std::map<std::string, nlohmann::json> axis_values(const StudySpec& spec, const Value& value) {
  value.expect_type(nlohmann::json::value_t::object, "an object of axis names and values");
  std::map<std::string, nlohmann::json> values;
  for (const auto& item : value.json().items()) {
    const Value entry = *value.member(item.key());
    const StudyAxis& axis = spec.axes[axis_index(spec, entry, item.key())];
    entry.require(std::find(axis.values.begin(), axis.values.end(), item.value()) != axis.values.end(),
                  "not one of the axis's values");
    values[item.key()] = item.value();
  }
  return values;
}

std::map<std::string, std::vector<nlohmann::json>> read_conditions(const StudySpec& spec, const Value& value) {
  value.expect_type(nlohmann::json::value_t::object, "an object of axis names and values, e.g. {\"technique\": [\"pom\"]}");
  std::map<std::string, std::vector<nlohmann::json>> when;
  for (const auto& item : value.json().items()) {
    const Value v = *value.member(item.key());
    axis_index(spec, v, item.key());
    if (v.json().is_array())
      when[item.key()] = std::vector<nlohmann::json>(v.json().begin(), v.json().end());
    else
      when[item.key()] = {v.json()};
  }
  value.require(!when.empty(), "a condition needs at least one axis");
  return when;
}

bool matches(const StudySpec& spec, const std::vector<nlohmann::json>& values,
             const std::map<std::string, std::vector<nlohmann::json>>& when) {
  for (const auto& [name, accepted] : when) {
    std::size_t i = 0;
    while (spec.axes[i].name != name) ++i;
    if (std::find(accepted.begin(), accepted.end(), values[i]) == accepted.end()) return false;
  }
  return true;
}

std::string json_text(const nlohmann::json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

}  // namespace

bool StudySpec::wants(StudyMetric m) const { return std::find(metrics.begin(), metrics.end(), m) != metrics.end(); }

std::string study_label(const StudySpec& spec, const StudyConfig& config) {
  std::string out;
  for (std::size_t i = 0; i < spec.axes.size(); ++i)
    if (!config.values[i].is_null()) out += (out.empty() ? "" : " ") + spec.axes[i].name + "=" + json_text(config.values[i]);
  return out;
}

StudySpec read_study_spec(const std::filesystem::path& file) {
  return read_study_spec_json(scene_detail::parse_json_file(file, InputKind::StudySpec), file,
                              std::filesystem::absolute(file).parent_path());
}

StudySpec read_study_spec_json(const nlohmann::json& document, const std::filesystem::path& name,
                               const std::filesystem::path& base_dir) {
  StudySpec spec;
  spec.file = name;
  spec.document = document;
  const scene_detail::Context context{name.string(), base_dir};
  const Value root(context, spec.document, "");
  const Object object(root, {"scene", "set", "width", "height", "frames", "warmup", "axes", "zip", "rules",
                             "metrics", "baseline", "diff_threshold", "keep", "group_by", "max_configurations",
                             "budget"});
  spec.scene = object.required("scene").existing_file();
  if (auto v = object.find("set")) {
    v->expect_type(nlohmann::json::value_t::object, "an object of JSON pointers and values");
    for (const auto& item : v->json().items()) {
      try {
        spec.overrides.push_back(parse_override(item.key() + "=" + item.value().dump()));
      } catch (const Error& e) {
        v->member(item.key())->fail(e.what());
      }
    }
  }
  if (auto v = object.find("width")) spec.width = int(v->integer(1, limits::kMaxImageSide));
  if (auto v = object.find("height")) spec.height = int(v->integer(1, limits::kMaxImageSide));
  if (auto v = object.find("frames")) spec.frames = int(v->integer(1, 1000));
  if (auto v = object.find("warmup")) spec.warmup = int(v->integer(0, 1000));
  std::set<std::string> names;
  const Value axes = object.required("axes");
  for (const Value& item : axes.array()) {
    spec.axes.push_back(read_axis(item));
    if (!names.insert(spec.axes.back().name).second) item.member("name")->fail("axis name '" + spec.axes.back().name + "' is used twice");
  }
  axes.require(!spec.axes.empty(), "a study needs at least one axis");
  if (auto v = object.find("zip")) {
    std::set<std::string> zipped;
    for (const Value& group : v->array()) {
      std::vector<std::string> members;
      for (const Value& name : group.array()) {
        const std::size_t i = axis_index(spec, name, name.string());
        name.require(zipped.insert(spec.axes[i].name).second, "axis '" + spec.axes[i].name + "' is zipped twice");
        name.require(spec.axes[i].values.size() == spec.axes[axis_index(spec, group, group.element(0).string())].values.size(),
                     "zipped axes need the same number of values");
        members.push_back(spec.axes[i].name);
      }
      group.require(members.size() >= 2, "a zip joins at least two axes");
      spec.zips.push_back(members);
    }
  }
  if (auto v = object.find("rules")) {
    for (const Value& item : v->array()) {
      const Object rule(item, {"only_when", "drop_when", "axis"});
      StudyRule r;
      if (auto when = rule.find("only_when")) {
        r.kind = StudyRule::Kind::OnlyWhen;
        const Value axis = rule.required("axis");
        r.axis = spec.axes[axis_index(spec, axis, axis.string())].name;
        r.when = read_conditions(spec, *when);
      } else if (auto drop = rule.find("drop_when")) {
        item.require(!rule.find("axis"), "a drop_when rule has no \"axis\"");
        r.when = read_conditions(spec, *drop);
      } else {
        item.fail("a rule is {\"axis\": A, \"only_when\": {...}} or {\"drop_when\": {...}}");
      }
      spec.rules.push_back(std::move(r));
    }
  }
  spec.metrics = {StudyMetric::Time, StudyMetric::Iterations, StudyMetric::Error, StudyMetric::ImageDiff};
  if (auto v = object.find("metrics")) {
    spec.metrics.clear();
    for (const Value& item : v->array())
      spec.metrics.push_back(item.choice<StudyMetric>({{"time", StudyMetric::Time},
                                                        {"iterations", StudyMetric::Iterations},
                                                        {"error", StudyMetric::Error},
                                                        {"image_diff", StudyMetric::ImageDiff},
                                                        {"cache", StudyMetric::Cache}}));
    v->require(!spec.metrics.empty(), "expected at least one metric");
  }
  if (auto v = object.find("baseline")) {
    spec.baseline = axis_values(spec, *v);
  }
  if (auto v = object.find("diff_threshold")) spec.diff_threshold = v->non_negative();
  if (auto v = object.find("keep"))
    for (const Value& item : v->array()) {
      const std::string kind = item.choice<std::string>({{"image", "image"}, {"error_texels", "error_texels"},
                                                         {"iterations", "iterations"},
                                                         {"cache_misses", "cache_misses"},
                                                         {"reference", "reference"}});
      spec.keep.push_back(kind);
    }
  if (auto v = object.find("group_by")) {
    spec.group_axis = spec.axes[axis_index(spec, *v, v->string())].name;
  } else {
    for (const StudyAxis& a : spec.axes)
      if (a.name == "technique") spec.group_axis = a.name;
  }
  if (auto v = object.find("max_configurations")) spec.max_configurations = std::size_t(v->integer(1, 1000000));
  // The report's "within budget" table (docs/studies.md); nothing here depends on it but its validity.
  if (auto v = object.find("budget")) {
    const Object budget(*v, {"missed_fraction", "per", "relative_to"});
    budget.required("missed_fraction").number_in(0.0, 1.0);
    if (auto per = budget.find("per"))
      for (const Value& name : per->array()) axis_index(spec, name, name.string());
    if (auto to = budget.find("relative_to")) axis_values(spec, *to);
    v->require(spec.wants(StudyMetric::Time) && spec.wants(StudyMetric::Error),
               "a budget compares time at a missed fraction: it needs the time and error metrics");
  }

  // The hash of what decides the rows: the canonical JSON (sorted keys) of the document.
  const std::string canonical = spec.document.dump();
  spec.hash = "sha1:" + sha1_hex(canonical.data(), canonical.size());
  for (char& c : spec.hash) c = char(std::tolower(static_cast<unsigned char>(c)));
  return spec;
}

std::vector<StudyConfig> expand_study(const StudySpec& spec, bool force) {
  // Groups: each zip is one group; every other axis its own. The product runs over groups, last fastest.
  std::vector<std::vector<std::size_t>> groups;
  std::set<std::string> zipped;
  for (const auto& zip : spec.zips) zipped.insert(zip.begin(), zip.end());
  for (std::size_t i = 0; i < spec.axes.size(); ++i) {
    const std::string& name = spec.axes[i].name;
    if (!zipped.count(name)) {
      groups.push_back({i});
      continue;
    }
    for (const auto& zip : spec.zips)
      if (zip.front() == name) {
        std::vector<std::size_t> members;
        for (const std::string& m : zip)
          for (std::size_t k = 0; k < spec.axes.size(); ++k)
            if (spec.axes[k].name == m) members.push_back(k);
        groups.push_back(members);
      }
  }
  double product = 1;
  for (const auto& g : groups) product *= double(spec.axes[g.front()].values.size());
  if (product > double(spec.max_configurations) && !force)
    throw Error(spec.file.string() + ": /axes",
                "the axes make " + std::to_string(static_cast<long long>(product)) + " combinations, more than " +
                    std::to_string(spec.max_configurations) + " (max_configurations); run with --force to sweep them");

  std::vector<StudyConfig> configs;
  std::set<std::string> seen;
  std::vector<std::size_t> position(groups.size(), 0);
  while (true) {
    std::vector<nlohmann::json> values(spec.axes.size());
    for (std::size_t g = 0; g < groups.size(); ++g)
      for (std::size_t i : groups[g]) values[i] = spec.axes[i].values[position[g]];
    bool keep = true;
    for (const StudyRule& rule : spec.rules) {
      if (rule.kind == StudyRule::Kind::DropWhen && matches(spec, values, rule.when)) keep = false;
      if (rule.kind == StudyRule::Kind::OnlyWhen && !matches(spec, values, rule.when)) {
        std::size_t i = 0;
        while (spec.axes[i].name != rule.axis) ++i;
        if (values[i] != spec.axes[i].values.front()) keep = false;  // one configuration stands for all values
        else values[i] = nullptr;
      }
    }
    if (keep && seen.insert(nlohmann::json(values).dump()).second) configs.push_back({configs.size(), values});
    // The next combination, the last group fastest; done after the first group wraps.
    bool advanced = false;
    for (std::size_t g = groups.size(); g-- > 0 && !advanced;) {
      if (++position[g] < spec.axes[groups[g].front()].values.size()) advanced = true;
      else position[g] = 0;
    }
    if (!advanced) break;
  }
  if (configs.empty()) throw Error(spec.file.string() + ": /rules", "the rules drop every configuration");
  return configs;
}

std::vector<SceneOverride> study_overrides(const StudySpec& spec, const StudyConfig& config,
                                           const std::array<double, 9>& base) {
  std::vector<SceneOverride> overrides = spec.overrides;
  overrides.push_back({"/output/width", std::to_string(spec.width)});
  overrides.push_back({"/output/height", std::to_string(spec.height)});
  std::optional<double> elevation, azimuth;
  for (std::size_t i = 0; i < spec.axes.size(); ++i) {
    const nlohmann::json& v = config.values[i];
    if (v.is_null()) continue;
    switch (spec.axes[i].kind) {
      case StudyAxis::Kind::Set: overrides.push_back({spec.axes[i].pointer, v.dump()}); break;
      case StudyAxis::Kind::Elevation: elevation = v.get<double>(); break;
      case StudyAxis::Kind::Azimuth: azimuth = v.get<double>(); break;
    }
  }
  if (!elevation && !azimuth) return overrides;
  // Orbit the target at the base distance: elevation above the plane normal to `up`, azimuth around `up` from
  // the base camera's direction.
  const auto sub = [](const double* a, const double* b) { return std::array<double, 3>{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  const auto dot = [](const std::array<double, 3>& a, const std::array<double, 3>& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const auto norm = [&](std::array<double, 3> a) {
    const double l = std::sqrt(dot(a, a));
    return l > 0 ? std::array<double, 3>{a[0] / l, a[1] / l, a[2] / l} : a;
  };
  const std::array<double, 3> offset = sub(&base[0], &base[3]);
  const double distance = std::sqrt(dot(offset, offset));
  const std::array<double, 3> up = norm({base[6], base[7], base[8]});
  const std::array<double, 3> view = norm(offset);
  const double along = dot(view, up);
  std::array<double, 3> e1 = norm({view[0] - along * up[0], view[1] - along * up[1], view[2] - along * up[2]});
  if (dot(e1, e1) < 0.5) e1 = norm(std::abs(up[0]) < 0.9 ? std::array<double, 3>{1 - up[0] * up[0], -up[0] * up[1], -up[0] * up[2]}
                                                           : std::array<double, 3>{-up[1] * up[0], 1 - up[1] * up[1], -up[1] * up[2]});
  const std::array<double, 3> e2{up[1] * e1[2] - up[2] * e1[1], up[2] * e1[0] - up[0] * e1[2], up[0] * e1[1] - up[1] * e1[0]};
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  const double el = elevation ? *elevation * kDeg : std::asin(std::clamp(along, -1.0, 1.0));
  const double az = azimuth ? *azimuth * kDeg : 0.0;
  std::array<double, 3> position, camera_up = up;
  for (int k = 0; k < 3; ++k)
    position[std::size_t(k)] = base[3 + std::size_t(k)] +
                               distance * (std::cos(el) * (std::cos(az) * e1[std::size_t(k)] + std::sin(az) * e2[std::size_t(k)]) +
                                           std::sin(el) * up[std::size_t(k)]);
  if (std::cos(el) < 1e-4)  // looking straight down `up`: the image's up becomes the horizontal direction
    for (int k = 0; k < 3; ++k) camera_up[std::size_t(k)] = -(std::cos(az) * e1[std::size_t(k)] + std::sin(az) * e2[std::size_t(k)]);
  const auto vec = [](const std::array<double, 3>& v) {
    std::ostringstream out;
    out.precision(17);
    out << "[" << v[0] << "," << v[1] << "," << v[2] << "]";
    return out.str();
  };
  overrides.push_back({"/camera/position", vec(position)});
  overrides.push_back({"/camera/up", vec(camera_up)});
  return overrides;
}

}  // namespace qdmr
