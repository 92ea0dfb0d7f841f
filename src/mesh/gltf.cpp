// glTF 2.0 (.gltf and .glb) through tinygltf, behind qdmr's own checks: the container and every URI are checked
// before tinygltf parses (mesh/gltf_files.hpp), tinygltf reads only files inside the asset's folder through the
// callbacks here, decodes no image (qdmr's readers do, from the file or from the embedded bytes stored in the
// cache folder), and every accessor, buffer view and index is checked here before it is read.
#include <tiny_gltf.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <memory>
#include <span>
#include <set>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>

#include "file/atomic_file.hpp"
#include "file/input_file.hpp"
#include "mesh/builders.hpp"
#include "mesh/gltf_files.hpp"
#include "mesh/mikktspace.hpp"
#include "mesh/to_frame.hpp"
#include "qdmr/bake/bake_cache.hpp"
#include "qdmr/bake/cone_map.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/texture/image.hpp"
#include "scene/reader.hpp"
#include "core/sha1.hpp"

namespace qdmr::mesh_detail {

namespace fs = std::filesystem;

namespace {

// The extensions qdmr reads; an asset that requires any other is refused.
const std::set<std::string> kSupportedExtensions = {"KHR_texture_transform", "KHR_materials_emissive_strength"};

// glTF is +Y up, qdmr +Z up: a quarter turn about X, (x, y, z) -> (x, -z, y), as Blender imports glTF. Its entries
// are exactly 0 and +-1, so a vertex is moved without rounding.
const glm::dmat4 kZUp(1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1);

// Where a buffer's bytes are: in a file (the .glb's BIN chunk, or a .bin beside the asset), read an accessor at a
// time, or in memory (a data: URI, which tinygltf decodes).
struct BufferSource {
  std::uint64_t size = 0;
  const InputFile* file = nullptr;
  std::uint64_t offset = 0;  // of the buffer's first byte in `file`
  const unsigned char* memory = nullptr;
};

// What the file callbacks and the image callback share with the loader.
struct Reading {
  fs::path folder;                       // the asset's folder, lexically normal and absolute
  std::string where;                     // for messages
  std::set<fs::path> image_files;        // external images: checked, never read by tinygltf
  std::string error;                     // the first qdmr error raised inside a callback
  Error::Kind error_kind = Error::Kind::Value;  // ... and its kind
  std::vector<std::string> embedded;     // per image: its bytes when stored in a data: URI
  std::map<int, int> image_views;        // image -> the buffer view that holds it (not handed to tinygltf)
  // The asset's files that hold buffers, open (the .glb first), and per buffer where its bytes are: tinygltf gets a
  // one-byte stand-in for each buffer in a file, so no buffer is ever held whole.
  std::map<fs::path, std::unique_ptr<InputFile>> files;
  std::vector<BufferSource> buffers;
};

bool inside(const Reading& r, const fs::path& file) {
  const fs::path normal = file.lexically_normal();
  const auto [a, b] = std::mismatch(r.folder.begin(), r.folder.end(), normal.begin(), normal.end());
  return a == r.folder.end() && b != normal.end();
}

bool file_exists(const std::string& file, void* user) {
  const auto& r = *static_cast<Reading*>(user);
  return inside(r, file) && non_regular_reason(file).empty();
}

std::string expand_file_path(const std::string& file, void*) { return file; }  // never a shell expansion

bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& file, void* user) {
  auto& r = *static_cast<Reading*>(user);
  try {
    if (!inside(r, file)) throw Error(r.where, "refused to read " + shown_path(file) + ": outside the asset's folder");
    const fs::path path = fs::path(file).lexically_normal();
    if (r.image_files.count(path)) {
      // Checked now, decoded later by qdmr's image readers: tinygltf gets one placeholder byte.
      check_input_file(path, r.where, InputKind::Image);
      out->assign(1, 0);
      return true;
    }
    const std::string bytes = read_input_file(path, r.where, InputKind::GltfBuffer);
    out->assign(bytes.begin(), bytes.end());
    return true;
  } catch (const Error& e) {
    if (r.error.empty()) {
      r.error = e.what();
      r.error_kind = e.kind();
    }
    if (err) *err += e.what();
    return false;
  }
}

bool write_whole_file(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "qdmr writes no glTF files";
  return false;
}

// tinygltf hands over the bytes of an image in a data: URI (and one placeholder byte for an external one; an image
// in a buffer view is not handed to tinygltf, see Reading::image_views).
bool keep_image(tinygltf::Image* image, const int index, std::string* err, std::string*, int, int,
                const unsigned char* bytes, int size, void* user) {
  auto& r = *static_cast<Reading*>(user);
  const std::string at = r.where + ": /images/" + std::to_string(index);
  if (!image->uri.empty()) return true;  // external: read from its file
  if (size <= 0) {
    if (r.error.empty()) r.error = at + ": the image is empty";
    if (err) *err += "the image is empty";
    return false;
  }
  if (std::size_t(index) >= r.embedded.size()) r.embedded.resize(std::size_t(index) + 1);
  r.embedded[std::size_t(index)].assign(reinterpret_cast<const char*>(bytes), std::size_t(size));
  return true;
}

// The file an embedded image is read from: its bytes stored once in the cache folder under their SHA-1 (the
// same bytes, the same file: plans, keys and caches see a stable path).
fs::path store_embedded_image(const std::string& bytes, const std::string& where) {
  const bool png = bytes.size() >= 8 && std::memcmp(bytes.data(), "\x89PNG\r\n\x1a\n", 8) == 0;
  const bool jpeg = bytes.size() >= 3 && std::memcmp(bytes.data(), "\xff\xd8\xff", 3) == 0;
  if (!png && !jpeg) throw Error(where, "an embedded image must be PNG or JPEG (glTF's image formats)");
  const fs::path file = default_cache_dir() / ("gltf-image-" + sha1_hex(bytes.data(), bytes.size()) + (png ? ".png" : ".jpg"));
  std::error_code ec;
  if (fs::is_regular_file(file, ec) && fs::file_size(file, ec) == bytes.size()) {
    std::ifstream in(file, std::ios::binary);
    std::string stored(bytes.size(), '\0');
    if (in.read(stored.data(), std::streamsize(stored.size())) && stored == bytes) {
      touch_bake_cache_entry(file);  // recently used: evicted last (qdmr/bake/bake_cache.hpp)
      return file;
    }
  }
  fs::create_directories(file.parent_path(), ec);
  write_atomically(file, "embedded glTF image", [&](const fs::path& temporary) -> std::string {
    std::ofstream out(temporary, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    return out.flush() ? "" : "write failed";
  });
  return file;
}

// One accessor's elements, checked against its buffer view and buffer.
struct Elements {
  const BufferSource* source = nullptr;
  std::uint64_t first = 0;  // the first element's byte in its buffer
  std::size_t count = 0, stride = 0, bytes = 0;  // bytes: of one element
  int components = 0, component_type = 0;
  bool normalized = false;
};

class Asset {
public:
  Asset(const tinygltf::Model& model, const std::vector<BufferSource>& buffers, std::string where)
      : model_(model), buffers_(buffers), where_(std::move(where)) {}

  [[noreturn]] void fail(const std::string& pointer, const std::string& what) const {
    throw Error(where_ + ": " + pointer, what);
  }

  Elements elements(int index, const std::string& pointer, std::initializer_list<int> types,
                    std::initializer_list<int> component_types) const {
    if (index < 0 || std::size_t(index) >= model_.accessors.size())
      fail(pointer, "accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& a = model_.accessors[std::size_t(index)];
    const std::string at = "/accessors/" + std::to_string(index);
    if (a.sparse.isSparse) fail(at + "/sparse", "sparse accessors are not supported");
    if (std::find(types.begin(), types.end(), a.type) == types.end())
      fail(at + "/type", "this attribute cannot be of this type");
    if (std::find(component_types.begin(), component_types.end(), a.componentType) == component_types.end())
      fail(at + "/componentType", std::to_string(a.componentType) + " is not a component type this attribute may have");
    if (a.bufferView < 0) fail(at, "has no bufferView (an accessor of zeros is not supported)");
    if (std::size_t(a.bufferView) >= model_.bufferViews.size())
      fail(at + "/bufferView", "buffer view " + std::to_string(a.bufferView) + " does not exist");
    const tinygltf::BufferView& view = model_.bufferViews[std::size_t(a.bufferView)];
    const std::string view_at = "/bufferViews/" + std::to_string(a.bufferView);
    const BufferSource* source = view_source(view, view_at);
    Elements e;
    e.components = tinygltf::GetNumComponentsInType(std::uint32_t(a.type));
    const int size = tinygltf::GetComponentSizeInBytes(std::uint32_t(a.componentType));
    e.bytes = std::size_t(e.components) * std::size_t(size);
    e.stride = view.byteStride ? view.byteStride : e.bytes;
    if (e.stride < e.bytes)
      fail(view_at + "/byteStride", std::to_string(e.stride) + " is less than an element (" + std::to_string(e.bytes) +
                                        " bytes): the elements overlap");
    if (a.count == 0) fail(at + "/count", "must be at least 1");
    if (a.byteOffset > view.byteLength || a.count > view.byteLength ||
        (a.count - 1) * e.stride + e.bytes > view.byteLength - a.byteOffset || e.stride > view.byteLength)
      fail(at + "/count", std::to_string(a.count) + " elements of " + std::to_string(e.bytes) + " bytes every " +
                              std::to_string(e.stride) + " from byte " + std::to_string(a.byteOffset) +
                              " do not fit buffer view " + std::to_string(a.bufferView) + " (" +
                              std::to_string(view.byteLength) + " bytes)");
    e.source = source;
    e.first = view.byteOffset + a.byteOffset;
    e.count = a.count;
    e.component_type = a.componentType;
    e.normalized = a.normalized;
    return e;
  }

  // The buffer of a view, which the view must fit.
  const BufferSource* view_source(const tinygltf::BufferView& view, const std::string& view_at) const {
    if (view.buffer < 0 || std::size_t(view.buffer) >= buffers_.size())
      fail(view_at + "/buffer", "buffer " + std::to_string(view.buffer) + " does not exist");
    const BufferSource& source = buffers_[std::size_t(view.buffer)];
    if (view.byteOffset > source.size || view.byteLength > source.size - view.byteOffset)
      fail(view_at, "bytes " + std::to_string(view.byteOffset) + " + " + std::to_string(view.byteLength) +
                        " run past the end of buffer " + std::to_string(view.buffer) + " (" + std::to_string(source.size) +
                        " bytes)");
    return &source;
  }

  // `n` bytes of a buffer from `offset` (checked to be inside it) into `out`.
  static void read(const BufferSource& source, std::uint64_t offset, std::size_t n, unsigned char* out) {
    if (source.file) {
      source.file->read(source.offset + offset, n, out);
    } else {
      std::memcpy(out, source.memory + offset, n);
    }
  }

  // visit(element bytes, i) for every element in order; a file is read a block of elements at a time, so no
  // accessor is held whole beside what it becomes.
  template <class Visit>
  void for_each_element(const Elements& e, Visit&& visit) const {
    if (!e.source->file) {
      for (std::size_t i = 0; i < e.count; ++i) visit(e.source->memory + e.first + i * e.stride, i);
      return;
    }
    const std::size_t per_block = std::max<std::size_t>(1, kBlockBytes / e.stride);
    for (std::size_t first = 0; first < e.count; first += per_block) {
      const std::size_t n = std::min(per_block, e.count - first);
      block_.resize((n - 1) * e.stride + e.bytes);
      read(*e.source, e.first + first * e.stride, block_.size(), block_.data());
      for (std::size_t k = 0; k < n; ++k) visit(block_.data() + k * e.stride, first + k);
    }
  }

  // Every component as float (float, or a normalised unsigned byte or short), into set(i, components).
  template <class Set>
  void floats(const Elements& e, int index, Set&& set) const {
    if (e.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT && !e.normalized)
      fail("/accessors/" + std::to_string(index) + "/normalized", "integer texture coordinates must be normalized");
    const int components = std::min(e.components, 4);  // VEC2, VEC3 or VEC4
    for_each_element(e, [&](const unsigned char* p, std::size_t i) {
      float v[4] = {0.0f, 0.0f, 0.0f, 0.0f};
      for (int c = 0; c < components; ++c) {
        if (e.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT) {
          std::memcpy(&v[c], p + 4 * c, 4);
          if (!std::isfinite(v[c])) fail("/accessors/" + std::to_string(index), "element " + std::to_string(i) + " is not finite");
        } else if (e.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
          v[c] = float(p[c]) / 255.0f;
        } else {
          std::uint16_t s = 0;
          std::memcpy(&s, p + 2 * c, 2);
          v[c] = float(s) / 65535.0f;
        }
      }
      set(i, v);
    });
  }

  // The elements as floats into out[components i + c] (`components`: the accessor's, at most 4): floats stored one
  // after the other are read straight into `out` and then checked (on threads; the first that is not finite is
  // named, as floats() names it), any other layout through floats().
  void float_array(const Elements& e, int index, float* out) const {
    const auto components = std::size_t(std::min(e.components, 4));
    if (e.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT || e.stride != e.bytes || e.bytes != 4 * components) {
      floats(e, index, [&](std::size_t i, const float* v) { std::copy(v, v + components, out + components * i); });
      return;
    }
    read(*e.source, e.first, e.count * e.bytes, reinterpret_cast<unsigned char*>(out));
    // Float by float: one is not finite where its exponent's bits are all set.
    const std::size_t bad = first_where(components * e.count, [&](std::size_t j) {
      std::uint32_t bits = 0;
      std::memcpy(&bits, out + j, 4);
      return (bits & 0x7f800000u) == 0x7f800000u;
    }) / components;
    if (bad < e.count) fail("/accessors/" + std::to_string(index), "element " + std::to_string(bad) + " is not finite");
  }

  // The smallest i < count for which bad(i), else count; on threads. Blocks of kCheckBlock are first asked whether
  // any i is bad, without stopping at one (a loop the compiler vectorises); a block where one is, is searched.
  template <class Bad>
  static std::size_t first_where(std::size_t count, Bad&& bad) {
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count, kCheckGrain), count,
        [&](const tbb::blocked_range<std::size_t>& r, std::size_t found) {
          for (std::size_t lo = r.begin(); lo < r.end() && lo < found; lo += kCheckBlock) {
            const std::size_t hi = std::min(r.end(), lo + kCheckBlock);
            unsigned any = 0;
            for (std::size_t i = lo; i < hi; ++i) any |= unsigned(bad(i));
            if (any)
              for (std::size_t i = lo;; ++i)
                if (bad(i)) return std::min(i, found);
          }
          return found;
        },
        [](std::size_t a, std::size_t b) { return std::min(a, b); });
  }

  // The elements of a float attribute (of one type; `normalized_ok`: also normalised unsigned bytes or shorts).
  Elements float_elements(int index, const std::string& pointer, int type, bool normalized_ok) const {
    return normalized_ok ? elements(index, pointer, {type}, {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                                             TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT})
                         : elements(index, pointer, {type}, {TINYGLTF_COMPONENT_TYPE_FLOAT});
  }

  Elements index_elements(int index, const std::string& pointer) const {
    return elements(index, pointer, {TINYGLTF_TYPE_SCALAR},
                    {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                     TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT});
  }

  // The indices, each checked against the vertex count, into out[0, e.count).
  void indices(const Elements& e, int index, std::size_t vertices, std::uint32_t* out) const {
    const auto past = [&](std::size_t i, std::uint32_t v) {
      fail("/accessors/" + std::to_string(index), "index " + std::to_string(i) + " is " + std::to_string(v) +
                                                      ", past the primitive's " + std::to_string(vertices) + " vertices");
    };
    if (e.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT && e.stride == 4) {
      // 32-bit indices one after the other: read straight into `out`, then checked on threads.
      read(*e.source, e.first, 4 * e.count, reinterpret_cast<unsigned char*>(out));
      const std::size_t bad = first_where(e.count, [&](std::size_t i) { return out[i] >= vertices; });
      if (bad < e.count) past(bad, out[bad]);
      return;
    }
    for_each_element(e, [&](const unsigned char* p, std::size_t i) {
      std::uint32_t v = 0;
      if (e.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
        v = p[0];
      } else if (e.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
        std::uint16_t s = 0;
        std::memcpy(&s, p, 2);
        v = s;
      } else {
        std::memcpy(&v, p, 4);
      }
      if (v >= vertices) past(i, v);
      out[i] = v;
    });
  }

private:
  static constexpr std::size_t kBlockBytes = std::size_t(64) << 10;
  static constexpr std::size_t kCheckGrain = 16384;  // elements a task checks
  static constexpr std::size_t kCheckBlock = 512;    // elements checked before a hit is looked for
  const tinygltf::Model& model_;
  const std::vector<BufferSource>& buffers_;
  std::string where_;
  mutable std::vector<unsigned char> block_;  // the block of a file being read
};

glm::dmat4 local_matrix(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) {
    glm::dmat4 m;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[std::size_t(c * 4 + r)];
    return m;
  }
  glm::dmat4 m(1.0);
  if (node.translation.size() == 3) m = glm::translate(m, glm::dvec3(node.translation[0], node.translation[1], node.translation[2]));
  if (node.rotation.size() == 4)
    m = m * glm::mat4_cast(glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]));
  if (node.scale.size() == 3) m = glm::scale(m, glm::dvec3(node.scale[0], node.scale[1], node.scale[2]));
  return m;
}

