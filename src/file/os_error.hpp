#pragma once
// An error of the operating system (std::filesystem) in qdmr's one-line form: "FILE: cannot OPERATION: REASON",
// instead of the library's "filesystem error: cannot OPERATION: REASON [FILE]".
#include <filesystem>
#include <string>

namespace qdmr {

std::string os_error_line(const std::filesystem::filesystem_error& e);

}  // namespace qdmr
