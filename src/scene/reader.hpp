#pragma once
// Typed, validating access to a JSON document: every failure throws qdmr::Error("FILE: /pointer", what).
#include <cstdint>
#include <filesystem>
#include <glm/vec3.hpp>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "qdmr/core/error.hpp"

#include "file/input_file.hpp"

namespace qdmr::scene_detail {

// The closest candidate to `word` by edit distance, if it is close enough to be a plausible typo.
std::optional<std::string> closest_match(std::string_view word, const std::vector<std::string>& candidates);

// "; did you mean 'x'?" or "; expected one of: a, b, c" (what_list names the candidates, e.g. "valid keys").
std::string suggestion(std::string_view word, const std::vector<std::string>& candidates, std::string_view what_list);

std::string format_number(double value);

// nlohmann::json::parse with the nesting depth bounded by limits::kMaxJsonDepth (deeper documents would make
// the recursive copy and destruction of the tree overflow the stack). Throws nlohmann::json::parse_error
// (deeper than the limit: an out_of_range naming the depth) like parse itself.
nlohmann::json parse_json_bounded(const std::string& text);

// A JSON file qdmr reads (a scene, check manifest or study spec): checked and read as an input of `kind`, then
// parsed with parse_json_bounded. Throws qdmr::Error(file, "parse error at line L, column C: ..."). `text` (if
// given) gets the file's text.
nlohmann::json parse_json_file(const std::filesystem::path& file, InputKind kind, std::string* text = nullptr);

// `text` cut to at most `max` characters with "..." (keys and values quoted in messages stay one short line).
std::string shorten(std::string_view text, std::size_t max = 64);
std::string escape_pointer_token(std::string_view token);

struct Context {
  std::string file;                // the scene file as named in messages
  std::filesystem::path base_dir;  // relative paths resolve against this
  int frames = 1;                  // frames of the scene's animation (file sequences and keyframes are checked against it)
};

// One value in the document and where it is.
class Value {
public:
  Value(const Context& context, const nlohmann::json& json, std::string pointer)
      : context_(&context), json_(&json), pointer_(std::move(pointer)) {}

  const nlohmann::json& json() const { return *json_; }
  const std::string& pointer() const { return pointer_; }
  const Context& context() const { return *context_; }

  [[noreturn]] void fail(const std::string& what, Error::Kind kind = Error::Kind::Value) const;
  void require(bool ok, const std::string& what) const {
    if (!ok) fail(what);
  }

  Value element(std::size_t index) const;
  std::optional<Value> member(std::string_view key) const;  // no unknown-key checks: see Object

  double number() const;                         // finite, representable as float
  double positive() const;                       // > 0
  double non_negative() const;                   // >= 0
  double number_in(double lo, double hi) const;  // inclusive
  double non_zero() const;
  std::int64_t integer(std::int64_t lo, std::int64_t hi) const;
  bool boolean() const;
  std::string string() const;
  using NumberCheck = double (Value::*)() const;
  glm::vec3 vec3(NumberCheck component = &Value::number) const;  // [x, y, z]
  glm::vec3 color() const { return vec3(&Value::non_negative); }
  std::vector<Value> array() const;
  std::filesystem::path file_path() const;      // a path string resolved against base_dir
  std::filesystem::path existing_file() const;  // file_path(), which must exist

  // One of a fixed set of names, e.g. {{"point", Filter::Point}, ...}.
  template <class E>
  E choice(std::initializer_list<std::pair<std::string_view, E>> options) const {
    const std::string text = string();
    std::vector<std::string> names;
    for (const auto& [name, value] : options) {
      if (name == text) return value;
      names.emplace_back(name);
    }
    fail("unknown value '" + text + "'" + suggestion(text, names, "expected one of"));
  }

  void expect_type(nlohmann::json::value_t type, std::string_view description) const;

private:
  const Context* context_;
  const nlohmann::json* json_;
  std::string pointer_;
};

// A JSON object whose keys must all be in `keys` ("comment" is always allowed and ignored).
class Object {
public:
  Object(const Value& value, std::initializer_list<std::string_view> keys);

  const Value& value() const { return value_; }
  std::optional<Value> find(std::string_view key) const { return value_.member(key); }
  Value required(std::string_view key) const;

private:
  Value value_;
};

}  // namespace qdmr::scene_detail