struct TextureChoice {
  const tinygltf::TextureInfo* base = nullptr;  // the texture whose UV set and transform the material uses
  int tex_coord = 0;
  glm::dvec2 offset{0.0}, scale{1.0};
  double rotation = 0.0;
};

double number_or(const tinygltf::Value& object, const char* key, double fallback) {
  if (!object.IsObject() || !object.Has(key)) return fallback;
  const tinygltf::Value& v = object.Get(key);
  return v.IsNumber() ? v.GetNumberAsDouble() : fallback;
}

// The transform (KHR_texture_transform) and UV set of one textureInfo.
TextureChoice choice_of(int index, int tex_coord, const tinygltf::ExtensionMap& extensions) {
  TextureChoice c;
  c.tex_coord = index >= 0 ? tex_coord : 0;
  if (const auto it = extensions.find("KHR_texture_transform"); it != extensions.end()) {
    const tinygltf::Value& t = it->second;
    if (t.Has("offset") && t.Get("offset").IsArray() && t.Get("offset").ArrayLen() == 2)
      c.offset = {t.Get("offset").Get(0).GetNumberAsDouble(), t.Get("offset").Get(1).GetNumberAsDouble()};
    if (t.Has("scale") && t.Get("scale").IsArray() && t.Get("scale").ArrayLen() == 2)
      c.scale = {t.Get("scale").Get(0).GetNumberAsDouble(), t.Get("scale").Get(1).GetNumberAsDouble()};
    c.rotation = number_or(t, "rotation", 0.0);
    if (t.Has("texCoord") && t.Get("texCoord").IsInt()) c.tex_coord = t.Get("texCoord").GetNumberAsInt();
  }
  return c;
}

