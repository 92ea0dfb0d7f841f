#include "scene/validate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#if __has_include(<unistd.h>)
#include <unistd.h>
#endif

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "core/frame_pattern.hpp"
#include "file/input_file.hpp"
#include "qdmr/core/limits.hpp"
#include "qdmr/core/texture_cache.hpp"

namespace qdmr::scene_detail {

namespace {

using nlohmann::json;

// Colour, depth and AOV buffers of one frame cost about this much per pixel.
constexpr std::uint64_t kFrameBytesPerPixel = 64;
constexpr std::uint64_t kMiB = 1024 * 1024;

std::optional<std::uint64_t> physical_memory_bytes() {
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGE_SIZE)
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page_size = ::sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page_size > 0) return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size);
#endif
  return std::nullopt;
}

// The given member if present, else the object itself: where to point a message about a default.
Value member_or_self(const Object& object, std::string_view key) { return object.find(key).value_or(object.value()); }

// A number (both components alike) or an array of 2 numbers.
glm::vec2 read_pair(const Value& value, Value::NumberCheck component) {
  if (value.json().is_number()) {
    const float v = static_cast<float>((value.*component)());
    return {v, v};
  }
  value.require(
      value.json().is_array() && value.json().size() == 2,
      std::string("expected a number or an array of 2 numbers, got ") +
          (value.json().is_array() ? "an array of " + std::to_string(value.json().size()) : value.json().type_name()));
  return {(value.element(0).*component)(), (value.element(1).*component)()};
}

OutputDesc read_output(const Value& value) {
  const Object object(value, {"width", "height", "background"});
  OutputDesc output;
  if (auto v = object.find("width")) output.width = static_cast<int>(v->integer(1, limits::kMaxImageSide));
  if (auto v = object.find("height")) output.height = static_cast<int>(v->integer(1, limits::kMaxImageSide));
  if (auto v = object.find("background")) output.background = v->color();

  const std::uint64_t pixels = static_cast<std::uint64_t>(output.width) * static_cast<std::uint64_t>(output.height);
  if (pixels > limits::kMaxImagePixels)
    value.fail("an output of " + std::to_string(output.width) + "x" + std::to_string(output.height) + " has " +
               std::to_string(pixels) + " pixels, more than the limit of " + std::to_string(limits::kMaxImagePixels) +
               " (16384x8192)");
  const std::uint64_t bytes = pixels * kFrameBytesPerPixel;
  if (const auto memory = physical_memory_bytes(); memory && bytes > *memory) {
    value.fail("an output of " + std::to_string(output.width) + "x" + std::to_string(output.height) + " needs about " +
               std::to_string(bytes / kMiB) + " MiB of frame buffers, more than this machine's " +
               std::to_string(*memory / kMiB) + " MiB of memory");
  }
  return output;
}

// The camera's view at one frame: a target apart from the position, an up vector not along the view.
void check_view(const Value& target, const Value& up, const CameraDesc& camera, const std::string& frame) {
  const glm::vec3 view = camera.target - camera.position;
  target.require(glm::length(view) > 0, frame + "the target must differ from the position");
  up.require(glm::length(glm::cross(glm::normalize(view), glm::normalize(camera.up))) > 1e-4f,
             frame + "the up vector must not be parallel to the view direction (target - position)");
}

float read_fov(const Value& value) {
  const float fov = static_cast<float>(value.number());
  value.require(fov > 0 && fov < 180, "must be greater than 0 and less than 180, got " + format_number(fov));
  return fov;
}

// Keyframes of a moving camera, sorted by frame, each inside the animation; `fov` is the camera's field of view,
// which a keyframe without its own keeps.
std::vector<CameraKeyframe> read_keyframes(const Value& value, float fov) {
  const std::vector<Value> items = value.array();
  value.require(!items.empty(), "expected at least one keyframe");
  const int frames = value.context().frames;
  std::vector<CameraKeyframe> keys;
  for (const Value& item : items) {
    const Object object(item, {"frame", "position", "target", "fov_deg"});
    CameraKeyframe k;
    const Value frame = object.required("frame");
    k.frame = static_cast<int>(frame.integer(0, std::numeric_limits<int>::max()));
    frame.require(k.frame < frames, "frame " + std::to_string(k.frame) + " is outside the animation's frames 0 to " +
                                        std::to_string(frames - 1));
    if (!keys.empty()) {
      frame.require(k.frame != keys.back().frame, "two keyframes at frame " + std::to_string(k.frame));
      frame.require(k.frame > keys.back().frame, "keyframes are listed by frame: " + std::to_string(k.frame) +
                                                     " comes after " + std::to_string(keys.back().frame));
    }
    k.position = object.required("position").vec3();
    k.target = object.required("target").vec3();
    k.fov_y_deg = fov;
    if (auto v = object.find("fov_deg")) k.fov_y_deg = read_fov(*v);
    keys.push_back(k);
  }
  return keys;
}

CameraDesc read_camera(const Value& value) {
  const Object object(value, {"position", "target", "up", "fov_deg", "near", "far", "keyframes", "interpolation"});
  CameraDesc camera;
  if (auto v = object.find("position")) camera.position = v->vec3();
  if (auto v = object.find("target")) camera.target = v->vec3();
  if (auto v = object.find("up")) camera.up = v->vec3();
  if (auto v = object.find("fov_deg")) camera.fov_y_deg = read_fov(*v);
  if (auto v = object.find("near")) camera.near = static_cast<float>(v->positive());
  if (auto v = object.find("far")) camera.far = static_cast<float>(v->number());
  member_or_self(object, "far")
      .require(camera.far > camera.near, "far (" + format_number(camera.far) + ") must be greater than near (" +
                                             format_number(camera.near) + ")");
  const Value up = member_or_self(object, "up");
  up.require(glm::length(camera.up) > 0, "the up vector must not be zero");

  const auto keyframes = object.find("keyframes");
  if (auto v = object.find("interpolation")) {
    v->require(keyframes.has_value(), "only a camera with keyframes interpolates");
    camera.interpolation = v->choice<CameraInterpolation>(
        {{"linear", CameraInterpolation::Linear}, {"smooth", CameraInterpolation::Smooth}});
  }
  if (!keyframes) {
    check_view(member_or_self(object, "target"), up, camera, "");
    return camera;
  }
  for (const char* key : {"position", "target"})
    if (auto v = object.find(key))
      v->fail(std::string("a camera with keyframes takes its ") + key + " from them: give it there");
  camera.keyframes = read_keyframes(*keyframes, camera.fov_y_deg);
  // Every frame the keyframes span, as it will be drawn (before the first and after the last they hold).
  for (int f = camera.keyframes.front().frame; f <= camera.keyframes.back().frame; ++f)
    check_view(*keyframes, *keyframes, camera_at_frame(camera, f), "at frame " + std::to_string(f) + ", ");
  return camera_at_frame(camera, 0);
}

