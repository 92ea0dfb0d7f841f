#include "qdmr/plan/plan.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "codec/native_reader.hpp"
#include "plan/program_choice.hpp"
#include "raster/framebuffer.hpp"
#include "bake/ao_map.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/mesh/mesh.hpp"
#include "texture/blend_box_values.hpp"
#include "texture/height_texture.hpp"
#include "qdmr/texture/image.hpp"
#include "texture/layer_heights.hpp"
#include "texture/pattern_reuse.hpp"
#include "texture/twin_texels.hpp"

namespace qdmr {
namespace {

// Texture keys print floats exactly (hexfloat): values that differ in the last bit are different textures.
std::string source_key(const TextureDesc& d) {
  std::ostringstream k;
  k << std::hexfloat;
  // The storage: the same source stored as r8 or BC3 is another texture.
  k << "fmt" << int(d.format) << ":bc" << int(d.compression) << ":";
  switch (d.source) {
    case TextureSource::None: k << "none"; break;
    case TextureSource::File: k << "file:" << d.file.string() << ":ch" << int(d.channel) << ":srgb" << d.srgb; break;
    case TextureSource::Constant: k << "const:" << d.constant.x << "," << d.constant.y << "," << d.constant.z << "," << d.constant.w; break;
    case TextureSource::Procedural: k << "proc:" << procedural_key(d.procedural); break;
    case TextureSource::FromHeight: k << "from_height"; break;
    case TextureSource::Pixels: k << "pixels:" << d.pixels_version; break;
  }
  return k.str();
}

std::string height_key(const LayerDesc& layer) {
  std::ostringstream k;
  k << std::hexfloat << source_key(layer.height) << ":scale" << layer.height_scale << ":offset" << layer.height_offset;
  return k.str();
}

std::string request_key(const TextureDesc& d, TexturePurpose purpose, const LayerDesc& layer) {
  std::ostringstream k;
  k << std::hexfloat << purpose_name(purpose) << "|" << source_key(d);
  if (purpose == TexturePurpose::Albedo && d.source == TextureSource::Procedural)
    k << ":low" << d.color_low.x << "," << d.color_low.y << "," << d.color_low.z << ":high" << d.color_high.x << ","
      << d.color_high.y << "," << d.color_high.z << ":var" << d.variation;
  // Only a factor other than 1 is in the key: the keys of untinted files stay as they were.
  if (purpose == TexturePurpose::Albedo && d.source == TextureSource::File && d.factor != glm::vec3(1.0f))
    k << ":factor" << d.factor.x << "," << d.factor.y << "," << d.factor.z;
  if (purpose == TexturePurpose::Normal)
    k << ":conv" << int(layer.normal_convention) << ":strength" << layer.normal_strength;
  if (purpose == TexturePurpose::Orm) k << "|occlusion:" << source_key(layer.occlusion);
  // What is made from the layer's heights (a procedural albedo is coloured by its own pattern, not by them).
  if (purpose == TexturePurpose::Height || d.source == TextureSource::FromHeight) k << "|height:" << height_key(layer);
  return k.str();
}

struct SourceInfo {
  int width = 1, height = 1;
  int bits = 8;  // per channel: 8 or 16 for integer files, 32 otherwise (as Image::source_bits)
  std::optional<ImageHeader> file;  // a file's header
};

// Level-0 size and bit depth of a texture without building it (file headers are read). A from_height normal
// map's are those of the layer's height.
SourceInfo texture_source(const TextureDesc& d, const LayerDesc& layer, const std::string& where) {
  switch (d.source) {
    case TextureSource::None:
    case TextureSource::Constant: return {};
    case TextureSource::Procedural: return {d.procedural.size, d.procedural.size, 16, std::nullopt};
    case TextureSource::Pixels: return {d.pixels->width, d.pixels->height, d.pixels->source_bits, std::nullopt};
    case TextureSource::FromHeight:
      if (layer.height.source == TextureSource::None || layer.height.source == TextureSource::FromHeight) return {};
      return texture_source(layer.height, layer, where);
    case TextureSource::File: {
      // The same checks as when the texture is read (kind, size, format, header), nothing decoded.
      const ImageHeader header = read_image_header(d.file, where + "/file");
      return {header.width, header.height, header.source_bits, header};
    }
  }
  return {};
}

// What building the request holds at once besides the finished texture: prepare's build_texture, step by step.
std::uint64_t texture_working_bytes(const TextureRequest& r, const SourceInfo& source) {
  const ImageHeader* file = source.file ? &*source.file : nullptr;
  const std::uint64_t texels = std::uint64_t(r.width) * std::uint64_t(r.height);
  const std::uint64_t height_image = texels * sizeof(float), colour_image = 3 * height_image;
  std::uint64_t peak = 0;
  if (r.purpose == TexturePurpose::Orm) {
    peak = std::max(orm_source(r.layer, r.where).build_bytes, colour_image + r.bytes);
  } else if (r.purpose == TexturePurpose::Height) {
    // The layer's heights, then that image while the chain is made from it.
    peak = std::max(make_texture_bytes(r.desc, r.purpose, r.width, r.height, file), height_image + r.bytes);
  } else if (r.desc.source == TextureSource::FromHeight) {
    const std::uint64_t stored = mip_chain_bytes(r.width, r.height, height_format(r.layer.height, source.bits));
    peak = std::max({make_texture_bytes(r.layer.height, TexturePurpose::Height, r.width, r.height, file),
                     height_image + stored,  // the heights as stored, and then their level 0 decoded from that
                     height_image + make_texture_bytes(r.desc, r.purpose, r.width, r.height, nullptr),  // normals
                     colour_image + r.bytes});  // level 0 while the chain is made
  } else {
    peak = std::max(make_texture_bytes(r.desc, r.purpose, r.width, r.height, file), colour_image + r.bytes);
  }
  return peak > r.bytes ? peak - r.bytes : 0;
}

// Texture build groups are built kTexturesBuiltAtOnce at a time, in any order: the most their builds hold at once is
// the sum of that many of the largest. A group holds its shared heights while its textures are built one by one.
std::uint64_t textures_working_bytes(const std::vector<TextureRequest>& textures) {
  std::vector<std::uint64_t> working;
  for (const std::vector<std::size_t>& group : texture_build_groups(textures)) {
    std::uint64_t shared = 0, most = 0;
    for (std::size_t i : group) {
      shared = std::max(shared, textures[i].shared_height_bytes);
      most = std::max(most, textures[i].working_bytes);
    }
    working.push_back((group.size() > 1 ? shared : 0) + most);
  }
  std::sort(working.begin(), working.end(), std::greater<>());
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < working.size() && i < kTexturesBuiltAtOnce; ++i) sum += working[i];
  return sum;
}

// The patterns asked for more than once while the weight maps, meshes and textures are built (PatternReuse): per
// texture build group, the layer's heights once where a member is made from them (the group shares them) and each
// member's own procedural source; a terrain blend's weight heights; a grid's height map. A pattern larger than
// kMaxReusedPatternSide is never kept. Textures a previous frame still holds are counted too: an upper bound.
void find_reused_patterns(FramePlan& plan) {
  std::map<std::string, std::pair<int, int>> uses;  // key -> (how many times, side)
  const auto use = [&](const TextureDesc& t) {
    if (t.source != TextureSource::Procedural || t.procedural.size > kMaxReusedPatternSide) return;
    auto& [count, side] = uses[procedural_key(t.procedural)];
    ++count, side = t.procedural.size;
  };
  for (const std::vector<std::size_t>& group : texture_build_groups(plan.textures)) {
    bool from_height = false;
    for (std::size_t i : group) {
      const TextureRequest& r = plan.textures[i];
      if (r.purpose == TexturePurpose::Height || r.desc.source == TextureSource::FromHeight)
        from_height = true;
      else
        use(r.desc);
    }
    if (from_height) use(plan.textures[group.front()].layer.height);
  }
  for (const MaterialPlan& m : plan.materials)
    if (m.blend && m.desc.blend.weights.source == WeightSource::Terrain) use(m.desc.blend.weights.height);
  for (const ObjectDesc& object : plan.scene.objects)
    if (object.mesh.kind == MeshKind::Grid) use(object.mesh.height_map);
  for (const auto& [key, count_side] : uses)
    if (count_side.first > 1) {
      plan.reused_patterns.push_back(key);
      plan.reused_pattern_bytes += kept_pattern_bytes(count_side.second);
    }
}

int mip_levels(int w, int h) {
  int levels = 1;
  while (w > 1 || h > 1) {
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
    ++levels;
  }
  return levels;
}

// Whether the texture keeps Texture::wrap_footprints: asked for, and within wrap_footprint_bytes' bound.
bool keeps_wrap_footprints(const TextureRequest& t) {
  return t.wrap_footprints && wrap_footprint_bytes(t.width, t.height, t.format, t.srgb) > 0;
}

const char* reduce_name(MipReduce r) {
  switch (r) {
    case MipReduce::Box: return "box";
    case MipReduce::BoxNormal: return "box, renormalised";
    case MipReduce::Max: return "max (quadtree)";
    case MipReduce::Min: return "min";
  }
  return "?";
}

int add_request(std::vector<TextureRequest>& textures, const TextureDesc& desc, TexturePurpose purpose,
                MipReduce reduce, const LayerDesc& layer, const std::string& where, const std::string& user,
                bool wrap_footprints = false) {
  // The footprints are in the key: a texture built without them is not reused where they are wanted.
  const std::string key =
      request_key(desc, purpose, layer) + "|mip" + std::to_string(int(reduce)) + (wrap_footprints ? "|wrap2x2" : "");
  for (std::size_t i = 0; i < textures.size(); ++i) {
    if (textures[i].key != key) continue;
    if (std::find(textures[i].users.begin(), textures[i].users.end(), user) == textures[i].users.end())
      textures[i].users.push_back(user);
    return int(i);
  }
  TextureRequest r;
  r.key = key;
  r.purpose = purpose;
  r.desc = desc;
  r.layer = layer;
  r.where = where;
  SourceInfo source;
  if (purpose == TexturePurpose::Orm) {
    const OrmSource orm = orm_source(layer, where);
    source.width = orm.width;
    source.height = orm.height;
  } else {
    source = texture_source(desc, layer, where);
  }
  r.width = source.width;
  r.height = source.height;
  r.reduce = reduce;
  r.srgb = purpose == TexturePurpose::Albedo;
  r.format = purpose == TexturePurpose::Height ? height_format(desc, source.bits) : TexelFormat::RGBA8;
  r.levels = mip_levels(r.width, r.height);
  r.wrap_footprints = wrap_footprints;
  r.bytes = mip_chain_bytes(r.width, r.height, r.format) + linear_copy_bytes(r.width, r.height, r.format, r.srgb) +
            (wrap_footprints ? wrap_footprint_bytes(r.width, r.height, r.format, r.srgb) : 0);
  r.working_bytes = texture_working_bytes(r, source);
  // Dynamic exactly when the key carries time or a handed-over version: the key then changes every frame.
  const auto changes = [](const TextureDesc& t) { return time_dependent(t) || t.source == TextureSource::Pixels; };
  const bool from_height = purpose == TexturePurpose::Height || desc.source == TextureSource::FromHeight;
  r.dynamic = changes(desc) || (from_height && changes(layer.height));
  if (from_height) {
    r.height_key = height_key(layer);
    r.shared_height_bytes = std::uint64_t(r.width) * std::uint64_t(r.height) * sizeof(float) +
                            mip_chain_bytes(r.width, r.height, height_format(layer.height, source.bits));
  }
  r.users.push_back(user);
  textures.push_back(std::move(r));
  return int(textures.size() - 1);
}

MeshPlan plan_mesh(const ObjectDesc& object, const std::string& mesh_key) {
  MeshPlan m;
  m.object = object.name;
  m.key = mesh_key;
  const MeshDesc& d = object.mesh;
  switch (d.kind) {
    case MeshKind::Plane: m.kind = "plane"; m.vertices = 4; m.triangles = 2; break;
    case MeshKind::Box: m.kind = "box"; m.vertices = 24; m.triangles = 12; break;
    case MeshKind::Sphere: {
      m.kind = "sphere";
      const std::uint64_t rings = std::uint64_t(std::max(2, d.segments / 2));
      m.vertices = (std::uint64_t(d.segments) + 1) * (rings + 1);
      m.triangles = std::uint64_t(d.segments) * rings * 2;
      break;
    }
    case MeshKind::Grid:
      m.kind = "grid";
      m.vertices = (std::uint64_t(d.resolution) + 1) * (std::uint64_t(d.resolution) + 1);
      m.triangles = 2ull * std::uint64_t(d.resolution) * std::uint64_t(d.resolution);
      break;
    case MeshKind::Obj:
    case MeshKind::Gltf:
      m.kind = (d.kind == MeshKind::Obj ? "obj " : "gltf ") + d.file.filename().string();
      m.vertices = object.obj_mesh ? object.obj_mesh->vertex_count() : 0;
      m.triangles = object.obj_mesh ? object.obj_mesh->triangle_count() : 0;
      if (object.obj_mesh) m.notes = object.obj_mesh->notes;
      m.degenerate_faces = object.obj_mesh ? object.obj_mesh->degenerate_faces : 0;
      break;
  }
  // position, normal, tangent, uv per vertex; three indices and a material id per triangle
  m.bytes = m.vertices * (3 + 3 + 4 + 2) * sizeof(float) + m.triangles * 4 * sizeof(std::uint32_t);
  return m;
}

// Content keys: every value that changes what is built, printed exactly (floats as their bits).
struct Key {
  std::ostringstream s;
  Key& operator()(const char* name) { s << name << "="; return *this; }
  Key& v(float x) { s << std::bit_cast<std::uint32_t>(x) << ";"; return *this; }
  Key& v(int x) { s << x << ";"; return *this; }
  Key& v(std::uint32_t x) { s << x << ";"; return *this; }
  Key& v(bool x) { s << (x ? 1 : 0) << ";"; return *this; }
  Key& v(const std::string& x) { s << x.size() << ":" << x << ";"; return *this; }
  Key& v(glm::vec2 x) { return v(x.x).v(x.y); }
  std::string str() const { return s.str(); }
};

std::string mesh_key(const ObjectDesc& object) {
  const MeshDesc& d = object.mesh;
  Key k;
  k("kind").v(int(d.kind));
  switch (d.kind) {
    case MeshKind::Obj: k("file").v(d.file.string())("uv_scale").v(d.uv_scale); break;
    case MeshKind::Gltf:
      k("file").v(d.file.string())("scene").v(d.gltf_scene.index).v(d.gltf_scene.name)("node").v(d.gltf_node.index)
          .v(d.gltf_node.name);
      break;
    case MeshKind::Grid:
      k("size").v(d.size)("uv_scale").v(d.uv_scale)("resolution").v(d.resolution)("height").v(d.height)("map")
          .v(source_key(d.height_map));
      break;
    default: k("size").v(d.size)("uv_scale").v(d.uv_scale)("segments").v(d.segments); break;
  }
  return k.str();
}

std::string weights_key(const WeightsDesc& w, int layers) {
  Key k;
  k("layers").v(layers)("mode").v(int(w.mode))("source").v(int(w.source))("scale").v(w.scale)("resolution").v(w.resolution)(
       "from_vertices")
      .v(w.from_vertices)("seed").v(w.seed)("cells").v(w.cells)("sharpness").v(w.sharpness)("height")
      .v(source_key(w.height))("low").v(w.low)("slope").v(w.slope)("relief").v(w.relief)("file").v(w.file.string());
  return k.str();
}

std::string ao_key(const AoDesc& ao, float depth_scale) {
  Key k;
  k("depth_scale").v(depth_scale)("directions").v(ao.directions)("jitter").v(ao.jitter)("seed").v(ao.seed)("radius")
      .v(ao.radius)("coarse").v(ao.coarse)("strength").v(ao.strength)("resolution").v(ao.resolution);
  if (ao.amortize_frames > 1) k("amortize_frames").v(ao.amortize_frames);
  return k.str();
}

// A dynamic AO map amortized over frames keeps its rows in floats for the next frame (prepare's AoHistory).
void keep_ao_rows(DerivedPlan& d, const AoDesc& ao, AoMapSize side) {
  if (d.dynamic && ao.amortize_frames > 1) d.bytes += std::uint64_t(side.width) * std::uint64_t(side.height) * sizeof(float);
}

std::string mib(std::uint64_t bytes) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(2);
  s << double(bytes) / (1024.0 * 1024.0) << " MiB";
  return s.str();
}

}  // namespace