bool same_choice(const TextureChoice& a, const TextureChoice& b) {
  return a.tex_coord == b.tex_coord && a.offset == b.offset && a.scale == b.scale && a.rotation == b.rotation;
}

Filter filter_of(int min_filter) {
  switch (min_filter) {
    case TINYGLTF_TEXTURE_FILTER_NEAREST: return Filter::Point;
    case TINYGLTF_TEXTURE_FILTER_LINEAR: return Filter::Bilinear;
    case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_NEAREST: return Filter::PointMipPoint;
    case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_LINEAR: return Filter::PointMipLinear;
    case TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_NEAREST: return Filter::LinearMipPoint;
    default: return Filter::Trilinear;
  }
}

AddressMode address_of(int wrap) {
  switch (wrap) {
    case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return AddressMode::Clamp;
    case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return AddressMode::Mirror;
    default: return AddressMode::Wrap;
  }
}

// Turns the asset into one MeshData: every primitive of the drawn nodes, in qdmr's frame.
class Builder {
public:
  Builder(tinygltf::Model& model, Reading& reading, const fs::path& file, std::string where,
          std::uint64_t max_memory_bytes)
      : model_(model), reading_(reading), file_(file), where_(std::move(where)), asset_(model, reading.buffers, where_),
        max_memory_bytes_(max_memory_bytes) {}

  MeshData build(const MeshDesc& desc) {
    check_nodes();
    const std::vector<int> roots = drawn_roots(desc);
    check_drawn_size(roots);
    count_buffer_reads(roots);
    // Every primitive is read straight into the mesh's arrays, reserved once (only the copies of vertices on
    // mirrored UV seams, which MikkTSpace makes, can grow them). The triangles' materials, written last, grow as
    // they come: a single primitive's then take the memory MikkTSpace worked in.
    mesh_.positions.reserve(reserve_vertices_);
    mesh_.normals.reserve(reserve_vertices_);
    mesh_.tangents.reserve(reserve_vertices_);
    mesh_.uvs.reserve(reserve_vertices_);
    mesh_.indices.reserve(3 * reserve_triangles_);
    for (std::size_t m = 0; m < model_.materials.size(); ++m) materials_.push_back(convert_material(int(m)));
    for (const int root : roots) visit(root, parent_world(root));
    if (mesh_.indices.empty()) throw Error(where_, "no triangles to draw in " + shown_path(file_));
    mesh_.materials = materials_;
    if (default_material_ >= 0) {
      MaterialDesc m = default_gltf_material();
      m.name = unique("default");
      mesh_.materials.push_back(m);
    }
    mesh_.bump_maps.assign(mesh_.materials.size(), fs::path());
    for (const auto& [what, n] : notes_) mesh_.notes.push_back(n > 1 ? what + " (" + std::to_string(n) + " times)" : what);
    return std::move(mesh_);
  }

private:
  void note(const std::string& what) {
    for (auto& [w, n] : notes_)
      if (w == what) {
        ++n;
        return;
      }
    notes_.emplace_back(what, 1);
  }

  // Every child index exists, no node has two parents, and the graph has no cycle.
  void check_nodes() {
    parent_.assign(model_.nodes.size(), -1);
    for (std::size_t n = 0; n < model_.nodes.size(); ++n)
      for (std::size_t k = 0; k < model_.nodes[n].children.size(); ++k) {
        const int child = model_.nodes[n].children[k];
        const std::string at = "/nodes/" + std::to_string(n) + "/children/" + std::to_string(k);
        if (child < 0 || std::size_t(child) >= model_.nodes.size())
          asset_.fail(at, "node " + std::to_string(child) + " does not exist");
        if (parent_[std::size_t(child)] >= 0)
          asset_.fail(at, "node " + std::to_string(child) + " has two parents (nodes " +
                              std::to_string(parent_[std::size_t(child)]) + " and " + std::to_string(n) + ")");
        parent_[std::size_t(child)] = int(n);
      }
    // With one parent each, a cycle is a chain of parents that comes back to where it started.
    std::vector<int> state(model_.nodes.size(), 0);  // 0 unknown, 1 on the current walk, 2 reaches a root
    for (std::size_t n = 0; n < model_.nodes.size(); ++n) {
      std::vector<std::size_t> walk;
      std::size_t at = n;
      while (state[at] == 0 && parent_[at] >= 0) {
        state[at] = 1;
        walk.push_back(at);
        at = std::size_t(parent_[at]);
      }
      if (state[at] == 1) asset_.fail("/nodes/" + std::to_string(at) + "/children", "the node graph has a cycle through node " + std::to_string(at));
      state[at] = 2;
      for (std::size_t w : walk) state[w] = 2;
    }
  }

  // A mesh drawn by several nodes is copied for each: the copies' size, from the accessors' counts (each at most
  // the bytes of its buffer view: a count that lies is refused later, by name), is bounded before anything is read,
  // by the triangle limit, by the memory limit (--max-memory) and by the machine's memory.
  // It also counts the vertices and triangles the mesh will have, if the asset is as it says.
  void check_drawn_size(const std::vector<int>& roots) {
    const auto count = [&](int accessor) -> std::uint64_t {
      if (accessor < 0 || std::size_t(accessor) >= model_.accessors.size()) return 0;
      const tinygltf::Accessor& a = model_.accessors[std::size_t(accessor)];
      const bool view = a.bufferView >= 0 && std::size_t(a.bufferView) < model_.bufferViews.size();
      return view ? std::min<std::uint64_t>(a.count, model_.bufferViews[std::size_t(a.bufferView)].byteLength) : 0;
    };
    std::uint64_t vertices = 0, corners = 0;
    for_each_drawn_primitive(roots, [&](const tinygltf::Primitive& prim) {
      const auto position = prim.attributes.find("POSITION");
      const std::uint64_t v = position == prim.attributes.end() ? 0 : count(position->second);
      const std::uint64_t c = prim.indices >= 0 ? count(prim.indices) : v;
      vertices += std::max(v, c);  // flat normals: one vertex per corner
      corners += c;
      const std::uint64_t triangles = prim.mode == TINYGLTF_MODE_TRIANGLES ? c / 3 : c >= 3 ? c - 2 : 0;
      reserve_vertices_ += prim.attributes.count("NORMAL") ? v : 3 * triangles;
      reserve_triangles_ += triangles;
      if (corners / 3 > limits::kMaxTriangles)
        throw Error(where_, "the drawn nodes hold more than " + std::to_string(limits::kMaxTriangles) +
                                " triangles (a mesh drawn by several nodes counts for each)");
    });
    // As the plan counts a mesh: position, normal, tangent, uv per vertex; three indices and a material per triangle.
    const std::uint64_t mesh_bytes = vertices * (3 + 3 + 4 + 2) * sizeof(float) + corners / 3 * 4 * sizeof(std::uint32_t);
    const auto mib = [](std::uint64_t b) { return std::to_string((b + (1u << 20) - 1) >> 20); };
    if (max_memory_bytes_ > 0 && mesh_bytes > max_memory_bytes_)
      throw Error(where_, "the drawn meshes (a mesh drawn by several nodes once per node) take " + mib(mesh_bytes) +
                              " MiB, more than the limit of " + std::to_string(max_memory_bytes_ >> 20) + " MiB");
    // Doubled for the copies made while reading.
    const std::uint64_t bytes = 2 * mesh_bytes;
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    if (pages > 0 && page > 0 && bytes > std::uint64_t(pages) * std::uint64_t(page))
      throw Error(where_, "the drawn meshes need " + std::to_string(bytes >> 20) +
                              " MiB while they are read, more than this machine's memory");
  }

