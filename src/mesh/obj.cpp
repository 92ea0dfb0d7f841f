// OBJ (+ MTL) through tinyobjloader: triangulated, vertices deduplicated per (position, uv, normal) corner.
#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <unordered_map>

#include <glm/geometric.hpp>

#include "mesh/builders.hpp"
#include "mesh/triangulate.hpp"
#include "file/input_file.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr::mesh_detail {

namespace fs = std::filesystem;

namespace {


// 0: v, 1: vt, 2: vn, 3: f, -1: anything else.
int line_kind(std::string_view line) {
  const auto is_space = [&](std::size_t i) { return i < line.size() && (line[i] == ' ' || line[i] == '\t'); };
  if (line.starts_with("vt") && is_space(2)) return 1;
  if (line.starts_with("vn") && is_space(2)) return 2;
  if (line.starts_with('v') && is_space(1)) return 0;
  if (line.starts_with('f') && (is_space(1) || line.size() == 1)) return 3;  // a bare "f" is an empty face
  return -1;
}

template <class Visit>
void for_each_line(const std::string& text, Visit visit) {
  std::size_t line_no = 0;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + start, end - start);
    line.remove_prefix(std::min(line.find_first_not_of(" \t"), line.size()));
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    visit(++line_no, line);
    start = end + 1;
  }
}

// tinyobjloader reads positions through face indices unchecked while triangulating, and only warns about
// indices out of range: check every face index first. Positive indices may point forward (to the file's
// total); negative ones count back from the vertices read so far.
// Returns the number of corners of every face, in file order (tinyobjloader keeps a face's count in an unsigned
// char: 1000 corners come out as 232).
std::vector<std::size_t> check_face_indices(const std::string& text, const std::string& where) {
  std::vector<std::size_t> face_corners;
  static constexpr const char* kNames[3] = {"position", "texture coordinate", "normal"};
  std::array<long long, 3> total{}, seen{};
  for_each_line(text, [&](std::size_t, std::string_view line) {
    const int kind = line_kind(line);
    if (kind >= 0 && kind < 3) ++total[kind];
  });
  for_each_line(text, [&](std::size_t line_no, std::string_view line) {
    const int kind = line_kind(line);
    if (kind >= 0 && kind < 3) ++seen[kind];
    if (kind != 3) return;
    const auto fail = [&](const std::string& what) {
      throw Error(where, "line " + std::to_string(line_no) + ": " + what);
    };
    std::istringstream tokens{std::string(line.substr(1))};
    long long corners = 0;
    for (std::string token; tokens >> token;) {
      ++corners;
      std::size_t part_start = 0;
      for (int k = 0; k < 3 && part_start <= token.size(); ++k) {
        std::size_t part_end = std::min(token.find('/', part_start), token.size());
        const std::string_view part(token.data() + part_start, part_end - part_start);
        part_start = part_end + 1;
        if (part.empty() && k > 0) continue;
        long long index = 0;
        const auto [ptr, ec] = std::from_chars(part.data(), part.data() + part.size(), index);
        if (ec != std::errc() || ptr != part.data() + part.size())
          fail("cannot read the face index '" + std::string(part) + "' in '" + token + "'");
        if (index == 0) fail("face index 0 in '" + token + "' (OBJ indices start at 1)");
        const long long count = index > 0 ? total[k] : seen[k];
        const long long resolved = index > 0 ? index - 1 : seen[k] + index;
        if (resolved < 0 || resolved >= count)
          fail(std::string(kNames[k]) + " index " + std::to_string(index) + " in '" + token + "' is out of range (" +
               std::to_string(count) + " " + kNames[k] + (count == 1 ? "" : "s") +
               (index > 0 ? " in the file)" : " before this line)"));
      }
    }
    if (corners < 3)
      fail("a face needs at least 3 vertices, this one has " + std::to_string(corners) +
           " (use 'l' for lines)");
    face_corners.push_back(std::size_t(corners));
  });
  return face_corners;
}

