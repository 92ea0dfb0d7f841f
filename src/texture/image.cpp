#include "qdmr/texture/image.hpp"

#include <OpenImageIO/imageio.h>

#include <cstdint>
#include <vector>

#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"

namespace qdmr {

Image read_image(const std::filesystem::path& file, const std::string& where) {
  const std::string name = file.string();
  // OIIO may report several lines (e.g. "Read error: hit end of file\nPNG read error: ..."): an error is one line.
  const auto fail = [&](std::string message) {
    while (!message.empty() && message.back() == '\n') message.pop_back();
    for (std::size_t at; (at = message.find('\n')) != std::string::npos;) message.replace(at, 1, "; ");
    return Error(where, "cannot read '" + name + "': " + (message.empty() ? "unknown error" : message));
  };
  auto in = OIIO::ImageInput::open(name);
  if (!in) throw fail(OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.width > limits::kMaxTextureSide ||
      spec.height > limits::kMaxTextureSide)
    throw fail("size " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + " is outside 1.." +
               std::to_string(limits::kMaxTextureSide));
  if (spec.depth > 1) throw fail("volume images are not supported");
  if (spec.nchannels < 1 || spec.nchannels > 4)
    throw fail(std::to_string(spec.nchannels) + " channels (textures take 1 to 4)");
  Image image(spec.width, spec.height, spec.nchannels);
  // Rows are stored bottom-up: the file's last row becomes row 0 (v = 0), the OpenGL/OBJ convention, so
  // UVs from OBJ files and +Y-up (GL) normal maps need no flipping.
  const auto read = [&](OIIO::TypeDesc type, void* data) {
    const OIIO::stride_t row = OIIO::stride_t(type.size()) * spec.nchannels * spec.width;
    char* last_row = static_cast<char*>(data) + row * (spec.height - 1);
    if (!in->read_image(0, 0, 0, spec.nchannels, type, last_row, OIIO::AutoStride, -row)) {
      const std::string message = in->geterror();
      throw fail(message.empty() ? OIIO::geterror() : message);
    }
  };
  // 8- and 16-bit integers are converted here as k / (2^bits - 1), correctly rounded, so values are exact
  // (OIIO multiplies by a rounded reciprocal).
  const auto convert = [&](auto integer, float max) {
    std::vector<decltype(integer)> raw(image.texels.size());
    read(OIIO::TypeDesc(OIIO::BaseTypeFromC<decltype(integer)>::value), raw.data());
    for (std::size_t i = 0; i < raw.size(); ++i) image.texels[i] = float(raw[i]) / max;
  };
  const bool uniform = spec.channelformats.empty();
  if (uniform && spec.format == OIIO::TypeDesc::UINT8) {
    convert(std::uint8_t{}, 255.0f);
    image.source_bits = 8;
  } else if (uniform && spec.format == OIIO::TypeDesc::UINT16) {
    convert(std::uint16_t{}, 65535.0f);
    image.source_bits = 16;
  }
  else
    read(OIIO::TypeDesc::FLOAT, image.texels.data());
  return image;
}

}  // namespace qdmr
