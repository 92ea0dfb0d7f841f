#include "qdmr/plan/plan.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "qdmr/core/error.hpp"
#include "qdmr/texture/height_texture.hpp"
#include "qdmr/texture/image.hpp"

namespace qdmr {
namespace {

const char* filter_name(Filter f) {
  switch (f) {
    case Filter::Point: return "point";
    case Filter::Bilinear: return "bilinear";
    case Filter::Trilinear: return "trilinear";
    case Filter::PointMipPoint: return "point_mip_point";
    case Filter::PointMipLinear: return "point_mip_linear";
    case Filter::LinearMipPoint: return "linear_mip_point";
  }
  return "?";
}

std::string source_key(const TextureDesc& d) {
  std::ostringstream k;
  switch (d.source) {
    case TextureSource::None: k << "none"; break;
    case TextureSource::File: k << "file:" << d.file.string() << ":ch" << int(d.channel) << ":srgb" << d.srgb; break;
    case TextureSource::Constant: k << "const:" << d.constant.x << "," << d.constant.y << "," << d.constant.z << "," << d.constant.w; break;
    case TextureSource::Procedural: {
      const ProceduralDesc& p = d.procedural;
      k << "proc:" << int(p.pattern) << ":" << p.size << ":" << p.seed << ":" << p.cells << ":" << p.octaves << ":" << p.gain
        << ":" << p.mortar;
      break;
    }
    case TextureSource::FromHeight: k << "from_height"; break;
  }
  return k.str();
}

std::string height_key(const LayerDesc& layer) {
  std::ostringstream k;
  k << source_key(layer.height) << ":scale" << layer.height_scale << ":offset" << layer.height_offset;
  return k.str();
}

std::string request_key(const TextureDesc& d, TexturePurpose purpose, const LayerDesc& layer) {
  std::ostringstream k;
  k << purpose_name(purpose) << "|" << source_key(d);
  if (purpose == TexturePurpose::Albedo && d.source == TextureSource::Procedural)
    k << ":low" << d.color_low.x << "," << d.color_low.y << "," << d.color_low.z << ":high" << d.color_high.x << ","
      << d.color_high.y << "," << d.color_high.z << ":var" << d.variation;
  if (purpose == TexturePurpose::Normal)
    k << ":conv" << int(layer.normal_convention) << ":strength" << layer.normal_strength;
  if (purpose == TexturePurpose::Height || d.source == TextureSource::FromHeight ||
      (purpose == TexturePurpose::Albedo && d.source == TextureSource::Procedural))
    k << "|height:" << height_key(layer);
  return k.str();
}

struct SourceInfo {
  int width = 1, height = 1;
  int bits = 8;  // per channel: 8 or 16 for integer files, 32 otherwise (as Image::source_bits)
};

// Level-0 size and bit depth of a texture without building it (file headers are read).
SourceInfo texture_source(const TextureDesc& d, const LayerDesc& layer, const std::string& where) {
  switch (d.source) {
    case TextureSource::None:
    case TextureSource::Constant: return {};
    case TextureSource::Procedural: return {d.procedural.size, d.procedural.size, 16};
    case TextureSource::FromHeight:
      if (layer.height.source == TextureSource::None || layer.height.source == TextureSource::FromHeight) return {};
      return texture_source(layer.height, layer, where);
    case TextureSource::File: {
      // The same checks as when the texture is read (kind, size, format, header), nothing decoded.
      const ImageHeader header = read_image_header(d.file, where + "/file");
      return {header.width, header.height, header.source_bits};
    }
  }
  return {};
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

// Storage of a typed chain: levels at 64-byte aligned offsets plus the gather padding (see mip_texture.hpp).
std::uint64_t chain_bytes(int w, int h, TexelFormat format) {
  std::uint64_t bytes = 0;
  for (;;) {
    bytes = (bytes + 63) / 64 * 64 + std::uint64_t(w) * std::uint64_t(h) * std::uint64_t(bytes_per_texel(format));
    if (w == 1 && h == 1) return bytes + Texture::kTailPadding;
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
  }
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
                MipReduce reduce, const LayerDesc& layer, const std::string& where, const std::string& user) {
  const std::string key = request_key(desc, purpose, layer) + "|mip" + std::to_string(int(reduce));
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
  const SourceInfo source = texture_source(desc, layer, where);
  r.width = source.width;
  r.height = source.height;
  r.reduce = reduce;
  r.srgb = purpose == TexturePurpose::Albedo;
  r.format = purpose == TexturePurpose::Height ? height_format(desc, source.bits) : TexelFormat::RGBA8;
  r.levels = mip_levels(r.width, r.height);
  r.bytes = chain_bytes(r.width, r.height, r.format);
  r.users.push_back(user);
  textures.push_back(std::move(r));
  return int(textures.size() - 1);
}

std::uint64_t count_obj_lines(const std::filesystem::path& file, std::uint64_t& faces) {
  std::ifstream in(file);
  std::string line;
  std::uint64_t vertices = 0;
  faces = 0;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) ++vertices;
    else if (line.rfind("f ", 0) == 0) ++faces;
  }
  return vertices;
}

MeshPlan plan_mesh(const ObjectDesc& object) {
  MeshPlan m;
  m.object = object.name;
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
    case MeshKind::Obj: {
      m.kind = "obj " + d.file.filename().string();
      std::uint64_t faces = 0;
      m.vertices = count_obj_lines(d.file, faces);
      m.triangles = faces;
      m.estimated = true;
      break;
    }
  }
  // position, normal, tangent, uv per vertex; three indices and a material id per triangle
  m.bytes = m.vertices * (3 + 3 + 4 + 2) * sizeof(float) + m.triangles * 4 * sizeof(std::uint32_t);
  return m;
}