  // The buffers a primitive reads (its attributes' and indices'; references that do not exist are refused when read).
  std::set<int> buffers_of(const tinygltf::Primitive& prim) const {
    std::set<int> buffers;
    const auto add = [&](int accessor) {
      if (accessor < 0 || std::size_t(accessor) >= model_.accessors.size()) return;
      const int view = model_.accessors[std::size_t(accessor)].bufferView;
      if (view >= 0 && std::size_t(view) < model_.bufferViews.size()) buffers.insert(model_.bufferViews[std::size_t(view)].buffer);
    };
    for (const auto& [name, accessor] : prim.attributes) add(accessor);
    add(prim.indices);
    return buffers;
  }

  // How many drawn primitives read each buffer (a mesh drawn by several nodes counts once per node), so that a
  // buffer in memory is released as soon as the last of them has read it (the materials' images are read before).
  void count_buffer_reads(const std::vector<int>& roots) {
    buffer_reads_.assign(model_.buffers.size(), 0);
    for_each_drawn_primitive(roots, [&](const tinygltf::Primitive& prim) {
      for (const int b : buffers_of(prim))
        if (b >= 0 && std::size_t(b) < buffer_reads_.size()) ++buffer_reads_[std::size_t(b)];
    });
  }

  // Every primitive of the nodes below `roots` (each node once: check_nodes), a mesh drawn by several nodes once
  // per node; mesh indices that do not exist are refused when visited.
  template <class Visit>
  void for_each_drawn_primitive(const std::vector<int>& roots, Visit&& visit_primitive) const {
    std::vector<int> stack(roots.begin(), roots.end());
    while (!stack.empty()) {
      const tinygltf::Node& node = model_.nodes[std::size_t(stack.back())];
      stack.pop_back();
      stack.insert(stack.end(), node.children.begin(), node.children.end());
      if (node.mesh < 0 || std::size_t(node.mesh) >= model_.meshes.size()) continue;
      for (const tinygltf::Primitive& prim : model_.meshes[std::size_t(node.mesh)].primitives) visit_primitive(prim);
    }
  }

  // A buffer tinygltf holds (a data: URI's) is released once the last drawn primitive has read it.
  void primitive_read(const tinygltf::Primitive& prim) {
    for (const int b : buffers_of(prim))
      if (b >= 0 && std::size_t(b) < buffer_reads_.size() && buffer_reads_[std::size_t(b)] > 0 &&
          --buffer_reads_[std::size_t(b)] == 0 && reading_.buffers[std::size_t(b)].memory) {
        reading_.buffers[std::size_t(b)] = BufferSource{};
        std::vector<unsigned char>().swap(model_.buffers[std::size_t(b)].data);
      }
  }

