#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include "imageio/backend.hpp"

namespace qdmr::imageio {

struct Reader {
  std::unique_ptr<OIIO::ImageInput> input;
};

namespace {

OIIO::TypeDesc type_desc(PixelType type) {
  switch (type) {
    case PixelType::UInt8: return OIIO::TypeDesc::UINT8;
    case PixelType::UInt16: return OIIO::TypeDesc::UINT16;
    case PixelType::Float: break;
  }
  return OIIO::TypeDesc::FLOAT;
}

Reader* open(const std::string& path, ReadSpec& spec, std::string& error) {
  auto input = OIIO::ImageInput::open(path);
  if (!input) {
    error = OIIO::geterror();
    return nullptr;
  }
  const OIIO::ImageSpec& s = input->spec();
  spec.width = s.width;
  spec.height = s.height;
  spec.depth = s.depth;
  spec.channels = s.nchannels;
  spec.format = input->format_name();
  spec.uniform = s.channelformats.empty();
  spec.type = s.format == OIIO::TypeDesc::UINT8 ? PixelType::UInt8
              : s.format == OIIO::TypeDesc::UINT16 ? PixelType::UInt16
                                                   : PixelType::Float;
  spec.bits_version = s.get_string_attribute("qdmr:bits_version");
  spec.software = s.get_string_attribute("Software");
  return new Reader{std::move(input)};
}

bool read(Reader* reader, PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) {
  OIIO::ImageInput& in = *reader->input;
  const int channels = in.spec().nchannels;
  if (in.read_image(0, 0, 0, channels, type_desc(type), first_row, OIIO::AutoStride, OIIO::stride_t(row_stride)) &&
      !in.has_error())
    return true;
  error = in.geterror();
  if (error.empty()) error = OIIO::geterror();
  return false;
}

void close(Reader* reader) { delete reader; }

bool write(const std::string& path, const WriteSpec& spec, const void* data, std::string& error) {
  OIIO::ImageSpec s(spec.width, spec.height, spec.channels, type_desc(spec.type));
  if (!spec.channel_names.empty()) s.channelnames = spec.channel_names;
  for (const auto& [name, value] : spec.strings) s.attribute(name, value);
  for (const auto& [name, value] : spec.ints) s.attribute(name, value);
  auto output = OIIO::ImageOutput::create(path);
  if (!output) {
    error = OIIO::geterror();
    return false;
  }
  if (output->open(path, s) && output->write_image(type_desc(spec.type), data) && output->close()) return true;
  error = output->geterror();
  if (error.empty()) error = "unknown error";
  return false;
}

void color_map(const float* values, int width, int height, const char* map, float* rgb) {
  OIIO::ImageBuf delta(OIIO::ImageSpec(width, height, 1, OIIO::TypeDesc::FLOAT));
  delta.set_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, values);
  const OIIO::ImageBuf colored = OIIO::ImageBufAlgo::color_map(delta, 0, map);
  colored.get_pixels(OIIO::ROI(0, width, 0, height, 0, 1, 0, 3), OIIO::TypeDesc::FLOAT, rgb);
}

}  // namespace

const Backend& oiio_backend() {
  static const Backend backend{&open, &read, &close, &write, &color_map};
  return backend;
}

}  // namespace qdmr::imageio
