#include "file/atomic_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cstring>
#include <fstream>
#include <string_view>

#include "qdmr/core/error.hpp"

namespace qdmr {
namespace {

std::filesystem::path folder_of(const std::filesystem::path& file) {
  return file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
}

// Every temporary of `file` is ".NAME.tmp" PID "-" N EXT: in the target's folder (so the rename is atomic),
// hidden, with the target's extension (OpenImageIO picks the format by extension).
std::string temporary_prefix(const std::filesystem::path& file) {
  std::string prefix = ".";  // appended piecewise: GCC 12 warns falsely on a chain of string '+'
  prefix.append(file.filename().string()).append(".tmp");
  return prefix;
}

std::filesystem::path temporary_for(const std::filesystem::path& file) {
  static std::atomic<unsigned> counter{0};
  std::string name = temporary_prefix(file);
  name.append(std::to_string(::getpid())).append("-").append(std::to_string(counter++));
  name.append(file.extension().string());
  return folder_of(file) / name;
}

bool all_digits(std::string_view text) {
  return !text.empty() && text.find_first_not_of("0123456789") == std::string_view::npos;
}

// The PID in `name` if it is a temporary of the target with this prefix and extension, else 0.
long long temporary_pid(const std::string& name, const std::string& prefix, const std::string& extension) {
  if (name.size() <= prefix.size() + extension.size() || name.compare(0, prefix.size(), prefix) != 0 ||
      name.compare(name.size() - extension.size(), extension.size(), extension) != 0)
    return 0;
  const std::string_view middle(name.data() + prefix.size(), name.size() - prefix.size() - extension.size());
  const std::size_t dash = middle.find('-');
  if (dash == std::string_view::npos || dash > 18 || !all_digits(middle.substr(0, dash)) ||
      !all_digits(middle.substr(dash + 1)))
    return 0;
  long long pid = 0;
  std::from_chars(middle.data(), middle.data() + dash, pid);
  return pid;
}

bool running(long long pid) {
  if (pid > INT_MAX) return false;  // no such process can exist
  return ::kill(pid_t(pid), 0) == 0 || errno == EPERM;  // EPERM: it exists, owned by someone else
}

// Removes `temporary` if nobody holds its lock (its writer is dead: the kernel dropped the lock) and the name
// still refers to the file that was locked. Anything unexpected (not a regular file, not readable, locked,
// replaced meanwhile) leaves it alone.
void remove_if_unlocked(const std::filesystem::path& temporary) {
  const int fd = ::open(temporary.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return;
  struct stat locked{}, named{};
  if (::fstat(fd, &locked) == 0 && S_ISREG(locked.st_mode) && ::flock(fd, LOCK_EX | LOCK_NB) == 0 &&
      ::lstat(temporary.c_str(), &named) == 0 && named.st_dev == locked.st_dev && named.st_ino == locked.st_ino)
    ::unlink(temporary.c_str());
  ::close(fd);
}

// The temporaries of `file` left behind by processes that are gone (killed while writing).
void remove_stale_temporaries(const std::filesystem::path& file) {
  const std::string prefix = temporary_prefix(file), extension = file.extension().string();
  std::vector<std::filesystem::path> stale;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(folder_of(file), ec), end; !ec && it != end; it.increment(ec)) {
    const long long pid = temporary_pid(it->path().filename().string(), prefix, extension);
    if (pid > 0 && pid != ::getpid() && !running(pid)) stale.push_back(it->path());
  }
  for (const std::filesystem::path& temporary : stale) remove_if_unlocked(temporary);
}

struct LockedTemporary {
  std::filesystem::path path;
  int fd = -1;
};

// A new, empty temporary of `file`, created exclusively and locked. If another process removed it as stale in
// the instant between its creation and the lock (possible only from another PID namespace), it takes a new name.
LockedTemporary create_temporary(const std::filesystem::path& file, const std::string& what) {
  for (int attempt = 0; attempt < 16; ++attempt) {
    LockedTemporary t{temporary_for(file), -1};
    t.fd = ::open(t.path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (t.fd < 0) {
      if (errno == EEXIST) continue;
      throw FileError(file.string(), "cannot write " + what + ": cannot create a temporary file in its folder: " +
                                     std::strerror(errno));
    }
    struct stat locked{}, named{};
    if (::flock(t.fd, LOCK_EX) == 0 && ::fstat(t.fd, &locked) == 0 && ::lstat(t.path.c_str(), &named) == 0 &&
        named.st_dev == locked.st_dev && named.st_ino == locked.st_ino)
      return t;
    ::close(t.fd);
  }
  throw FileError(file.string(), "cannot write " + what + ": no temporary file could be created and locked");
}

// An image library's message ("File output failed") with the OS reason behind it where it has none: the errno
// of the failed write when it says why, else a full file system when statvfs finds no space left.
std::string with_os_reason(const std::string& message, int error, const std::filesystem::path& folder) {
  const auto with = [&](int reason) {
    const std::string text = std::strerror(reason);
    return message.find(text) != std::string::npos ? message : message + " (" + text + ")";
  };
  if (error == ENOSPC || error == EDQUOT || error == EFBIG || error == EIO || error == EROFS) return with(error);
  struct statvfs space{};
  if (::statvfs(folder.c_str(), &space) == 0 && space.f_bavail == 0) return with(ENOSPC);
  return message;
}

thread_local OutputBatch* current_batch = nullptr;

}  // namespace

OutputBatch::OutputBatch() : previous_(current_batch) { current_batch = this; }

OutputBatch::~OutputBatch() {
  current_batch = previous_;
  std::error_code ec;
  for (const Pending& p : pending_) {
    std::filesystem::remove(p.temporary, ec);
    ::close(p.lock);
  }
}

void OutputBatch::commit() {
  std::error_code ec;
  while (!pending_.empty()) {
    const Pending& p = pending_.front();
    std::filesystem::rename(p.temporary, p.target, ec);
    if (ec) throw FileError(p.target.string(), "cannot write: " + ec.message());  // the rest: the destructor's
    ::close(p.lock);
    pending_.erase(pending_.begin());
  }
}

void write_atomically(const std::filesystem::path& file, const std::string& what,
                      const std::function<std::string(const std::filesystem::path&)>& write) {
  const std::filesystem::path folder = folder_of(file);
  if (!std::filesystem::is_directory(folder)) throw FileError(file.string(), "folder does not exist: " + folder.string());
  remove_stale_temporaries(file);
  const LockedTemporary temporary = create_temporary(file, what);
  std::string message;
  errno = 0;
  try {
    message = write(temporary.path);
  } catch (const std::exception& e) {
    message = e.what();
  }
  if (!message.empty()) message = with_os_reason(message, errno, folder);
  std::error_code ec;
  if (message.empty() && current_batch) {
    current_batch->pending_.push_back({temporary.path, file, temporary.fd});
    return;
  }
  if (message.empty()) {
    std::filesystem::rename(temporary.path, file, ec);
    if (!ec) {
      ::close(temporary.fd);  // after the rename: the lock is held as long as the temporary has its name
      return;
    }
    message = ec.message();
  }
  std::filesystem::remove(temporary.path, ec);
  ::close(temporary.fd);
  throw FileError(file.string(), "cannot write " + what + ": " + message);
}

void write_text_file(const std::filesystem::path& file, const std::string& text) {
  write_atomically(file, "file", [&](const std::filesystem::path& temporary) -> std::string {
    errno = 0;
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    if (out.flush()) return "";
    return errno ? std::strerror(errno) : "write failed";  // the OS reason (a full disk) where the stream has it
  });
}

void copy_file_atomically(const std::filesystem::path& from, const std::filesystem::path& file) {
  write_atomically(file, "copy of " + from.string(), [&](const std::filesystem::path& temporary) -> std::string {
    std::error_code ec;
    std::filesystem::copy_file(from, temporary, std::filesystem::copy_options::overwrite_existing, ec);
    return ec ? ec.message() : "";
  });
}

}  // namespace qdmr
