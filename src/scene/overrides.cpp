#include "scene/overrides.hpp"

#include <algorithm>
#include <vector>

#include <nlohmann/json.hpp>

#include "qdmr/core/error.hpp"
#include "scene/reader.hpp"

namespace qdmr {

SceneOverride parse_override(std::string_view text) {
  const std::string where = "--set '" + scene_detail::shorten(text) + "'";
  const auto equals = text.find('=');
  if (equals == std::string_view::npos) throw Error(where, "expected POINTER=VALUE, e.g. /camera/fov_deg=30");
  SceneOverride result{std::string(text.substr(0, equals)), std::string(text.substr(equals + 1))};
  if (!result.pointer.starts_with('/'))
    throw Error(where, "the JSON pointer must start with '/', e.g. /camera/fov_deg=30");
  try {
    static_cast<void>(nlohmann::json::json_pointer(result.pointer));  // throws on a bad ~ escape
  } catch (const nlohmann::json::exception&) {
    throw Error(where, "invalid JSON pointer '" + result.pointer + "' ('~' must be written ~0, '/' in a key ~1)");
  }
  return result;
}

namespace scene_detail {

namespace {

// JSON if it parses, else the text as a string; nesting deeper than the limit is an error.
nlohmann::json parse_value(const std::string& text, const std::string& where) {
  try {
    return parse_json_bounded(text);
  } catch (const Error& e) {
    throw e.within(where);
  } catch (const nlohmann::json::exception&) {
    return nlohmann::json(text);
  }
}

void apply_override(nlohmann::json& document, const SceneOverride& override_, const std::string& file) {
  const auto fail = [&](const std::string& what) {
    throw Error(file + ": " + override_.pointer, "cannot apply --set: " + what);
  };
  nlohmann::json::json_pointer pointer;
  try {
    pointer = nlohmann::json::json_pointer{override_.pointer};
  } catch (const nlohmann::json::exception&) {
    fail("invalid JSON pointer");
  }
  if (pointer.empty()) fail("cannot replace the whole document");
  const nlohmann::json::json_pointer parent_pointer = pointer.parent_pointer();
  // The parent's tokens, root first. The walk below goes down one token at a time from the node above: building
  // every ancestor's pointer (and its text) made an override of N tokens cost N^2 string copies.
  std::vector<std::string> tokens;
  for (auto p = parent_pointer; !p.empty(); p.pop_back()) tokens.push_back(p.back());
  std::reverse(tokens.begin(), tokens.end());
  const auto text_of = [&](std::size_t count) {  // the pointer of the first `count` tokens, for messages
    nlohmann::json::json_pointer p;
    for (std::size_t i = 0; i < count; ++i) p.push_back(tokens[i]);
    return p.empty() ? std::string("/") : p.to_string();
  };
  // Optional blocks the file leaves out (a material's "technique", the "camera") are created as empty objects
  // on the way, so any value can be set; validation then reports misspelt keys with suggestions. Array
  // elements are never created, except by '-' at the end.
  nlohmann::json* node = &document;
  for (std::size_t i = 0; i < tokens.size(); ++i) {
    nlohmann::json::json_pointer step;
    step.push_back(tokens[i]);
    if (node->contains(step)) {  // contains() accepts only well-formed, in-range indices
      node = &node->at(step);
      continue;
    }
    if (node->is_array()) fail(text_of(i) + " has no element '" + tokens[i] + "'");
    if (!node->is_object()) fail(text_of(i) + " is a " + std::string(node->type_name()) + ", not an object or array");
    node = &((*node)[tokens[i]] = nlohmann::json::object());
  }
  nlohmann::json& parent = *node;
  const std::string& key = pointer.back();
  nlohmann::json value = parse_value(override_.value, file + ": " + override_.pointer);

  if (parent.is_object()) {
    parent[key] = std::move(value);
  } else if (parent.is_array()) {
    if (key == "-") {
      parent.push_back(std::move(value));
      return;
    }
    // contains() accepts only well-formed, in-range indices.
    if (!document.contains(pointer))
      fail("no element '" + key + "' in " + text_of(tokens.size()) + " (it has " + std::to_string(parent.size()) +
           " elements; use '-' to append)");
    document[pointer] = std::move(value);
  } else {
    fail(text_of(tokens.size()) + " is a " + parent.type_name() + ", not an object or array");
  }
}

}  // namespace

void apply_overrides(nlohmann::json& document, const std::vector<SceneOverride>& overrides, const std::string& file) {
  for (const auto& override_ : overrides) {
    // A pointer nlohmann::json cannot resolve in some way apply_override does not foresee (found by fuzz_set:
    // "/objects/=1", an empty token on an array) is an input error like the others, not an internal one.
    try {
      apply_override(document, override_, file);
    } catch (const nlohmann::json::exception& e) {
      const std::string what = e.what();
      const auto bracket = what.find("] ");
      throw Error(file + ": " + override_.pointer,
                  "cannot apply --set: " + (bracket == std::string::npos ? what : what.substr(bracket + 2)));
    }
  }
}

}  // namespace scene_detail
}  // namespace qdmr
