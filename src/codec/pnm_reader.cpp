// A PBM, PGM or PPM file (P1 to P6) read as Netpbm defines it: a header of whitespace-separated decimal fields with
// comments from '#' to the end of a line, one whitespace byte, then the samples, big-endian when maxval > 255. A
// sample k stands for k / maxval, kept as stored when maxval is 255 or 65535 (8- and 16-bit samples) and given as
// that value correctly rounded to a float for any other maxval; a sample above maxval counts as maxval. A bitmap's
// 1 is black: 0, and its 0 white: 255.
//
// Where this differs from OpenImageIO 2.4's reader (pnm.imageio/pnminput.cpp), which read these files before:
// that reader scaled k to k · (2^b - 1) / maxval in int arithmetic, which truncates (maxval 100: 1 became 2/255)
// and overflows from k = 32769 on (16-bit samples above 32768 came out one lower: 65535 as 65534), and it read
// a plain PBM's "0110" as one sample.
//
// And a PFM file ("Pf" grey, "PF" RGB) as that reader read it, which is the format as Netpbm describes it but for
// the scale: a header of width, height and a nonzero scale whose sign gives the byte order (negative: little-endian),
// then 32-bit float samples, rows from the bottom up. Every sample is multiplied by the scale's magnitude, as
// OpenImageIO does (Netpbm leaves the scale's meaning to the reader; files are written with 1 or -1, where the
// product is the sample itself, but for a signalling NaN, which comes out quiet). A scale of 0, which OpenImageIO
// read as little-endian zeros, is refused.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "codec/native_reader.hpp"
#include "codec/pixel_conversion.hpp"

namespace qdmr::imageio {
namespace {

constexpr std::uint64_t kMaxField = std::uint64_t(1) << 31;  // larger sizes are refused later by every caller

class PnmReader final : public NativeReader {
public:
  ~PnmReader() override {
    if (file_) std::fclose(file_);
  }

  bool open(const std::string& path, ReadSpec& spec, std::string& error) {
    file_ = std::fopen(path.c_str(), "rb");
    if (!file_) {
      error = "cannot open the file";
      return false;
    }
    char magic[2] = {};
    if (std::fread(magic, 1, 2, file_) != 2 || magic[0] != 'P' ||
        !((magic[1] >= '1' && magic[1] <= '6') || magic[1] == 'f' || magic[1] == 'F')) {
      error = "not a PBM, PGM, PPM or PFM file";
      return false;
    }
    floats_ = magic[1] == 'f' || magic[1] == 'F';
    kind_ = floats_ ? 0 : magic[1] - '0';
    const bool bitmap = kind_ == 1 || kind_ == 4;
    std::uint64_t width = 0, height = 0, maxval = floats_ ? 65535 : 1;  // a PFM has no maxval: any in range
    if (!header_field(width) || !header_field(height) || (!bitmap && !floats_ && !header_field(maxval))) {
      error = "PNM header is malformed";
      return false;
    }
    if (floats_ && !scale_field(error)) return false;
    // Exactly one whitespace byte ends the header (read with the last field's end).
    if (!std::isspace(last_)) {
      error = "PNM header is malformed (no whitespace after its last field)";
      return false;
    }
    if (width == 0 || height == 0 || width > kMaxField || height > kMaxField || maxval == 0 || maxval > 65535) {
      error = "PNM header fields out of range (" + std::to_string(width) + "x" + std::to_string(height) +
              ", maxval " + std::to_string(maxval) + ")";
      return false;
    }
    width_ = width;
    height_ = height;
    maxval_ = std::uint32_t(maxval);
    channels_ = kind_ == 3 || kind_ == 6 || magic[1] == 'F' ? 3 : 1;
    stored_ = floats_                        ? PixelType::Float
              : bitmap || maxval_ == 255     ? PixelType::UInt8
              : maxval_ == 65535             ? PixelType::UInt16
                                             : PixelType::Float;
    set_image(spec, int(width_), int(height_), int(channels_), "pnm", stored_);
    return true;
  }

