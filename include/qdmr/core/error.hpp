#pragma once
// The one error type qdmr throws for bad input: the message names the file and the offending field.
#include <stdexcept>
#include <string>

namespace qdmr {

class Error : public std::runtime_error {
public:
  // where: the file (and JSON pointer or CLI option) at fault, e.g. "scene.json: /camera/fov_deg".
  Error(const std::string& where, const std::string& what) : std::runtime_error(where + ": " + what) {}
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace qdmr