const char* derived_kind_name(DerivedKind kind) {
  switch (kind) {
    case DerivedKind::WeightTexture: return "weight_texture";
    case DerivedKind::CombinedSurface: return "combined_surface";
    case DerivedKind::CombinedQuadtree: return "combined_quadtree";
    case DerivedKind::BlendAoMap: return "blend_ao_map";
    case DerivedKind::HeightField: return "height_field";
    case DerivedKind::LayerAoMap: return "layer_ao_map";
    case DerivedKind::ConeMap: return "cone_map";
    case DerivedKind::BilinearBound: return "bilinear_bound";
    case DerivedKind::TwinTexels: return "twin_texels";
  }
  return "?";
}

namespace {

// Plans a frame: materials on first use, their textures and derived data, deduplicated by content key.
class Planner {
public:
  Planner(const SceneDesc& scene, FramePlan& plan) : scene_(scene), plan_(plan), file_(scene.file.string()) {}

  // `where` names the field that uses the material; a file's materials (`file_kind` "MTL" or "glTF") are named
  // after it, scene materials (`file_kind` null) by their own JSON pointer.
  std::uint32_t material(const std::string& name, const std::string& where, const char* file_kind) {
    for (std::size_t i = 0; i < plan_.materials.size(); ++i)
      if (plan_.materials[i].name == name) return std::uint32_t(i);
    const MaterialDesc* desc = scene_.find_material(name);
    if (!desc) throw Error(where, "unknown material '" + name + "'");
    choices_.emplace_back();
    plan_.materials.push_back(plan_material(
        *desc, file_kind ? where + ": " + file_kind + " material '" + name + "'" : file_ + ": /materials/" + name,
        choices_.back()));
    return std::uint32_t(plan_.materials.size() - 1);
  }