  bool read_pixels(PixelType type, void* first_row, std::ptrdiff_t row_stride, std::string& error) override {
    if (type != stored_ && stored_ == PixelType::Float) {
      error = floats_ ? "a PFM file is read as floats only"
                      : "a PNM file of maxval " + std::to_string(maxval_) + " is read as floats only";
      return false;
    }
    if (floats_) return read_floats(first_row, row_stride, error);
    const std::size_t values = std::size_t(width_) * channels_;
    std::vector<std::uint32_t> samples(values);  // one row's k, clamped to maxval
    const std::size_t stored_size = stored_ == PixelType::UInt8 ? 1 : stored_ == PixelType::UInt16 ? 2 : 4;
    std::vector<unsigned char> row(values * stored_size);
    std::vector<unsigned char> raw;
    for (std::uint64_t y = 0; y < height_; ++y) {
      if (!read_row(samples, raw, error)) {
        if (error.empty())
          error = "truncated PNM pixel data (row " + std::to_string(y) + " of " + std::to_string(height_) + ")";
        return false;
      }
      for (std::size_t i = 0; i < values; ++i) {
        const std::uint32_t k = samples[i];
        if (kind_ == 1 || kind_ == 4) {
          row[i] = k ? 0 : 255;
        } else if (stored_ == PixelType::UInt8) {
          row[i] = std::uint8_t(k);
        } else if (stored_ == PixelType::UInt16) {
          const auto sample = std::uint16_t(k);
          std::memcpy(row.data() + 2 * i, &sample, 2);
        } else {
          const float value = float(k) / float(maxval_);  // both exact in float: one correctly rounded division
          std::memcpy(row.data() + 4 * i, &value, 4);
        }
      }
      void* out = static_cast<char*>(first_row) + row_stride * std::ptrdiff_t(y);
      if (type == stored_)
        std::memcpy(out, row.data(), row.size());
      else
        convert_values(stored_, row.data(), type, out, values);
    }
    return true;
  }

private:
  // A PFM's rows: the file's first row is the image's last.
  bool read_floats(void* first_row, std::ptrdiff_t row_stride, std::string& error) {
    const std::size_t values = std::size_t(width_) * channels_;
    std::vector<unsigned char> raw(values * 4);
    for (std::uint64_t r = 0; r < height_; ++r) {
      if (std::fread(raw.data(), 1, raw.size(), file_) != raw.size()) {
        error = "truncated PFM pixel data (row " + std::to_string(r) + " of " + std::to_string(height_) +
                " from the bottom)";
        return false;
      }
      auto* out = reinterpret_cast<unsigned char*>(first_row) + row_stride * std::ptrdiff_t(height_ - 1 - r);
      for (std::size_t i = 0; i < values; ++i) {
        const unsigned char* b = raw.data() + 4 * i;
        const std::uint32_t bits = little_endian_ ? std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 |
                                                        std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24
                                                  : std::uint32_t(b[3]) | std::uint32_t(b[2]) << 8 |
                                                        std::uint32_t(b[1]) << 16 | std::uint32_t(b[0]) << 24;
        float sample;
        std::memcpy(&sample, &bits, 4);
        const float value = scale_ * sample;
        std::memcpy(out + 4 * i, &value, 4);
      }
    }
    return true;
  }

  // A PFM's scale (leading whitespace and comments skipped, as for the other fields): a decimal number, not 0, whose
  // sign is the byte order; scale_ keeps its magnitude. Reads one byte past it, into last_.
  bool scale_field(std::string& error) {
    skip_separators();
    std::string text;
    for (; last_ != EOF && !std::isspace(last_) && text.size() < 64; next()) text += char(last_);
    const char* first = text.data() + (!text.empty() && text[0] == '+' ? 1 : 0);  // from_chars takes no '+'
    float scale = 0.0f;
    const auto [end, problem] = std::from_chars(first, text.data() + text.size(), scale);
    if (text.empty() || problem != std::errc() || end != text.data() + text.size() || !std::isfinite(scale) ||
        scale == 0.0f) {
      error = "PFM header is malformed (its scale '" + text.substr(0, 24) + "' is not a finite nonzero number)";
      return false;
    }
    little_endian_ = scale < 0.0f;
    scale_ = std::fabs(scale);
    return true;
  }

