// libFuzzer harness: an OBJ file and its MTL file through the loader the renderer uses
// (mesh_detail::load_obj, tinyobjloader behind qdmr's checks). Input: the OBJ text, optionally followed by a
// line "#MTL" and the text of "m.mtl" (which the OBJ can name with "mtllib m.mtl").
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.hpp"
#include "mesh/builders.hpp"
#include "qdmr/core/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::size_t split = text.find("\n#MTL\n");
  const std::string obj = text.substr(0, split);
  const std::string mtl = split == std::string::npos ? std::string() : text.substr(split + 6);
  qdmr::MeshDesc desc;
  desc.kind = qdmr::MeshKind::Obj;
  desc.file = qdmr::fuzz::write("model.obj", obj.data(), obj.size());
  qdmr::fuzz::write("m.mtl", mtl.data(), mtl.size());
  try {
    static_cast<void>(qdmr::mesh_detail::load_obj(desc, "fuzz"));
  } catch (const qdmr::Error&) {
  }
  return 0;
}
