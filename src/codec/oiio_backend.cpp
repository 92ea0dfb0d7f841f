#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <cctype>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>
#include <string_view>
#include <vector>

#include "codec/backend.hpp"

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

// Opens `input` on `path`.
bool open_file(std::unique_ptr<OIIO::ImageInput> input, const std::string& path, Reader& reader, std::string& error) {
  OIIO::ImageSpec header;
  // A texture's channels are data: alpha is one more channel (often a height or a roughness packed beside colour
  // or a normal), read as stored. OpenImageIO's PNG and TIFF readers would otherwise multiply the other channels
  // by it ("associate" it), as for a colour image with coverage.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  if (!input->open(path, header, config)) {
    error = input->geterror();
    return false;
  }
  reader.input = std::move(input);
  return true;
}

// The reader of the file's extension, then, for a file it does not open, the readers of the formats qdmr reads textures
// from that it does not read itself (PNG, JPEG, OpenEXR, PBM/PGM/PPM and the TIFF layouts it reads never get here:
// codec/read_file.cpp), each of which checks the magic number first (valid_file). OpenImageIO's own fallback
// (ImageInput::open) tries every reader it has, ~30 of them (LibRaw, FFmpeg, DICOM, ...), on any damaged file: each a
// decoder run on an untrusted file for a format qdmr refuses anyway, and a few milliseconds.
bool open_input(const std::string& path, Reader& reader, std::string& error) {
  // OpenImageIO's "extension_list": "tiff:tif,tiff;jpeg:jpg,jpe,jpeg;..." (every reader's and writer's).
  static const std::map<std::string, std::string> formats = [] {
    std::map<std::string, std::string> map;
    std::istringstream list(OIIO::get_string_attribute("extension_list"));
    for (std::string entry; std::getline(list, entry, ';');) {
      const std::size_t colon = entry.find(':');
      if (colon == std::string::npos) continue;
      std::istringstream extensions(entry.substr(colon + 1));
      for (std::string e; std::getline(extensions, e, ',');) map.emplace(e, entry.substr(0, colon));
    }
    return map;
  }();
  std::string extension = std::filesystem::path(path).extension().string();
  if (!extension.empty()) extension.erase(0, 1);
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  std::string tried;  // the format of the extension's reader
  if (const auto format = formats.find(extension); format != formats.end()) {
    // A format name alone: the reader is created, not opened.
    if (auto input = OIIO::ImageInput::create(format->second)) {
      tried = input->format_name();
      if (open_file(std::move(input), path, reader, error)) return true;
    }
  }
  for (const char* format : {"openexr", "tiff", "pnm"}) {
    if (format == tried) continue;
    auto input = OIIO::ImageInput::create(format);
    if (!input || !input->valid_file(path)) continue;
    std::string failed;
    if (open_file(std::move(input), path, reader, failed)) return true;
    if (error.empty()) error = failed;
  }
  if (error.empty()) error = tried.empty() ? "not a PNG, JPEG, OpenEXR, TIFF or PNM file" : "not a " + tried + " file";
  return false;
}

Reader* open(const std::string& path, ReadSpec& spec, std::string& error) {
  auto reader = std::make_unique<Reader>();
  if (!open_input(path, *reader, error)) return nullptr;
  const OIIO::ImageInput* input = reader->input.get();
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
  return reader.release();
}

bool read(Reader* reader, PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) {
  OIIO::ImageInput& in = *reader->input;
  const OIIO::ImageSpec& spec = in.spec();
  const int channels = spec.nchannels;
  const OIIO::TypeDesc want = type_desc(type);
  const auto failed = [&] {
    error = in.geterror();
    if (error.empty()) error = OIIO::geterror();
    return false;
  };
  // Tiled files, and channels of different types, as OpenImageIO reads them.
  if (spec.tile_width > 0 || !spec.channelformats.empty()) {
    if (in.read_image(0, 0, 0, channels, want, first_row, OIIO::AutoStride, OIIO::stride_t(row_stride)) &&
        !in.has_error())
      return true;
    return failed();
  }
  // Scanlines: read as the file stores them, top-down and contiguous, a few MB at a time, then converted and
  // flipped here. Asked for another type or row order, OpenImageIO decodes through a buffer of 64 MB whatever
  // the image's size (ImageInput::read_scanlines), allocated for every image read; and OpenImageIO 2.4 takes
  // its direct path only for TypeUnknown ("as stored"), not for the file's own type named explicitly.
  //
  // A TIFF whose photometric interpretation is "min is white" is read one scanline per call: OpenImageIO 2.4
  // (TIFFInput::read_native_scanlines) inverts each deflate-compressed strip it reads as a strip over `channels`
  // times the strip's size, so past the end of the caller's rows for a file of more than one channel (a heap
  // overflow that fuzz_image found). A single scanline takes its per-scanline path, which inverts the row only.
  const bool min_is_white = spec.get_int_attribute("tiff:PhotometricInterpretation", -1) == 0;
  const std::size_t row_values = std::size_t(spec.width) * std::size_t(channels);
  const std::size_t row_bytes = row_values * spec.format.size();
  const int strip = std::max(1, spec.get_int_attribute("tiff:RowsPerStrip", 64));
  const int chunk_rows = std::max(1, int((std::size_t(4) << 20) / row_bytes) / strip) * strip;
  const int rows = min_is_white ? 1 : std::min(spec.height, chunk_rows);
  std::unique_ptr<unsigned char[]> native(new unsigned char[row_bytes * std::size_t(rows)]);
  for (int y0 = 0; y0 < spec.height; y0 += rows) {
    const int y1 = std::min(y0 + rows, spec.height);
    if (!in.read_scanlines(0, 0, spec.y + y0, spec.y + y1, 0, 0, channels, OIIO::TypeUnknown, native.get()) ||
        in.has_error())
      return failed();
    for (int y = y0; y < y1; ++y) {
      const unsigned char* from = native.get() + row_bytes * std::size_t(y - y0);
      void* to = static_cast<char*>(first_row) + row_stride * y;
      if (!OIIO::convert_pixel_values(spec.format, from, want, to, int(row_values))) {
        error = "no conversion from " + std::string(spec.format.c_str()) + " pixels";
        return false;
      }
    }
  }
  return true;
}

