#pragma once
// An exclusive lock on a folder that one process writes (a study's results): flock(2) on FOLDER/.qdmr-lock, held
// while the FolderLock lives. The kernel drops it when the process dies, even by SIGKILL, so a killed run never
// leaves a folder locked; the file itself stays (it is empty but for the holder's process id).
#include <filesystem>
#include <string>

namespace qdmr {

class FolderLock {
public:
  // Throws qdmr::Error(folder, "is in use by another qdmr process (PID): ...") when another process holds it,
  // or the OS reason when the lock file cannot be created. `what` names the job in the message ("study").
  // `created`: the caller made the folder for this job.
  FolderLock(const std::filesystem::path& folder, const std::string& what, bool created);
  // Left by an exception (a full disk before anything was written): the lock file goes when the folder holds
  // nothing else, and the folder too when the job created it, so a failed job leaves no trace.
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

  static constexpr const char* kFileName = ".qdmr-lock";

private:
  std::filesystem::path folder_;
  bool created_;
  int exceptions_;  // std::uncaught_exceptions() when made
  int fd_ = -1;
};

}  // namespace qdmr