// The emulated texture cache: present means on, unless "enabled": false.
TextureCacheDesc read_texture_cache(const Value& value) {
  const Object object(value, {"enabled", "size_bytes", "line_bytes", "ways", "replacement", "layout", "quadtree",
                              "region", "warp"});
  TextureCacheDesc d;
  d.enabled = true;
  if (auto v = object.find("enabled")) d.enabled = v->boolean();
  if (auto v = object.find("size_bytes")) d.size_bytes = static_cast<int>(v->integer(4, 64 << 20));
  if (auto v = object.find("line_bytes")) d.line_bytes = static_cast<int>(v->integer(4, 4096));
  if (auto v = object.find("ways")) d.ways = static_cast<int>(v->integer(1, 1024));
  if (auto v = object.find("replacement"))
    d.replacement = v->choice<CacheReplacement>({{"lru", CacheReplacement::Lru}, {"fifo", CacheReplacement::Fifo}});
  if (auto v = object.find("layout"))
    d.layout = v->choice<TexelLayout>({{"linear", TexelLayout::Linear},
                                       {"tiled4", TexelLayout::Tiled4},
                                       {"tiled8", TexelLayout::Tiled8},
                                       {"morton", TexelLayout::Morton}});
  if (auto v = object.find("quadtree"))
    d.quadtree = v->choice<QuadtreeStorage>({{"mip_chain", QuadtreeStorage::MipChain}, {"volume", QuadtreeStorage::Volume}});
  if (auto v = object.find("region")) d.region = static_cast<int>(v->integer(8, 1024));
  if (auto v = object.find("warp")) d.warp = static_cast<int>(v->integer(4, 1024));
  if (const auto problem = check_texture_cache(d)) {
    const auto field = object.find(problem->field);
    (field ? *field : value).fail(problem->what);
  }
  return d;
}

LightsDesc read_lights(const Value& value) {
  enum class LightType { Directional, Ambient };
  LightsDesc lights;
  lights.ambient.intensity = 0.0f;  // only the lights listed exist
  bool have_ambient = false;
  for (const Value& light : value.array()) {
    light.expect_type(json::value_t::object, "an object");
    const auto type = light.member("type");
    if (!type) light.fail("missing key 'type' (directional or ambient)");
    if (type->choice<LightType>({{"directional", LightType::Directional}, {"ambient", LightType::Ambient}}) ==
        LightType::Directional) {
      const Object object(light, {"type", "direction", "color", "intensity"});
      light.require(lights.directional.size() < static_cast<std::size_t>(limits::kMaxDirectionalLights),
                    "at most " + std::to_string(limits::kMaxDirectionalLights) + " directional lights are supported");
      DirectionalLightDesc directional;
      if (auto v = object.find("direction")) {
        directional.direction = v->vec3();
        v->require(glm::length(directional.direction) > 0, "the direction must not be zero");
      }
      directional.direction = glm::normalize(directional.direction);
      if (auto v = object.find("color")) directional.color = v->color();
      if (auto v = object.find("intensity")) directional.intensity = static_cast<float>(v->non_negative());
      lights.directional.push_back(directional);
    } else {
      const Object object(light, {"type", "color", "intensity"});
      light.require(!have_ambient, "only one ambient light is allowed");
      have_ambient = true;
      lights.ambient = AmbientLightDesc{};
      if (auto v = object.find("color")) lights.ambient.color = v->color();
      if (auto v = object.find("intensity")) lights.ambient.intensity = static_cast<float>(v->non_negative());
    }
  }
  return lights;
}

enum class Slot { Albedo, Normal, Height, Orm, Occlusion };

// Height storage: "format" (auto, r8, r16, r32f) and "compression" (none, bc3).
void read_height_storage(const Object& object, TextureDesc& texture) {
  if (auto v = object.find("format"))
    texture.format = v->choice<TextureFormatChoice>({{"auto", TextureFormatChoice::Auto},
                                                     {"r8", TextureFormatChoice::R8},
                                                     {"r16", TextureFormatChoice::R16},
                                                     {"r32f", TextureFormatChoice::R32F}});
  if (auto v = object.find("compression")) {
    texture.compression = v->choice<Compression>({{"none", Compression::None}, {"bc3", Compression::Bc3}});
    v->require(texture.compression == Compression::None || texture.format == TextureFormatChoice::Auto ||
                   texture.format == TextureFormatChoice::R8,
               "bc3 stores 8-bit heights: use format r8 or auto");
  }
}

// A height's file: one file, or a frame-numbered sequence ("h_%04d.exr") whose `frames` FIRST:LAST[:STEP] (default
// 0 up) are the file numbers of the animation's frames 0, 1, ... Every frame's file must exist now; their sizes are
// compared when the scene is loaded (load/load.cpp reads the headers).
void read_height_file(const Value& file, const std::optional<Value>& frames, TextureDesc& texture) {
  const auto where = [](const Value& v) { return v.context().file + ": " + v.pointer(); };
  texture.source = TextureSource::File;
  if (!has_frame_number(where(file), file.string())) {
    if (frames) frames->fail("only a frame-numbered file (e.g. h_%04d.exr) has frames");
    texture.file = file.existing_file();
    return;
  }
  FileSequence& sequence = texture.sequence;
  sequence.pattern = file.file_path().string();
  sequence.field = where(file);
  const int count = file.context().frames;
  FrameRange range{0, count - 1, 1};
  if (frames) {
    range = parse_frame_range(where(*frames), frames->string());
    const long long needed = range.first + static_cast<long long>(count - 1) * range.step;
    frames->require(needed <= range.last, "numbers " + std::to_string(range.size()) +
                                              " files, fewer than the animation's " + std::to_string(count) +
                                              " frames");
  }
  sequence.first = range.first;
  sequence.step = range.step;
  int found = 0;
  std::optional<int> missing;
  for (int n = 0; n < count; ++n) {
    const std::filesystem::path path = sequence_file(sequence, n);
    const std::string reason = non_regular_reason(path);
    if (reason == "file not found") {
      if (!missing) missing = n;
      continue;
    }
    if (!reason.empty()) file.fail("frame " + std::to_string(n) + " of the animation: " + shown_path(path) + " " + reason);
    note_input(path);
    ++found;
  }
  if (found == 0)
    file.fail("names no file: none of " + sequence_file(sequence, 0).filename().string() +
              (count > 1 ? " to " + sequence_file(sequence, count - 1).filename().string() : std::string()) +
              " exists in " + shown_path(sequence_file(sequence, 0).parent_path()));
  if (missing)
    file.fail("frame " + std::to_string(*missing) + " of the animation: file not found: " +
              shown_path(sequence_file(sequence, *missing)));
  texture.file = sequence_file(sequence, 0);
}