  // Derived data of materials, once every object is known (blend weights read the meshes using them).
  void derived(std::uint32_t index) {
    MaterialPlan& m = plan_.materials[index];
    const Choices& c = choices_[index];
    const MaterialDesc& desc = m.desc;
    const std::string& where = m.where;
    const bool displaced = m.technique != TechniqueKind::Normal;
    m.reference = displaced && (desc.technique.exact_hits ||
                                std::any_of(plan_.aovs.begin(), plan_.aovs.end(), is_reference_aov));
    const std::string address = "address=" + std::to_string(int(desc.sampling.address));
    const auto field_of = [&](std::size_t layer) {
      LayerPlan& l = m.layers[layer];
      if (l.field < 0)
        l.field = add(DerivedKind::HeightField, "field|" + plan_.textures[std::size_t(l.height)].key + "|" + address,
                      where + "/layers/" + std::to_string(layer) + "/height", {}, index,
                      std::uint64_t(plan_.textures[std::size_t(l.height)].width) *
                          std::uint64_t(plan_.textures[std::size_t(l.height)].height) * sizeof(double),
                      l.height);
      return l.field;
    };
    std::string heights;
    bool heights_dynamic = false;
    for (const LayerPlan& l : m.layers) {
      heights += (l.height >= 0 ? plan_.textures[std::size_t(l.height)].key : "-") + "|";
      heights_dynamic = heights_dynamic || (l.height >= 0 && plan_.textures[std::size_t(l.height)].dynamic);
    }

    // Albedo and normal map interleaved where the program samples them as twins (TwinSampler: RGBA8 chains of one
    // size, the albedo with its decoded copy, under a sampling whose twins share addresses).
    for (std::size_t layer = 0; layer < m.layers.size() && twin_sampling(desc.sampling); ++layer) {
      LayerPlan& l = m.layers[layer];
      if (l.albedo < 0 || l.normal < 0) continue;
      const TextureRequest &a = plan_.textures[std::size_t(l.albedo)], &n = plan_.textures[std::size_t(l.normal)];
      const std::uint64_t bytes = twin_texels_bytes(a.width, a.height);
      if (a.format != TexelFormat::RGBA8 || !a.srgb || n.format != TexelFormat::RGBA8 || n.srgb || a.width != n.width ||
          a.height != n.height || bytes == 0)
        continue;
      l.twin = add(DerivedKind::TwinTexels, a.key + "|" + n.key, where + "/layers/" + std::to_string(layer), {}, index,
                   bytes, l.albedo, 0, l.normal);
    }

    if (m.blend) {
      const WeightsDesc& w = desc.blend.weights;
      std::string wkey = "weights|" + weights_key(w, int(m.layers.size()));
      if (w.from_vertices)
        for (std::size_t o : m.objects) wkey += "|mesh:" + plan_.meshes[o].key;
      const bool whole = w.scale == std::floor(w.scale) && w.scale >= 1.0f;
      const bool needs_combined = c.combined_quadtree || m.reference || c.blend_ao;
      if (m.weight_mode == WeightMode::Pixel || needs_combined)
        m.weights = add(DerivedKind::WeightTexture, wkey, where + "/blend/weights", {}, index,
                        mip_chain_bytes(w.resolution, w.resolution, TexelFormat::RGBA8), -1, 0, -1,
                        time_dependent(w.height));
      if (needs_combined) {
        if (!whole)
          throw Error(where + "/blend/weights/scale", m.reference ? "error AOVs of a blend need a whole number of repeats"
                                                                 : "must be a whole number of repeats here");
        const TextureRequest& h = plan_.textures[std::size_t(m.layers[0].height)];
        m.weights_scale = int(w.scale);
        const std::uint64_t texels = std::uint64_t(h.width) * std::uint64_t(h.height) * std::uint64_t(m.weights_scale) *
                                     std::uint64_t(m.weights_scale);
        if (m.reference && texels > (1ull << 26))
          throw Error(where + "/blend/weights/scale", "error AOVs of this blend need a reference of " +
                                                          std::to_string(texels) +
                                                          " texels (the layers' size times scale squared), more than 2^26");
        Key op;
        op("op").v(int(desc.blend.op))("width").v(desc.blend.width);
        const std::string surface_key = "combined|" + heights + wkey + "|" + op.str();
        // Where the walk keeps its fp32 level 0 (blend_box_values), the tree and the AO map are made from those
        // values: the surface the walk intersects. The fp64 surface is then made for the exact reference only.
        const bool from_box_values = c.combined_quadtree && c.box_values;
        if (m.reference || !from_box_values)
          m.combined_surface = add(DerivedKind::CombinedSurface, surface_key, where + "/blend", {m.weights}, index,
                                   texels * sizeof(double), -1, 0, -1, heights_dynamic);
        const std::string source_key =
            from_box_values ? "box|" + surface_key : plan_.derived[std::size_t(m.combined_surface)].key;
        if (c.combined_quadtree) {
          // From the box values: the weights are its only input (the tree and the AO map read the values as floats).
          std::vector<int> inputs{m.weights};
          if (!from_box_values) inputs.insert(inputs.begin(), m.combined_surface);
          m.combined_quadtree = add(DerivedKind::CombinedQuadtree, "quadtree|" + source_key, where + "/blend/quadtree",
                                    std::move(inputs), index, c.combined_bytes, -1, 0, -1, heights_dynamic);
        }
        if (c.blend_ao) {
          AoDesc ao = desc.ao;
          ao.resolution = c.ao_side;
          const int field_w = h.width * m.weights_scale, field_h = h.height * m.weights_scale;
          const AoMapSize side = ao_map_size(field_w, field_h, ao);
          m.blend_ao = add(DerivedKind::BlendAoMap, "ao|" + source_key + "|" + ao_key(ao, desc.technique.depth_scale),
                           where + "/ao", {from_box_values ? m.combined_quadtree : m.combined_surface}, index,
                           mip_chain_bytes(side.width, side.height, TexelFormat::R16), -1, side.width);
          plan_.derived[std::size_t(m.blend_ao)].working_bytes =
              ao_bake_bytes(field_w, field_h, ao, from_box_values ? int(sizeof(float)) : int(sizeof(double)));
          keep_ao_rows(plan_.derived[std::size_t(m.blend_ao)], ao, side);
        }
      }
    }
    if (desc.ao.mode == AoMode::Baked && !c.blend_ao) {
      for (std::size_t l = 0; l < m.layers.size(); ++l) {
        const int field = field_of(l);
        const TextureRequest& h = plan_.textures[std::size_t(m.layers[l].height)];
        const AoMapSize side = ao_map_size(h.width, h.height, desc.ao);
        m.layers[l].ao = add(DerivedKind::LayerAoMap,
                             "ao|" + plan_.derived[std::size_t(field)].key + "|" + ao_key(desc.ao, desc.technique.depth_scale),
                             where + "/ao", {field}, index, mip_chain_bytes(side.width, side.height, TexelFormat::R16), -1,
                             side.width);
        // Baked (unless cached): the map in floats and, for coarse taps, the heights' max pyramid.
        plan_.derived[std::size_t(m.layers[l].ao)].working_bytes = ao_bake_bytes(h.width, h.height, desc.ao);
        keep_ao_rows(plan_.derived[std::size_t(m.layers[l].ao)], desc.ao, side);
      }
    }
    const bool bilinear_patch =
        m.technique == TechniqueKind::Qdm && desc.technique.refinement == QdmRefinement::BilinearPatch && !m.blend;
    if (m.cone_map || bilinear_patch || (m.reference && !m.blend)) {
      const int field = field_of(0);
      const TextureRequest& h = plan_.textures[std::size_t(m.layers[0].height)];
      const std::string& field_key = plan_.derived[std::size_t(field)].key;
      if (m.cone_map && plan_.derived[std::size_t(field)].dynamic && !scene_.animation.rebake_cones)
        throw Error(where + "/technique/name",
                    std::string("'") + technique_name(m.technique) +
                        "' marches a cone map baked from the heights, and this material's heights change every frame "
                        "(a bake per frame takes seconds to minutes): use qdm or pom for dynamic surfaces (qdm rebuilds "
                        "its max-quadtree per frame in well under a millisecond), or set /animation/rebake_cones to "
                        "true to bake every frame");
      if (m.cone_map) {
        const std::uint64_t map = std::uint64_t(h.width) * std::uint64_t(h.height) * sizeof(float);
        m.cones = add(DerivedKind::ConeMap, "cones|" + std::to_string(int(m.cone_kind)) + "|" + field_key,
                      where + "/technique", {field}, index, map);
        // Baked (unless the cache has it; the plan cannot count on that): the baker's grid of doubles (mirror
        // unfolded to 2W x 2H; 4 wall channels for relaxed) and its max hierarchy, held while it bakes. Its
        // field is item `field`, its map `map`.
        plan_.derived[std::size_t(m.cones)].working_bytes =
            cone_bake_bytes(h.width, h.height, m.cone_kind, desc.sampling.address) - map;
      }
      if (bilinear_patch)
        m.bilinear_bound = add(DerivedKind::BilinearBound, "bilinear_bound|" + field_key, where + "/technique/refinement",
                               {field}, index, mip_chain_bytes(h.width, h.height, TexelFormat::R32F));
    }
  }

private:
  // `dynamic`: made from something that changes every frame besides its inputs and textures (a blend's heights).
  int add(DerivedKind kind, const std::string& key, const std::string& where, std::vector<int> inputs, std::uint32_t material,
          std::uint64_t bytes, int texture = -1, int side = 0, int second_texture = -1, bool dynamic = false) {
    const std::string full = std::string(derived_kind_name(kind)) + "|" + key;
    for (std::size_t i = 0; i < plan_.derived.size(); ++i)
      if (plan_.derived[i].key == full) return int(i);
    for (int in : inputs) dynamic = dynamic || plan_.derived[std::size_t(in)].dynamic;
    for (int t : {texture, second_texture}) dynamic = dynamic || (t >= 0 && plan_.textures[std::size_t(t)].dynamic);
    DerivedPlan d{kind, full, where, std::move(inputs), texture, second_texture, int(material), side, bytes};
    d.dynamic = dynamic;
    plan_.derived.push_back(std::move(d));
    return int(plan_.derived.size() - 1);
  }

