#include "scene/reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <sstream>

#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "file/input_file.hpp"

namespace qdmr::scene_detail {

namespace {

// Optimal string alignment distance: Levenshtein plus adjacent transpositions ("widht" -> "width" is 1).
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const auto lower = [](char c) { return std::tolower(static_cast<unsigned char>(c)); };
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

}  // namespace

nlohmann::json parse_json_bounded(const std::string& text) {
  const nlohmann::json::parser_callback_t limit_depth = [](int depth, nlohmann::json::parse_event_t event,
                                                           nlohmann::json&) {
    if ((event == nlohmann::json::parse_event_t::object_start || event == nlohmann::json::parse_event_t::array_start) &&
        depth >= limits::kMaxJsonDepth)
      throw Error("nesting deeper than " + std::to_string(limits::kMaxJsonDepth) + " levels of arrays and objects");
    return true;
  };
  return nlohmann::json::parse(text, limit_depth);
}

nlohmann::json parse_json_file(const std::filesystem::path& file, InputKind kind, std::string* text) {
  const std::string name = file.string();
  std::string contents = read_input_file(file, name, kind);
  nlohmann::json document;
  try {
    document = parse_json_bounded(contents);
  } catch (const Error& e) {
    throw e.within(name);
  } catch (const nlohmann::json::exception& e) {
    // what() is "[json.exception.parse_error.N] parse error at line L, column C: ..."; keep from "parse error".
    // Other exceptions of the parser (a number too large for a double: out_of_range.406) lose the bracket.
    const std::string what = e.what();
    const auto start = what.find("parse error");
    const auto bracket = what.find("] ");
    throw Error(name, start != std::string::npos ? what.substr(start)
                      : bracket != std::string::npos ? what.substr(bracket + 2) : what);
  }
  if (text) *text = std::move(contents);
  return document;
}

std::string shorten(std::string_view text, std::size_t max) {
  if (text.size() <= max) return std::string(text);
  return std::string(text.substr(0, max)) + "...";
}

std::optional<std::string> closest_match(std::string_view word, const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  if (word.size() > 64) return best;  // no key is that long: no suggestion, and no quadratic table
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const auto& candidate : candidates) {
    const std::size_t distance = edit_distance(word, candidate);
    const bool prefix = word.size() >= 2 && (candidate.starts_with(word) || word.starts_with(candidate));
    const std::size_t tolerance = std::max<std::size_t>(2, candidate.size() / 3);
    if ((distance <= tolerance || prefix) && distance < best_distance) {
      best = candidate;
      best_distance = distance;
    }
  }
  return best;
}

std::string suggestion(std::string_view word, const std::vector<std::string>& candidates, std::string_view what_list) {
  if (auto match = closest_match(word, candidates)) return "; did you mean '" + *match + "'?";
  return "; " + std::string(what_list) + ": " + join(candidates);
}

std::string format_number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

std::string escape_pointer_token(std::string_view token) {
  std::string out;
  for (char c : token) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

void Value::fail(const std::string& what, Error::Kind kind) const {
  throw Error(context_->file + ": " + (pointer_.empty() ? "/" : pointer_), what, kind);
}

void Value::expect_type(nlohmann::json::value_t type, std::string_view description) const {
  if (json_->type() != type) fail("expected " + std::string(description) + ", got " + json_->type_name());
}

Value Value::element(std::size_t index) const {
  return Value(*context_, json_->at(index), pointer_ + "/" + std::to_string(index));
}

std::optional<Value> Value::member(std::string_view key) const {
  const auto it = json_->find(key);
  if (it == json_->end()) return std::nullopt;
  return Value(*context_, *it, pointer_ + "/" + escape_pointer_token(key));
}

double Value::number() const {
  if (!json_->is_number()) fail(std::string("expected a number, got ") + json_->type_name());
  const double v = json_->get<double>();
  // Values beyond float range would silently become infinity downstream.
  if (!std::isfinite(v) || std::abs(v) > std::numeric_limits<float>::max())
    fail("expected a finite number, got " + format_number(v));
  return v;
}

double Value::positive() const {
  const double v = number();
  require(v > 0, "must be greater than 0, got " + format_number(v));
  return v;
}

double Value::non_negative() const {
  const double v = number();
  require(v >= 0, "must not be negative, got " + format_number(v));
  return v;
}

double Value::number_in(double lo, double hi) const {
  const double v = number();
  require(v >= lo && v <= hi,
          "must be from " + format_number(lo) + " to " + format_number(hi) + ", got " + format_number(v));
  return v;
}

double Value::non_zero() const {
  const double v = number();
  require(v != 0, "must not be 0");
  return v;
}

std::int64_t Value::integer(std::int64_t lo, std::int64_t hi) const {
  const double v = number();
  require(std::floor(v) == v, "expected an integer, got " + format_number(v));
  require(v >= static_cast<double>(lo) && v <= static_cast<double>(hi),
          "must be an integer from " + std::to_string(lo) + " to " + std::to_string(hi) + ", got " + format_number(v));
  return static_cast<std::int64_t>(v);
}

bool Value::boolean() const {
  expect_type(nlohmann::json::value_t::boolean, "true or false");
  return json_->get<bool>();
}

std::string Value::string() const {
  expect_type(nlohmann::json::value_t::string, "a string");
  return json_->get<std::string>();
}

std::vector<Value> Value::array() const {
  expect_type(nlohmann::json::value_t::array, "an array");
  std::vector<Value> out;
  for (std::size_t i = 0; i < json_->size(); ++i) out.push_back(element(i));
  return out;
}

glm::vec3 Value::vec3(NumberCheck component) const {
  require(json_->is_array() && json_->size() == 3,
          std::string("expected an array of 3 numbers, got ") +
              (json_->is_array() ? "an array of " + std::to_string(json_->size()) : json_->type_name()));
  return {(element(0).*component)(), (element(1).*component)(), (element(2).*component)()};
}

std::filesystem::path Value::file_path() const {
  const std::string text = string();
  require(!text.empty(), "expected a file path, got an empty string");
  std::filesystem::path path =
      std::filesystem::absolute(context_->base_dir / std::filesystem::path(text)).lexically_normal();
  if (!path.has_filename()) path = path.parent_path();  // "dir/." normalises to "dir/"
  return path;
}

std::filesystem::path Value::existing_file() const {
  const std::filesystem::path path = file_path();
  // Devices, FIFOs and sockets are refused here, before anything opens them; sizes are checked when read.
  const std::string reason = non_regular_reason(path);
  if (reason == "file not found" || reason == "is a directory, not a file")
    fail(reason + ": " + shown_path(path), Error::Kind::File);
  if (!reason.empty()) fail(shown_path(path) + " " + reason, Error::Kind::File);
  note_input(path);
  return path;
}

Object::Object(const Value& value, std::initializer_list<std::string_view> keys) : value_(value) {
  value.expect_type(nlohmann::json::value_t::object, "an object");
  std::vector<std::string> valid(keys.begin(), keys.end());
  for (const auto& item : value.json().items()) {
    const std::string& key = item.key();
    if (key == "comment" || std::find(valid.begin(), valid.end(), key) != valid.end()) continue;
    value.fail("unknown key '" + shorten(key) + "'" + suggestion(key, valid, "valid keys are"));
  }
}

Value Object::required(std::string_view key) const {
  auto member = find(key);
  if (!member) value_.fail("missing key '" + std::string(key) + "'");
  return *member;
}

}  // namespace qdmr::scene_detail