void read_texture_file(const Value& value, Slot slot, TextureDesc& texture) {
  const Object object = slot == Slot::Albedo      ? Object(value, {"file", "channel", "srgb", "factor"})
                        : slot == Slot::Height    ? Object(value, {"file", "frames", "channel", "format", "compression"})
                        : slot == Slot::Occlusion ? Object(value, {"file", "channel"})
                                                  : Object(value, {"file"});
  texture.source = TextureSource::File;
  if (slot == Slot::Height)
    read_height_file(object.required("file"), object.find("frames"), texture);
  else
    texture.file = object.required("file").existing_file();
  if (auto v = object.find("channel")) {
    texture.channel = v->choice<Channel>({{"r", Channel::R},
                                          {"g", Channel::G},
                                          {"b", Channel::B},
                                          {"a", Channel::A},
                                          {"rgb", Channel::RGB},
                                          {"rgba", Channel::RGBA}});
    v->require((slot != Slot::Height && slot != Slot::Occlusion) ||
                   (texture.channel != Channel::RGB && texture.channel != Channel::RGBA),
               slot == Slot::Height ? "a height reads one channel: r, g, b or a" : "an occlusion reads one channel: r, g, b or a");
  }
  if (auto v = object.find("srgb")) texture.srgb = v->boolean();
  if (auto v = object.find("factor")) texture.factor = v->color();
  if (slot == Slot::Height) read_height_storage(object, texture);
}

// One wave of the waves pattern; its wave vector snapped to whole cycles per repeat of a `size` texture.
WaveDesc read_wave(const Value& value, int size) {
  const Object object(value, {"amplitude", "wavelength", "direction_deg", "speed", "sharpness"});
  WaveDesc w;
  if (auto v = object.find("amplitude")) w.amplitude = static_cast<float>(v->non_negative());
  if (auto v = object.find("wavelength")) w.wavelength = static_cast<float>(v->positive());
  if (auto v = object.find("direction_deg")) w.direction_deg = static_cast<float>(v->number_in(-360.0, 360.0));
  if (auto v = object.find("speed")) w.speed = static_cast<float>(v->number_in(-100.0, 100.0));
  if (auto v = object.find("sharpness")) w.sharpness = static_cast<int>(v->integer(1, 8));
  const double angle = double(w.direction_deg) * 3.14159265358979323846 / 180.0;
  const double cycles = 1.0 / double(w.wavelength);
  const double ku = std::round(std::cos(angle) * cycles), kv = std::round(std::sin(angle) * cycles);
  const Value wavelength = member_or_self(object, "wavelength");
  wavelength.require(ku != 0.0 || kv != 0.0, "a wavelength of " + format_number(w.wavelength) +
                                                 " along this direction has no whole cycle per texture repeat "
                                                 "(the pattern tiles): make it shorter");
  wavelength.require(std::abs(ku) <= size / 2 && std::abs(kv) <= size / 2,
                     "a wavelength of " + format_number(w.wavelength) + " is shorter than two texels of a " +
                         std::to_string(size) + "-texel pattern");
  w.cycles_u = static_cast<int>(ku);
  w.cycles_v = static_cast<int>(kv);
  return w;
}

void read_procedural(const Value& value, Slot slot, TextureDesc& texture) {
  const Object object = slot == Slot::Albedo
                            ? Object(value, {"procedural", "size", "seed", "cells", "octaves", "gain", "mortar",
                                             "waves", "scroll", "color_low", "color_high", "variation"})
                            : Object(value, {"procedural", "size", "seed", "cells", "octaves", "gain", "mortar",
                                             "waves", "scroll", "format", "compression"});
  texture.source = TextureSource::Procedural;
  ProceduralDesc& p = texture.procedural;
  p.pattern = object.required("procedural")
                  .choice<ProceduralPattern>({{"bricks", ProceduralPattern::Bricks},
                                              {"cobbles", ProceduralPattern::Cobbles},
                                              {"sine", ProceduralPattern::Sine},
                                              {"steps", ProceduralPattern::Steps},
                                              {"spikes", ProceduralPattern::Spikes},
                                              {"noise", ProceduralPattern::Noise},
                                              {"flat", ProceduralPattern::Flat},
                                              {"checker", ProceduralPattern::Checker},
                                              {"waves", ProceduralPattern::Waves}});
  if (auto v = object.find("size")) {
    p.size = static_cast<int>(v->integer(1, limits::kMaxTextureSide));
    v->require((p.size & (p.size - 1)) == 0, "must be a power of two, got " + std::to_string(p.size));
  }
  if (auto v = object.find("waves")) {
    v->require(p.pattern == ProceduralPattern::Waves, "only the 'waves' pattern has waves");
    const std::vector<Value> waves = v->array();
    v->require(!waves.empty() && waves.size() <= 16, "expected 1 to 16 waves, got " + std::to_string(waves.size()));
    for (const Value& w : waves) p.waves.push_back(read_wave(w, p.size));
    v->require(std::any_of(p.waves.begin(), p.waves.end(), [](const WaveDesc& w) { return w.amplitude > 0.0f; }),
               "at least one wave needs an amplitude above 0");
  } else if (p.pattern == ProceduralPattern::Waves) {
    object.required("waves");
  }
  if (auto v = object.find("scroll")) p.scroll = read_pair(*v, &Value::number);
  if (auto v = object.find("seed"))
    p.seed = static_cast<std::uint32_t>(v->integer(0, std::numeric_limits<std::uint32_t>::max()));
  if (auto v = object.find("cells")) p.cells = static_cast<int>(v->integer(1, 4096));
  if (auto v = object.find("octaves")) p.octaves = static_cast<int>(v->integer(1, 16));
  if (auto v = object.find("gain")) p.gain = static_cast<float>(v->positive());
  if (auto v = object.find("mortar")) p.mortar = static_cast<float>(v->number_in(0.0, 0.5));
  if (auto v = object.find("color_low")) texture.color_low = v->color();
  if (auto v = object.find("color_high")) texture.color_high = v->color();
  if (auto v = object.find("variation")) texture.variation = static_cast<float>(v->number_in(0.0, 1.0));
  if (slot != Slot::Albedo) read_height_storage(object, texture);
}