  // What plan_material decided that derived() turns into items.
  struct Choices {
    bool combined_quadtree = false, blend_ao = false;
    bool box_values = false;  // with the combined quadtree: the walk's fp32 level 0 (blend_box_values)
    std::uint64_t combined_bytes = 0;
    int ao_side = 0;
  };
  MaterialPlan plan_material(const MaterialDesc& material, const std::string& where, Choices& choices);

  const SceneDesc& scene_;
  FramePlan& plan_;
  std::string file_;
  std::vector<Choices> choices_;  // parallel to plan_.materials
};

MaterialPlan Planner::plan_material(const MaterialDesc& material, const std::string& where, Choices& choices) {
  std::vector<TextureRequest>& textures = plan_.textures;
  MaterialPlan plan;
  plan.name = material.name;
  plan.where = where;
  plan.desc = material;
  plan.technique = material.technique.kind;
  const TechniqueKind kind = material.technique.kind;
  const std::size_t layer_count = material.layers.size();
  plan.blend = layer_count > 1;
  plan.weight_mode = material.blend.weights.mode;
  const bool displaced = kind != TechniqueKind::Normal;
  const bool blend_by_height = plan.blend && material.blend.op != BlendOperator::Alpha;
  // The max-quadtree serves QDM, and self-shadowing and AO queries that read coarse levels.
  const bool hierarchy = kind == TechniqueKind::Qdm || material.shadow.mode == ShadowMode::QdmSoft ||
                         (material.ao.mode != AoMode::Off && material.ao.coarse);
  plan.key = program_key(material);
  plan.params = program_params(material);
  plan.variant = variant_name(plan.key);

  if (plan.blend && (kind == TechniqueKind::Csm || kind == TechniqueKind::Rcsm))
    throw Error(where + "/technique/name", std::string("'") + technique_name(kind) +
                                               "' needs a cone map of one height map and cannot march blended layers "
                                               "(use relief, pom or qdm)");
  int side_w = 0, side_h = 0;
  for (std::size_t i = 0; i < layer_count; ++i) {
    const LayerDesc& layer = material.layers[i];
    const std::string layer_where = where + "/layers/" + std::to_string(i);
    LayerPlan lp;
    lp.albedo = add_request(textures, layer.albedo, TexturePurpose::Albedo, MipReduce::Box, layer,
                            layer_where + "/albedo", material.name);
    lp.normal = add_request(textures, layer.normal, TexturePurpose::Normal, MipReduce::BoxNormal, layer,
                            layer_where + "/normal", material.name);
    if (plan.key.orm)
      lp.orm = add_request(textures, layer.orm, TexturePurpose::Orm, MipReduce::Box, layer, layer_where, material.name);
    if (displaced || blend_by_height) {
      if (layer.height.source == TextureSource::None)
        throw Error(layer_where + "/height", displaced ? std::string("technique '") + technique_name(kind) + "' needs a height map"
                                                       : std::string("height blending needs a height map in every layer"));
      // Heights fetched bilinearly with wrap addressing read level 0's footprints whole (Texture::wrap_footprints).
      // Not for blended layers: their fetches read every layer at one point, and four footprint arrays (16 bytes
      // per texel each) missed the cache more than they saved (the terrain's frame slower, docs/performance-history.md).
      const bool wrap_footprints = !plan.blend && material.technique.height_fetch == HeightFetch::Bilinear &&
                                   material.sampling.address == AddressMode::Wrap;
      lp.height = add_request(textures, layer.height, TexturePurpose::Height, MipReduce::Box, layer,
                              layer_where + "/height", material.name, wrap_footprints);
      const TextureRequest& h = textures[std::size_t(lp.height)];
      if (plan.blend && displaced) {
        // Blended layers are marched as one surface on one texel grid.
        if (i == 0) {
          side_w = h.width;
          side_h = h.height;
        } else if (h.width != side_w || h.height != side_h) {
          throw Error(layer_where + "/height", "blended layers need height maps of one size: layer 0 is " +
                                                   std::to_string(side_w) + "x" + std::to_string(side_h) + ", this one " +
                                                   std::to_string(h.width) + "x" + std::to_string(h.height));
        }
      }
      if (displaced && hierarchy) {
        const bool pot = (h.width & (h.width - 1)) == 0 && (h.height & (h.height - 1)) == 0;
        if (!pot)
          throw Error(layer_where + "/height", std::string(kind == TechniqueKind::Qdm ? "qdm" : "a max-quadtree (qdm_soft shadows, coarse AO)") +
                                                   " needs a power-of-two height map, got " + std::to_string(h.width) +
                                                   "x" + std::to_string(h.height));
        lp.height_max = add_request(textures, layer.height, TexturePurpose::Height, MipReduce::Max, layer,
                                    layer_where + "/height", material.name);
      }
    }
    plan.layers.push_back(lp);
  }
  if (plan.blend && material.blend.weights.mode == WeightMode::Pixel) {
    const int r = material.blend.weights.resolution;
    if ((r & (r - 1)) != 0)
      throw Error(where + "/blend/weights/resolution", "must be a power of two, got " + std::to_string(r));
    const BlendQuadtree choice = material.blend.quadtree;
    if (kind == TechniqueKind::Qdm && choice != BlendQuadtree::Product) {
      // The combined tree spans the weights' repeats: a whole number of them, and not too many texels.
      const float scale = material.blend.weights.scale;
      const TextureRequest& h = textures[std::size_t(plan.layers[0].height)];
      const std::uint64_t side_x = std::uint64_t(h.width) * std::uint64_t(scale) / 2;
      const std::uint64_t side_y = std::uint64_t(h.height) * std::uint64_t(scale) / 2;
      const bool whole = scale == std::floor(scale) && scale >= 1.0f;
      const bool fits = whole && side_x * side_y <= (1ull << 22);
      if (choice == BlendQuadtree::Combined && !fits)
        throw Error(where + "/blend/quadtree",
                    whole ? "the combined quadtree would have " + std::to_string(side_x * side_y) +
                                " texels at its first level, more than 2^22 (use 'product')"
                          : "'combined' needs blend/weights/scale to be a whole number of repeats (use 'product')");
      if (fits) {
        choices.combined_quadtree = true;
        // The tree, the layers' level-0 heights side by side (LayerHeights) and, from them, the blended level-0
        // values of the period (blend_box_values) for the walk's level-0 cells.
        std::vector<TexelFormat> formats;
        for (const LayerPlan& l : plan.layers) formats.push_back(textures[std::size_t(l.height_max)].format);
        const std::uint64_t heights = layer_heights_bytes(h.width, h.height, formats);
        const std::uint64_t box_values = blend_box_values_bytes(h.width, h.height, int(scale), heights);
        choices.box_values = box_values > 0;
        choices.combined_bytes = mip_chain_bytes(int(side_x), int(side_y), TexelFormat::R16) + heights + box_values;
      }
    }
  }
  const float weight_scale = material.blend.weights.scale;
  if (material.ao.mode == AoMode::Baked && plan.blend && weight_scale == std::floor(weight_scale) && weight_scale >= 1.0f) {
    // One map of the blended surface over the weights span (side: the setting, else that span's texels up to 2048).
    const TextureRequest& h = textures[std::size_t(plan.layers[0].height)];
    const std::uint64_t span = std::uint64_t(h.width) * std::uint64_t(weight_scale);
    choices.blend_ao = true;
    choices.ao_side = material.ao.resolution > 0 ? material.ao.resolution : int(std::min<std::uint64_t>(span, 2048));
  }
  if (kind == TechniqueKind::Csm || kind == TechniqueKind::Rcsm) {
    // Cones of the stored heights' level 0 (the box surface); the box-filtered chain serves the refinement.
    plan.cone_map = true;
    plan.cone_kind = kind == TechniqueKind::Csm ? ConeKind::Conservative : ConeKind::Relaxed;
  }
  return plan;
}

// Whether building the frame reads an image file through the image module (the `qdmr` command then loads it):
// PNG, JPEG, OpenEXR, PBM/PGM/PPM and most TIFF files are read in process (codec/native_reader.hpp).
bool reads_image_files(const SceneDesc& scene, const FramePlan& plan) {
  const auto through_module = [](const TextureDesc& d) {
    return d.source == TextureSource::File && !imageio::read_natively(d.file.string());
  };
  for (const TextureRequest& t : plan.textures)
    if (through_module(t.desc) || (t.desc.source == TextureSource::FromHeight && through_module(t.layer.height))) return true;
  for (const ObjectDesc& object : scene.objects)
    if (through_module(object.mesh.height_map)) return true;
  for (const MaterialPlan& m : plan.materials) {
    if (!m.blend) continue;
    const WeightsDesc& w = m.desc.blend.weights;
    if ((w.source == WeightSource::File && !imageio::read_natively(w.file.string())) ||
        (w.source == WeightSource::Terrain && through_module(w.height)))
      return true;
  }
  return false;
}

}  // namespace

