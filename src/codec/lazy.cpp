// The `qdmr` command's image backend: libqdmr_imageio.so, loaded on the first image read or write, so that
// commands and jobs that touch no image file never load OpenImageIO (see backend.hpp). Looked for at
// $QDMR_IMAGEIO_MODULE, beside the executable (a build tree), then where `cmake --install` puts it relative to
// the executable (QDMR_IMAGEIO_RELATIVE_DIR, e.g. ../lib/qdmr); then the same beside the shared object holding
// this code, when that is not the executable (the Python module qdmr, which keeps a copy beside itself).
#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <vector>

#include "codec/backend.hpp"
#include "qdmr/core/error.hpp"

namespace qdmr::imageio {
namespace {

constexpr const char* kModule = "libqdmr_imageio.so";

const Backend& load() {
  std::vector<std::filesystem::path> candidates;
  if (const char* forced = std::getenv("QDMR_IMAGEIO_MODULE"); forced && *forced) {
    candidates.emplace_back(forced);
  } else {
    std::vector<std::filesystem::path> binaries;
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) binaries.push_back(exe);
    // A shared object holding this code (the Python module): dladdr names it (for an executable, argv[0]).
    Dl_info info{};
    if (dladdr(reinterpret_cast<const void*>(&load), &info) != 0 && info.dli_fname && *info.dli_fname) {
      const std::filesystem::path binary = std::filesystem::canonical(info.dli_fname, ec);
      if (!ec && binary != exe) binaries.push_back(binary);
    }
    for (const std::filesystem::path& binary : binaries) {
      candidates.push_back(binary.parent_path() / kModule);
      candidates.push_back(binary.parent_path() / QDMR_IMAGEIO_RELATIVE_DIR / kModule);
    }
  }
  std::string tried, last_error = "not found";
  for (const std::filesystem::path& path : candidates) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
      tried += (tried.empty() ? "" : ", ") + path.string();
      continue;
    }
    if (void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)) {
      using Entry = const Backend* (*)();
      if (const auto entry = reinterpret_cast<Entry>(dlsym(module, "qdmr_imageio_backend_v1"))) return *entry();
      last_error = path.string() + " has no qdmr_imageio_backend_v1";
    } else {
      const char* message = dlerror();
      last_error = message ? message : "dlopen failed";
    }
    tried += (tried.empty() ? "" : ", ") + path.string();
  }
  throw FileError("image I/O", std::string("cannot load ") + kModule + " (" + last_error + "; looked at " + tried +
                               "; set QDMR_IMAGEIO_MODULE to its path)");
}

}  // namespace

const Backend& backend() {
  static const Backend& loaded = load();  // thread-safe, once; a failure is retried by the next call
  return loaded;
}

}  // namespace qdmr::imageio
