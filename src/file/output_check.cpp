#include "file/output_check.hpp"

#include <sys/stat.h>

#include "file/input_file.hpp"
#include "qdmr/core/error.hpp"

namespace qdmr {

void check_outputs(const std::vector<OutputPath>& outputs) {
  namespace fs = std::filesystem;
  const std::vector<KnownInput> inputs = known_inputs();
  struct Resolved {
    fs::path canonical;
    bool exists = false;
    FileIdentity id;
  };
  std::vector<Resolved> resolved;
  for (const OutputPath& out : outputs) {
    const std::string where = out.option + " " + out.path.string();
    const fs::path folder = out.path.parent_path().empty() ? fs::path(".") : out.path.parent_path();
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) throw FileError(where, "folder does not exist: " + folder.string());
    Resolved r;
    r.canonical = fs::weakly_canonical(fs::absolute(out.path), ec);
    if (ec) r.canonical = fs::absolute(out.path).lexically_normal();
    struct stat st {};
    if (::stat(out.path.c_str(), &st) == 0) {
      r.exists = true;
      r.id = {st.st_dev, st.st_ino};
      if (!S_ISREG(st.st_mode)) {
        throw FileError(where, non_regular_reason(out.path) + "; an output must be a regular file or a new name");
      }
      for (const KnownInput& input : inputs)
        if (input.id == r.id)
          throw FileError(where, "refusing to overwrite an input of this job: " + input.path.string());
    } else {
      for (const KnownInput& input : inputs) {
        std::error_code ignored;
        if (fs::weakly_canonical(fs::absolute(input.path), ignored) == r.canonical)
          throw FileError(where, "refusing to overwrite an input of this job: " + input.path.string());
      }
    }
    for (std::size_t i = 0; i < resolved.size(); ++i)
      if (resolved[i].canonical == r.canonical || (r.exists && resolved[i].exists && resolved[i].id == r.id))
        throw FileError(where, "is the same file as " + outputs[i].option + " " + outputs[i].path.string() +
                               " (every output needs its own file)");
    resolved.push_back(r);
  }
}

}  // namespace qdmr