void read_constant(const Value& value, Slot slot, TextureDesc& texture) {
  const Object object(value, {"constant"});
  const Value constant = object.required("constant");
  texture.source = TextureSource::Constant;
  if (slot == Slot::Height || slot == Slot::Occlusion) {
    const float h = static_cast<float>(constant.number_in(0.0, 1.0));
    texture.constant = {h, h, h, 1.0f};
    return;
  }
  if (constant.json().is_number()) {
    const float v = static_cast<float>(constant.non_negative());
    texture.constant = {v, v, v, 1.0f};
    return;
  }
  const std::size_t n = constant.json().is_array() ? constant.json().size() : 0;
  constant.require(n == 3 || n == 4,
                   std::string("expected a number or an array of 3 or 4 numbers, got ") +
                       (constant.json().is_array() ? "an array of " + std::to_string(n) : constant.json().type_name()));
  for (std::size_t i = 0; i < n; ++i)
    texture.constant[static_cast<int>(i)] = static_cast<float>(
        slot == Slot::Orm ? constant.element(i).number_in(0.0, 1.0) : constant.element(i).non_negative());
}

// TEX: "path" | "from_height" (normals) | {"file": ...} | {"procedural": ...} | {"constant": ...}
TextureDesc read_texture(const Value& value, Slot slot) {
  TextureDesc texture;
  if (value.json().is_string()) {
    if (value.string() == "from_height") {
      value.require(slot == Slot::Normal, "'from_height' is only valid for a normal map");
      texture.source = TextureSource::FromHeight;
    } else if (slot == Slot::Height) {
      read_height_file(value, std::nullopt, texture);
    } else {
      texture.source = TextureSource::File;
      texture.file = value.existing_file();
    }
    return texture;
  }
  value.require(value.json().is_object(),
                std::string("expected a file path or an object with 'file', 'procedural' or 'constant', got ") +
                    value.json().type_name());
  const bool file = value.member("file").has_value();
  const bool procedural = value.member("procedural").has_value();
  const bool constant = value.member("constant").has_value();
  value.require(int(file) + int(procedural) + int(constant) == 1,
                "expected exactly one of the keys 'file', 'procedural' or 'constant'");
  value.require(slot != Slot::Normal || file, "a normal map is a file path or \"from_height\"");
  value.require((slot != Slot::Orm && slot != Slot::Occlusion) || !procedural,
                slot == Slot::Orm ? "an orm texture is a file path or a constant" : "an occlusion is a file path or a constant");
  if (file)
    read_texture_file(value, slot, texture);
  else if (procedural)
    read_procedural(value, slot, texture);
  else
    read_constant(value, slot, texture);
  return texture;
}

// The keys of an occlusion-roughness-metal texture (LayerDesc::orm).
void read_orm_keys(const Object& object, LayerDesc& layer) {
  if (auto v = object.find("orm")) layer.orm = read_texture(*v, Slot::Orm);
  if (auto v = object.find("occlusion")) layer.occlusion = read_texture(*v, Slot::Occlusion);
  if (auto v = object.find("metallic")) layer.metallic = static_cast<float>(v->number_in(0.0, 1.0));
  if (auto v = object.find("occlusion_strength")) layer.occlusion_strength = static_cast<float>(v->number_in(0.0, 1.0));
}

LayerDesc read_layer(const Value& value) {
  const Object object(
      value, {"albedo", "normal", "normal_convention", "normal_strength", "height", "height_scale", "height_offset",
              "specular", "orm", "occlusion", "metallic", "occlusion_strength"});
  LayerDesc layer;
  layer.albedo.source = TextureSource::Constant;
  if (auto v = object.find("albedo")) layer.albedo = read_texture(*v, Slot::Albedo);
  if (auto v = object.find("height")) layer.height = read_texture(*v, Slot::Height);
  const bool has_height = layer.height.source != TextureSource::None;
  if (auto v = object.find("normal")) {
    layer.normal = read_texture(*v, Slot::Normal);
    v->require(layer.normal.source != TextureSource::FromHeight || has_height,
               "'from_height' needs a 'height' in the same layer");
  } else if (has_height) {
    layer.normal.source = TextureSource::FromHeight;
  }
  if (auto v = object.find("normal_convention"))
    layer.normal_convention = v->choice<NormalConvention>({{"gl", NormalConvention::GL}, {"dx", NormalConvention::DX}});
  if (auto v = object.find("normal_strength")) layer.normal_strength = static_cast<float>(v->non_negative());
  if (auto v = object.find("height_scale")) layer.height_scale = static_cast<float>(v->number());
  if (auto v = object.find("height_offset")) layer.height_offset = static_cast<float>(v->number());
  if (auto v = object.find("specular")) {
    const Object specular(*v, {"power", "scale", "invert"});
    layer.specular.enabled = true;
    if (auto s = specular.find("power")) layer.specular.power = static_cast<float>(s->number_in(0.0, 64.0));
    if (auto s = specular.find("scale")) layer.specular.scale = static_cast<float>(s->number_in(0.0, 16.0));
    if (auto s = specular.find("invert")) layer.specular.invert = s->boolean();
  }
  read_orm_keys(object, layer);
  return layer;
}