  std::vector<int> drawn_roots(const MeshDesc& desc) {
    const auto pick = [&](const GltfPick& p, std::size_t count, auto name_of, const char* what) -> int {
      if (p.index >= 0) {
        if (std::size_t(p.index) >= count)
          throw Error(where_, std::string("the asset has no ") + what + " " + std::to_string(p.index) + " (it has " +
                                  std::to_string(count) + ")");
        return p.index;
      }
      std::vector<std::string> names;
      for (std::size_t i = 0; i < count; ++i) {
        if (name_of(i) == p.name) return int(i);
        if (!name_of(i).empty()) names.push_back(name_of(i));
      }
      throw Error(where_, std::string("the asset has no ") + what + " named '" + scene_detail::shorten(p.name) + "'" +
                              scene_detail::suggestion(p.name, names, std::string("its ") + what + "s are"));
    };
    if (desc.gltf_node.given())
      return {pick(desc.gltf_node, model_.nodes.size(), [&](std::size_t i) { return model_.nodes[i].name; }, "node")};
    int scene = -1;
    if (desc.gltf_scene.given())
      scene = pick(desc.gltf_scene, model_.scenes.size(), [&](std::size_t i) { return model_.scenes[i].name; }, "scene");
    else if (model_.defaultScene >= 0 && std::size_t(model_.defaultScene) < model_.scenes.size())
      scene = model_.defaultScene;
    else if (model_.defaultScene >= 0)
      asset_.fail("/scene", "scene " + std::to_string(model_.defaultScene) + " does not exist");
    else if (!model_.scenes.empty())
      scene = 0;
    std::vector<int> roots;
    if (scene < 0) {  // no scene: every node without a parent
      for (std::size_t n = 0; n < model_.nodes.size(); ++n)
        if (parent_[n] < 0) roots.push_back(int(n));
      return roots;
    }
    const auto& nodes = model_.scenes[std::size_t(scene)].nodes;
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const std::string at = "/scenes/" + std::to_string(scene) + "/nodes/" + std::to_string(k);
      if (nodes[k] < 0 || std::size_t(nodes[k]) >= model_.nodes.size())
        asset_.fail(at, "node " + std::to_string(nodes[k]) + " does not exist");
      if (parent_[std::size_t(nodes[k])] >= 0) asset_.fail(at, "node " + std::to_string(nodes[k]) + " is not a root node");
      if (std::find(roots.begin(), roots.end(), nodes[k]) != roots.end())
        asset_.fail(at, "node " + std::to_string(nodes[k]) + " is listed twice");
      roots.push_back(nodes[k]);
    }
    return roots;
  }

  glm::dmat4 parent_world(int node) const {
    glm::dmat4 m = kZUp;
    std::vector<int> chain;
    for (int p = parent_[std::size_t(node)]; p >= 0; p = parent_[std::size_t(p)]) chain.push_back(p);
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) m = m * local_matrix(model_.nodes[std::size_t(*it)]);
    return m;
  }

  void visit(int root, const glm::dmat4& parent) {
    std::vector<std::pair<int, glm::dmat4>> stack{{root, parent}};
    while (!stack.empty()) {
      const auto [n, above] = stack.back();
      stack.pop_back();
      const tinygltf::Node& node = model_.nodes[std::size_t(n)];
      const std::string at = "/nodes/" + std::to_string(n);
      if (node.matrix.size() != 0 && node.matrix.size() != 16) asset_.fail(at + "/matrix", "must have 16 numbers");
      const glm::dmat4 world = above * local_matrix(node);
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
          if (!std::isfinite(world[c][r])) asset_.fail(at, "its transform is not finite");
      if (node.mesh >= 0) {
        if (std::size_t(node.mesh) >= model_.meshes.size()) asset_.fail(at + "/mesh", "mesh " + std::to_string(node.mesh) + " does not exist");
        if (node.skin >= 0) asset_.fail(at + "/skin", "skinned meshes cannot be drawn (qdmr draws rigid meshes)");
        add_mesh(node.mesh, world);
      }
      if (node.camera >= 0) add_camera(node.camera, world, at);
      for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.emplace_back(*it, world);
    }
  }

  void add_camera(int index, const glm::dmat4& world, const std::string& at) {
    if (std::size_t(index) >= model_.cameras.size()) asset_.fail(at + "/camera", "camera " + std::to_string(index) + " does not exist");
    const tinygltf::Camera& c = model_.cameras[std::size_t(index)];
    if (c.type != "perspective") {
      note("camera " + std::to_string(index) + " (" + c.type + ") ignored: only perspective cameras are read");
      return;
    }
    const std::string cat = "/cameras/" + std::to_string(index) + "/perspective";
    const double fov = c.perspective.yfov * 180.0 / 3.14159265358979323846;
    if (!(fov > 0.0 && fov < 180.0)) asset_.fail(cat + "/yfov", "must be between 0 and pi radians");
    if (!(c.perspective.znear > 0.0)) asset_.fail(cat + "/znear", "must be positive");
    if (c.perspective.zfar != 0.0 && !(c.perspective.zfar > c.perspective.znear)) asset_.fail(cat + "/zfar", "must exceed znear");
    CameraDesc camera;
    const glm::dvec3 position(world * glm::dvec4(0, 0, 0, 1));
    const glm::dvec3 forward = glm::normalize(glm::dvec3(world * glm::dvec4(0, 0, -1, 0)));
    const glm::dvec3 up = glm::normalize(glm::dvec3(world * glm::dvec4(0, 1, 0, 0)));
    if (!std::isfinite(forward.x + forward.y + forward.z + up.x + up.y + up.z) || glm::length(glm::cross(forward, up)) < 1e-6)
      asset_.fail(at, "the camera's transform has no view direction");
    camera.position = glm::vec3(position);
    camera.target = glm::vec3(position + forward);
    camera.up = glm::vec3(up);
    camera.fov_y_deg = float(fov);
    camera.near = float(c.perspective.znear);
    camera.far = c.perspective.zfar > 0.0 ? float(c.perspective.zfar) : std::max(1000.0f, camera.near * 1e4f);
    mesh_.cameras.push_back(camera);
  }

  int material_slot(int material, const std::string& at) {
    if (material < 0) {
      if (default_material_ < 0) default_material_ = int(materials_.size());
      return default_material_;
    }
    if (std::size_t(material) >= model_.materials.size()) asset_.fail(at + "/material", "material " + std::to_string(material) + " does not exist");
    return material;
  }

  void add_mesh(int index, const glm::dmat4& world) {
    const tinygltf::Mesh& gltf_mesh = model_.meshes[std::size_t(index)];
    const glm::dmat3 linear(world);
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
    const bool mirrored = glm::determinant(linear) < 0.0;
    for (std::size_t p = 0; p < gltf_mesh.primitives.size(); ++p) {
      const tinygltf::Primitive& prim = gltf_mesh.primitives[p];
      const std::string at = "/meshes/" + std::to_string(index) + "/primitives/" + std::to_string(p);
      if (prim.mode == TINYGLTF_MODE_POINTS) asset_.fail(at + "/mode", "points cannot be drawn (qdmr draws triangles)");
      if (prim.mode >= TINYGLTF_MODE_LINE && prim.mode <= TINYGLTF_MODE_LINE_STRIP)
        asset_.fail(at + "/mode", "lines cannot be drawn (qdmr draws triangles)");
      if (prim.mode < 0 || prim.mode > TINYGLTF_MODE_TRIANGLE_FAN) asset_.fail(at + "/mode", "unknown mode " + std::to_string(prim.mode));
      if (!prim.targets.empty()) asset_.fail(at + "/targets", "morph targets cannot be drawn");
      const auto attribute = [&](const std::string& name) {
        const auto it = prim.attributes.find(name);
        return it == prim.attributes.end() ? -1 : it->second;
      };
      Primitive in;
      in.mode = prim.mode;
      in.position_accessor = attribute("POSITION");
      if (in.position_accessor < 0) asset_.fail(at + "/attributes", "no POSITION");
      in.positions = asset_.float_elements(in.position_accessor, at + "/attributes/POSITION", TINYGLTF_TYPE_VEC3, false);
      const std::size_t count = in.positions.count;
      const auto same_count = [&](const Elements& e, const std::string& name) {
        if (e.count != count)
          asset_.fail(at + "/attributes/" + name, std::to_string(e.count) + " elements, but POSITION has " + std::to_string(count));
      };
      const int slot = material_slot(prim.material, at);
      in.uv_choice = slot < int(uv_choices_.size()) ? uv_choices_[std::size_t(slot)] : TextureChoice{};
      if (const int a = attribute("NORMAL"); a >= 0) {
        in.normal_accessor = a;
        in.normals = asset_.float_elements(a, at + "/attributes/NORMAL", TINYGLTF_TYPE_VEC3, false);
        same_count(in.normals, "NORMAL");
        if (const int t = attribute("TANGENT"); t >= 0) {
          in.tangent_accessor = t;
          in.tangents = asset_.float_elements(t, at + "/attributes/TANGENT", TINYGLTF_TYPE_VEC4, false);
          same_count(in.tangents, "TANGENT");
        }
      } else {
        note("flat normals generated (a primitive has no NORMAL)");
      }
      const std::string uv_name = "TEXCOORD_" + std::to_string(in.uv_choice.tex_coord);
      if (const int a = attribute(uv_name); a >= 0) {
        in.uv_accessor = a;
        in.uvs = asset_.float_elements(a, at + "/attributes/" + uv_name, TINYGLTF_TYPE_VEC2, true);
        same_count(in.uvs, uv_name);
      } else if (in.uv_choice.base) {
        asset_.fail(at + "/attributes", "no " + uv_name + ", which the material's textures use");
      }
      for (const auto& [name, accessor] : prim.attributes)
        if (name.starts_with("JOINTS_") || name.starts_with("WEIGHTS_")) note("skinning attributes ignored");

      in.corners = count;
      if (prim.indices >= 0) {
        in.index_accessor = prim.indices;
        in.indices = asset_.index_elements(prim.indices, at + "/indices");
        in.corners = in.indices.count;
      }
      if (prim.mode == TINYGLTF_MODE_TRIANGLES && in.corners % 3 != 0)
        asset_.fail(at, std::to_string(in.corners) + " corners are not whole triangles");
      if (prim.mode != TINYGLTF_MODE_TRIANGLES && in.corners < 3) asset_.fail(at, "a strip or fan needs at least 3 corners");
      in.triangles = prim.mode == TINYGLTF_MODE_TRIANGLES ? in.corners / 3 : in.corners - 2;
      check_triangle_count(mesh_.indices.size() / 3 + in.triangles, where_);
      if (in.normal_accessor >= 0) {
        add_smooth(in, world, normal_matrix, mirrored, std::uint32_t(slot));
      } else {
        add_flat(in, world, std::uint32_t(slot));
      }
      primitive_read(prim);
    }
  }

  // One primitive's accessors, checked, before they are read.
  struct Primitive {
    int mode = TINYGLTF_MODE_TRIANGLES;
    int position_accessor = -1, normal_accessor = -1, tangent_accessor = -1, uv_accessor = -1, index_accessor = -1;
    Elements positions, normals, tangents, uvs, indices;
    TextureChoice uv_choice;
    std::size_t corners = 0, triangles = 0;
  };

  // qdmr's UV of a glTF UV: the texture transform, then v up (glTF's v runs down the image, qdmr's up).
  static glm::vec2 qdmr_uv(glm::dvec2 uv, const TextureChoice& choice, double cosine, double sine) {
    uv *= choice.scale;
    if (choice.rotation != 0.0) uv = glm::dvec2(cosine * uv.x - sine * uv.y, sine * uv.x + cosine * uv.y);
    uv += choice.offset;
    return glm::vec2(float(uv.x), float(1.0 - uv.y));
  }

  void read_uvs(const Primitive& in, glm::vec2* out) const {
    const double c = std::cos(in.uv_choice.rotation), s = std::sin(in.uv_choice.rotation);
    if (in.uv_accessor < 0) {
      std::fill(out, out + in.positions.count, qdmr_uv(glm::dvec2(0.0), in.uv_choice, c, s));
      return;
    }
    asset_.float_array(in.uvs, in.uv_accessor, glm::value_ptr(out[0]));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, in.positions.count, 16384), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) out[i] = qdmr_uv(glm::dvec2(out[i]), in.uv_choice, c, s);
    });
  }

  // The primitive's triangles, 3 corners each (from its indices, else its vertices in order), into `out`.
  void read_triangles(const Primitive& in, std::uint32_t* out) const {
    const std::size_t vertices = in.positions.count;
    const auto corners = [&](std::uint32_t* c) {
      if (in.index_accessor >= 0) {
        asset_.indices(in.indices, in.index_accessor, vertices, c);
      } else {
        for (std::size_t i = 0; i < vertices; ++i) c[i] = std::uint32_t(i);
      }
    };
    if (in.mode == TINYGLTF_MODE_TRIANGLES) {
      corners(out);
      return;
    }
    std::vector<std::uint32_t> c(in.corners);
    corners(c.data());
    for (std::size_t i = 2; i < c.size(); ++i, out += 3) {
      if (in.mode == TINYGLTF_MODE_TRIANGLE_FAN) {
        out[0] = c[0], out[1] = c[i - 1], out[2] = c[i];
      } else if (i % 2 == 0) {
        out[0] = c[i - 2], out[1] = c[i - 1], out[2] = c[i];
      } else {
        out[0] = c[i - 1], out[1] = c[i - 2], out[2] = c[i];
      }
    }
  }

  // A primitive with normals, read straight into the mesh's arrays in its own space (where MikkTSpace makes missing
  // tangents, as glTF defines them), then moved into qdmr's frame in place.
  void add_smooth(const Primitive& in, const glm::dmat4& world, const glm::dmat3& normal_matrix, bool mirrored,
                  std::uint32_t material) {
    const std::size_t count = in.positions.count, base = mesh_.positions.size(), first = mesh_.indices.size();
    mesh_.positions.resize(base + count);
    asset_.float_array(in.positions, in.position_accessor, glm::value_ptr(mesh_.positions[base]));
    mesh_.normals.resize(base + count);
    asset_.float_array(in.normals, in.normal_accessor, glm::value_ptr(mesh_.normals[base]));
    mesh_.uvs.resize(base + count);
    read_uvs(in, mesh_.uvs.data() + base);
    mesh_.tangents.resize(base + count);
    if (in.tangent_accessor >= 0) asset_.float_array(in.tangents, in.tangent_accessor, glm::value_ptr(mesh_.tangents[base]));
    mesh_.indices.resize(first + 3 * in.triangles);
    read_triangles(in, mesh_.indices.data() + first);
    if (in.tangent_accessor < 0) {
      // Missing tangents: MikkTSpace's. A vertex on a mirrored UV seam is split: copy k is vertex count + k.
      const std::span<std::uint32_t> triangles(mesh_.indices.data() + first, 3 * in.triangles);
      const MikkTSpaceCopies copies =
          mikktspace_tangents({mesh_.positions.data() + base, count}, {mesh_.normals.data() + base, count},
                              {mesh_.uvs.data() + base, count}, triangles, {mesh_.tangents.data() + base, count});
      if (has_textures_) note("tangents generated (a primitive has no TANGENT; MikkTSpace's essentials: see docs/scene-format.md)");
      if (!copies.of.empty()) {
        const std::size_t grown = base + count + copies.of.size();
        for (auto* v : {&mesh_.positions, &mesh_.normals}) v->reserve(std::max(v->capacity(), grown));
        mesh_.uvs.reserve(std::max(mesh_.uvs.capacity(), grown));
        mesh_.tangents.reserve(std::max(mesh_.tangents.capacity(), grown));
        for (const std::uint32_t s : copies.of) {
          mesh_.positions.push_back(mesh_.positions[base + s]);
          mesh_.normals.push_back(mesh_.normals[base + s]);
          mesh_.uvs.push_back(mesh_.uvs[base + s]);
        }
        mesh_.tangents.insert(mesh_.tangents.end(), copies.tangents.begin(), copies.tangents.end());
      }
    }
    // Into qdmr's frame, each vertex alone (the same bits in any order).
    const std::size_t moved = mesh_.positions.size() - base;
    to_frame({mesh_.positions.data() + base, moved}, {mesh_.normals.data() + base, moved},
             {mesh_.tangents.data() + base, moved}, world, normal_matrix, mirrored);
    if (base > 0)
      for (std::size_t i = first; i < mesh_.indices.size(); ++i) mesh_.indices[i] += std::uint32_t(base);
    mesh_.triangle_materials.resize(mesh_.triangle_materials.size() + in.triangles, material);
  }

  // A primitive without normals: each triangle gets its own corners, flat-shaded (glTF 2.0, "Meshes"), with the
  // per-triangle tangent (what MikkTSpace gives a corner alone) from qdmr's generator.
  void add_flat(const Primitive& in, const glm::dmat4& world, std::uint32_t material) {
    const std::size_t count = in.positions.count;
    std::vector<glm::vec3> positions(count);
    asset_.float_array(in.positions, in.position_accessor, glm::value_ptr(positions[0]));
    std::vector<glm::vec2> uvs(count);
    read_uvs(in, uvs.data());
    std::vector<std::uint32_t> triangles(3 * in.triangles);
    read_triangles(in, triangles.data());
    MeshData part;
    for (std::size_t k = 0; k < triangles.size(); ++k) {
      part.positions.push_back(glm::vec3(world * glm::dvec4(glm::dvec3(positions[triangles[k]]), 1.0)));
      part.uvs.push_back(uvs[triangles[k]]);
      part.indices.push_back(std::uint32_t(k));
    }
    for (std::size_t k = 0; k < triangles.size(); k += 3) {
      const glm::dvec3 a(part.positions[k]), b(part.positions[k + 1]), c(part.positions[k + 2]);
      const glm::dvec3 face = glm::cross(b - a, c - a);
      const double len = glm::length(face);
      const glm::vec3 n = len > 0.0 && std::isfinite(len) ? glm::vec3(face / len) : glm::vec3(0, 0, 1);
      part.normals.insert(part.normals.end(), {n, n, n});
    }
    compute_tangents(part);
    if (has_textures_) note("tangents generated per flat triangle (a primitive has no NORMAL nor TANGENT)");
    const auto base = std::uint32_t(mesh_.positions.size());
    mesh_.positions.insert(mesh_.positions.end(), part.positions.begin(), part.positions.end());
    mesh_.normals.insert(mesh_.normals.end(), part.normals.begin(), part.normals.end());
    mesh_.tangents.insert(mesh_.tangents.end(), part.tangents.begin(), part.tangents.end());
    mesh_.uvs.insert(mesh_.uvs.end(), part.uvs.begin(), part.uvs.end());
    for (const std::uint32_t i : part.indices) mesh_.indices.push_back(base + i);
    mesh_.triangle_materials.insert(mesh_.triangle_materials.end(), part.indices.size() / 3, material);
  }

  std::string unique(std::string name) const {
    const auto taken = [&](const std::string& n) {
      return std::any_of(materials_.begin(), materials_.end(), [&](const MaterialDesc& m) { return m.name == n; });
    };
    while (taken(name)) name += "_";
    return name;
  }

  static MaterialDesc default_gltf_material() {
    // glTF's default material: white, metallic 1, roughness 1 (qdmr: Cook-Torrance, no diffuse, F0 of white).
    MaterialDesc m;
    LayerDesc layer;
    layer.albedo.source = TextureSource::Constant;
    layer.albedo.constant = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    m.layers = {layer};
    m.lighting.model = LightingModel::CookTorrance;
    m.lighting.specular = 1.0f;
    m.lighting.roughness = 1.0f;
    return m;
  }

  // The file of image `index` (an external file beside the asset, or the embedded bytes stored in the cache),
  // checked by qdmr's image reader up to its header.
  fs::path image_file(int texture, const std::string& at) {
    if (texture < 0 || std::size_t(texture) >= model_.textures.size()) asset_.fail(at + "/index", "texture " + std::to_string(texture) + " does not exist");
    const int source = model_.textures[std::size_t(texture)].source;
    if (source < 0 || std::size_t(source) >= model_.images.size())
      asset_.fail("/textures/" + std::to_string(texture) + "/source", "no image qdmr can read (an image of an extension is not read)");
    if (const auto it = image_files_.find(source); it != image_files_.end()) return it->second;
    const tinygltf::Image& image = model_.images[std::size_t(source)];
    const std::string image_at = where_ + ": /images/" + std::to_string(source);
    fs::path file;
    if (!image.uri.empty()) {
      // tinygltf keeps the URI of an image it did not decode: a file, or a data: URI it could not read.
      const auto relative = relative_uri(image.uri, image_at);
      if (!relative) throw Error(image_at, "a data: URI that is not base64 data of a known media type");
      file = (reading_.folder / *relative).lexically_normal();
    } else if (const auto view = reading_.image_views.find(source); view != reading_.image_views.end()) {
      // In a buffer view (checked when the asset was read).
      const tinygltf::BufferView& v = model_.bufferViews[std::size_t(view->second)];
      std::string bytes(v.byteLength, '\0');
      Asset::read(reading_.buffers[std::size_t(v.buffer)], v.byteOffset, bytes.size(), reinterpret_cast<unsigned char*>(bytes.data()));
      file = store_embedded_image(bytes, image_at);
    } else {
      if (std::size_t(source) >= reading_.embedded.size() || reading_.embedded[std::size_t(source)].empty())
        throw Error(image_at, "the image has no data");
      file = store_embedded_image(reading_.embedded[std::size_t(source)], image_at);
    }
    static_cast<void>(read_image_header(file, image_at));
    image_files_[source] = file;
    return file;
  }

  TextureDesc texture(int index, const std::string& at, bool srgb) {
    TextureDesc t;
    t.source = TextureSource::File;
    t.file = image_file(index, at);
    t.srgb = srgb;
    return t;
  }

  // The layer's orm texture (LayerDesc::orm) from a material's metallicRoughnessTexture (G roughness, B metalness)
  // and occlusionTexture (R): one image when both name the same; else the occlusion's R replaces the orm's (an
  // image of another size is not applied, with a note); a missing one leaves its channels at 1.
  void convert_orm(const tinygltf::Material& g, const std::string& at, const std::string& name, double metallic,
                   LayerDesc& layer) {
    const tinygltf::TextureInfo& mr = g.pbrMetallicRoughness.metallicRoughnessTexture;
    const tinygltf::OcclusionTextureInfo& occlusion = g.occlusionTexture;
    layer.metallic = float(metallic);
    std::optional<ImageHeader> mr_header;
    if (mr.index >= 0) {
      layer.orm = texture(mr.index, at + "/pbrMetallicRoughness/metallicRoughnessTexture", false);
      mr_header = read_image_header(layer.orm.file, where_ + ": /images");
      if (mr_header->channels < 3) asset_.fail(at + "/pbrMetallicRoughness/metallicRoughnessTexture", "its image has fewer than 3 channels (G is roughness, B metalness)");
    }
    if (occlusion.index < 0) {
      layer.occlusion.source = TextureSource::Constant;  // the metallicRoughnessTexture's R is not occlusion
      layer.occlusion.constant = glm::vec4(1.0f);
      return;
    }
    if (!(occlusion.strength >= 0.0 && occlusion.strength <= 1.0)) asset_.fail(at + "/occlusionTexture/strength", "must be in [0, 1]");
    layer.occlusion_strength = float(occlusion.strength);
    const TextureDesc occ = texture(occlusion.index, at + "/occlusionTexture", false);
    if (mr_header && occ.file == layer.orm.file) return;  // one image: R occlusion, G roughness, B metalness
    const ImageHeader occ_header = read_image_header(occ.file, where_ + ": /images");
    if (mr_header && (occ_header.width != mr_header->width || occ_header.height != mr_header->height)) {
      note("material '" + name + "': occlusionTexture not applied (its image is " + std::to_string(occ_header.width) +
           "x" + std::to_string(occ_header.height) + ", the metallicRoughnessTexture's " + std::to_string(mr_header->width) +
           "x" + std::to_string(mr_header->height) + ")");
      layer.occlusion.source = TextureSource::Constant;
      layer.occlusion.constant = glm::vec4(1.0f);
      return;
    }
    layer.occlusion = occ;
    layer.occlusion.channel = Channel::R;
  }

  MaterialDesc convert_material(int index) {
    const tinygltf::Material& g = model_.materials[std::size_t(index)];
    const std::string at = "/materials/" + std::to_string(index);
    const tinygltf::PbrMetallicRoughness& pbr = g.pbrMetallicRoughness;
    MaterialDesc m = default_gltf_material();
    m.name = unique(g.name.empty() ? "material " + std::to_string(index) : g.name);
    LayerDesc& layer = m.layers.front();
    std::vector<double> color = pbr.baseColorFactor;
    if (color.size() != 4) color = {1, 1, 1, 1};
    for (std::size_t k = 0; k < 4; ++k)
      if (!(color[k] >= 0.0 && color[k] <= 1.0)) asset_.fail(at + "/pbrMetallicRoughness/baseColorFactor", "components must be in [0, 1]");
    const double metallic = pbr.metallicFactor, roughness = pbr.roughnessFactor;
    if (!(metallic >= 0.0 && metallic <= 1.0)) asset_.fail(at + "/pbrMetallicRoughness/metallicFactor", "must be in [0, 1]");
    if (!(roughness >= 0.0 && roughness <= 1.0)) asset_.fail(at + "/pbrMetallicRoughness/roughnessFactor", "must be in [0, 1]");

    // The UV set and transform: the base colour texture's, else the normal texture's.
    TextureChoice choice;
    std::vector<std::pair<std::string, TextureChoice>> used;
    const auto consider = [&](const char* name, int tex, int coord, const tinygltf::ExtensionMap& ext) {
      if (tex < 0) return;
      used.emplace_back(name, choice_of(tex, coord, ext));
    };
    consider("baseColorTexture", pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, pbr.baseColorTexture.extensions);
    consider("normalTexture", g.normalTexture.index, g.normalTexture.texCoord, g.normalTexture.extensions);
    consider("metallicRoughnessTexture", pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
             pbr.metallicRoughnessTexture.extensions);
    consider("occlusionTexture", g.occlusionTexture.index, g.occlusionTexture.texCoord, g.occlusionTexture.extensions);
    if (!used.empty()) {
      has_textures_ = true;
      choice = used.front().second;
      choice.base = &pbr.baseColorTexture;
      for (const auto& [name, c] : used)
        if (!same_choice(c, choice))
          note("material '" + m.name + "': " + name + " uses another UV set or transform than " + used.front().first +
               "; qdmr samples a material's textures alike, with " + used.front().first + "'s");
    }
    uv_choices_.resize(std::size_t(index) + 1);
    uv_choices_[std::size_t(index)] = choice;

    // With a metallicRoughnessTexture or an occlusionTexture the program applies the metalness per texel (the
    // layer's orm: diffuse times 1 - m, F0 from 0.04 towards the base colour's luminance); without, the factors are
    // constants folded in here: the same formulas.
    const bool orm = pbr.metallicRoughnessTexture.index >= 0 || g.occlusionTexture.index >= 0;
    const double diffuse = orm ? 1.0 : 1.0 - metallic;
    const double f0 = 0.04 + (0.2126 * color[0] + 0.7152 * color[1] + 0.0722 * color[2] - 0.04) * metallic;
    m.lighting.roughness = float(std::clamp(roughness, 0.02, 1.0));
    m.lighting.specular = orm ? 0.04f : float(f0);
    if (orm) convert_orm(g, at, m.name, metallic, layer);
    if (pbr.baseColorTexture.index >= 0) {
      // The diffuse colour: the texture times baseColorFactor, less what the metal reflects specularly.
      layer.albedo = texture(pbr.baseColorTexture.index, at + "/pbrMetallicRoughness/baseColorTexture", true);
      layer.albedo.factor = glm::vec3(float(color[0] * diffuse), float(color[1] * diffuse), float(color[2] * diffuse));
      const int sampler = model_.textures[std::size_t(pbr.baseColorTexture.index)].sampler;
      if (sampler >= 0) {
        if (std::size_t(sampler) >= model_.samplers.size())
          asset_.fail("/textures/" + std::to_string(pbr.baseColorTexture.index) + "/sampler", "sampler " + std::to_string(sampler) + " does not exist");
        const tinygltf::Sampler& s = model_.samplers[std::size_t(sampler)];
        m.sampling.filter = filter_of(s.minFilter);
        m.sampling.address = address_of(s.wrapS);
        if (s.wrapS != s.wrapT) note("material '" + m.name + "': wrapT differs from wrapS; qdmr addresses both axes with wrapS");
        // One texel filter for minified and magnified texels (qdmr's filters): minFilter's. A magFilter that asks
        // for the other one is a warning.
        const bool min_nearest = m.sampling.filter == Filter::Point || m.sampling.filter == Filter::PointMipPoint ||
                                 m.sampling.filter == Filter::PointMipLinear;
        if ((s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST && !min_nearest) ||
            (s.magFilter == TINYGLTF_TEXTURE_FILTER_LINEAR && min_nearest))
          note("material '" + m.name + "': magFilter " + (min_nearest ? "LINEAR" : "NEAREST") +
               " differs from minFilter's texel filter; qdmr filters magnified texels as minFilter says");
      }
    } else {
      layer.albedo.constant =
          glm::vec4(float(color[0] * diffuse), float(color[1] * diffuse), float(color[2] * diffuse), float(color[3]));
    }
    if (g.normalTexture.index >= 0) {
      layer.normal = texture(g.normalTexture.index, at + "/normalTexture", false);
      if (!std::isfinite(g.normalTexture.scale)) asset_.fail(at + "/normalTexture/scale", "must be finite");
      layer.normal_strength = float(std::max(0.0, g.normalTexture.scale));
    }
    double emissive_strength = 1.0;
    if (const auto it = g.extensions.find("KHR_materials_emissive_strength"); it != g.extensions.end())
      emissive_strength = number_or(it->second, "emissiveStrength", 1.0);
    const bool emits = g.emissiveTexture.index >= 0 ||
                       (g.emissiveFactor.size() == 3 && emissive_strength > 0.0 &&
                        (g.emissiveFactor[0] > 0.0 || g.emissiveFactor[1] > 0.0 || g.emissiveFactor[2] > 0.0));
    if (emits) note("material '" + m.name + "': emission not drawn (qdmr has no emissive term)");
    if (g.alphaMode != "OPAQUE" && !g.alphaMode.empty()) note("material '" + m.name + "': alphaMode " + g.alphaMode + " drawn opaque");
    return m;
  }

  tinygltf::Model& model_;  // its buffers are released once no drawn primitive reads them
  Reading& reading_;
  fs::path file_;
  std::string where_;
  Asset asset_;
  std::vector<int> parent_;
  std::vector<MaterialDesc> materials_;
  std::vector<TextureChoice> uv_choices_;
  std::map<int, fs::path> image_files_;
  std::uint64_t max_memory_bytes_ = 0;
  std::vector<std::size_t> buffer_reads_;  // per buffer: the drawn primitives that have yet to read it
  std::uint64_t reserve_vertices_ = 0, reserve_triangles_ = 0;  // check_drawn_size's count
  int default_material_ = -1;
  bool has_textures_ = false;
  std::vector<std::pair<std::string, int>> notes_;
  MeshData mesh_;
};