  // The next byte of the file, or EOF.
  int next() { return last_ = std::getc(file_); }

  // Skips whitespace and comments; the first byte of what follows is in last_ (EOF at the end).
  void skip_separators() {
    next();
    while (last_ != EOF && (std::isspace(last_) || last_ == '#')) {
      if (last_ == '#')
        while (last_ != EOF && last_ != '\n') next();
      else
        next();
    }
  }

  // A decimal field of the header (leading whitespace and comments skipped); false when there is none. Reads one
  // byte past it, into last_.
  bool header_field(std::uint64_t& value) {
    skip_separators();
    if (last_ == EOF || !std::isdigit(last_)) return false;
    value = 0;
    for (; last_ != EOF && std::isdigit(last_); next())
      if (value <= kMaxField) value = value * 10 + std::uint64_t(last_ - '0');
    return true;
  }

  // One row's samples as numbers k (clamped to maxval; a bitmap's bits), from the plain (P1-P3) or binary (P4-P6)
  // encoding. False with `error` set for malformed plain data, false alone when the file ends first.
  bool read_row(std::vector<std::uint32_t>& samples, std::vector<unsigned char>& raw, std::string& error) {
    const std::size_t values = samples.size();
    if (kind_ == 4) {
      raw.resize((width_ + 7) / 8);
      if (std::fread(raw.data(), 1, raw.size(), file_) != raw.size()) return false;
      for (std::size_t i = 0; i < values; ++i) samples[i] = (raw[i / 8] >> (7 - i % 8)) & 1u;
      return true;
    }
    if (kind_ >= 5) {
      const std::size_t bytes = maxval_ > 255 ? 2 : 1;
      raw.resize(values * bytes);
      if (std::fread(raw.data(), 1, raw.size(), file_) != raw.size()) return false;
      for (std::size_t i = 0; i < values; ++i) {
        const std::uint32_t k = bytes == 2 ? std::uint32_t(raw[2 * i]) << 8 | raw[2 * i + 1] : raw[i];
        samples[i] = std::min(k, maxval_);
      }
      return true;
    }
    for (std::size_t i = 0; i < values; ++i) {
      skip_separators();
      if (last_ == EOF) return false;
      if (!std::isdigit(last_)) {
        error = "PNM pixel data is malformed (a byte " + std::to_string(last_) + " where a sample was expected)";
        return false;
      }
      if (kind_ == 1) {  // every 0 or 1 is a pixel of its own, with or without whitespace between them
        samples[i] = last_ == '1' ? 1 : 0;
        if (last_ > '1') {
          error = "PBM pixel data is malformed (a '" + std::string(1, char(last_)) + "' where 0 or 1 was expected)";
          return false;
        }
        continue;
      }
      std::uint64_t k = 0;
      for (; last_ != EOF && std::isdigit(last_); next())
        if (k <= maxval_) k = k * 10 + std::uint64_t(last_ - '0');
      samples[i] = std::uint32_t(std::min<std::uint64_t>(k, maxval_));
      if (last_ != EOF) std::ungetc(last_, file_);  // the separator is read again by the next sample's skip
    }
    return true;
  }

  std::FILE* file_ = nullptr;
  int last_ = 0;  // the byte read last
  int kind_ = 0;  // the N of "PN" (0: a PFM)
  bool floats_ = false, little_endian_ = false;
  float scale_ = 1.0f;  // a PFM's: its magnitude
  std::uint64_t width_ = 0, height_ = 0;
  std::uint32_t maxval_ = 1, channels_ = 1;
  PixelType stored_ = PixelType::UInt8;
};

}  // namespace

std::unique_ptr<NativeReader> open_pnm(const std::string& path, ReadSpec& spec, std::string& error) {
  return opened<PnmReader>(path, spec, error);
}

}  // namespace qdmr::imageio
