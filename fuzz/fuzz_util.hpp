#pragma once
// Shared by the libFuzzer harnesses: a private temporary folder per process, and the rule that qdmr::Error is
// the only acceptable way to fail (any other exception escapes and libFuzzer reports it as a crash: the qdmr
// command would exit 1 for it, not 2).
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace qdmr::fuzz {

inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "qdmr_fuzz_XXXXXX").string();
    if (!::mkdtemp(pattern.data())) std::abort();
    return std::filesystem::path(pattern);
  }();
  return dir;
}

inline std::filesystem::path write(const std::string& name, const char* data, std::size_t size) {
  const std::filesystem::path file = scratch() / name;
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(data, std::streamsize(size));
  if (!out.flush()) std::abort();
  return file;
}

}  // namespace qdmr::fuzz
