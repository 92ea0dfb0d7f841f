// An OpenEXR file read by the OpenEXR library, as OpenImageIO 2.4's reader (openexr.imageio/exrinput.cpp) reads it: the
// first part, its data window, level 0 of a tiled multi-resolution file, the channels in OpenImageIO's order (by layer,
// then R, G, B, Y, A and the other reserved names, then by name; R, G, B, X, Y, Z in a layer that has X and Y or Z),
// half and float samples as floats, 32-bit unsigned integers scaled to [0, 1]. A file OpenImageIO refuses is refused
// too (subsampled channels), and so is deep data (samples per pixel, not an image). Metadata: the string attributes
// Software and qdmr:bits_version, whatever their case, a later one (in the header's order) replacing an earlier, an
// empty one ignored.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStringAttribute.h>
#include <ImfPartType.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <tbb/task_arena.h>

#include "codec/exr_writer.hpp"
#include "codec/native_reader.hpp"

namespace qdmr::imageio {
namespace {

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return (x >= 'A' && x <= 'Z' ? x - 'A' + 'a' : x) == (y >= 'A' && y <= 'Z' ? y - 'A' + 'a' : y);
         });
}

struct Channel {
  std::string name;
  Imf::PixelType type = Imf::HALF;
  std::size_t suffix_at = 0;  // "diffuse." and "R" of "diffuse.R"; "" and "R" of "R"
  int order = 10000;          // among the reserved names of its layer; others after them

  std::string_view layer() const { return std::string_view(name).substr(0, suffix_at); }
  std::string_view suffix() const { return std::string_view(name).substr(suffix_at); }
};

// OpenImageIO's canonical channel order (exrinput.cpp: ChanNameHolder).
void sort_channels(std::vector<Channel>& channels) {
  static constexpr std::string_view kReserved[] = {"R",  "Red", "G",  "Green", "B",     "Blue",  "Y",
                                                   "real", "imag", "A", "Alpha", "AR", "RA", "AG",
                                                   "GA", "AB", "BA", "Z", "Depth", "Zback"};
  static constexpr std::string_view kReservedXyz[] = {"R",  "Red",  "G",  "Green", "B",  "Blue", "X",
                                                      "Y",  "Z",    "real", "imag", "A", "Alpha", "AR",
                                                      "RA", "AG",   "GA", "AB",    "BA", "Depth", "Zback"};
  for (Channel& c : channels) {
    const std::size_t dot = c.name.rfind('.');
    c.suffix_at = dot == std::string::npos ? 0 : dot + 1;
  }
  const auto in_layer = [&](std::string_view layer, std::string_view suffix) {
    return std::any_of(channels.begin(), channels.end(),
                       [&](const Channel& c) { return c.layer() == layer && iequals(c.suffix(), suffix); });
  };
  for (Channel& c : channels) {
    const bool xyz = in_layer(c.layer(), "X") && (in_layer(c.layer(), "Y") || in_layer(c.layer(), "Z"));
    const std::string_view* first = xyz ? std::begin(kReservedXyz) : std::begin(kReserved);
    const std::string_view* last = xyz ? std::end(kReservedXyz) : std::end(kReserved);
    const auto found = std::find_if(first, last, [&](std::string_view r) { return iequals(c.suffix(), r); });
    if (found != last) c.order = int(found - first);
  }
  std::sort(channels.begin(), channels.end(), [](const Channel& a, const Channel& b) {
    if (a.layer() != b.layer()) return a.layer() < b.layer();
    if (a.order != b.order) return a.order < b.order;
    return a.suffix() < b.suffix();
  });
}

