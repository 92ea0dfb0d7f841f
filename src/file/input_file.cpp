#include "file/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <mutex>
#include <utility>

#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"

namespace qdmr {
namespace {

std::mutex inputs_mutex;
std::vector<KnownInput>& inputs() {
  static std::vector<KnownInput> list;
  return list;
}

void note_identity(const FileIdentity& id, const std::filesystem::path& file) {
  const std::lock_guard lock(inputs_mutex);
  for (const KnownInput& k : inputs())
    if (k.id == id) return;
  inputs().push_back({id, file});
}

std::string type_reason(mode_t mode) {
  if (S_ISREG(mode)) return "";
  if (S_ISDIR(mode)) return "is a directory, not a file";
  if (S_ISFIFO(mode)) return "is a FIFO (named pipe), not a regular file";
  if (S_ISSOCK(mode)) return "is a socket, not a regular file";
  if (S_ISCHR(mode)) return "is a character device, not a regular file";
  if (S_ISBLK(mode)) return "is a block device, not a regular file";
  return "is not a regular file";
}

std::string size_reason(std::uint64_t size, InputKind kind) {
  if (size == 0) return "is empty (0 bytes)";
  const std::uint64_t limit = input_size_limit(kind);
  if (size > limit)
    return "is " + std::to_string(size) + " bytes, more than the limit of " + std::to_string(limit) + " bytes for a " +
           input_kind_name(kind);
  return "";
}

// "<reason>" when the message already starts with the file (where == file), else "<file> <reason>".
std::string about(const std::filesystem::path& file, const std::string& where, const std::string& reason) {
  if (where == file.string()) return reason;
  if (reason == "file not found") return reason + ": " + shown_path(file);
  return shown_path(file) + " " + reason;
}

}  // namespace

std::string shown_path(const std::filesystem::path& file) {
  const std::string& path = file.native();
  if (path.size() <= 240) return path;
  return path.substr(0, 120) + "...(" + std::to_string(path.size() - 220) + " bytes)..." + path.substr(path.size() - 100);
}

const char* input_kind_name(InputKind kind) {
  switch (kind) {
    case InputKind::Scene: return "scene file";
    case InputKind::Obj: return "OBJ file";
    case InputKind::Mtl: return "MTL file";
    case InputKind::Image: return "image file";
    case InputKind::Cache: return "cache file";
    case InputKind::Manifest: return "check manifest";
    case InputKind::StudySpec: return "study spec";
    case InputKind::Gltf: return "glTF file";
    case InputKind::GltfBuffer: return "glTF buffer";
  }
  return "file";
}

std::uint64_t input_size_limit(InputKind kind) {
  switch (kind) {
    case InputKind::Scene: return limits::kMaxSceneFileBytes;
    case InputKind::Obj: return limits::kMaxObjFileBytes;
    case InputKind::Mtl: return limits::kMaxMtlFileBytes;
    case InputKind::Image: return limits::kMaxImageFileBytes;
    case InputKind::Cache: return limits::kMaxImageFileBytes;
    case InputKind::Manifest: return limits::kMaxManifestFileBytes;
    case InputKind::StudySpec: return limits::kMaxSceneFileBytes;
    case InputKind::Gltf: return limits::kMaxGltfFileBytes;
    case InputKind::GltfBuffer: return limits::kMaxGltfFileBytes;
  }
  return 0;
}

std::string non_regular_reason(const std::filesystem::path& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) return "file not found";
    return std::string("cannot access the file (") + std::strerror(errno) + ")";
  }
  return type_reason(st.st_mode);
}

std::uint64_t check_input_file(const std::filesystem::path& file, const std::string& where, InputKind kind) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) throw FileError(where, about(file, where, "file not found"));
    throw FileError(where, about(file, where, std::string("cannot be accessed (") + std::strerror(errno) + ")"));
  }
  std::string reason = type_reason(st.st_mode);
  if (reason.empty()) reason = size_reason(std::uint64_t(st.st_size), kind);
  if (!reason.empty()) throw FileError(where, about(file, where, reason));
  note_identity({st.st_dev, st.st_ino}, file);
  return std::uint64_t(st.st_size);
}

