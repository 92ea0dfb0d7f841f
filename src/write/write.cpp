#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>
#include <string>
#include <span>
#include <vector>

#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <nlohmann/json.hpp>

#include "file/atomic_file.hpp"
#include "codec/image_file.hpp"
#include "codec/png_writer.hpp"
#include "qdmr/core/pixel_buffer.hpp"
#include "qdmr/core/version.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/write/write.hpp"
#include "write/srgb_encode.hpp"

namespace qdmr {
namespace {

enum class Container { Png, Tiff, Exr };

Container container_of(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".png") return Container::Png;
  if (ext == ".tif" || ext == ".tiff") return Container::Tiff;
  if (ext == ".exr") return Container::Exr;
  throw Error(file.string(), "unsupported image type '" + ext + "' (use .png, .tif or .exr)");
}

// Codes of an image, not zeroed before they are written, on huge pages where large (as the frame's planes).
template <typename T>
using Codes = std::vector<T, DefaultInitAllocator<T>>;

// Pixels as codes of max_code steps (255 or 65535): sRGB-encoded or linear. Non-finite linear values give 0.
template <typename T>
Codes<T> quantize(std::span<const float> values, float max_code, bool srgb) {
  Codes<T> out(values.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, values.size(), 1 << 16), [&](const auto& range) {
    if constexpr (sizeof(T) == 1)
      if (srgb) return srgb_codes8(values.data() + range.begin(), range.size(), out.data() + range.begin());
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      if (srgb) {
        out[i] = T(srgb_code(values[i], max_code));
        continue;
      }
      const float v = std::isfinite(values[i]) ? std::clamp(values[i], 0.0f, 1.0f) : 0.0f;
      out[i] = T(std::floor(v * max_code + 0.5f));
    }
  });
  return out;
}

// The current local time as TIFF/EXIF write it ("YYYY:MM:DD hh:mm:ss"), for WriteOptions::timestamp.
std::string local_time_now() {
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char text[32];
  std::strftime(text, sizeof text, "%Y:%m:%d %H:%M:%S", &local);
  return text;
}

// Pixels as a file of `container` stores them: 8-bit sRGB codes for PNG, 16-bit sRGB codes for a colour TIFF,
// floats otherwise.
struct Encoded {
  imageio::PixelType format = imageio::PixelType::Float;
  Codes<std::uint8_t> bytes8;
  Codes<std::uint16_t> bytes16;
  std::vector<float> floats;
  const void* data() const {
    if (format == imageio::PixelType::UInt8) return bytes8.data();
    if (format == imageio::PixelType::UInt16) return bytes16.data();
    return floats.data();
  }
};

Encoded encode(Container container, std::span<const float> pixels, bool srgb) {
  Encoded encoded;
  if (container == Container::Png) {
    encoded.format = imageio::PixelType::UInt8;
    encoded.bytes8 = quantize<std::uint8_t>(pixels, 255.0f, srgb);
  } else if (container == Container::Tiff && srgb) {
    encoded.format = imageio::PixelType::UInt16;
    encoded.bytes16 = quantize<std::uint16_t>(pixels, 65535.0f, true);
  } else {
    encoded.floats.assign(pixels.begin(), pixels.end());  // EXR keeps full float precision
  }
  return encoded;
}

struct AovPixels {
  int channels = 0;
  std::vector<float> values;
};

// An AOV's values as a file of `container` holds them: as they are in float files; mapped into [0, 1] for an
// 8-bit PNG so the picture is readable (normals to 0.5 + 0.5 n, UVs to their fractional part, depth,
// iterations, hit depth, errors and cache misses divided by their maximum; two channels into red and green).
AovPixels aov_pixels(const Frame& frame, Aov aov, Container container, const std::filesystem::path& file) {
  const AovImage* image = nullptr;
  for (const AovImage& a : frame.aovs)
    if (a.aov == aov) image = &a;
  if (!image) throw Error(file.string(), "AOV '" + aov_name(aov) + "' was not rendered");
  AovPixels out{image->channels, std::vector<float>(image->pixels.begin(), image->pixels.end())};
  if (container != Container::Png) return out;
  std::vector<float>& mapped = out.values;
  if (aov == Aov::Normal)
    for (float& v : mapped) v = 0.5f + 0.5f * v;
  if (aov == Aov::UV || aov == Aov::HitUV)
    for (float& v : mapped) v -= std::floor(v);
  if (aov == Aov::Depth || aov == Aov::Iterations || aov == Aov::HitDepth || aov == Aov::ErrorTexels ||
      aov == Aov::CacheMisses) {
    float max_depth = 0.0f;
    for (float v : mapped) max_depth = std::max(max_depth, v);
    if (max_depth > 0.0f)
      for (float& v : mapped) v /= max_depth;
  }
  if (image->channels == 2) {  // PNG has no two-channel colour: u, v into red and green
    std::vector<float> rgb(mapped.size() / 2 * 3, 0.0f);
    for (std::size_t i = 0; i < mapped.size() / 2; ++i) {
      rgb[3 * i] = mapped[2 * i];
      rgb[3 * i + 1] = mapped[2 * i + 1];
    }
    mapped = std::move(rgb);
    out.channels = 3;
  }
  return out;
}

}  // namespace