FramePlan plan_frame(const SceneDesc& scene, const PlanOptions& options) {
  FramePlan plan;
  plan.scene = scene;
  plan.options = options;
  plan.width = scene.output.width;
  plan.height = scene.output.height;
  plan.aovs = options.aovs;
  // The cache_misses AOV is the emulated cache's output: asking for it turns the cache on (default settings).
  if (std::find(plan.aovs.begin(), plan.aovs.end(), Aov::CacheMisses) != plan.aovs.end())
    plan.scene.texture_cache.enabled = true;
  const std::string file = scene.file.string();
  Planner planner(scene, plan);
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const ObjectDesc& object = scene.objects[i];
    const std::string where = file + ": /objects/" + std::to_string(i);
    MeshPlan mesh = plan_mesh(object, mesh_key(object));
    mesh.dynamic = time_dependent(object.mesh.height_map);
    if (!object.material.empty()) {
      // An explicit material overrides the MTL: every triangle of the object uses it.
      mesh.material = planner.material(object.material, where + "/material", nullptr);
      plan.materials[mesh.material].objects.push_back(i);
      if (object.obj_mesh) mesh.mtl_materials.assign(object.obj_mesh->materials.size(), mesh.material);
    } else {
      for (const std::string& name : object.mtl_materials) {
        mesh.mtl_materials.push_back(planner.material(name, object.mesh.file.string() + " (" + where + "/mesh/file)",
                                                      object.mesh.kind == MeshKind::Gltf ? "glTF" : "MTL"));
        plan.materials[mesh.mtl_materials.back()].objects.push_back(i);
      }
      if (mesh.mtl_materials.empty()) throw Error(where + "/material", "required (the mesh has no MTL materials)");
    }
    plan.meshes.push_back(std::move(mesh));
  }
  // Per-vertex blend weights live in the meshes: part of their content.
  for (std::size_t m = 0; m < plan.materials.size(); ++m) {
    const MaterialPlan& material = plan.materials[m];
    if (!material.blend || material.weight_mode != WeightMode::Vertex) continue;
    for (std::size_t o : material.objects) {
      MeshPlan& mesh = plan.meshes[o];
      mesh.vertex_weights = int(m);
      mesh.key += "|vertex_weights:" + weights_key(material.desc.blend.weights, int(material.layers.size()));
      mesh.bytes += mesh.vertices * 4 * sizeof(float);
    }
  }
  for (std::size_t m = 0; m < plan.materials.size(); ++m) planner.derived(std::uint32_t(m));

  for (const MeshPlan& m : plan.meshes) plan.mesh_bytes += m.bytes;
  for (const TextureRequest& t : plan.textures) plan.texture_bytes += t.bytes;
  find_reused_patterns(plan);
  plan.texture_working_bytes = textures_working_bytes(plan.textures) + plan.reused_pattern_bytes;
  plan.working_bytes = plan.texture_working_bytes;
  for (const DerivedPlan& d : plan.derived) {
    plan.derived_bytes += d.bytes;
    plan.working_bytes = std::max(plan.working_bytes, d.working_bytes);
  }
  std::uint64_t per_pixel = keeps_depth_plane(plan.aovs) ? 4 : 3;  // colour (3) and depth (1) floats
  for (Aov aov : plan.aovs) per_pixel += std::uint64_t(aov_channels(aov));
  plan.framebuffer_bytes = std::uint64_t(plan.width) * std::uint64_t(plan.height) * per_pixel * sizeof(float);
  plan.image_module_bytes = reads_image_files(scene, plan) ? kImageModuleBytes : 0;
  return plan;
}