// What the document says before tinygltf reads it: the URIs it names (checked), the extensions it requires
// (refused unless qdmr reads them), and what qdmr ignores (the plan's notes).
std::vector<std::string> prescan(const std::string& json_text, Reading& reading, nlohmann::json& doc) {
  try {
    doc = scene_detail::parse_json_bounded(json_text);
  } catch (const Error& e) {
    throw e.within(reading.where);
  } catch (const nlohmann::json::exception& e) {
    const std::string what = e.what();
    const auto start = what.find("parse error");
    throw Error(reading.where, start != std::string::npos ? what.substr(start) : what);
  }
  if (!doc.is_object()) throw Error(reading.where, "a glTF document is a JSON object");
  std::vector<std::string> notes;
  for (const char* kind : {"buffers", "images"}) {
    const auto it = doc.find(kind);
    if (it == doc.end() || !it->is_array()) continue;
    for (std::size_t i = 0; i < it->size(); ++i) {
      const nlohmann::json& item = (*it)[i];
      if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
      const auto path = relative_uri(item["uri"].get_ref<const std::string&>(),
                                     reading.where + ": /" + kind + "/" + std::to_string(i) + "/uri");
      if (path && std::string(kind) == "images") reading.image_files.insert((reading.folder / *path).lexically_normal());
    }
  }
  if (const auto it = doc.find("extensionsRequired"); it != doc.end() && it->is_array())
    for (std::size_t i = 0; i < it->size(); ++i)
      if ((*it)[i].is_string() && !kSupportedExtensions.count((*it)[i].get<std::string>()))
        throw Error(reading.where + ": /extensionsRequired/" + std::to_string(i),
                    "the asset requires " + scene_detail::shorten((*it)[i].get<std::string>()) + ", which qdmr does not read");
  if (const auto it = doc.find("extensionsUsed"); it != doc.end() && it->is_array())
    for (const auto& e : *it)
      if (e.is_string() && !kSupportedExtensions.count(e.get<std::string>()))
        notes.push_back("extension " + scene_detail::shorten(e.get<std::string>()) + " ignored");
  if (const auto it = doc.find("animations"); it != doc.end() && it->is_array() && !it->empty())
    notes.push_back(std::to_string(it->size()) + " animation" + (it->size() > 1 ? "s" : "") + " ignored (drawn at rest)");
  return notes;
}