std::string mib(std::uint64_t bytes) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(2);
  s << double(bytes) / (1024.0 * 1024.0) << " MiB";
  return s.str();
}

}  // namespace

const char* technique_name(TechniqueKind k) {
  switch (k) {
    case TechniqueKind::Normal: return "normal";
    case TechniqueKind::Relief: return "relief";
    case TechniqueKind::Pom: return "pom";
    case TechniqueKind::Csm: return "csm";
    case TechniqueKind::Rcsm: return "rcsm";
    case TechniqueKind::Qdm: return "qdm";
  }
  return "?";
}

namespace {

const char* lighting_name(LightingModel m) { return m == LightingModel::CookTorrance ? "cook_torrance" : "blinn_phong"; }

const char* shadow_name(ShadowMode m) {
  switch (m) {
    case ShadowMode::Off: return "off";
    case ShadowMode::Hard: return "hard";
    case ShadowMode::Horizon: return "horizon";
    case ShadowMode::QdmSoft: return "qdm_soft";
  }
  return "?";
}

const char* blend_name(BlendOperator op) {
  switch (op) {
    case BlendOperator::Alpha: return "alpha";
    case BlendOperator::Height: return "height";
    case BlendOperator::HeightWidth: return "height_width";
  }
  return "?";
}

}  // namespace

