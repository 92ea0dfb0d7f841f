#include "io/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <fstream>

#include "qdmr/core/error.hpp"

namespace qdmr {
namespace {

// Unique per process and call, in the target's folder (so the rename is atomic), hidden, same extension
// (OpenImageIO picks the format by extension).
std::filesystem::path temporary_for(const std::filesystem::path& file) {
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path folder = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
  std::string name = ".";  // appended piecewise: GCC 12 warns falsely on a chain of string '+'
  name.append(file.filename().string()).append(".tmp").append(std::to_string(::getpid()));
  name.append("-").append(std::to_string(counter++)).append(file.extension().string());
  return folder / name;
}

thread_local OutputBatch* current_batch = nullptr;

}  // namespace

OutputBatch::OutputBatch() : previous_(current_batch) { current_batch = this; }

OutputBatch::~OutputBatch() {
  current_batch = previous_;
  std::error_code ec;
  for (const auto& [temporary, target] : pending_) std::filesystem::remove(temporary, ec);
}

void OutputBatch::commit() {
  std::error_code ec;
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    std::filesystem::rename(pending_[i].first, pending_[i].second, ec);
    if (ec) {
      pending_.erase(pending_.begin(), pending_.begin() + std::ptrdiff_t(i));
      throw Error(pending_.front().second.string(), "cannot write: " + ec.message());
    }
  }
  pending_.clear();
}

void write_atomically(const std::filesystem::path& file, const std::string& what,
                      const std::function<std::string(const std::filesystem::path&)>& write) {
  const std::filesystem::path folder = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
  if (!std::filesystem::is_directory(folder)) throw Error(file.string(), "folder does not exist: " + folder.string());
  const std::filesystem::path temporary = temporary_for(file);
  std::string message;
  try {
    message = write(temporary);
  } catch (const std::exception& e) {
    message = e.what();
  }
  std::error_code ec;
  if (message.empty() && current_batch) {
    current_batch->pending_.emplace_back(temporary, file);
    return;
  }
  if (message.empty()) {
    std::filesystem::rename(temporary, file, ec);
    if (!ec) return;
    message = ec.message();
  }
  std::filesystem::remove(temporary, ec);
  throw Error(file.string(), "cannot write " + what + ": " + message);
}

void write_image_file(const std::filesystem::path& file, const OIIO::ImageSpec& spec, OIIO::TypeDesc format,
                      const void* data, const std::string& what) {
  // Same pixels, same bytes: OpenImageIO 2.4 stamps EXR (capDate) and TIFF (tag 306) files with the current time
  // when the spec has no DateTime; an empty DateTime is written as an empty string instead. A caller that wants a
  // time in the file sets DateTime itself (write_frame's WriteOptions::timestamp).
  OIIO::ImageSpec stamped = spec;
  if (!spec.find_attribute("DateTime")) stamped.attribute("DateTime", "");
  write_atomically(file, what, [&](const std::filesystem::path& temporary) -> std::string {
    auto output = OIIO::ImageOutput::create(temporary.string());
    if (!output) return OIIO::geterror();
    if (output->open(temporary.string(), stamped) && output->write_image(format, data) && output->close()) return "";
    const std::string message = output->geterror();
    return message.empty() ? "unknown error" : message;
  });
}

void write_text_file(const std::filesystem::path& file, const std::string& text) {
  write_atomically(file, "file", [&](const std::filesystem::path& temporary) -> std::string {
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    return out.flush() ? "" : "write failed";
  });
}

}  // namespace qdmr
