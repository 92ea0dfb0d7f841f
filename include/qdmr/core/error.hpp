#pragma once
// The error qdmr throws for bad input: the message names the file and the offending field. Its kind says what
// was wrong, so callers (the Python module's SceneError and InputError) tell them apart without reading words.
#include <stdexcept>
#include <string>

namespace qdmr {

class Error : public std::runtime_error {
public:
  enum class Kind {
    Value,  // a value: a field, an option, a document's content (JSON, OBJ, MTL, glTF), a limit
    File    // a file as a whole: missing, not a regular file, empty or too large, unreadable, an image that does
            // not decode, an output that cannot be written
  };
  // where: the file (and JSON pointer or CLI option) at fault, e.g. "scene.json: /camera/fov_deg".
  Error(const std::string& where, const std::string& what, Kind kind = Kind::Value)
      : std::runtime_error(where + ": " + what), kind_(kind) {}
  explicit Error(const std::string& message, Kind kind = Kind::Value) : std::runtime_error(message), kind_(kind) {}

  Kind kind() const { return kind_; }
  // The same error led by `where` (the field or file that led to it), of the same kind.
  Error within(const std::string& where) const { return Error(where, what(), kind_); }

private:
  Kind kind_;
};

// An Error of kind File.
class FileError : public Error {
public:
  FileError(const std::string& where, const std::string& what) : Error(where, what, Kind::File) {}
};

}  // namespace qdmr