std::vector<std::string> FramePlan::items() const {
  std::vector<std::string> items;
  for (const MeshPlan& m : meshes) items.push_back("mesh " + m.key);
  for (const TextureRequest& t : textures) items.push_back("texture " + t.key);
  for (const DerivedPlan& d : derived) items.push_back(d.key);
  return items;
}

std::vector<std::vector<std::size_t>> texture_build_groups(const std::vector<TextureRequest>& textures) {
  std::vector<std::vector<std::size_t>> groups;
  std::map<std::string, std::size_t> group_of;  // height_key -> its group
  for (std::size_t i = 0; i < textures.size(); ++i) {
    const std::string& key = textures[i].height_key;
    if (!key.empty()) {
      if (const auto [it, added] = group_of.emplace(key, groups.size()); !added) {
        groups[it->second].push_back(i);
        continue;
      }
    }
    groups.push_back({i});
  }
  return groups;
}

std::vector<std::string> FramePlan::dynamic_items() const {
  std::vector<std::string> items;
  for (const MeshPlan& m : meshes)
    if (m.dynamic) items.push_back("mesh " + m.key);
  for (const TextureRequest& t : textures)
    if (t.dynamic) items.push_back("texture " + t.key);
  for (const DerivedPlan& d : derived)
    if (d.dynamic) items.push_back(d.key);
  return items;
}

