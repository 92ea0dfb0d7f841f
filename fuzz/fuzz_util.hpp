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