class ExrReader final : public NativeReader {
public:
  bool open(const std::string& path, ReadSpec& spec, std::string& error) {
    try {
      // The threads of the caller's task arena, as a write takes them (codec/image_file.hpp): the chunks are
      // decompressed on that many threads of their own, 1 being the calling thread alone (ExrThreads), never on
      // the pool that OpenEXR's other users in the process (OpenImageIO among them) share.
      const ExrThreads threads(tbb::this_task_arena::max_concurrency());
      threads_ = threads.threads();
      file_ = std::make_unique<Imf::InputFile>(path.c_str(), threads_);
      const Imf::Header& header = file_->header();
      if (header.hasType() && Imf::isDeepData(header.type())) {
        error = "deep OpenEXR data (samples per pixel) is not an image qdmr reads";
        return false;
      }
      for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
        if (it.channel().xSampling != 1 || it.channel().ySampling != 1) {
          error = "subsampled OpenEXR channels are not supported (channel '" + std::string(it.name()) + "' has " +
                  "sampling " + std::to_string(it.channel().xSampling) + "," +
                  std::to_string(it.channel().ySampling) + ")";
          return false;
        }
        channels_.push_back({it.name(), it.channel().type});
      }
      if (channels_.empty()) {
        error = "the OpenEXR file has no channels";
        return false;
      }
      sort_channels(channels_);
      const Imath::Box2i window = header.dataWindow();
      x_ = window.min.x;
      y_ = window.min.y;
      width_ = std::int64_t(window.max.x) - window.min.x + 1;
      height_ = std::int64_t(window.max.y) - window.min.y + 1;
      if (width_ <= 0 || height_ <= 0 || width_ > INT32_MAX || height_ > INT32_MAX) {
        error = "the OpenEXR data window is empty or too large";
        return false;
      }
      set_image(spec, int(width_), int(height_), int(channels_.size()), "openexr", PixelType::Float,
                std::all_of(channels_.begin(), channels_.end(),
                            [&](const Channel& c) { return c.type == channels_[0].type; }));
      for (auto it = header.begin(); it != header.end(); ++it) {
        const auto* text = dynamic_cast<const Imf::StringAttribute*>(&it.attribute());
        if (!text || text->value().empty()) continue;
        if (iequals(it.name(), "Software")) spec.software = text->value();
        if (iequals(it.name(), "qdmr:bits_version")) spec.bits_version = text->value();
      }
      return true;
    } catch (const std::exception& e) {
      error = std::string("OpenEXR: ") + e.what();
      return false;
    }
  }

  bool read_pixels(PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) override {
    if (type != PixelType::Float) {
      error = "an OpenEXR file is read as floats only";
      return false;
    }
    // A band of rows at a time, decoded into a buffer with the file's row order and then copied to the caller's
    // rows (OpenEXR's slices take unsigned strides). 64 rows: whole line blocks of every compression (1, 16 or 32
    // lines) and the common tile heights, so no block is decoded twice.
    const std::size_t pixel = channels_.size() * 4;
    const std::size_t row_bytes = std::size_t(width_) * pixel;
    const std::int64_t band = std::clamp<std::int64_t>((std::int64_t(16) << 20) / std::int64_t(row_bytes), 1, 64);
    const auto buffer = std::make_unique_for_overwrite<char[]>(row_bytes * std::size_t(std::min(band, height_)));
    try {
      const ExrThreads threads(threads_);
      for (std::int64_t y0 = 0; y0 < height_; y0 += band) {
        const std::int64_t rows = std::min(band, height_ - y0);
        Imf::FrameBuffer frame;
        for (std::size_t c = 0; c < channels_.size(); ++c) {
          const Imf::PixelType as = channels_[c].type == Imf::UINT ? Imf::UINT : Imf::FLOAT;
          frame.insert(channels_[c].name, Imf::Slice::Make(as, buffer.get() + 4 * c, Imath::V2i(x_, y_ + int(y0)),
                                                           width_, rows, pixel, row_bytes));
        }
        file_->setFrameBuffer(frame);
        file_->readPixels(y_ + int(y0), y_ + int(y0 + rows - 1));
        for (std::int64_t r = 0; r < rows; ++r) {
          char* row = buffer.get() + row_bytes * std::size_t(r);
          scale_integers(row);
          std::memcpy(static_cast<char*>(first_row) + row_stride * std::ptrdiff_t(y0 + r), row, row_bytes);
        }
      }
      return true;
    } catch (const std::exception& e) {
      error = std::string("Failed OpenEXR read: ") + e.what();
      return false;
    }
  }

private:
  // 32-bit unsigned samples of a row as floats k / (2^32 - 1), as OpenImageIO converts them.
  void scale_integers(char* row) const {
    for (std::size_t c = 0; c < channels_.size(); ++c) {
      if (channels_[c].type != Imf::UINT) continue;
      for (std::int64_t x = 0; x < width_; ++x) {
        char* at = row + (std::size_t(x) * channels_.size() + c) * 4;
        std::uint32_t k;
        std::memcpy(&k, at, 4);
        const float value = float(k) * (1.0f / 4294967295.0f);
        std::memcpy(at, &value, 4);
      }
    }
  }

  std::unique_ptr<Imf::InputFile> file_;
  int threads_ = 1;                // OpenEXR's threads for the file (ExrThreads)
  std::vector<Channel> channels_;  // in OpenImageIO's order
  int x_ = 0, y_ = 0;              // the data window's corner
  std::int64_t width_ = 0, height_ = 0;
};

}  // namespace

std::unique_ptr<NativeReader> open_exr(const std::string& path, ReadSpec& spec, std::string& error) {
  return opened<ExrReader>(path, spec, error);
}

}  // namespace qdmr::imageio