std::string FramePlan::describe() const {
  std::ostringstream s;
  s << "output: " << width << "x" << height << "\n";
  if (scene.animation.present)
    s << "animation: " << scene.animation.frames << " frames at " << scene.animation.fps << " fps; "
      << dynamic_items().size() << " dynamic items, rebuilt every frame\n";
  // A moving camera rebuilds nothing: each frame's camera is only the draw's view.
  if (!scene.camera.keyframes.empty())
    s << "camera: animated, " << scene.camera.keyframes.size() << " keyframes, "
      << (scene.camera.interpolation == CameraInterpolation::Smooth ? "smooth" : "linear") << " interpolation\n";
  s << "materials (" << materials.size() << "):\n";
  for (const MaterialPlan& m : materials) {
    s << "  " << m.name << ": " << m.variant << "\n";
    for (std::size_t i = 0; i < m.layers.size(); ++i) {
      const LayerPlan& l = m.layers[i];
      s << "    layer " << i << ": albedo: texture " << l.albedo << ", normal: texture " << l.normal;
      if (l.height >= 0) s << ", height: texture " << l.height;
      if (l.height_max >= 0) s << ", max-quadtree: texture " << l.height_max;
      if (l.ao >= 0) s << ", ao: derived " << l.ao;
      if (l.orm >= 0) s << ", orm: texture " << l.orm;
      s << "\n";
    }
    if (m.blend)
      s << "    blend weights: " << (m.weight_mode == WeightMode::Vertex ? "per vertex (in the meshes)" : "per pixel") << "\n";
    std::ostringstream uses;
    for (int d : {m.weights, m.combined_surface, m.combined_quadtree, m.blend_ao, m.cones, m.bilinear_bound})
      if (d >= 0) uses << " [" << d << "]";
    if (!m.layers.empty() && m.layers[0].field >= 0) uses << " [" << m.layers[0].field << "]";
    if (!uses.str().empty()) s << "    derived:" << uses.str() << "\n";
    if (m.reference)
      s << (m.desc.technique.exact_hits ? "    takes its hits from the exact reference (exact_hits)\n"
                                        : "    traces the exact reference (error AOVs)\n");
  }
  s << "textures to build (" << textures.size() << "):\n";
  for (std::size_t i = 0; i < textures.size(); ++i) {
    const TextureRequest& t = textures[i];
    s << "  [" << i << "] " << purpose_name(t.purpose) << " " << t.width << "x" << t.height << " "
      << format_name(t.format) << (t.srgb ? " sRGB" : "") << ", " << reduce_name(t.reduce) << " mip chain of "
      << t.levels << " levels" << (keeps_wrap_footprints(t) ? " and level 0's wrap footprints" : "") << ", "
      << mib(t.bytes);
    if (t.working_bytes >= (1 << 20) / 100) s << " (" << mib(t.working_bytes) << " more while it is built)";
    s << "  <- " << t.where;
    if (t.desc.source == TextureSource::File) s << " (" << t.desc.file.filename().string() << ")";
    if (t.purpose == TexturePurpose::Orm && t.layer.occlusion.source == TextureSource::File)
      s << " (occlusion from " << t.layer.occlusion.file.filename().string() << ")";
    if (t.dynamic) s << ", dynamic (rebuilt every frame)";
    s << "\n";
  }
  s << "derived data to build (" << derived.size() << "):\n";
  for (std::size_t i = 0; i < derived.size(); ++i) {
    const DerivedPlan& d = derived[i];
    s << "  [" << i << "] " << derived_kind_name(d.kind);
    if (d.kind == DerivedKind::ConeMap || d.kind == DerivedKind::BlendAoMap || d.kind == DerivedKind::LayerAoMap)
      s << " (baked or from the cache)";
    if (!d.inputs.empty()) {
      s << " from";
      for (int in : d.inputs) s << " [" << in << "]";
    }
    if (d.texture >= 0) s << " from texture " << d.texture;
    s << ", " << mib(d.bytes);
    if (d.working_bytes > 0) s << " (" << mib(d.working_bytes) << " more while it is baked)";
    const int amortize = materials[std::size_t(d.material)].desc.ao.amortize_frames;
    const bool ao = d.kind == DerivedKind::BlendAoMap || d.kind == DerivedKind::LayerAoMap;
    s << "  <- " << d.where;
    if (d.dynamic && ao && amortize > 1)
      s << ", dynamic (1/" << amortize << " of its rows rebaked every frame, the others kept from the frames before)";
    else if (d.dynamic)
      s << ", dynamic (rebuilt every frame)";
    s << "\n";
  }
  s << "meshes (" << meshes.size() << "):\n";
  for (const MeshPlan& m : meshes) {
    s << "  " << m.object << ": " << m.kind << ", " << m.vertices << " vertices, " << m.triangles << " triangles, "
      << mib(m.bytes);
    if (m.degenerate_faces > 0) s << ", " << m.degenerate_faces << " degenerate faces dropped";
    if (m.vertex_weights >= 0) s << ", per-vertex weights of " << materials[std::size_t(m.vertex_weights)].name;
    if (m.dynamic) s << ", dynamic (rebuilt every frame)";
    if (!m.mtl_materials.empty() && (m.mtl_materials.size() > 1 || m.mtl_materials[0] != m.material)) {
      s << (m.kind.starts_with("gltf") ? ", glTF materials:" : ", MTL materials:");
      for (std::uint32_t mat : m.mtl_materials) s << " " << materials[mat].name;
    }
    s << "\n";
    for (const std::string& note : m.notes) s << "    warning: " << note << "\n";
  }
  s << "aovs:";
  if (aovs.empty()) s << " none";
  for (Aov a : aovs) s << " " << aov_name(a);
  s << "\n";
  if (const TextureCacheDesc& c = scene.texture_cache; c.enabled)
    s << "texture cache (emulated): " << c.size_bytes << " bytes, " << c.line_bytes << "-byte lines, " << c.ways
      << "-way " << cache_replacement_name(c.replacement) << "; " << texel_layout_name(c.layout) << " texels, quadtrees as "
      << quadtree_storage_name(c.quadtree) << "; " << c.warp << "-pixel warps, cold in each " << c.region << "x"
      << c.region << " region\n";
  s << "memory: framebuffer " << mib(framebuffer_bytes) << ", textures " << mib(texture_bytes)
    << (derived_bytes > 0 ? ", derived " + mib(derived_bytes) : std::string()) << ", meshes " << mib(mesh_bytes);
  if (working_bytes > 0)
    s << ", working " << mib(working_bytes)
      << (working_bytes == texture_working_bytes ? " (while textures are built)" : " (while a map is baked)");
  if (image_module_bytes > 0) s << ", image library " << mib(image_module_bytes) << " (to read image files)";
  s << ", total " << mib(total_bytes()) << "\n";
  return s.str();
}