MaterialPlan plan_material(const MaterialDesc& material, const std::string& where,
                           std::vector<TextureRequest>& textures) {
  MaterialPlan plan;
  plan.name = material.name;
  plan.technique = material.technique.kind;
  plan.sampling = material.sampling;
  plan.lighting = material.lighting;
  const TechniqueKind kind = material.technique.kind;
  const std::size_t layer_count = material.layers.size();
  plan.blend = layer_count > 1;
  plan.weight_mode = material.blend.weights.mode;
  const bool displaced = kind != TechniqueKind::Normal;
  const bool blend_by_height = plan.blend && material.blend.op != BlendOperator::Alpha;
  // The max-quadtree serves QDM, and self-shadowing and AO queries that read coarse levels.
  const bool hierarchy = kind == TechniqueKind::Qdm || material.shadow.mode == ShadowMode::QdmSoft ||
                         (material.ao.mode != AoMode::Off && material.ao.coarse);
  plan.program = (kind == TechniqueKind::Normal && !plan.blend ? std::string("normal_mapping")
                                                               : std::string("displacement:") + technique_name(kind));
  if (plan.blend)
    plan.program += std::string(" | blend ") + blend_name(material.blend.op) + " x" + std::to_string(layer_count) +
                    (material.blend.weights.mode == WeightMode::Vertex ? " per vertex" : " per pixel");
  if (material.shadow.mode != ShadowMode::Off) plan.program += std::string(" | shadow ") + shadow_name(material.shadow.mode);
  if (material.ao.mode != AoMode::Off)
    plan.program += std::string(" | ao ") + (material.ao.mode == AoMode::Baked ? "baked" : "frame");
  plan.program += std::string(" | ") + lighting_name(material.lighting.model) + " | " + filter_name(material.sampling.filter);

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
    if (displaced || blend_by_height) {
      if (layer.height.source == TextureSource::None)
        throw Error(layer_where + "/height", displaced ? std::string("technique '") + technique_name(kind) + "' needs a height map"
                                                       : std::string("height blending needs a height map in every layer"));
      lp.height = add_request(textures, layer.height, TexturePurpose::Height, MipReduce::Box, layer,
                              layer_where + "/height", material.name);
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
    plan.weight_bytes = chain_bytes(r, r, TexelFormat::RGBA8);
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
        plan.combined_quadtree = true;
        plan.combined_bytes = chain_bytes(int(side_x), int(side_y), TexelFormat::R16);
      }
    }
  }
  const float weight_scale = material.blend.weights.scale;
  if (material.ao.mode == AoMode::Baked && plan.blend && weight_scale == std::floor(weight_scale)) {
    // One map of the blended surface over the weights span (side: the setting, else that span's texels up to 2048).
    const TextureRequest& h = textures[std::size_t(plan.layers[0].height)];
    const std::uint64_t span = std::uint64_t(h.width) * std::uint64_t(weight_scale);
    plan.ao_map = plan.blend_ao = true;
    plan.ao_resolution = material.ao.resolution > 0 ? material.ao.resolution : int(std::min<std::uint64_t>(span, 2048));
    plan.ao_bytes = chain_bytes(plan.ao_resolution, plan.ao_resolution, TexelFormat::R16);
  } else if (material.ao.mode == AoMode::Baked) {
    const TextureRequest& h = textures[std::size_t(plan.layers[0].height)];
    const int w = material.ao.resolution > 0 ? material.ao.resolution : h.width;
    const int hh = material.ao.resolution > 0 ? material.ao.resolution : h.height;
    plan.ao_map = true;
    plan.ao_bytes = chain_bytes(w, hh, TexelFormat::R16) * layer_count;  // one map per layer (same sizes)
  }
  if (kind == TechniqueKind::Csm || kind == TechniqueKind::Rcsm) {
    // Cones of the stored heights' level 0 (the box surface); the box-filtered chain serves the refinement.
    const TextureRequest& h = textures[std::size_t(plan.layers[0].height)];
    plan.cone_map = true;
    plan.cone_kind = kind == TechniqueKind::Csm ? ConeKind::Conservative : ConeKind::Relaxed;
    plan.cone_bytes = std::uint64_t(h.width) * std::uint64_t(h.height) * sizeof(float);
  }
  return plan;
}

FramePlan plan_frame(const SceneDesc& scene, const RenderOptions& options) {
  FramePlan plan;
  plan.width = scene.output.width;
  plan.height = scene.output.height;
  plan.aovs = options.aovs;
  const std::string file = scene.file.string();
  for (const ObjectDesc& object : scene.objects) {
    plan.meshes.push_back(plan_mesh(object));
    plan.mesh_bytes += plan.meshes.back().bytes;
  }
  for (const MaterialDesc& material : scene.materials) {
    const bool used = std::any_of(scene.objects.begin(), scene.objects.end(),
                                  [&](const ObjectDesc& o) { return o.material == material.name; });
    if (!used) continue;  // unused materials cost nothing
    plan.materials.push_back(plan_material(material, file + ": /materials/" + material.name, plan.textures));
  }
  for (const TextureRequest& t : plan.textures) plan.texture_bytes += t.bytes;
  for (const MaterialPlan& m : plan.materials) {
    plan.cone_map_bytes += m.cone_bytes;
    plan.derived_bytes += m.weight_bytes + m.combined_bytes + m.ao_bytes;
  }
  std::uint64_t per_pixel = 4;  // colour (3) and depth (1) floats
  for (Aov aov : plan.aovs) per_pixel += std::uint64_t(aov_channels(aov));
  plan.framebuffer_bytes = std::uint64_t(plan.width) * std::uint64_t(plan.height) * per_pixel * sizeof(float);
  return plan;
}

