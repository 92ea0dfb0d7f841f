#include "file/folder_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <exception>
#include <iterator>

#include "qdmr/core/error.hpp"

namespace qdmr {

FolderLock::FolderLock(const std::filesystem::path& folder, const std::string& what, bool created)
    : folder_(folder), created_(created), exceptions_(std::uncaught_exceptions()) {
  const std::filesystem::path file = folder / kFileName;
  fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd_ < 0) throw FileError(file.string(), "cannot create the " + what + " lock: " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    char holder[32] = {};
    const ssize_t n = ::pread(fd_, holder, sizeof holder - 1, 0);
    ::close(fd_);
    if (error != EWOULDBLOCK)
      throw FileError(file.string(), "cannot lock the " + what + " folder: " + std::strerror(error));
    std::string pid(holder, std::size_t(std::max<ssize_t>(n, 0)));
    pid.erase(pid.find_last_not_of(" \n") + 1);
    throw FileError(folder.string(), "is in use by another qdmr " + what + (pid.empty() ? "" : " (process " + pid + ")") +
                                     ": wait until it ends, or choose another -o");
  }
  // The holder's id, for the message above (best effort: a full disk only loses the id).
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) == 0) static_cast<void>(::pwrite(fd_, pid.data(), pid.size(), 0));
}

FolderLock::~FolderLock() {
  if (std::uncaught_exceptions() > exceptions_) {
    std::error_code ec;
    std::filesystem::directory_iterator it(folder_, ec);
    const bool only_the_lock = !ec && it != std::filesystem::directory_iterator() &&
                               it->path().filename() == kFileName && std::next(it) == std::filesystem::directory_iterator();
    if (only_the_lock) {
      std::filesystem::remove(folder_ / kFileName, ec);
      if (created_) std::filesystem::remove(folder_, ec);
    }
  }
  ::close(fd_);
}

}  // namespace qdmr
