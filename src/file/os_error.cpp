#include "file/os_error.hpp"

#include <string_view>

namespace qdmr {

std::string os_error_line(const std::filesystem::filesystem_error& e) {
  // The operation is what() between libstdc++'s "filesystem error: " and ": REASON"; the reason is the code's.
  std::string_view what = e.what();
  const std::string reason = e.code().message();
  if (what.starts_with("filesystem error: ")) what.remove_prefix(std::string_view("filesystem error: ").size());
  const std::size_t end = what.find(": " + reason);
  std::string operation(what.substr(0, end == std::string_view::npos ? what.find(" [") : end));
  if (operation.empty() || operation == reason) operation = "file system operation failed";
  std::string line = e.path1().empty() ? std::string("qdmr") : e.path1().string();
  line.append(": ").append(operation).append(": ").append(reason);
  if (!e.path2().empty()) line.append(" (and ").append(e.path2().string()).append(")");
  return line;
}

}  // namespace qdmr
