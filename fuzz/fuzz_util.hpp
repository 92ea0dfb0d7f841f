#pragma once
// Shared by the libFuzzer harnesses: a private temporary folder per process, and the rule that qdmr::Error is
// the only acceptable way to fail (any other exception escapes and libFuzzer reports it as a crash: the qdmr
// command would exit 1 for it, not 2).
//
// The folder is in memory (/dev/shm, a tmpfs, when it is there; else $TMPDIR): the harnesses write their input
// to a real file for every execution, so that the file checks are exercised as the command runs them, and on a
// disk file system rewriting a file makes close() wait for the data to reach the disk (ext4's auto_da_alloc):
// a third of the time of fuzz_scene went there.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace qdmr::fuzz {

inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    std::error_code ec;
    const std::filesystem::path base = std::filesystem::is_directory("/dev/shm", ec) && ::access("/dev/shm", W_OK) == 0
                                           ? std::filesystem::path("/dev/shm")
                                           : std::filesystem::temp_directory_path();
    std::string pattern = (base / "qdmr_fuzz_XXXXXX").string();
    if (!::mkdtemp(pattern.data())) std::abort();
    return std::filesystem::path(pattern);
  }();
  // Removed at a normal exit (registered after `dir` is built, so it runs before `dir` is destroyed); a crash
  // leaves it for the reproducer's investigation.
  static const bool cleanup = (std::atexit([] {
                                 std::error_code ec;
                                 std::filesystem::remove_all(scratch(), ec);
                               }) == 0);
  static_cast<void>(cleanup);
  return dir;
}

inline std::filesystem::path write(const std::string& name, const char* data, std::size_t size) {
  const std::filesystem::path file = scratch() / name;
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(data, std::streamsize(size));
  if (!out.flush()) std::abort();
  return file;
}

// A small valid scene, written once as scratch()/"scene.json", for the harnesses whose input names a scene
// (check manifests, study specs). Its materials are those the seeds' pointers name ("bricks", "surface"), all
// procedural: loading it reads no other file.
inline constexpr const char* kBaseScene = R"({
  "output": {"width": 64, "height": 48},
  "camera": {"position": [0, -2, 1.5], "target": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 50},
  "lights": [{"type": "directional", "direction": [0, -1, 1]}, {"type": "ambient", "intensity": 0.2}],
  "materials": {
    "bricks": {"layers": [{"height": {"procedural": "bricks", "size": 64, "cells": 4}, "normal": "from_height"}],
               "technique": {"name": "qdm", "depth_scale": 0.05}},
    "surface": {"layers": [{"height": {"procedural": "noise", "size": 64}, "normal": "from_height"}],
                "technique": {"name": "pom"}}
  },
  "objects": [{"mesh": {"type": "plane"}, "material": "bricks"}, {"mesh": {"type": "sphere"}, "material": "surface"}]
})";

inline const std::filesystem::path& base_scene() {
  static const std::filesystem::path file = [] {
    const std::string text = kBaseScene;
    return write("scene.json", text.data(), text.size());
  }();
  return file;
}

}  // namespace qdmr::fuzz