ShadowDesc read_shadow(const Value& value) {
  const Object object(value, {"mode", "strength", "max_iterations", "samples", "length", "profile", "penumbra",
                              "tap_weights", "bias"});
  ShadowDesc d;
  if (auto v = object.find("mode"))
    d.mode = v->choice<ShadowMode>({{"off", ShadowMode::Off},
                                    {"hard", ShadowMode::Hard},
                                    {"horizon", ShadowMode::Horizon},
                                    {"qdm_soft", ShadowMode::QdmSoft}});
  if (auto v = object.find("strength")) d.strength = static_cast<float>(v->number_in(1e-3, 1e6));
  if (auto v = object.find("max_iterations")) d.max_iterations = static_cast<int>(v->integer(1, 1 << 20));
  if (auto v = object.find("samples")) d.samples = static_cast<int>(v->integer(1, 1024));
  if (auto v = object.find("length")) d.length = static_cast<float>(v->number_in(0.0, 1e4));
  if (auto v = object.find("profile"))
    d.profile = v->choice<ProfileOperator>(
        {{"max", ProfileOperator::Max}, {"min", ProfileOperator::Min}, {"average", ProfileOperator::Average}});
  if (auto v = object.find("penumbra")) d.penumbra = static_cast<float>(v->number_in(0.0, 1e6));
  if (auto v = object.find("bias")) d.bias = static_cast<float>(v->number_in(0.0, 1.0));
  if (auto v = object.find("tap_weights")) {
    const std::vector<Value> items = v->array();
    v->require(!items.empty() && items.size() <= 16, "expected 1 to 16 weights, got " + std::to_string(items.size()));
    d.tap_weights.clear();
    for (const Value& item : items) d.tap_weights.push_back(static_cast<float>(item.number_in(0.0, 1e3)));
  }
  return d;
}

AoDesc read_ao(const Value& value) {
  const Object object(value, {"mode", "directions", "jitter", "seed", "radius", "coarse", "strength", "resolution",
                              "amortize_frames"});
  AoDesc d;
  if (auto v = object.find("mode"))
    d.mode = v->choice<AoMode>({{"off", AoMode::Off}, {"frame", AoMode::Frame}, {"baked", AoMode::Baked}});
  if (auto v = object.find("directions")) d.directions = static_cast<int>(v->integer(4, 16));
  if (auto v = object.find("jitter")) d.jitter = v->boolean();
  if (auto v = object.find("seed")) d.seed = static_cast<std::uint32_t>(v->integer(0, std::numeric_limits<std::uint32_t>::max()));
  if (auto v = object.find("radius")) d.radius = static_cast<float>(v->number_in(1e-6, 1e3));
  if (auto v = object.find("coarse")) d.coarse = v->boolean();
  if (auto v = object.find("strength")) d.strength = static_cast<float>(v->number_in(0.0, 1.0));
  if (auto v = object.find("resolution")) d.resolution = static_cast<int>(v->integer(0, limits::kMaxTextureSide));
  if (auto v = object.find("amortize_frames")) d.amortize_frames = static_cast<int>(v->integer(1, AoDesc::kMaxAmortizeFrames));
  return d;
}

WeightsDesc read_weights(const Value& value) {
  const Object object(value, {"mode", "source", "scale", "resolution", "from_vertices", "seed", "cells", "sharpness",
                              "height", "low", "slope", "relief", "file"});
  WeightsDesc d;
  if (auto v = object.find("mode")) d.mode = v->choice<WeightMode>({{"vertex", WeightMode::Vertex}, {"pixel", WeightMode::Pixel}});
  if (auto v = object.find("source"))
    d.source = v->choice<WeightSource>(
        {{"noise", WeightSource::Noise}, {"terrain", WeightSource::Terrain}, {"file", WeightSource::File}});
  if (auto v = object.find("scale")) d.scale = static_cast<float>(v->number_in(1e-3, 1e5));
  if (auto v = object.find("resolution")) d.resolution = static_cast<int>(v->integer(1, limits::kMaxTextureSide));
  if (auto v = object.find("from_vertices")) d.from_vertices = v->boolean();
  if (auto v = object.find("seed")) d.seed = static_cast<std::uint32_t>(v->integer(0, std::numeric_limits<std::uint32_t>::max()));
  if (auto v = object.find("cells")) d.cells = static_cast<int>(v->integer(1, 4096));
  if (auto v = object.find("sharpness")) d.sharpness = static_cast<int>(v->integer(1, 32));
  if (auto v = object.find("low")) d.low = static_cast<float>(v->number_in(0.0, 1.0));
  if (auto v = object.find("slope")) d.slope = static_cast<float>(v->positive());
  if (auto v = object.find("relief")) d.relief = static_cast<float>(v->positive());
  if (auto v = object.find("height")) {
    d.height = read_texture(*v, Slot::Height);
    v->require(d.height.source == TextureSource::File || d.height.source == TextureSource::Procedural,
               "expected a height file or a procedural height");
  }
  if (auto v = object.find("file")) d.file = v->existing_file();
  if (d.source == WeightSource::Terrain && d.height.source == TextureSource::None)
    object.value().fail("source 'terrain' needs a 'height'");
  if (d.source == WeightSource::File && d.file.empty()) object.value().fail("source 'file' needs a 'file'");
  return d;
}

BlendDesc read_blend(const Value& value) {
  const Object object(value, {"operator", "width", "quadtree", "weights"});
  BlendDesc d;
  if (auto v = object.find("operator"))
    d.op = v->choice<BlendOperator>(
        {{"alpha", BlendOperator::Alpha}, {"height", BlendOperator::Height}, {"height_width", BlendOperator::HeightWidth}});
  if (auto v = object.find("width")) d.width = static_cast<float>(v->number_in(1e-4, 1.0));
  if (auto v = object.find("quadtree"))
    d.quadtree = v->choice<BlendQuadtree>(
        {{"auto", BlendQuadtree::Auto}, {"combined", BlendQuadtree::Combined}, {"product", BlendQuadtree::Product}});
  if (auto v = object.find("weights")) d.weights = read_weights(*v);
  return d;
}

// Shadows and AO trace the displaced surface: a material with either needs a displacement technique.
void check_visibility_needs_displacement(const Object& object, const MaterialDesc& material) {
  const bool displaced = material.technique.kind != TechniqueKind::Normal;
  if (material.shadow.mode != ShadowMode::Off && !displaced)
    object.required("shadow").fail("self-shadowing needs a displacement technique (technique/name is 'normal')");
  if (material.ao.mode != AoMode::Off && !displaced)
    object.required("ao").fail("ambient occlusion needs a displacement technique (technique/name is 'normal')");
}