// tinyobjloader reads "nan", "inf" and other words as 0 without a warning: check every number of the v, vt
// and vn lines first (up to an end-of-line comment). Values too large for float are left to check_finite.
void check_vertex_numbers(const std::string& text, const std::string& where) {
  static constexpr const char* kNames[3] = {"position", "texture coordinate", "normal"};
  for_each_line(text, [&](std::size_t line_no, std::string_view line) {
    const int kind = line_kind(line);
    if (kind < 0 || kind > 2) return;
    std::istringstream tokens{std::string(line.substr(kind == 0 ? 1 : 2))};
    for (std::string token; tokens >> token && !token.starts_with('#');) {
      char* end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      if (end != token.c_str() + token.size() || !std::isfinite(value))
        throw Error(where, "line " + std::to_string(line_no) + ": " + kNames[kind] + " component '" + token +
                               "' is not a finite number");
    }
  });
}

// Loads MTL files relative to the OBJ folder and remembers each material's folder (texture paths in an
// MTL file are relative to that file).
class MtlReader final : public tinyobj::MaterialReader {
public:
  MtlReader(fs::path folder, std::string where) : folder_(std::move(folder)), where_(std::move(where)) {}

  bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* names, std::string* warn, std::string* err) override {
    const fs::path file = (folder_ / name).lexically_normal();
    if (non_regular_reason(file) == "file not found") {
      missing_ += (missing_.empty() ? "" : ", ") + file.string();
      return false;
    }
    // Not a regular file, too large or unreadable: an error, kept until tinyobjloader returns.
    std::string text;
    try {
      text = read_input_file(file, where_, InputKind::Mtl);
    } catch (const Error& e) {
      if (!error_) error_ = e;
      return false;
    }
    std::istringstream in(text);
    tinyobj::LoadMtl(names, materials, &in, warn, err);
    material_folders_.resize(materials->size(), file.parent_path());
    return true;
  }

  const std::string& missing() const { return missing_; }
  const std::optional<Error>& error() const { return error_; }
  const fs::path& folder_of(std::size_t material) const { return material_folders_.at(material); }

private:
  fs::path folder_;
  std::string where_;
  std::string missing_;
  std::optional<Error> error_;
  std::vector<fs::path> material_folders_;
};

TextureDesc file_texture(const fs::path& folder, const std::string& name) {
  TextureDesc t;
  t.source = TextureSource::File;
  t.file = (folder / name).lexically_normal();
  return t;
}

TextureDesc constant_texture(glm::vec3 color) {
  TextureDesc t;
  t.source = TextureSource::Constant;
  t.constant = glm::vec4(color, 1.0f);
  return t;
}

// The MTL maps qdmr reads: map_Kd -> albedo (sRGB); disp -> the height a displacement technique marches (POM
// by default); bump / map_Bump -> a height for normals only (bump mapping), unless a disp is given; norm -> a
// tangent-space normal map, which wins over normals derived from a height. Scenes change any of this per MTL
// material in the object's `mtl` block (scene/validate.cpp, read_mtl_override).
MaterialDesc convert_material(const tinyobj::material_t& mtl, const fs::path& folder) {
  LayerDesc layer;
  layer.albedo = mtl.diffuse_texname.empty()
                     ? constant_texture({mtl.diffuse[0], mtl.diffuse[1], mtl.diffuse[2]})
                     : file_texture(folder, mtl.diffuse_texname);
  MaterialDesc m;
  if (!mtl.displacement_texname.empty()) {
    layer.height = file_texture(folder, mtl.displacement_texname);
    m.technique.kind = TechniqueKind::Pom;
  } else if (!mtl.bump_texname.empty()) {
    layer.height = file_texture(folder, mtl.bump_texname);
  }
  if (!mtl.normal_texname.empty())
    layer.normal = file_texture(folder, mtl.normal_texname);
  else if (layer.height.source != TextureSource::None)
    layer.normal.source = TextureSource::FromHeight;
  m.name = mtl.name;
  m.layers = {layer};
  return m;
}