// Takes the buffers whose bytes are in files (the .glb's BIN chunk, a .bin beside the asset) out of tinygltf's
// hands: each becomes a one-byte data: URI in the document, and its place in its file is kept in
// reading.buffers, so the accessors are read from the file straight into the mesh. Images in buffer views are
// kept out likewise (reading.image_views). Returns the document for tinygltf, or "" when nothing was changed.
// What tinygltf would refuse anyway (a byteLength that is not a count, a uri that is not a string in a .gltf) is
// left to it.
std::string stand_in_buffers(nlohmann::json& doc, Reading& reading, const fs::path& file, const GlbChunks* glb) {
  bool changed = false;
  if (const auto it = doc.find("buffers"); it != doc.end() && it->is_array()) {
    reading.buffers.resize(it->size());
    for (std::size_t i = 0; i < it->size(); ++i) {
      nlohmann::json& item = (*it)[i];
      if (!item.is_object() || !item.contains("byteLength") || !item["byteLength"].is_number_unsigned()) continue;
      const std::uint64_t length = item["byteLength"].get<std::uint64_t>();
      const std::string at = reading.where + ": /buffers/" + std::to_string(i);
      const bool has_uri = item.contains("uri") && item["uri"].is_string();
      BufferSource& source = reading.buffers[i];
      if (has_uri) {
        const auto relative = relative_uri(item["uri"].get_ref<const std::string&>(), at + "/uri");
        if (!relative) continue;  // data: tinygltf decodes it
        const fs::path path = (reading.folder / *relative).lexically_normal();
        if (!inside(reading, path)) throw Error(at + "/uri", "refused to read " + shown_path(path) + ": outside the asset's folder");
        auto& open = reading.files[path];
        if (!open) open = std::make_unique<InputFile>(path, at + "/uri", InputKind::GltfBuffer);
        if (open->size() != length)
          throw Error(at + "/byteLength", std::to_string(length) + " bytes, but " + shown_path(path) + " has " +
                                              std::to_string(open->size()));
        source = BufferSource{length, open.get(), 0, nullptr};
      } else if (glb) {
        // A .glb's buffer without a uri is its BIN chunk.
        if (!glb->has_bin) throw Error(at, "a buffer without a uri is the .glb's BIN chunk, and this .glb has none");
        if (length > glb->bin_length)
          throw Error(at + "/byteLength", std::to_string(length) + " bytes, more than the .glb's BIN chunk (" +
                                              std::to_string(glb->bin_length) + " bytes)");
        source = BufferSource{length, reading.files.at(file).get(), glb->bin_offset, nullptr};
      } else {
        continue;
      }
      item["uri"] = "data:application/octet-stream;base64,AA==";
      item["byteLength"] = 1;
      changed = true;
    }
  }
  if (const auto it = doc.find("images"); it != doc.end() && it->is_array())
    for (std::size_t i = 0; i < it->size(); ++i) {
      nlohmann::json& item = (*it)[i];
      if (!item.is_object() || item.contains("uri") || !item.contains("bufferView") || !item["bufferView"].is_number_integer() ||
          item["bufferView"].get<std::int64_t>() < 0 || item["bufferView"].get<std::int64_t>() > std::numeric_limits<int>::max())
        continue;
      reading.image_views[int(i)] = item["bufferView"].get<int>();
      item["bufferView"] = -1;  // tinygltf then hands over no bytes
      changed = true;
    }
  return changed ? doc.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) : "";
}