nlohmann::json FramePlan::to_json() const {
  nlohmann::json j;
  j["width"] = width;
  j["height"] = height;
  j["materials"] = nlohmann::json::array();
  for (const MaterialPlan& m : materials) {
    nlohmann::json layers = nlohmann::json::array();
    for (const LayerPlan& l : m.layers)
      layers.push_back({{"albedo", l.albedo}, {"normal", l.normal}, {"height", l.height}, {"height_max", l.height_max},
                        {"field", l.field}, {"ao", l.ao}});
    if (!m.layers.empty() && m.layers.front().orm >= 0) layers.front()["orm"] = m.layers.front().orm;
    j["materials"].push_back({{"name", m.name}, {"variant", m.variant}, {"technique", technique_name(m.technique)},
                              {"layers", layers}, {"reference", m.reference},
                              {"derived", {{"weights", m.weights}, {"combined_surface", m.combined_surface},
                                           {"combined_quadtree", m.combined_quadtree}, {"blend_ao", m.blend_ao},
                                           {"cones", m.cones}, {"bilinear_bound", m.bilinear_bound}}}});
  }
  j["textures"] = nlohmann::json::array();
  for (const TextureRequest& t : textures) {
    nlohmann::json entry = {{"purpose", purpose_name(t.purpose)}, {"width", t.width}, {"height", t.height},
                            {"format", format_name(t.format)}, {"srgb", t.srgb}, {"mip", reduce_name(t.reduce)},
                            {"levels", t.levels}, {"wrap_footprints", keeps_wrap_footprints(t)}, {"bytes", t.bytes},
                            {"working_bytes", t.working_bytes}, {"where", t.where}, {"users", t.users},
                            {"dynamic", t.dynamic}};
    if (t.desc.source == TextureSource::File) entry["file"] = t.desc.file.string();
    j["textures"].push_back(entry);
  }
  j["derived"] = nlohmann::json::array();
  for (const DerivedPlan& d : derived)
    j["derived"].push_back({{"kind", derived_kind_name(d.kind)}, {"inputs", d.inputs}, {"texture", d.texture},
                            {"bytes", d.bytes}, {"working_bytes", d.working_bytes}, {"where", d.where},
                            {"dynamic", d.dynamic}});
  j["meshes"] = nlohmann::json::array();
  for (const MeshPlan& m : meshes) {
    nlohmann::json mtl = nlohmann::json::array();
    for (std::uint32_t mat : m.mtl_materials) mtl.push_back(materials[mat].name);
    j["meshes"].push_back({{"object", m.object}, {"kind", m.kind}, {"vertices", m.vertices}, {"triangles", m.triangles},
                           {"degenerate_faces", m.degenerate_faces}, {"bytes", m.bytes},
                           {"material", materials.empty() ? "" : materials[m.material].name},
                           {"mtl_materials", mtl}, {"warnings", m.notes}, {"dynamic", m.dynamic}});
  }
  j["items"] = items();
  j["dynamic_items"] = dynamic_items();
  if (scene.animation.present) j["animation"] = {{"frames", scene.animation.frames}, {"fps", scene.animation.fps}};
  if (!scene.camera.keyframes.empty())
    j["camera"] = {{"animated", true},
                   {"keyframes", scene.camera.keyframes.size()},
                   {"interpolation", scene.camera.interpolation == CameraInterpolation::Smooth ? "smooth" : "linear"}};
  j["aovs"] = nlohmann::json::array();
  for (Aov a : aovs) j["aovs"].push_back(aov_name(a));
  if (const TextureCacheDesc& c = scene.texture_cache; c.enabled)
    j["texture_cache"] = {{"size_bytes", c.size_bytes}, {"line_bytes", c.line_bytes}, {"ways", c.ways},
                          {"replacement", cache_replacement_name(c.replacement)}, {"layout", texel_layout_name(c.layout)},
                          {"quadtree", quadtree_storage_name(c.quadtree)}, {"region", c.region}, {"warp", c.warp}};
  j["memory"] = {{"framebuffer_bytes", framebuffer_bytes}, {"texture_bytes", texture_bytes}, {"mesh_bytes", mesh_bytes},
                 {"derived_bytes", derived_bytes},
                 {"texture_working_bytes", texture_working_bytes}, {"reused_pattern_bytes", reused_pattern_bytes},
                 {"working_bytes", working_bytes},
                 {"image_module_bytes", image_module_bytes}, {"total_bytes", total_bytes()}};
  return j;
}

}  // namespace qdmr