template <std::size_t N>
void check_finite(const std::vector<tinyobj::real_t>& values, const char* what, const std::string& where) {
  for (std::size_t i = 0; i + N <= values.size(); i += N) {
    bool ok = true;
    for (std::size_t k = 0; k < N; ++k) ok = ok && std::isfinite(values[i + k]);
    if (ok) continue;
    std::ostringstream s;
    s << what << " " << i / N + 1 << " is not finite: (";
    for (std::size_t k = 0; k < N; ++k) {
      s << (k ? ", " : "");
      if (std::isnan(values[i + k]))
        s << "nan";  // without the sign bit, which depends on how the NaN arose
      else
        s << values[i + k];
    }
    s << ")";
    throw Error(where, s.str());
  }
}

std::string first_line_containing(const std::string& text, const std::string& needle) {
  const std::size_t at = text.find(needle);
  if (at == std::string::npos) return {};
  const std::size_t begin = text.rfind('\n', at), end = text.find('\n', at);
  const std::size_t from = begin == std::string::npos ? 0 : begin + 1;
  return text.substr(from, (end == std::string::npos ? text.size() : end) - from);
}

struct CornerKey {
  int v, vt, vn;
  bool operator==(const CornerKey&) const = default;
};

struct CornerHash {
  std::size_t operator()(const CornerKey& k) const {
    std::uint64_t h = std::uint64_t(std::uint32_t(k.v)) * 0x9E3779B97F4A7C15ull;
    h ^= (std::uint64_t(std::uint32_t(k.vt)) + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2));
    h ^= (std::uint64_t(std::uint32_t(k.vn)) + 0x94D049BB133111EBull + (h << 6) + (h >> 2));
    return std::size_t(h);
  }
};

std::string unique_name(const std::vector<MaterialDesc>& materials, std::string name) {
  const auto taken = [&](const std::string& n) {
    for (const auto& m : materials)
      if (m.name == n) return true;
    return false;
  };
  while (taken(name)) name += "_";
  return name;
}

struct FaceTriangles {
  std::vector<std::uint32_t> corners;  // 3 per triangle: indices into the shape's mesh.indices
  std::vector<std::uint32_t> faces;    // per triangle: its face
  std::size_t degenerate_faces = 0;    // faces of 4 or more corners without area, dropped
};

// The shape's faces as triangles. Triangles stay as they are (a degenerate one too: the rasterizer culls it);
// quads are split along their shorter diagonal, as tinyobjloader split them (the same float arithmetic, so
// meshes keep their triangles); larger faces are ear-clipped (mesh/triangulate.hpp). Faces of 4 or more corners
// with no area are dropped and counted.
// `corners_of`: the true corner count of each face of the file, from `next` on (check_face_indices), advanced past
// this shape's faces.
FaceTriangles triangulate_faces(const tinyobj::mesh_t& mesh, const tinyobj::attrib_t& attrib, const std::string& where,
                                const std::vector<std::size_t>& corners_of, std::size_t& next) {
  FaceTriangles out;
  const auto position = [&](std::size_t corner) {
    const float* p = &attrib.vertices[3 * std::size_t(mesh.indices[corner].vertex_index)];
    return glm::vec3(p[0], p[1], p[2]);
  };
  std::vector<glm::dvec3> polygon;
  std::size_t first = 0;
  for (std::size_t f = 0; f < mesh.num_face_vertices.size(); first += corners_of[next++], ++f) {
    if (next >= corners_of.size() || corners_of[next] % 256 != mesh.num_face_vertices[f] ||
        first + corners_of[next] > mesh.indices.size())
      throw Error(where, "the faces tinyobjloader read differ from the file's face lines");
    const std::size_t count = corners_of[next];
    const auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      out.corners.insert(out.corners.end(), {std::uint32_t(first) + a, std::uint32_t(first) + b, std::uint32_t(first) + c});
      out.faces.push_back(std::uint32_t(f));
    };
    if (count < 3) continue;  // check_face_indices refused these already
    if (count == 3) {
      add(0, 1, 2);
      continue;
    }
    polygon.resize(count);
    for (std::size_t k = 0; k < count; ++k) polygon[k] = glm::dvec3(position(first + k));
    const PolygonTriangles split = triangulate_polygon(polygon, where);
    if (split.degenerate) {
      ++out.degenerate_faces;
      continue;
    }
    if (count == 4) {
      const glm::vec3 e02 = position(first + 2) - position(first), e13 = position(first + 3) - position(first + 1);
      const float d02 = e02.x * e02.x + e02.y * e02.y + e02.z * e02.z, d13 = e13.x * e13.x + e13.y * e13.y + e13.z * e13.z;
      if (d02 < d13) {
        add(0, 1, 2);
        add(0, 2, 3);
      } else {
        add(0, 1, 3);
        add(1, 2, 3);
      }
      continue;
    }
    for (std::size_t t = 0; t < split.corners.size(); t += 3) add(split.corners[t], split.corners[t + 1], split.corners[t + 2]);
  }
  return out;
}

}  // namespace