void write_image(const std::filesystem::path& file, int width, int height, int channels, std::span<const float> pixels,
                 bool srgb, const WriteOptions& write) {
  if (write.threads > 0 && write.threads != tbb::this_task_arena::max_concurrency()) {
    // The encoding and the writer (write_image_file) run in an arena of that many threads. More threads than cores
    // gain nothing here; oneTBB would not give them to an arena anyway.
    tbb::task_arena arena(std::min(write.threads, tbb::info::default_concurrency()));
    WriteOptions inside = write;
    inside.threads = 0;
    arena.execute([&] { write_image(file, width, height, channels, pixels, srgb, inside); });
    return;
  }
  const Container container = container_of(file);
  const Encoded encoded = encode(container, pixels, srgb);
  imageio::WriteSpec spec{width, height, channels, encoded.format, {}, {}, {}};
  if (encoded.format != imageio::PixelType::Float) spec.strings.emplace_back("oiio:ColorSpace", "sRGB");
  if (container == Container::Png)
    spec.ints.emplace_back("png:compressionLevel", write.smallest_png ? kPngSmallestLevel : kPngFastLevel);
  // TIFF keeps only its own tags: there the bits version is in Software (tag 305) alone.
  spec.strings.emplace_back("qdmr:bits_version", std::to_string(kBitsVersion));
  spec.strings.emplace_back("Software", std::string("qdmr ") + version() + " (bits version " + std::to_string(kBitsVersion) + ")");
  if (write.timestamp) spec.strings.emplace_back("DateTime", local_time_now());
  write_image_file(file, spec, encoded.data(), "image");
}

void write_frame(const Frame& frame, const std::filesystem::path& file, const WriteOptions& write) {
  write_image(file, frame.width, frame.height, 3, frame.color, true, write);
}

void write_stats(const RenderStats& stats, const std::filesystem::path& file) { write_json(stats.to_json(), file); }

void write_json(const nlohmann::json& document, const std::filesystem::path& file) {
  write_text_file(file, document.dump(2) + "\n");
}

void write_aov(const Frame& frame, Aov aov, const std::filesystem::path& file, const WriteOptions& write) {
  const AovPixels pixels = aov_pixels(frame, aov, container_of(file), file);
  write_image(file, frame.width, frame.height, pixels.channels, pixels.values, false, write);
}

Image stored_pixels(const Frame& frame, std::optional<Aov> aov, const std::filesystem::path& file) {
  const Container container = container_of(file);
  const AovPixels source = aov ? aov_pixels(frame, *aov, container, file)
                               : AovPixels{3, std::vector<float>(frame.color.begin(), frame.color.end())};
  const Encoded encoded = encode(container, source.values, !aov);
  Image image(frame.width, frame.height, source.channels);
  if (encoded.format == imageio::PixelType::UInt8) {
    for (std::size_t i = 0; i < image.texels.size(); ++i) image.texels[i] = float(encoded.bytes8[i]) / 255.0f;
    image.source_bits = 8;
  } else if (encoded.format == imageio::PixelType::UInt16) {
    for (std::size_t i = 0; i < image.texels.size(); ++i) image.texels[i] = float(encoded.bytes16[i]) / 65535.0f;
    image.source_bits = 16;
  } else {
    image.texels.assign(encoded.floats.begin(), encoded.floats.end());
    image.source_bits = 32;
  }
  return image;
}

}  // namespace qdmr