// The keys given in a `technique` block, over what `d` holds (the defaults, or an MTL material's mapping).
void read_technique(const Value& value, TechniqueDesc& d) {
  const Object technique(value, {"name", "depth_scale", "write_depth", "exact_hits", "linear_steps", "binary_steps", "min_steps",
                                 "max_steps", "lod_threshold", "lod_fade", "max_iterations", "min_iterations",
                                 "level_up", "refinement", "height_fetch", "lod_stop", "fade_start", "fade_end"});
  if (auto t = technique.find("name"))
    d.kind = t->choice<TechniqueKind>({{"normal", TechniqueKind::Normal},
                                       {"relief", TechniqueKind::Relief},
                                       {"pom", TechniqueKind::Pom},
                                       {"csm", TechniqueKind::Csm},
                                       {"rcsm", TechniqueKind::Rcsm},
                                       {"qdm", TechniqueKind::Qdm}});
  if (auto t = technique.find("depth_scale")) d.depth_scale = static_cast<float>(t->number_in(0.0, 100.0));
  if (auto t = technique.find("write_depth")) d.write_depth = t->boolean();
  if (auto t = technique.find("exact_hits")) d.exact_hits = t->boolean();
  if (auto t = technique.find("linear_steps")) d.linear_steps = static_cast<int>(t->integer(1, 4096));
  if (auto t = technique.find("binary_steps")) d.binary_steps = static_cast<int>(t->integer(0, 64));
  if (auto t = technique.find("min_steps")) d.min_steps = static_cast<int>(t->integer(1, 4096));
  if (auto t = technique.find("max_steps")) {
    d.max_steps = static_cast<int>(t->integer(1, 4096));
    t->require(d.max_steps >= d.min_steps, "must not be below min_steps");
  }
  if (auto t = technique.find("lod_threshold")) d.lod_threshold = static_cast<float>(t->number_in(-16.0, 16.0));
  if (auto t = technique.find("lod_fade")) d.lod_fade = static_cast<float>(t->number_in(0.0, 16.0));
  if (auto t = technique.find("max_iterations")) d.max_iterations = static_cast<int>(t->integer(1, 1 << 20));
  if (auto t = technique.find("min_iterations")) {
    d.min_iterations = static_cast<int>(t->integer(0, 1 << 20));
    t->require(d.min_iterations <= d.max_iterations, "must not exceed max_iterations");
  }
  if (auto t = technique.find("level_up"))
    d.level_up = t->choice<QdmLevelUp>(
        {{"stay", QdmLevelUp::Stay}, {"one", QdmLevelUp::One}, {"aligned", QdmLevelUp::Aligned}});
  if (auto t = technique.find("refinement"))
    d.refinement = t->choice<QdmRefinement>({{"none", QdmRefinement::None},
                                             {"linear", QdmRefinement::Linear},
                                             {"binary", QdmRefinement::Binary},
                                             {"bilinear_patch", QdmRefinement::BilinearPatch}});
  if (auto t = technique.find("height_fetch"))
    d.height_fetch = t->choice<HeightFetch>(
        {{"point", HeightFetch::Point}, {"bilinear", HeightFetch::Bilinear}, {"trilinear", HeightFetch::Trilinear}});
  if (auto t = technique.find("lod_stop")) d.lod_stop = t->boolean();
  if (auto t = technique.find("fade_start")) d.fade_start = static_cast<float>(t->non_negative());
  if (auto t = technique.find("fade_end")) {
    d.fade_end = static_cast<float>(t->non_negative());
    t->require(d.fade_end >= d.fade_start, "must not be below fade_start");
  }
}

void read_sampling(const Value& value, SamplingDesc& d) {
  const Object sampling(value, {"filter", "address", "precision", "lod", "lod_bias", "min_lod", "max_lod", "math"});
  if (auto s = sampling.find("filter"))
    d.filter = s->choice<Filter>({{"point", Filter::Point},
                                  {"bilinear", Filter::Bilinear},
                                  {"trilinear", Filter::Trilinear},
                                  {"point_mip_point", Filter::PointMipPoint},
                                  {"point_mip_linear", Filter::PointMipLinear},
                                  {"linear_mip_point", Filter::LinearMipPoint}});
  if (auto s = sampling.find("address"))
    d.address = s->choice<AddressMode>(
        {{"wrap", AddressMode::Wrap}, {"clamp", AddressMode::Clamp}, {"mirror", AddressMode::Mirror}});
  if (auto s = sampling.find("precision"))
    d.precision = s->choice<SamplePrecision>(
        {{"exact", SamplePrecision::Exact}, {"hw8", SamplePrecision::Hw8}, {"hw6", SamplePrecision::Hw6}});
  if (auto s = sampling.find("lod"))
    d.lod = s->choice<LodMode>({{"per_quad", LodMode::PerQuad}, {"per_pixel", LodMode::PerPixel}});
  if (auto s = sampling.find("lod_bias")) d.lod_bias = static_cast<float>(s->number_in(-16.0, 16.0));
  if (auto s = sampling.find("min_lod")) d.min_lod = static_cast<float>(s->number_in(0.0, 16.0));
  if (auto s = sampling.find("max_lod")) {
    d.max_lod = static_cast<float>(s->number_in(0.0, 16.0));
    s->require(d.max_lod >= d.min_lod, "must not be below min_lod");
  }
  if (auto s = sampling.find("math"))
    d.math = s->choice<MathMode>({{"sm4", MathMode::Sm4}, {"sm3", MathMode::Sm3}, {"exact", MathMode::Exact}});
}

void read_lighting(const Value& value, LightingDesc& d) {
  const Object lighting(value, {"model", "specular", "shininess", "roughness"});
  if (auto l = lighting.find("model"))
    d.model = l->choice<LightingModel>(
        {{"blinn_phong", LightingModel::BlinnPhong}, {"cook_torrance", LightingModel::CookTorrance}});
  if (auto l = lighting.find("specular")) d.specular = static_cast<float>(l->non_negative());
  if (auto l = lighting.find("shininess")) d.shininess = static_cast<float>(l->positive());
  if (auto l = lighting.find("roughness")) d.roughness = static_cast<float>(l->number_in(0.02, 1.0));
}