namespace {

// Opens a checked file without blocking and checks it again on the descriptor (a FIFO swapped in after the check
// cannot block). Returns the descriptor; `st` holds its status.
int open_checked(const std::filesystem::path& file, const std::string& where, InputKind kind, struct stat& st) {
  check_input_file(file, where, kind);
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) throw FileError(where, "cannot open " + shown_path(file) + ": " + std::strerror(errno));
  if (::fstat(fd, &st) != 0) {
    const std::string error = std::strerror(errno);
    ::close(fd);
    throw FileError(where, "cannot read " + shown_path(file) + ": " + error);
  }
  std::string reason = type_reason(st.st_mode);
  if (reason.empty()) reason = size_reason(std::uint64_t(st.st_size), kind);
  if (!reason.empty()) {
    ::close(fd);
    throw FileError(where, about(file, where, reason));
  }
  return fd;
}

}  // namespace

std::string read_input_file(const std::filesystem::path& file, const std::string& where, InputKind kind) {
  struct stat st {};
  const int fd = open_checked(file, where, kind, st);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  // The size fstat gave, then a probe for more through a small buffer: a file that grew while it is read is
  // still read to its end, bounded by the limit + 1, and a file that did not grow costs no larger buffer.
  const std::uint64_t limit = input_size_limit(kind);
  std::string text;
  text.resize(std::size_t(st.st_size));
  std::size_t have = 0;
  char probe[4096];
  for (;;) {
    const bool probing = have == text.size();
    if (probing && have > limit) break;
    char* const into = probing ? probe : text.data() + have;
    const std::size_t room = probing ? sizeof probe : text.size() - have;
    const ssize_t n = ::read(fd, into, room);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw FileError(where, "cannot read " + shown_path(file) + ": " + std::strerror(errno));
    }
    if (n == 0) break;
    if (probing) text.append(probe, std::size_t(n));
    have += std::size_t(n);
  }
  text.resize(have);
  if (have > limit || have == 0) throw FileError(where, about(file, where, size_reason(have, kind)));
  return text;
}

InputFile::InputFile(const std::filesystem::path& file, const std::string& where, InputKind kind) : file_(file), where_(where) {
  struct stat st {};
  fd_ = open_checked(file, where, kind, st);
  size_ = std::uint64_t(st.st_size);
}

InputFile::InputFile(InputFile&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), size_(other.size_), file_(std::move(other.file_)), where_(std::move(other.where_)) {}

InputFile::~InputFile() {
  if (fd_ >= 0) ::close(fd_);
}

void InputFile::read(std::uint64_t offset, std::size_t n, void* out) const {
  auto* into = static_cast<char*>(out);
  while (n > 0) {
    const ssize_t got = ::pread(fd_, into, n, off_t(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw FileError(where_, "cannot read " + shown_path(file_) + ": " + std::strerror(errno));
    if (got == 0)
      throw FileError(where_, shown_path(file_) + " ended at byte " + std::to_string(offset) + ", before the " +
                                  std::to_string(n) + " bytes to read there (did it change while it was read?)");
    into += got;
    offset += std::uint64_t(got);
    n -= std::size_t(got);
  }
}

std::string InputFile::read(std::uint64_t offset, std::size_t n) const {
  std::string bytes(n, '\0');
  read(offset, n, bytes.data());
  return bytes;
}

void note_input(const std::filesystem::path& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) == 0) note_identity({st.st_dev, st.st_ino}, file);
}

std::vector<KnownInput> known_inputs() {
  const std::lock_guard lock(inputs_mutex);
  return inputs();
}

}  // namespace qdmr
