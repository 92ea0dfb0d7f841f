#pragma once
// Files are written next to their target under a temporary name and renamed over it only when complete, so a
// failed write never leaves a partial file behind and never damages an existing one.
//
// Temporaries are named ".NAME.tmpPID-N.EXT" (NAME the target's file name, PID the writing process, N a counter
// of the process, EXT the target's extension) and the writer holds an exclusive flock(2) on the temporary until
// it is renamed or removed. A process killed while writing (SIGKILL, power loss aside) leaves its temporary
// behind; the next write to the same target removes every temporary of that target whose process is not
// running and whose lock is free (the kernel drops the lock of a dead process). A temporary of a live process,
// or one still locked (a writer in another PID namespace sharing the folder), is left alone.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace qdmr {

// write(temporary) returns an empty string on success or what went wrong. Throws qdmr::Error(file, what + ...)
// after removing the temporary.
void write_atomically(const std::filesystem::path& file, const std::string& what,
                      const std::function<std::string(const std::filesystem::path& temporary)>& write);

void write_text_file(const std::filesystem::path& file, const std::string& text);

// A copy of `from` at `file`, written like every other output (whole or not at all).
void copy_file_atomically(const std::filesystem::path& from, const std::filesystem::path& file);

// While an OutputBatch lives, write_atomically on this thread writes the temporary but defers the rename:
// commit() renames every file (after all of them were written), the destructor removes the temporaries of an
// uncommitted batch. A job with several outputs thus writes all or none of them.
class OutputBatch {
public:
  OutputBatch();
  ~OutputBatch();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
  void commit();  // throws qdmr::Error when a rename fails (files renamed before it stay)

private:
  friend void write_atomically(const std::filesystem::path&, const std::string&,
                               const std::function<std::string(const std::filesystem::path&)>&);
  struct Pending {
    std::filesystem::path temporary, target;
    int lock;  // the temporary's locked file descriptor, closed after the rename or removal
  };
  std::vector<Pending> pending_;
  OutputBatch* previous_;
};

}  // namespace qdmr