MaterialDesc read_material(const Value& value, const std::string& name) {
  const Object object(value, {"layers", "technique", "sampling", "lighting", "shadow", "ao", "blend"});
  MaterialDesc material;
  material.name = name;
  const Value layers = object.required("layers");
  const std::vector<Value> items = layers.array();
  layers.require(
      !items.empty() && items.size() <= static_cast<std::size_t>(limits::kMaxLayers),
      "expected 1 to " + std::to_string(limits::kMaxLayers) + " layers, got " + std::to_string(items.size()));
  for (const Value& item : items) material.layers.push_back(read_layer(item));
  for (std::size_t i = 0; i < items.size() && items.size() > 1; ++i)
    for (const char* key : {"orm", "occlusion"})
      if (auto v = items[i].member(key)) v->fail("an orm texture is read on a material of one layer, not on a blend");

  if (auto v = object.find("technique")) read_technique(*v, material.technique);
  if (auto v = object.find("sampling")) read_sampling(*v, material.sampling);
  if (auto v = object.find("lighting")) read_lighting(*v, material.lighting);
  if (auto v = object.find("shadow")) material.shadow = read_shadow(*v);
  if (auto v = object.find("ao")) material.ao = read_ao(*v);
  if (auto v = object.find("blend")) material.blend = read_blend(*v);
  check_visibility_needs_displacement(object, material);
  return material;
}

std::vector<MaterialDesc> read_materials(const Value& value) {
  value.expect_type(json::value_t::object, "an object mapping material names to materials");
  std::vector<MaterialDesc> materials;
  for (const auto& item : value.json().items()) {
    if (item.key() == "comment") continue;
    const Value material = *value.member(item.key());
    material.require(!item.key().empty(), "a material name must not be empty");
    materials.push_back(read_material(material, item.key()));
  }
  return materials;
}

MeshDesc read_mesh(const Value& value) {
  value.expect_type(json::value_t::object, "an object");
  const auto type = value.member("type");
  if (!type) value.fail("missing key 'type' (plane, box, sphere, grid, obj or gltf)");
  MeshDesc mesh;
  mesh.kind = type->choice<MeshKind>({{"plane", MeshKind::Plane},
                                      {"box", MeshKind::Box},
                                      {"sphere", MeshKind::Sphere},
                                      {"grid", MeshKind::Grid},
                                      {"obj", MeshKind::Obj},
                                      {"gltf", MeshKind::Gltf}});
  const Object object = [&] {
    switch (mesh.kind) {
      case MeshKind::Plane:
        return Object(value, {"type", "size", "uv_scale"});
      case MeshKind::Box:
        return Object(value, {"type", "size", "uv_scale"});
      case MeshKind::Sphere:
        return Object(value, {"type", "size", "segments", "uv_scale"});
      case MeshKind::Grid:
        return Object(value, {"type", "size", "resolution", "height_map", "height", "uv_scale"});
      case MeshKind::Obj:
        break;
      case MeshKind::Gltf:
        return Object(value, {"type", "file", "scene", "node"});
    }
    return Object(value, {"type", "file"});
  }();
  if (mesh.kind == MeshKind::Obj || mesh.kind == MeshKind::Gltf) {
    mesh.file = object.required("file").existing_file();
    const auto pick = [](const Value& v) {
      GltfPick p;
      if (v.json().is_number_integer() || v.json().is_number_unsigned()) {
        p.index = static_cast<int>(v.integer(0, 1 << 30));
      } else {
        p.name = v.string();
        v.require(!p.name.empty(), "a name must not be empty (or give an index)");
      }
      return p;
    };
    if (auto v = object.find("scene")) mesh.gltf_scene = pick(*v);
    if (auto v = object.find("node")) {
      mesh.gltf_node = pick(*v);
      v->require(!mesh.gltf_scene.given(), "give 'scene' or 'node', not both");
    }
    return mesh;
  }
  if (auto v = object.find("size")) {
    const bool one_number = mesh.kind == MeshKind::Box || mesh.kind == MeshKind::Sphere;
    if (one_number) {
      const float s = static_cast<float>(v->positive());
      mesh.size = {s, s};
    } else {
      mesh.size = read_pair(*v, &Value::positive);
    }
  }
  if (auto v = object.find("uv_scale")) mesh.uv_scale = read_pair(*v, &Value::non_zero);
  if (auto v = object.find("segments")) mesh.segments = static_cast<int>(v->integer(3, 4096));
  if (auto v = object.find("resolution")) mesh.resolution = static_cast<int>(v->integer(1, 4096));
  if (auto v = object.find("height_map")) mesh.height_map = read_texture(*v, Slot::Height);
  if (auto v = object.find("height")) mesh.height = static_cast<float>(v->number());
  return mesh;
}

TransformDesc read_transform(const Value& value) {
  const Object object(value, {"translate", "rotate_deg", "scale"});
  TransformDesc transform;
  if (auto v = object.find("translate")) transform.translate = v->vec3();
  if (auto v = object.find("rotate_deg")) transform.rotate_deg = v->vec3();
  if (auto v = object.find("scale"))
    transform.scale = v->json().is_number() ? glm::vec3(static_cast<float>(v->non_zero())) : v->vec3(&Value::non_zero);
  return transform;
}

ObjectDesc read_object(const Value& value, std::size_t index, const std::vector<MaterialDesc>& materials) {
  const Object object(value, {"name", "mesh", "material", "transform", "mtl", "materials"});
  ObjectDesc result;
  result.name = "object " + std::to_string(index);
  if (auto v = object.find("name")) {
    result.name = v->string();
    v->require(!result.name.empty(), "an object name must not be empty");
  }
  result.mesh = read_mesh(object.required("mesh"));
  if (auto v = object.find("material")) {
    result.material = v->string();
    if (!std::any_of(materials.begin(), materials.end(),
                     [&](const MaterialDesc& m) { return m.name == result.material; })) {
      std::vector<std::string> names;
      for (const auto& material : materials) names.push_back(material.name);
      v->fail(
          "unknown material '" + result.material + "'" +
          (names.empty() ? "; no materials are defined" : suggestion(result.material, names, "defined materials are")));
    }
  } else {
    value.require(result.mesh.kind == MeshKind::Obj || result.mesh.kind == MeshKind::Gltf,
                  "missing key 'material' (only obj and gltf meshes may leave it out to use their own materials)");
  }
  if (auto v = object.find("transform")) result.transform = read_transform(*v);
  if (auto v = object.find("mtl")) {
    // The entries are checked by read_mtl_override once the OBJ is read and its material names are known.
    v->require(result.mesh.kind == MeshKind::Obj && result.material.empty(),
               "only an obj mesh without 'material' has MTL materials to override");
    v->expect_type(json::value_t::object, "an object mapping MTL material names to overrides");
  }
  if (auto v = object.find("materials")) {
    // Checked by read_gltf_override once the asset is read and its material names are known.
    v->require(result.mesh.kind == MeshKind::Gltf && result.material.empty(),
               "only a gltf mesh without 'material' has glTF materials to override");
    v->expect_type(json::value_t::object, "an object mapping glTF material names to overrides");
  }
  return result;
}

}  // namespace