std::string FramePlan::describe() const {
  std::ostringstream s;
  s << "output: " << width << "x" << height << "\n";
  s << "materials (" << materials.size() << "):\n";
  for (const MaterialPlan& m : materials) {
    s << "  " << m.name << ": " << m.program << "\n";
    for (std::size_t i = 0; i < m.layers.size(); ++i) {
      const LayerPlan& l = m.layers[i];
      s << "    layer " << i << ": albedo: texture " << l.albedo << ", normal: texture " << l.normal;
      if (l.height >= 0) s << ", height: texture " << l.height;
      if (l.height_max >= 0) s << ", max-quadtree: texture " << l.height_max;
      s << "\n";
    }
    if (m.blend)
      s << "    blend weights: " << (m.weight_mode == WeightMode::Vertex ? "per vertex (interpolated)"
                                                                         : "per pixel, weight texture " + mib(m.weight_bytes))
        << (m.combined_quadtree ? ", combined quadtree " + mib(m.combined_bytes) : std::string())
        << "\n";
    if (m.ao_map)
      s << "    ao: baked map " << (m.blend_ao ? "of the blended surface" : "per layer") << ", " << mib(m.ao_bytes)
        << ", baked or from cache\n";
    if (m.cone_map)
      s << "    cone map (" << cone_kind_name(m.cone_kind) << "), baked or from cache, " << mib(m.cone_bytes) << "\n";
  }
  s << "textures to build (" << textures.size() << "):\n";
  for (std::size_t i = 0; i < textures.size(); ++i) {
    const TextureRequest& t = textures[i];
    s << "  [" << i << "] " << purpose_name(t.purpose) << " " << t.width << "x" << t.height << " "
      << format_name(t.format) << (t.srgb ? " sRGB" : "") << ", " << reduce_name(t.reduce) << " mip chain of "
      << t.levels << " levels, " << mib(t.bytes) << "  <- " << t.where << "\n";
  }
  s << "derived data: cone maps " << mib(cone_map_bytes) << ", blend weight and AO maps " << mib(derived_bytes) << "\n";
  s << "meshes (" << meshes.size() << "):\n";
  for (const MeshPlan& m : meshes)
    s << "  " << m.object << ": " << m.kind << ", " << m.vertices << " vertices, " << m.triangles << " triangles"
      << (m.estimated ? " (counted from the file)" : "") << ", " << mib(m.bytes) << "\n";
  s << "aovs:";
  if (aovs.empty()) s << " none";
  for (Aov a : aovs) s << " " << aov_name(a);
  s << "\n";
  s << "memory: framebuffer " << mib(framebuffer_bytes) << ", textures " << mib(texture_bytes)
    << (cone_map_bytes > 0 ? ", cone maps " + mib(cone_map_bytes) : std::string())
    << (derived_bytes > 0 ? ", weight/AO maps " + mib(derived_bytes) : std::string()) << ", meshes " << mib(mesh_bytes)
    << ", total " << mib(total_bytes()) << "\n";
  return s.str();
}

nlohmann::json FramePlan::to_json() const {
  nlohmann::json j;
  j["width"] = width;
  j["height"] = height;
  for (const MaterialPlan& m : materials) {
    nlohmann::json layers = nlohmann::json::array();
    for (const LayerPlan& l : m.layers)
      layers.push_back({{"albedo", l.albedo}, {"normal", l.normal}, {"height", l.height}, {"height_max", l.height_max}});
    j["materials"].push_back({{"name", m.name}, {"program", m.program}, {"layers", layers},
                              {"cone_map", m.cone_map ? nlohmann::json(cone_kind_name(m.cone_kind)) : nlohmann::json()},
                              {"cone_bytes", m.cone_bytes}, {"weight_bytes", m.weight_bytes},
                              {"combined_quadtree_bytes", m.combined_bytes}, {"ao_bytes", m.ao_bytes}});
  }
  for (const TextureRequest& t : textures)
    j["textures"].push_back({{"purpose", purpose_name(t.purpose)}, {"width", t.width}, {"height", t.height},
                             {"format", format_name(t.format)}, {"srgb", t.srgb}, {"mip", reduce_name(t.reduce)},
                             {"levels", t.levels}, {"bytes", t.bytes}, {"where", t.where}, {"users", t.users}});
  for (const MeshPlan& m : meshes)
    j["meshes"].push_back({{"object", m.object}, {"kind", m.kind}, {"vertices", m.vertices}, {"triangles", m.triangles},
                           {"bytes", m.bytes}, {"estimated", m.estimated}});
  j["aovs"] = nlohmann::json::array();
  for (Aov a : aovs) j["aovs"].push_back(aov_name(a));
  j["memory"] = {{"framebuffer_bytes", framebuffer_bytes}, {"texture_bytes", texture_bytes}, {"mesh_bytes", mesh_bytes},
                 {"cone_map_bytes", cone_map_bytes}, {"derived_bytes", derived_bytes}, {"total_bytes", total_bytes()}};
  return j;
}

}  // namespace qdmr
