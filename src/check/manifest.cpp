#include "qdmr/check/manifest.hpp"

#include <algorithm>
#include <set>
#include <sstream>

#include "file/input_file.hpp"
#include "qdmr/core/aov.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"
#include "scene/reader.hpp"

namespace qdmr {
namespace {

using scene_detail::Object;
using scene_detail::Value;

bool valid_name(const std::string& name) {
  if (name.empty() || name.size() > 128) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_';
  });
}

bool valid_hash(const std::string& hash) {
  if (hash.size() != 45 || !hash.starts_with("sha1:")) return false;
  return std::all_of(hash.begin() + 5, hash.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

// A path relative to the manifest's folder; it need not exist yet (goldens are created by --update).
std::filesystem::path path_in(const Value& value) {
  const std::string text = value.string();
  value.require(!text.empty(), "expected a file path, got an empty string");
  return std::filesystem::absolute(value.context().base_dir / text).lexically_normal();
}

Tolerance read_tolerance(const Value& value, Tolerance tolerance) {
  const Object object(value, {"max_abs", "max_pixels", "max_fraction", "radius", "max_rmse", "min_psnr"});
  if (auto v = object.find("max_abs")) tolerance.max_abs = v->non_negative();
  if (auto v = object.find("max_pixels")) tolerance.max_pixels = v->integer(0, std::int64_t(1) << 40);
  if (auto v = object.find("max_fraction")) tolerance.max_fraction = v->number_in(0, 1);
  if (auto v = object.find("radius")) tolerance.radius = int(v->integer(0, 16));
  if (auto v = object.find("max_rmse")) tolerance.max_rmse = v->non_negative();
  if (auto v = object.find("min_psnr")) tolerance.min_psnr = v->number();
  return tolerance;
}

std::vector<std::string> read_outputs(const Value& value) {
  std::vector<std::string> outputs;
  const std::vector<std::string> valid = check_output_names();
  for (const Value& item : value.array()) {
    const std::string name = item.string();
    if (std::find(valid.begin(), valid.end(), name) == valid.end())
      item.fail("unknown output '" + scene_detail::shorten(name) + "'" + scene_detail::suggestion(name, valid, "valid outputs are"));
    if (std::find(outputs.begin(), outputs.end(), name) != outputs.end()) item.fail("output '" + name + "' given twice");
    outputs.push_back(name);
  }
  value.require(!outputs.empty(), "expected at least one output, e.g. [\"color\"]");
  return outputs;
}

std::vector<CheckVariant> read_variants(const Value& value) {
  std::vector<CheckVariant> variants;
  for (const Value& item : value.array()) {
    const Object object(item, {"threads", "tile", "isa"});
    CheckVariant variant;
    if (auto v = object.find("threads")) variant.threads = int(v->integer(1, limits::kMaxThreads));
    if (auto v = object.find("tile")) {
      variant.tile = int(v->integer(8, limits::kMaxTileSize));
      v->require(*variant.tile % 8 == 0, "must be a multiple of 8, got " + std::to_string(*variant.tile));
    }
    std::vector<std::optional<Isa>> isas{std::nullopt};
    if (auto v = object.find("isa")) {
      const std::string name = v->string();
      if (name == "all") {  // every ISA this binary has and this CPU runs
        isas.clear();
        for (Isa isa : usable_isas()) isas.push_back(isa);
      } else {
        try {
          isas = {resolve_isa(name, "")};
        } catch (const Error& e) {
          std::string what = e.what();
          if (what.starts_with(": ")) what = what.substr(2);
          v->fail(what + " (\"all\" runs every ISA this machine has)");
        }
      }
    }
    for (const std::optional<Isa>& isa : isas) {
      variant.isa = isa;
      variants.push_back(variant);
    }
  }
  value.require(!variants.empty(), "expected at least one variant, e.g. [{}, {\"threads\": 1}]");
  return variants;
}

std::vector<SceneOverride> read_overrides(const Value& value) {
  std::vector<SceneOverride> overrides;
  if (value.json().is_object()) {  // {"/camera/fov_deg": 30}
    for (const auto& [pointer, item] : value.json().items()) {
      const Value entry = *value.member(pointer);
      SceneOverride o;
      try {
        o = parse_override(pointer + "=" + item.dump());
      } catch (const Error& e) {
        entry.fail(e.what());
      }
      overrides.push_back(o);
    }
    return overrides;
  }
  value.require(value.json().is_array(), std::string("expected an object of JSON pointers and values, or an array of "
                                                     "\"POINTER=VALUE\" strings, got ") + value.json().type_name());
  for (const Value& item : value.array()) {  // ["/camera/fov_deg=30"], as on the command line
    try {
      overrides.push_back(parse_override(item.string()));
    } catch (const Error& e) {
      item.fail(e.what());
    }
  }
  return overrides;
}

// The defaults block: what a check has unless it says otherwise.
struct Defaults {
  int width = 320, height = 180;
  CheckMode mode = CheckMode::Exact;
  std::vector<std::string> outputs{"color"};
  Tolerance tolerance;
  std::vector<CheckVariant> variants{CheckVariant{}};
};

CheckMode read_mode(const Value& value) {
  return value.choice<CheckMode>({{"exact", CheckMode::Exact}, {"tolerance", CheckMode::Tolerance}});
}

Defaults read_defaults(const Value& value) {
  Defaults d;
  const Object object(value, {"width", "height", "mode", "outputs", "tolerance", "variants"});
  if (auto v = object.find("width")) d.width = int(v->integer(1, limits::kMaxImageSide));
  if (auto v = object.find("height")) d.height = int(v->integer(1, limits::kMaxImageSide));
  if (auto v = object.find("mode")) d.mode = read_mode(*v);
  if (auto v = object.find("outputs")) d.outputs = read_outputs(*v);
  if (auto v = object.find("tolerance")) d.tolerance = read_tolerance(*v, d.tolerance);
  if (auto v = object.find("variants")) d.variants = read_variants(*v);
  return d;
}

std::string golden_file_name(const std::string& check, const std::string& output) {
  return output == "color" ? check + ".exr" : check + "." + output + ".exr";
}

CheckSpec read_check(const Value& value, const Defaults& d, const std::filesystem::path& golden_dir) {
  const Object object(value, {"name", "scene", "set", "width", "height", "outputs", "mode", "hash", "golden",
                              "tolerance", "variants", "skip_if_missing"});
  CheckSpec check;
  check.pointer = value.pointer();
  const Value name = object.required("name");
  check.name = name.string();
  name.require(valid_name(check.name), "a check name is 1 to 128 letters, digits, '.', '-' or '_', got '" +
                                           scene_detail::shorten(check.name) + "'");
  check.scene = path_in(object.required("scene"));
  if (auto v = object.find("set")) check.overrides = read_overrides(*v);
  check.width = d.width;
  check.height = d.height;
  if (auto v = object.find("width")) check.width = int(v->integer(1, limits::kMaxImageSide));
  if (auto v = object.find("height")) check.height = int(v->integer(1, limits::kMaxImageSide));
  check.mode = d.mode;
  if (auto v = object.find("mode")) check.mode = read_mode(*v);
  check.outputs = d.outputs;
  if (auto v = object.find("outputs")) check.outputs = read_outputs(*v);
  check.tolerance = d.tolerance;
  if (auto v = object.find("tolerance")) {
    v->require(check.mode == CheckMode::Tolerance, "a tolerance applies to mode \"tolerance\" only (this check is exact)");
    check.tolerance = read_tolerance(*v, d.tolerance);
  }
  check.variants = d.variants;
  if (auto v = object.find("variants")) check.variants = read_variants(*v);
  if (auto v = object.find("skip_if_missing"))
    for (const Value& item : v->array()) check.skip_if_missing.push_back(path_in(item));

  const auto check_keys = [&](const Value& map, const char* what) {
    for (const auto& item : map.json().items())
      if (std::find(check.outputs.begin(), check.outputs.end(), item.key()) == check.outputs.end())
        map.member(item.key())->fail(std::string(what) + " for '" + scene_detail::shorten(item.key()) +
                                     "', which is not one of this check's outputs");
  };
  if (auto v = object.find("hash")) {
    v->require(check.mode == CheckMode::Exact, "hashes belong to exact checks; a tolerance check has \"golden\" files");
    v->expect_type(nlohmann::json::value_t::object, "an object of output names and hashes, e.g. {\"color\": \"sha1:...\"}");
    check_keys(*v, "a hash");
    for (const auto& item : v->json().items()) {
      const Value hash = *v->member(item.key());
      const std::string text = hash.string();
      hash.require(valid_hash(text), "expected \"sha1:\" and 40 lowercase hex digits, got '" + scene_detail::shorten(text) + "'");
      check.hashes[item.key()] = text;
    }
  }
  if (check.mode == CheckMode::Tolerance) {
    for (const std::string& output : check.outputs)
      check.goldens[output] = golden_dir / golden_file_name(check.name, output);
    if (auto v = object.find("golden")) {
      v->expect_type(nlohmann::json::value_t::object, "an object of output names and image files, e.g. {\"color\": \"goldens/a.png\"}");
      check_keys(*v, "a golden");
      for (const auto& item : v->json().items()) {
        const Value file = *v->member(item.key());
        check.goldens[item.key()] = path_in(file);
        std::string ext = check.goldens[item.key()].extension().string();
        for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
        const bool image = ext == ".exr" || (item.key() == "color" && (ext == ".png" || ext == ".tif" || ext == ".tiff"));
        file.require(image, item.key() == "color" ? "a colour golden is .exr, .png or .tif"
                                                  : "an AOV golden is .exr (PNG and TIFF views of AOVs are rescaled)");
      }
    }
  } else if (object.find("golden")) {
    object.find("golden")->fail("golden files belong to tolerance checks; an exact check has \"hash\"");
  }
  return check;
}

}  // namespace

std::string CheckVariant::label() const {
  std::ostringstream out;
  if (threads) out << "threads=" << *threads;
  if (tile) out << (out.tellp() > 0 ? " " : "") << "tile=" << *tile;
  if (isa) out << (out.tellp() > 0 ? " " : "") << "isa=" << isa_name(*isa);
  return out.str();
}

std::vector<std::string> check_output_names() {
  std::vector<std::string> names{"color"};
  for (const std::string& aov : aov_names()) names.push_back(aov);
  return names;
}

Manifest read_manifest(const std::filesystem::path& file) {
  Manifest manifest;
  manifest.file = file;
  manifest.document = scene_detail::parse_json_file(file, InputKind::Manifest, &manifest.text);
  const scene_detail::Context context{file.string(), std::filesystem::absolute(file).parent_path()};
  const Value root(context, manifest.document, "");
  if (manifest.document.is_object() && !manifest.document.contains("checks") && manifest.document.contains("camera"))
    throw Error(file.string(), "this is a scene, not a check manifest: check a scene with --golden FILE or --hash "
                               "HASH, or list it in a manifest (docs/checks.md)");
  const Object object(root, {"bits_version", "defaults", "golden_dir", "checks"});
  manifest.bits_version = int(object.required("bits_version").integer(1, 1 << 30));
  const Defaults defaults = object.find("defaults") ? read_defaults(*object.find("defaults")) : Defaults{};
  std::filesystem::path golden_dir = context.base_dir / "goldens";
  if (auto v = object.find("golden_dir")) golden_dir = path_in(*v);
  std::set<std::string> names;
  const Value checks = object.required("checks");
  for (const Value& item : checks.array()) {
    CheckSpec check = read_check(item, defaults, golden_dir);
    if (!names.insert(check.name).second) item.member("name")->fail("check name '" + check.name + "' is used twice");
    manifest.checks.push_back(std::move(check));
  }
  checks.require(!manifest.checks.empty(), "a manifest needs at least one check");
  return manifest;
}

}  // namespace qdmr
