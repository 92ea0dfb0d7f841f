#pragma once
// --set overrides: a JSON pointer and a value, applied to the scene document before it is validated.
#include <string>
#include <string_view>

namespace qdmr {

// One --set /json/pointer=value override; value is JSON (a bare word that is not JSON is taken as a string).
struct SceneOverride {
  std::string pointer;
  std::string value;
};

// Parses "POINTER=VALUE"; throws qdmr::Error naming the option on malformed text.
SceneOverride parse_override(std::string_view text);

}  // namespace qdmr