void close(Reader* reader) { delete reader; }

// OpenEXR's bytes straight into the existing file `path` (truncated), every write checked: OpenEXR's own buffered
// stream loses a failed final flush (a full disk gave a 0-byte "written" file), so writes go out unbuffered with
// pwrite() and the first failure is kept with its OS reason (OpenEXR then fails the image too). No copy of the
// encoded file is held in memory.
class CheckedFileOutput final : public OIIO::Filesystem::IOProxy {
public:
  explicit CheckedFileOutput(const std::string& path)
      : IOProxy(path, Write), fd_(::open(path.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC)) {
    if (fd_ < 0) failure_ = errno;
  }
  ~CheckedFileOutput() override { close(); }
  const char* proxytype() const override { return "qdmr_checked_file"; }
  bool opened() const override { return fd_ >= 0; }
  void close() override {
    if (fd_ >= 0 && ::close(fd_) != 0 && failure_ == 0) failure_ = errno;
    fd_ = -1;
  }
  size_t size() const override { return std::size_t(end_); }
  size_t write(const void* buf, size_t size) override {
    const std::size_t done = pwrite(buf, size, m_pos);
    m_pos += std::int64_t(done);
    return done;
  }
  size_t pwrite(const void* buf, size_t size, int64_t offset) override {
    std::size_t done = 0;
    while (fd_ >= 0 && failure_ == 0 && done < size) {
      const ssize_t n = ::pwrite(fd_, static_cast<const char*>(buf) + done, size - done, offset + std::int64_t(done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) failure_ = n < 0 ? errno : ENOSPC;  // a write of 0 bytes: no room
      if (n > 0) done += std::size_t(n);
    }
    end_ = std::max(end_, offset + std::int64_t(done));
    return done;
  }
  int failure() const { return failure_; }  // the first OS error (errno), 0 for none

private:
  int fd_;
  int failure_ = 0;
  std::int64_t end_ = 0;
};

bool write(const std::string& path, const WriteSpec& spec, const void* data, std::string& error) {
  OIIO::ImageSpec s(spec.width, spec.height, spec.channels, type_desc(spec.type));
  if (!spec.channel_names.empty()) s.channelnames = spec.channel_names;
  for (const auto& [name, value] : spec.strings) s.attribute(name, value);
  for (const auto& [name, value] : spec.ints) s.attribute(name, value);
  std::unique_ptr<CheckedFileOutput> checked;  // declared first: outlives `output`, which may use it to the end
  auto output = OIIO::ImageOutput::create(path);
  if (!output) {
    error = OIIO::geterror();
    return false;
  }
  // OpenEXR files go through CheckedFileOutput. The TIFF and PNG writers report a full disk themselves (and TIFF
  // through a memory proxy wrote unreadable files).
  if (std::string_view(output->format_name()) == "openexr" && output->supports("ioproxy")) {
    checked = std::make_unique<CheckedFileOutput>(path);
    if (!output->set_ioproxy(checked.get())) checked.reset();
  }
  if (spec.threads > 0) output->threads(spec.threads);  // TIFF's strips compressed on OpenImageIO's threads
  const bool written = output->open(path, s) && output->write_image(type_desc(spec.type), data) && output->close();
  if (checked) checked->close();
  if (checked && checked->failure() != 0) {  // the OS's reason first: OpenEXR's own message does not say why
    error = std::strerror(checked->failure());
    return false;
  }
  if (!written) {
    error = output->geterror();
    if (error.empty()) error = "unknown error";
    return false;
  }
  return true;
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
