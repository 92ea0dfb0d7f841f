// libFuzzer harness: a glTF 2.0 asset through the loader the renderer uses (mesh_detail::load_gltf: qdmr's
// checks, then tinygltf behind its file and image callbacks, then the accessor checks). The input is the asset:
// a .glb when it starts with "glTF", else .gltf JSON text. Beside it in the folder: "b.bin" (256 bytes) and
// "i.png" (a valid 2x2 PNG), which the seeds name, so external buffers and images are reached too.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.hpp"
#include "mesh/builders.hpp"
#include "qdmr/core/error.hpp"

namespace {

// A 2x2 RGB PNG.
constexpr unsigned char kPng[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00,
    0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x02, 0x00, 0x00, 0x00, 0xfd, 0xd4, 0x9a, 0x73, 0x00, 0x00, 0x00, 0x12, 0x49,
    0x44, 0x41, 0x54, 0x78, 0xda, 0x63, 0xf8, 0xcf, 0xc0, 0xc0, 0x00, 0xc2, 0x0c, 0xff, 0x81, 0x00, 0x00, 0x1f, 0xee,
    0x05, 0xfb, 0xf1, 0xab, 0xba, 0x77, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};

const bool kSideFiles = [] {
  const std::string bin(256, '\0');
  qdmr::fuzz::write("b.bin", bin.data(), bin.size());
  qdmr::fuzz::write("i.png", reinterpret_cast<const char*>(kPng), sizeof kPng);
  // Embedded images go to the cache folder: keep it inside the scratch folder.
  setenv("QDMR_CACHE_DIR", (qdmr::fuzz::scratch() / "cache").c_str(), 1);
  return true;
}();

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static_cast<void>(kSideFiles);
  const bool binary = size >= 4 && std::string(reinterpret_cast<const char*>(data), 4) == "glTF";
  qdmr::MeshDesc desc;
  desc.kind = qdmr::MeshKind::Gltf;
  desc.file = qdmr::fuzz::write(binary ? "model.glb" : "model.gltf", reinterpret_cast<const char*>(data), size);
  try {
    static_cast<void>(qdmr::mesh_detail::load_gltf(desc, "fuzz"));
  } catch (const qdmr::Error&) {
  }
  return 0;
}