namespace {

// The keys an override of an MTL or a glTF material shares, applied after the kind's own keys: the layer's from
// `layer_keys` (the override itself, or a glTF override's layers[0]), the rest from `object`; `no_height` is the
// message when a displacement technique is asked of a material without a height.
void read_material_override(const Object& object, const Object& layer_keys, MaterialDesc& material,
                            const std::string& no_height) {
  LayerDesc& layer = material.layers.front();
  if (auto v = layer_keys.find("normal_convention"))
    layer.normal_convention = v->choice<NormalConvention>({{"gl", NormalConvention::GL}, {"dx", NormalConvention::DX}});
  if (auto v = layer_keys.find("normal_strength")) layer.normal_strength = static_cast<float>(v->non_negative());
  if (auto v = layer_keys.find("height_scale")) layer.height_scale = static_cast<float>(v->number());
  if (auto v = layer_keys.find("height_offset")) layer.height_offset = static_cast<float>(v->number());
  if (auto v = object.find("technique")) read_technique(*v, material.technique);
  if (auto v = object.find("sampling")) read_sampling(*v, material.sampling);
  if (auto v = object.find("lighting")) read_lighting(*v, material.lighting);
  if (auto v = object.find("shadow")) material.shadow = read_shadow(*v);
  if (auto v = object.find("ao")) material.ao = read_ao(*v);
  if (material.technique.kind != TechniqueKind::Normal && layer.height.source == TextureSource::None)
    member_or_self(object, "technique").fail(no_height);
  check_visibility_needs_displacement(object, material);
}

}  // namespace

// A glTF material's override has the form of a scene material: its one layer's keys in `layers[0]`. The same
// keys beside `technique` are a shorthand for them (one form or the other, not both).
void read_gltf_override(const Value& value, MaterialDesc& material) {
  const std::array<std::string_view, 5> layer_key_names = {"height", "height_scale", "height_offset",
                                                            "normal_strength", "normal_convention"};
  const Object object(value, {"technique", "sampling", "lighting", "shadow", "ao", "layers", "height", "normal_strength",
                              "normal_convention", "height_scale", "height_offset"});
  std::vector<Value> layers;
  if (auto v = object.find("layers")) {
    v->expect_type(json::value_t::array, "an array of one layer (a glTF material has one)");
    layers = v->array();
    // Not a blend: a blend's layers carry no ORM texture (read_material), and the glTF material's base colour,
    // normal, metallic-roughness and occlusion make one layer.
    v->require(layers.size() == 1, "a glTF material has one layer: 'layers' takes one element, not " +
                                       std::to_string(layers.size()) +
                                       " (it cannot become a blend; a blend is a scene material named by the object's "
                                       "'material')");
    for (const std::string_view key : layer_key_names)
      if (auto flat = object.find(key))
        flat->fail("give '" + std::string(key) + "' in 'layers'[0] or beside 'technique', not both");
  }
  const Object layer_keys =
      layers.empty() ? object
                     : Object(layers.front(), {"height", "height_scale", "height_offset", "normal_strength", "normal_convention"});
  LayerDesc& layer = material.layers.front();
  if (auto v = layer_keys.find("height")) {
    layer.height = read_texture(*v, Slot::Height);
    if (layer.normal.source == TextureSource::None) layer.normal.source = TextureSource::FromHeight;  // a normalTexture wins
  }
  read_material_override(object, layer_keys, material,
                         "a displacement technique needs a height: give this glTF material one in 'layers'[0].height");
}

void read_mtl_override(const Value& value, MaterialDesc& material, const std::filesystem::path& bump) {
  const Object object(value, {"technique", "sampling", "lighting", "shadow", "ao", "bump", "normal_strength",
                              "normal_convention", "height_scale", "height_offset"});
  LayerDesc& layer = material.layers.front();
  if (auto v = object.find("bump")) {
    enum class Bump { Height, Normal };
    if (v->choice<Bump>({{"height", Bump::Height}, {"normal", Bump::Normal}}) == Bump::Normal) {
      v->require(!bump.empty(), "the MTL material has no bump map");
      if (layer.height.source == TextureSource::File && layer.height.file == bump) layer.height = TextureDesc{};
      if (layer.normal.source != TextureSource::File) {  // a `norm` map wins
        layer.normal.source = TextureSource::File;
        layer.normal.file = bump;
      }
    }
  }
  read_material_override(object, object, material,
                         "a displacement technique needs a height: this MTL material has no disp map, and no bump map "
                         "read as a height");
}

AnimationDesc read_animation(const Value& value) {
  const Object object(value, {"frames", "fps", "rebake_cones"});
  AnimationDesc a;
  a.present = true;
  if (auto v = object.find("frames")) a.frames = static_cast<int>(v->integer(1, limits::kMaxAnimationFrames));
  if (auto v = object.find("fps")) a.fps = v->number_in(1e-3, 1000.0);
  if (auto v = object.find("rebake_cones")) a.rebake_cones = v->boolean();
  return a;
}

SceneDesc validate_scene(const json& document, const Context& untimed) {
  const auto top = [&](const Context& context) {
    return Object(Value(context, document, ""),
                  {"output", "camera", "lights", "materials", "objects", "texture_cache", "animation"});
  };
  SceneDesc scene;
  // The animation first: file sequences and camera keyframes are checked against its frames.
  if (auto v = top(untimed).find("animation")) scene.animation = read_animation(*v);
  Context context = untimed;
  context.frames = scene.animation.frames;
  const Object object = top(context);
  scene.file = context.file;
  if (auto v = object.find("output")) scene.output = read_output(*v);
  if (auto v = object.find("camera")) scene.camera = read_camera(*v);
  if (auto v = object.find("lights")) {
    scene.lights = read_lights(*v);
  } else {
    scene.lights.directional.push_back(DirectionalLightDesc{});
    scene.lights.directional.back().direction = glm::normalize(scene.lights.directional.back().direction);
  }
  if (auto v = object.find("materials")) scene.materials = read_materials(*v);
  if (auto v = object.find("texture_cache")) scene.texture_cache = read_texture_cache(*v);
  const std::vector<Value> objects = object.required("objects").array();
  for (std::size_t i = 0; i < objects.size(); ++i) scene.objects.push_back(read_object(objects[i], i, scene.materials));
  return scene;
}

}  // namespace qdmr::scene_detail
