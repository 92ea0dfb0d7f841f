#pragma once
// Outputs never destroy inputs: before anything is written, every output path of a job is resolved (symlinks,
// "..", hard links through device and inode) and refused when it is an input of the job (every file read so
// far, see file/input_file.hpp) or another output of the same job, or when something other than a regular file
// (a directory, FIFO, device, socket) is in its place.
#include <filesystem>
#include <string>
#include <vector>

namespace qdmr {

struct OutputPath {
  std::string option;  // "-o", "--aov", "--stats": how the message names it
  std::filesystem::path path;
};

// Throws qdmr::Error("<option> <path>", what) for the first output that may not be written.
void check_outputs(const std::vector<OutputPath>& outputs);

}  // namespace qdmr