MeshData load_obj(const MeshDesc& desc, const std::string& where) {
  const fs::path file = fs::absolute(desc.file).lexically_normal();
  const std::string text = read_input_file(file, where, InputKind::Obj);
  const std::vector<std::size_t> face_corners = check_face_indices(text, where);
  check_vertex_numbers(text, where);

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> mtls;
  std::string warn, err;
  MtlReader reader(file.parent_path(), where);
  std::istringstream stream(text);
  // Faces as they are (triangulate = false): tinyobjloader's own ear clipping misreads concave faces and takes
  // quadratic time and more; quads and larger faces are split below.
  const bool ok = tinyobj::LoadObj(&attrib, &shapes, &mtls, &warn, &err, &stream, &reader, false, false);
  if (reader.error()) throw *reader.error();
  if (!ok || !err.empty()) {
    while (!err.empty() && std::isspace(static_cast<unsigned char>(err.back()))) err.pop_back();
    throw Error(where, err.empty() ? "tinyobjloader failed to parse " + file.string() : err);
  }
  if (warn.find("Failed to load material file(s)") != std::string::npos)
    throw FileError(where, "material library not found: " + reader.missing());
  if (const std::string line = first_line_containing(warn, "not found in .mtl"); !line.empty())
    throw Error(where, line);

  check_finite<3>(attrib.vertices, "position of vertex", where);
  check_finite<3>(attrib.normals, "normal", where);
  check_finite<2>(attrib.texcoords, "texture coordinate", where);

  // Every face as triangles (corner indices into shape.mesh.indices), per shape.
  std::vector<FaceTriangles> triangles;
  std::size_t corners = 0, degenerate = 0;
  std::size_t next_face = 0;
  for (const tinyobj::shape_t& shape : shapes) {
    triangles.push_back(triangulate_faces(shape.mesh, attrib, where, face_corners, next_face));
    corners += triangles.back().corners.size();
    degenerate += triangles.back().degenerate_faces;
  }
  check_triangle_count(corners / 3, where);
  if (corners == 0)
    throw Error(where, degenerate ? "every face of " + file.string() + " is degenerate (no area)"
                                  : "no faces in " + file.string());

  MeshData m;
  m.degenerate_faces = degenerate;
  for (std::size_t i = 0; i < mtls.size(); ++i) {
    m.materials.push_back(convert_material(mtls[i], reader.folder_of(i)));
    m.bump_maps.push_back(mtls[i].bump_texname.empty() ? fs::path()
                                                        : file_texture(reader.folder_of(i), mtls[i].bump_texname).file);
    // Every map the MTL file names for qdmr (map_Kd, norm, disp, bump) is checked now, used or not: a damaged or
    // special file is an error even when the technique would not sample it.
    for (const std::string* map : {&mtls[i].diffuse_texname, &mtls[i].normal_texname, &mtls[i].displacement_texname,
                                   &mtls[i].bump_texname})
      if (!map->empty())
        static_cast<void>(read_image_header((reader.folder_of(i) / *map).lexically_normal(),
                                            where + ": material '" + mtls[i].name + "'"));
  }
  const auto default_material = std::uint32_t(m.materials.size());
  bool uses_default = false;

  const int positions = int(attrib.vertices.size() / 3), uvs = int(attrib.texcoords.size() / 2),
            normals = int(attrib.normals.size() / 3);
  std::unordered_map<CornerKey, std::uint32_t, CornerHash> vertex_of;
  vertex_of.reserve(corners);
  std::vector<int> position_of;    // per vertex: its OBJ position, to share computed normals
  std::vector<bool> needs_normal;  // per vertex: no usable normal in the file
  m.indices.reserve(corners);
  m.triangle_materials.reserve(corners / 3);
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const tinyobj::shape_t& shape = shapes[s];
    const std::vector<std::uint32_t>& corner_of = triangles[s].corners;
    for (std::size_t t = 0; t < corner_of.size(); t += 3) {
      const std::size_t f = triangles[s].faces[t / 3];
      const int material = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
      const bool known = material >= 0 && std::size_t(material) < mtls.size();
      uses_default = uses_default || !known;
      m.triangle_materials.push_back(known ? std::uint32_t(material) : default_material);
      for (std::size_t k = 0; k < 3; ++k) {
        const tinyobj::index_t& idx = shape.mesh.indices[corner_of[t + k]];
        if (idx.vertex_index < 0 || idx.vertex_index >= positions || idx.texcoord_index >= uvs ||
            idx.normal_index >= normals)
          throw Error(where, "face index out of range in " + file.string());
        const CornerKey key{idx.vertex_index, std::max(idx.texcoord_index, -1), std::max(idx.normal_index, -1)};
        const auto [it, inserted] = vertex_of.try_emplace(key, std::uint32_t(m.positions.size()));
        m.indices.push_back(it->second);
        if (!inserted) continue;
        const auto* p = &attrib.vertices[3 * std::size_t(key.v)];
        m.positions.emplace_back(p[0], p[1], p[2]);
        glm::vec2 uv(0.0f);
        if (key.vt >= 0) uv = glm::vec2(attrib.texcoords[2 * std::size_t(key.vt)], attrib.texcoords[2 * std::size_t(key.vt) + 1]);
        m.uvs.push_back(uv * desc.uv_scale);
        glm::dvec3 n(0.0);
        if (key.vn >= 0) {
          const auto* q = &attrib.normals[3 * std::size_t(key.vn)];
          n = glm::dvec3(q[0], q[1], q[2]);
        }
        const double len = glm::length(n);
        const bool usable = len > 0.0 && std::isfinite(len);
        m.normals.push_back(usable ? glm::vec3(n / len) : glm::vec3(0.0f));
        needs_normal.push_back(!usable);
        position_of.push_back(key.v);
      }
    }
  }
  if (uses_default) {
    LayerDesc white;
    white.albedo = constant_texture(glm::vec3(1.0f));
    MaterialDesc material;
    material.name = unique_name(m.materials, "default");
    material.layers = {white};
    m.materials.push_back(material);
    m.bump_maps.emplace_back();
  }

  // Missing normals: area-weighted face normals summed per OBJ position (smooth across UV seams).
  if (std::find(needs_normal.begin(), needs_normal.end(), true) != needs_normal.end()) {
    std::vector<glm::dvec3> sum(std::size_t(positions), glm::dvec3(0.0));
    for (std::size_t t = 0; t < m.indices.size(); t += 3) {
      const std::uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
      const glm::dvec3 pa(m.positions[a]);
      const glm::dvec3 face = glm::cross(glm::dvec3(m.positions[b]) - pa, glm::dvec3(m.positions[c]) - pa);
      for (const std::uint32_t v : {a, b, c}) sum[std::size_t(position_of[v])] += face;
    }
    for (std::size_t v = 0; v < m.positions.size(); ++v) {
      if (!needs_normal[v]) continue;
      const glm::dvec3 s = sum[std::size_t(position_of[v])];
      const double len = glm::length(s);
      m.normals[v] = len > 0.0 && std::isfinite(len) ? glm::vec3(s / len) : glm::vec3(0.0f, 0.0f, 1.0f);
    }
  }
  compute_tangents(m);
  return m;
}

}  // namespace qdmr::mesh_detail
