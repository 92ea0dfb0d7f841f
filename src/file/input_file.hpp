#pragma once
// Every file qdmr reads goes through here first: it must be a regular file (or a symlink to one) of a bounded
// size. Directories, FIFOs, sockets and devices are refused before they are opened, so nothing can block on
// them or read forever. Each file checked is also remembered (device and inode) as an input of the job, so
// outputs can be refused when they would overwrite one (see file/output_check.hpp).
#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace qdmr {

enum class InputKind { Scene, Obj, Mtl, Image, Cache, Manifest, StudySpec, Gltf, GltfBuffer };

const char* input_kind_name(InputKind kind);    // "scene file", "OBJ file", ...
std::uint64_t input_size_limit(InputKind kind);  // bytes, see qdmr/core/limits.hpp

// `file` as error messages show it: whole up to 240 bytes, longer ones (a name the system refuses as too long)
// with their middle elided, so an error stays one readable line.
std::string shown_path(const std::filesystem::path& file);

// "" when `file` is a regular file (following symlinks); otherwise what it is, e.g. "is a FIFO (named pipe),
// not a regular file", "file not found", "is a directory, not a file".
std::string non_regular_reason(const std::filesystem::path& file);

// Checks `file` (type, not empty, size within the limit of its kind) and remembers it as an input. Returns its
// size. Throws qdmr::Error(where, "<reason>: <file>").
std::uint64_t check_input_file(const std::filesystem::path& file, const std::string& where, InputKind kind);

// check_input_file, then the whole file. It is opened without blocking and checked again on the open
// descriptor, so a FIFO swapped in after the check cannot block either; reads at most the limit.
std::string read_input_file(const std::filesystem::path& file, const std::string& where, InputKind kind);

// An input file held open to read parts of it (a .glb's chunks, the accessors of a glTF buffer) without holding
// all of it: checked as check_input_file checks it, then again on the open descriptor, as read_input_file does.
class InputFile {
 public:
  InputFile(const std::filesystem::path& file, const std::string& where, InputKind kind);
  InputFile(InputFile&& other) noexcept;
  InputFile& operator=(InputFile&&) = delete;
  InputFile(const InputFile&) = delete;
  ~InputFile();

  std::uint64_t size() const { return size_; }
  // `n` bytes from `offset` into `out`. Throws qdmr::Error(where, ...) when they are not all there (the file
  // changed since it was checked) or cannot be read.
  void read(std::uint64_t offset, std::size_t n, void* out) const;
  std::string read(std::uint64_t offset, std::size_t n) const;

 private:
  int fd_ = -1;
  std::uint64_t size_ = 0;
  std::filesystem::path file_;
  std::string where_;
};

struct FileIdentity {
  dev_t device = 0;
  ino_t inode = 0;
  bool operator==(const FileIdentity&) const = default;
};

struct KnownInput {
  FileIdentity id;
  std::filesystem::path path;
};

// Remembers a file as an input of this process's job (no-op when it does not exist).
void note_input(const std::filesystem::path& file);
// Every input noted so far (thread-safe snapshot).
std::vector<KnownInput> known_inputs();

}  // namespace qdmr
