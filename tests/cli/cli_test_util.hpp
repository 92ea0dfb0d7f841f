#pragma once
// Shared by the end-to-end tests of the qdmr command: the shipped scenes, rendering one through a given
// binary, and reading back the float pixels it wrote.
#include <algorithm>
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "support/test_support.hpp"

namespace qdmr::test {

// Every end-to-end render is this small to keep CI fast; it still covers many tiles (64 px) and mip levels.
inline constexpr int kCliWidth = 480, kCliHeight = 270;

struct ShippedScene {
  std::string name;  // file stem in scenes/
  bool needs_data;   // references the real CC0 maps of QDMR_DATA_DIR
};

// Every scenes/*.json, sorted; scenes named real_* use the maps in QDMR_DATA_DIR.
inline std::vector<ShippedScene> shipped_scenes() {
  std::vector<ShippedScene> scenes;
  for (const auto& entry : std::filesystem::directory_iterator(source_dir() / "scenes"))
    if (entry.path().extension() == ".json") {
      const std::string name = entry.path().stem().string();
      scenes.push_back({name, name.rfind("real_", 0) == 0});
    }
  std::sort(scenes.begin(), scenes.end(), [](const ShippedScene& a, const ShippedScene& b) { return a.name < b.name; });
  return scenes;
}

// Test names allow only letters, digits and '_': "pom_vs_qdm_depth_1.0" becomes "pom_vs_qdm_depth_1_0".
inline std::string scene_name(const testing::TestParamInfo<ShippedScene>& info) {
  std::string name = info.param.name;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}
inline void PrintTo(const ShippedScene& scene, std::ostream* out) { *out << scene.name; }

// Every string of `value` that names a file under ../../shared/data/, as --set overrides pointing it at the same
// file under test::data_dir() instead, so a non-default QDMR_DATA_DIR works.
inline void relocate_data_paths(const nlohmann::json& value, const std::string& pointer, std::vector<std::string>& args) {
  static const std::string prefix = "../../shared/data/";
  if (value.is_string()) {
    const std::string text = value.get<std::string>();
    if (text.rfind(prefix, 0) == 0)
      args.insert(args.end(), {"--set", pointer + "=" + nlohmann::json((data_dir() / text.substr(prefix.size())).string()).dump()});
  } else if (value.is_object()) {
    for (const auto& [key, item] : value.items()) relocate_data_paths(item, pointer + "/" + key, args);
  } else if (value.is_array()) {
    for (std::size_t i = 0; i < value.size(); ++i) relocate_data_paths(value[i], pointer + "/" + std::to_string(i), args);
  }
}

// The scene file and the --set overrides it needs: the real_* scenes' data paths relocated.
inline std::vector<std::string> scene_args(const ShippedScene& scene) {
  const std::filesystem::path file = source_dir() / "scenes" / (scene.name + ".json");
  std::vector<std::string> args{file.string()};
  if (scene.needs_data) relocate_data_paths(nlohmann::json::parse(read_file(file)), "", args);
  return args;
}

// "qdmr render <scene> -o <output> --width 480 --height 270 <extra...>" through `binary`; fails the test
// (with the command's output) unless it exits 0.
inline void render_scene(const std::filesystem::path& binary, const ShippedScene& scene,
                         const std::filesystem::path& output, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args{"render"};
  const std::vector<std::string> scene_part = scene_args(scene);
  args.insert(args.end(), scene_part.begin(), scene_part.end());
  args.insert(args.end(), {"-o", output.string(), "--width", std::to_string(kCliWidth), "--height",
                           std::to_string(kCliHeight)});
  args.insert(args.end(), extra.begin(), extra.end());
  const CommandResult result = run(binary, args);
  ASSERT_EQ(result.exit_code, 0) << binary.filename() << " failed on " << scene.name << ":\n" << result.output;
}

struct FloatImage {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;
};

// Reads an image as float, every channel; fails the test when it cannot.
inline FloatImage read_float_image(const std::filesystem::path& file) {
  FloatImage image;
  auto in = OIIO::ImageInput::open(file.string());
  if (!in) {
    ADD_FAILURE() << "cannot open " << file << ": " << OIIO::geterror();
    return image;
  }
  const OIIO::ImageSpec& spec = in->spec();
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels;
  image.pixels.resize(std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(spec.nchannels));
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data()))
    ADD_FAILURE() << "cannot read " << file << ": " << in->geterror();
  return image;
}

// FNV-1a 64 over the size and the float bytes: equal hashes mean bit-identical pixels.
inline std::uint64_t pixel_hash(const FloatImage& image) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  const auto add = [&](const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) h = (h ^ bytes[i]) * 0x100000001b3ull;
  };
  for (int v : {image.width, image.height, image.channels}) add(&v, sizeof v);
  add(image.pixels.data(), image.pixels.size() * sizeof(float));
  return h;
}

// Empty when `a` and `b` are bit-identical, else where they first differ.
inline std::string first_difference(const FloatImage& a, const FloatImage& b) {
  std::ostringstream s;
  if (a.width != b.width || a.height != b.height || a.channels != b.channels) {
    s << "sizes differ: " << a.width << "x" << a.height << "x" << a.channels << " vs " << b.width << "x" << b.height
      << "x" << b.channels;
    return s.str();
  }
  std::size_t differing = 0, first = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i)
    if (std::memcmp(&a.pixels[i], &b.pixels[i], sizeof(float)) != 0 && differing++ == 0) first = i;
  if (differing == 0) return {};
  const std::size_t pixel = first / std::size_t(a.channels);
  s << differing << " of " << a.pixels.size() << " values differ; first at x=" << pixel % std::size_t(a.width)
    << " y=" << pixel / std::size_t(a.width) << " channel " << first % std::size_t(a.channels) << ": "
    << std::setprecision(9) << a.pixels[first] << " vs " << b.pixels[first];
  return s.str();
}

// Whether a --stats file lists a texture of `purpose` ("albedo", "height", ...) whose `where` contains where_part
// (e.g. "'quads/displaced'": the material it belongs to).
inline bool stats_have_texture(const nlohmann::json& stats, const std::string& where_part, const std::string& purpose) {
  for (const auto& t : stats["textures"])
    if (t["purpose"] == purpose && t["where"].get<std::string>().find(where_part) != std::string::npos) return true;
  return false;
}

}  // namespace qdmr::test