// The images in buffer views, checked as tinygltf would hand them over: their view and its buffer exist, and the
// view fits its buffer.
void check_image_views(const tinygltf::Model& model, const Reading& reading) {
  for (const auto& [image, view] : reading.image_views) {
    const std::string at = reading.where + ": /images/" + std::to_string(image);
    if (std::size_t(view) >= model.bufferViews.size())
      throw Error(at, "names buffer view " + std::to_string(view) + ", which does not exist");
    const tinygltf::BufferView& v = model.bufferViews[std::size_t(view)];
    if (v.buffer < 0 || std::size_t(v.buffer) >= reading.buffers.size())
      throw Error(at, "its buffer view names a buffer that does not exist");
    const std::uint64_t size = reading.buffers[std::size_t(v.buffer)].size;
    if (v.byteOffset > size || v.byteLength > size - v.byteOffset) throw Error(at, "its buffer view runs past the end of its buffer");
    if (v.byteLength == 0) throw Error(at, "the image is empty");
  }
}

}  // namespace

MeshData load_gltf(const MeshDesc& desc, const std::string& where, std::uint64_t max_memory_bytes) {
  const fs::path file = fs::absolute(desc.file).lexically_normal();
  Reading reading;
  reading.folder = file.parent_path();
  reading.where = where.empty() ? shown_path(file) : where + ": " + shown_path(file);
  // The asset is read in parts: a .glb's JSON chunk now, its BIN chunk an accessor at a time while the mesh is
  // built; a .gltf's text whole.
  const InputFile& asset = *(reading.files[file] = std::make_unique<InputFile>(file, where, InputKind::Gltf));
  const bool binary = looks_like_glb(asset.read(0, std::size_t(std::min<std::uint64_t>(asset.size(), 4))));
  GlbChunks glb;
  std::string text;
  if (binary) {
    glb = glb_chunks(asset.size(), [&](std::uint64_t at, std::size_t n) { return asset.read(at, n); }, reading.where);
    text = asset.read(glb.json_offset, std::size_t(glb.json_length));
  } else {
    text = asset.read(0, std::size_t(asset.size()));
  }
  std::vector<std::string> notes;
  {
    nlohmann::json doc;
    notes = prescan(text, reading, doc);
    if (std::string changed = stand_in_buffers(doc, reading, file, binary ? &glb : nullptr); !changed.empty()) text = std::move(changed);
  }

  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks({&file_exists, &expand_file_path, &read_whole_file, &write_whole_file, &reading});
  loader.SetImageLoader(&keep_image, &reading);
  std::string err, warn;
  bool ok = false;
  try {
    ok = loader.LoadASCIIFromString(&model, &err, &warn, text.data(), unsigned(text.size()), reading.folder.string());
  } catch (const std::exception& e) {
    throw Error(reading.where, std::string("tinygltf: ") + e.what());
  }
  std::string().swap(text);
  if (!reading.error.empty()) throw Error(reading.error, reading.error_kind);
  if (!ok || !err.empty()) {
    std::string first = err.substr(0, err.find('\n'));
    if (first.empty()) first = "tinygltf could not read the asset";
    throw Error(reading.where, first);
  }
  // The buffers tinygltf holds (data: URIs) are read from it.
  reading.buffers.resize(model.buffers.size());
  for (std::size_t b = 0; b < model.buffers.size(); ++b)
    if (!reading.buffers[b].file) reading.buffers[b] = BufferSource{model.buffers[b].data.size(), nullptr, 0, model.buffers[b].data.data()};
  check_image_views(model, reading);
  MeshData mesh = Builder(model, reading, file, reading.where, max_memory_bytes).build(desc);
  notes.insert(notes.end(), mesh.notes.begin(), mesh.notes.end());
  mesh.notes = std::move(notes);
  return mesh;
}

}  // namespace qdmr::mesh_detail
