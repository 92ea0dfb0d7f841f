#include "qdmr/texture/image.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <memory>
#include <string_view>
#include <utility>
#include <vector>

#include "codec/backend.hpp"
#include "file/input_file.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/limits.hpp"

namespace qdmr {
namespace {

// The formats whose failure modes (truncation, bad headers) are tested: anything else is refused rather than
// decoded by a reader that might return a partial image without an error.
constexpr std::string_view kFormats[] = {"png", "jpeg", "openexr", "tiff", "pnm"};

// Up to `count` bytes from `offset` (negative: from the end) of a regular file already checked.
std::string bytes_of(const std::filesystem::path& file, std::int64_t offset, std::size_t count) {
  std::ifstream in(file, std::ios::binary);
  if (offset < 0)
    in.seekg(offset, std::ios::end);
  else
    in.seekg(offset);
  std::string out(count, '\0');
  in.read(out.data(), std::streamsize(count));
  out.resize(std::size_t(std::max<std::streamsize>(in.gcount(), 0)));
  return out;
}

// PBM/PGM/PPM (and PFM): the header's fields and the pixel data's length, checked before a reader opens the file
// (OpenImageIO's PFM reader stops on a pixel array shorter than the header promises without saying why). Returns
// what is wrong, or "".
std::string check_pnm(const std::filesystem::path& file, std::uint64_t size) {
  const std::string head = bytes_of(file, 0, 4096);
  std::size_t at = 2;
  std::vector<std::uint64_t> fields;
  const char magic = head.size() > 1 ? head[1] : '?';
  const bool bitmap = magic == '1' || magic == '4';
  const bool floats = magic == 'f' || magic == 'F';  // PFM: width, height, then a scale whose sign is the byte order
  const std::size_t wanted = bitmap || floats ? 2 : 3;
  while (fields.size() < wanted) {
    while (at < head.size() && (std::isspace(static_cast<unsigned char>(head[at])) || head[at] == '#')) {
      if (head[at] == '#')
        while (at < head.size() && head[at] != '\n') ++at;
      else
        ++at;
    }
    if (at >= head.size() || !std::isdigit(static_cast<unsigned char>(head[at]))) return "PNM header is malformed";
    std::uint64_t v = 0;
    while (at < head.size() && std::isdigit(static_cast<unsigned char>(head[at])) && v < (1ull << 40))
      v = v * 10 + std::uint64_t(head[at++] - '0');
    fields.push_back(v);
  }
  if (floats) {
    while (at < head.size() && std::isspace(static_cast<unsigned char>(head[at]))) ++at;
    const std::size_t scale = at;
    while (at < head.size() && std::string_view("+-.0123456789eE").find(head[at]) != std::string_view::npos) ++at;
    if (at == scale || at >= head.size() || !std::isspace(static_cast<unsigned char>(head[at])))
      return "PFM header is malformed (no scale)";
    fields.push_back(1);  // stands for the maxval below
  }
  if (fields[0] == 0 || fields[1] == 0) return "PNM size " + std::to_string(fields[0]) + "x" + std::to_string(fields[1]) + " is empty";
  if (!bitmap && (fields[2] == 0 || fields[2] > 65535))
    return "PNM maxval " + std::to_string(fields[2]) + " is outside 1..65535";
  if (fields[0] > std::uint64_t(limits::kMaxTextureSide) || fields[1] > std::uint64_t(limits::kMaxTextureSide))
    return "size " + std::to_string(fields[0]) + "x" + std::to_string(fields[1]) + " is outside 1.." +
           std::to_string(limits::kMaxTextureSide);
  // Plain (ASCII) variants: every value takes a byte at least, and in PGM/PPM a separator too (PBM's bits need
  // none). OpenImageIO allocates the whole image before it finds them missing, and says nothing when it does.
  if (magic == '1' || magic == '2' || magic == '3') {
    const std::uint64_t values = fields[0] * fields[1] * (magic == '3' ? 3 : 1);
    const std::uint64_t least = magic == '1' ? values : 2 * values - 1;
    const std::uint64_t room = size > at ? size - at : 0;
    if (room < least)
      return "truncated: the header promises " + std::to_string(values) + " values, which take " +
             std::to_string(least) + " bytes at least, the file has " + std::to_string(room);
  }
  // Binary variants: exactly one whitespace byte after the header, then the pixels.
  if (magic == '4' || magic == '5' || magic == '6' || floats) {
    const std::uint64_t channels = magic == '6' || magic == 'F' ? 3 : 1;
    const std::uint64_t sample = floats ? 4 : bitmap || fields[2] <= 255 ? 1 : 2;  // a bitmap has no maxval
    const std::uint64_t bytes = magic == '4' ? (fields[0] + 7) / 8 * fields[1] : fields[0] * fields[1] * channels * sample;
    if (size < at + 1 + bytes)
      return "truncated: the header promises " + std::to_string(bytes) + " bytes of pixels, the file has " +
             std::to_string(size > at + 1 ? size - at - 1 : 0);
  }
  return "";
}

// A name read from a damaged file, fit for a one-line message: bytes outside printable ASCII as \xHH, at most 40
// of them shown.
std::string shown(std::string_view name) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (std::size_t i = 0; i < name.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(name[i]);
    if (c >= 0x20 && c < 0x7F && c != '\\') {
      out += char(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return name.size() > 40 ? out + "..." : out;
}

// The bytes of an OpenEXR attribute type whose value OpenEXR 3.1 reads at a fixed size, whatever size the file
// declares; -1 for the others (strings, vectors, previews and unknown types are read at the declared size, a
// channel list up to its terminating empty name).
std::int64_t exr_fixed_size(std::string_view type) {
  static constexpr std::pair<std::string_view, std::int64_t> kSizes[] = {
      {"box2i", 16},   {"box2f", 16},    {"chromaticities", 32}, {"compression", 1}, {"deepImageState", 1},
      {"double", 8},   {"envmap", 1},    {"float", 4},           {"int", 4},         {"keycode", 28},
      {"lineOrder", 1}, {"m33d", 72},    {"m33f", 36},           {"m44d", 128},      {"m44f", 64},
      {"rational", 8}, {"tiledesc", 9},  {"timecode", 8},        {"v2d", 16},        {"v2f", 8},
      {"v2i", 8},      {"v3d", 24},      {"v3f", 12},            {"v3i", 12}};
  for (const auto& [name, bytes] : kSizes)
    if (name == type) return bytes;
  return -1;
}

// OpenEXR: OpenEXR allocates each header attribute's value at the size the file declares before reading it
// (a 64 KiB file can claim a 2 GB string), and the tables of a part from its data window. So the headers are
// walked here first, without allocating: every attribute's value must fit in the file, and the first part's
// data window (the image qdmr reads) must be within the size limit. OpenEXR 3.1 does not check that a value it
// reads by its type (a box, a number, a channel list) takes the bytes the file declares for it, and reads the next
// attribute from wherever that value ended: a channel list longer than declared made it read a string's bytes as
// a 1.9 GB length. So those values must take exactly the declared bytes. Returns what is wrong, or "" (also when
// the walk meets what it does not know, a name longer than OpenEXR's 255 bytes: left to OpenEXR's own checks).
std::string check_exr(const std::filesystem::path& file, std::uint64_t size) {
  std::ifstream in(file, std::ios::binary);
  const auto le32 = [](const unsigned char* b) {
    return std::int32_t(std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24);
  };
  unsigned char head[8];
  if (!in.read(reinterpret_cast<char*>(head), 8)) return "truncated OpenEXR header";
  const bool multipart = (le32(head + 4) & 0x1000) != 0;
  std::uint64_t at = 8;
  // A null-terminated string of at most 255 bytes; false at the end of the file or when longer. Read in bulk
  // (istream::get stops before the null), and attribute values skipped through the stream's buffer: a seekg per
  // attribute cost an lseek and a refill of the buffer: with names read a byte at a time, a third of fuzz_image's
  // time on headers of many small attributes.
  const auto text = [&](std::string& out, bool& truncated) {
    char buffer[257];
    in.get(buffer, sizeof buffer, '\0');
    const auto got = std::size_t(in.gcount());
    if (in.eof()) {
      truncated = true;
      return false;
    }
    if (got > 255) return false;
    in.clear();  // get() sets failbit when the null comes first
    char null;
    if (!in.get(null)) {
      truncated = true;
      return false;
    }
    at += got + 1;
    out.assign(buffer, got);
    return true;
  };
  const auto skip = [&](std::uint64_t bytes) {
    if (bytes <= (std::uint64_t(1) << 16))
      in.ignore(std::streamsize(bytes));
    else
      in.seekg(std::streamoff(bytes), std::ios::cur);
  };
  for (int part = 0;; ++part) {
    for (bool first = true;; first = false) {
      std::string name, type;
      bool truncated = false;
      if (!text(name, truncated)) return truncated ? "truncated OpenEXR header" : "";
      if (name.empty()) {
        if (!multipart || (first && part > 0)) return "";  // the end of the header (or of the list of headers)
        break;                                               // the end of this part's header
      }
      if (!text(type, truncated)) return truncated ? "truncated OpenEXR header" : "";
      unsigned char field[4];
      if (!in.read(reinterpret_cast<char*>(field), 4)) return "truncated OpenEXR header";
      at += 4;
      const std::int32_t bytes = le32(field);
      const auto attribute = [&] { return "damaged OpenEXR header: attribute '" + shown(name) + "' "; };
      if (bytes < 0 || at + std::uint64_t(bytes) > size)
        return attribute() + "claims " + std::to_string(bytes) + " bytes, the file has " + std::to_string(size - at) +
               " left";
      if (const std::int64_t fixed = exr_fixed_size(type); fixed >= 0 && bytes != fixed)
        return attribute() + "of type " + shown(type) + " claims " + std::to_string(bytes) + " bytes, the type has " +
               std::to_string(fixed);
      if (type == "chlist") {
        // Channels until an empty name: each a name, then pixel type, linear flag, 3 reserved bytes, x and y
        // sampling (16 bytes).
        const std::uint64_t end = at + std::uint64_t(bytes);
        std::string channel;
        for (bool truncated = false;;) {
          if (!text(channel, truncated)) return truncated ? "truncated OpenEXR header" : "";
          if (channel.empty() || at > end) break;
          skip(16);
          at += 16;
        }
        if (at != end)
          return attribute() + "holds a channel list of " + std::to_string(at - (end - std::uint64_t(bytes))) +
                 " bytes, it claims " + std::to_string(bytes);
        continue;
      }
      if (part == 0 && name == "dataWindow" && type == "box2i") {
        unsigned char box[16];
        if (!in.read(reinterpret_cast<char*>(box), 16)) return "truncated OpenEXR header";
        const std::int64_t width = std::int64_t(le32(box + 8)) - le32(box) + 1;
        const std::int64_t height = std::int64_t(le32(box + 12)) - le32(box + 4) + 1;
        if (width < 1 || height < 1 || width > limits::kMaxTextureSide || height > limits::kMaxTextureSide)
          return "size " + std::to_string(width) + "x" + std::to_string(height) + " is outside 1.." +
                 std::to_string(limits::kMaxTextureSide);
      } else {
        skip(std::uint64_t(bytes));
      }
      at += std::uint64_t(bytes);
    }
  }
}

// PNG: libpng allocates and clears a buffer of each chunk's declared length (up to 8 MB) before it reads the
// chunk's data. The chunks are walked here first, without reading their data: each (length, type, data, CRC)
// must fit in the file, and the walk must reach IEND, so the decoder never reads past the end of the file
// (and the whole chunk is there to check). Returns what is wrong, or "".
std::string check_png_chunks(const std::filesystem::path& file, std::uint64_t size) {
  const std::string no_end = "truncated PNG (it does not end with an IEND chunk)";
  std::ifstream in(file, std::ios::binary);
  std::uint64_t at = 8;  // after the signature
  unsigned char head[8];
  while (at + 8 <= size) {
    in.seekg(std::streamoff(at));
    if (!in.read(reinterpret_cast<char*>(head), 8)) return no_end;
    const std::uint64_t length =
        std::uint64_t(head[0]) << 24 | std::uint64_t(head[1]) << 16 | std::uint64_t(head[2]) << 8 | head[3];
    if (length > 0x7FFFFFFF || at + 12 + length > size)
      return "truncated PNG (the chunk at byte " + std::to_string(at) + " claims " + std::to_string(length) +
             " bytes, the file has " + std::to_string(size - at) + " from there)";
    if (std::memcmp(head + 4, "IEND", 4) == 0) return "";
    at += 12 + length;
  }
  return no_end;  // what is left is shorter than a chunk header
}

// OIIO may report several lines (e.g. "Read error: hit end of file\nPNG read error: ..."): an error is one line,
// with the first three of them (a TIFF decoder missing its data reports once per row: 30 KB for 256 rows).
Error read_error(const std::string& where, const std::filesystem::path& file, std::string message) {
  while (!message.empty() && message.back() == '\n') message.pop_back();
  std::size_t lines = 1;
  for (std::size_t at; (at = message.find('\n')) != std::string::npos; ++lines) {
    if (lines == 3) {
      const auto more = std::count(message.begin() + std::ptrdiff_t(at), message.end(), '\n');
      message.replace(at, std::string::npos, "; and " + std::to_string(more) + " more decoder messages");
      break;
    }
    message.replace(at, 1, "; ");
  }
  if (message.empty()) message = "the decoder stopped without saying why (damaged or missing pixel data)";
  return FileError(where, "cannot read '" + shown_path(file) + "': " + message);
}

// The file checked before it is opened (kind, size, an OpenEXR header, PNG chunks, PNM fields): its size.
std::uint64_t check_file(const std::filesystem::path& file, const std::string& where) {
  const auto fail = [&](const std::string& message) { return read_error(where, file, message); };
  const std::uint64_t size = check_input_file(file, where, InputKind::Image);
  // OpenImageIO gives a file to OpenEXR by its magic number whatever its extension.
  if (bytes_of(file, 0, 4) == "\x76\x2F\x31\x01")
    if (const std::string problem = check_exr(file, size); !problem.empty()) throw fail(problem);
  if (bytes_of(file, 0, 8) == "\x89PNG\r\n\x1A\n")
    if (const std::string problem = check_png_chunks(file, size); !problem.empty()) throw fail(problem);
  // PBM, PGM, PPM and PFM: the header's fields and the pixel data's length.
  if (const std::string magic = bytes_of(file, 0, 2);
      magic.size() == 2 && magic[0] == 'P' && std::string_view("123456fF").find(magic[1]) != std::string_view::npos)
    if (const std::string problem = check_pnm(file, size); !problem.empty()) throw fail(problem);
  return size;
}

// The header of the file (of `size` bytes) checked: format, size, channels, a JPEG's end marker, a PNG's IEND.
void check_header(const std::filesystem::path& file, const std::string& where, std::uint64_t size,
                  const imageio::ReadSpec& spec) {
  const auto fail = [&](const std::string& message) { return read_error(where, file, message); };
  const std::string& format = spec.format;
  if (std::find(std::begin(kFormats), std::end(kFormats), format) == std::end(kFormats))
    throw fail("unsupported image format '" + format + "' (textures are PNG, JPEG, OpenEXR, TIFF or PGM/PPM)");
  // A JPEG ends with the EOI marker FF D9 (which cannot occur inside entropy-coded data); libjpeg pads a
  // truncated file with grey and only warns.
  if (format == "jpeg" && bytes_of(file, -std::int64_t(std::min<std::uint64_t>(size, 64)), 64).find("\xFF\xD9") ==
                              std::string::npos)
    throw fail("truncated JPEG (no end-of-image marker)");
  // A PNG ends with its IEND chunk (length 0, "IEND", its CRC): checked here so a truncated map is refused even
  // when no pixel of it is ever decoded.
  if (format == "png" && bytes_of(file, -std::int64_t(std::min<std::uint64_t>(size, 12)), 12) !=
                             std::string("\0\0\0\0IEND\xAE\x42\x60\x82", 12))
    throw fail("truncated PNG (it does not end with an IEND chunk)");
  if (spec.width <= 0 || spec.height <= 0 || spec.width > limits::kMaxTextureSide ||
      spec.height > limits::kMaxTextureSide)
    throw fail("size " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + " is outside 1.." +
               std::to_string(limits::kMaxTextureSide));
  if (spec.depth > 1) throw fail("volume images are not supported");
  if (spec.channels < 1 || spec.channels > 4)
    throw fail(std::to_string(spec.channels) + " channels (textures take 1 to 4)");
}

// The file checked, opened, and its header checked: nothing decoded yet.
std::unique_ptr<imageio::ReadFile> open_checked(const std::filesystem::path& file, const std::string& where) {
  const std::uint64_t size = check_file(file, where);
  std::string error;
  auto in = std::make_unique<imageio::ReadFile>(file.string(), error);
  if (!*in) throw read_error(where, file, error);
  check_header(file, where, size, in->spec());
  return in;
}

int source_bits(const imageio::ReadSpec& spec) {
  return spec.uniform && spec.type == imageio::PixelType::UInt8 ? 8 : spec.uniform && spec.type == imageio::PixelType::UInt16 ? 16 : 32;
}

}  // namespace

ImageHeader read_image_header(const std::filesystem::path& file, const std::string& where) {
  const std::uint64_t size = check_file(file, where);
  // The header alone, which a TIFF that OpenImageIO converts gives without the image module.
  imageio::ReadSpec spec;
  std::string error;
  if (!imageio::read_header(file.string(), spec, error)) throw read_error(where, file, error);
  check_header(file, where, size, spec);
  return {spec.width, spec.height, spec.channels, source_bits(spec)};
}

std::uint64_t read_image_bytes(const ImageHeader& header) {
  const std::uint64_t values = std::uint64_t(header.width) * std::uint64_t(header.height) * std::uint64_t(header.channels);
  return values * sizeof(float) + values * std::uint64_t(header.source_bits / 8);
}

Image read_image(const std::filesystem::path& file, const std::string& where) {
  const auto fail = [&](const std::string& message) { return read_error(where, file, message); };
  const auto in = open_checked(file, where);
  const imageio::ReadSpec& spec = in->spec();
  Image image(spec.width, spec.height, spec.channels);
  // Rows are stored bottom-up: the file's last row becomes row 0 (v = 0), the OpenGL/OBJ convention, so
  // UVs from OBJ files and +Y-up (GL) normal maps need no flipping.
  const auto read = [&](imageio::PixelType type, std::size_t type_size, void* data) {
    const std::ptrdiff_t row = std::ptrdiff_t(type_size) * spec.channels * spec.width;
    char* last_row = static_cast<char*>(data) + row * (spec.height - 1);
    // A decoder that reports an error but returns true (a warning about damaged data) fails too.
    std::string error;
    if (!in->read(type, last_row, -row, error)) throw fail(error);
  };
  // 8- and 16-bit integers are converted here as k / (2^bits - 1), correctly rounded, so values are exact
  // (OIIO multiplies by a rounded reciprocal). They are read into the front of the float buffer and widened from
  // the back, so no second buffer is held: float i (bytes 4i..4i+3) only overwrites integers i and above, which
  // are widened already.
  const auto convert = [&](auto integer, float max) {
    using Integer = decltype(integer);
    unsigned char* const bytes = reinterpret_cast<unsigned char*>(image.texels.data());
    read(sizeof(Integer) == 1 ? imageio::PixelType::UInt8 : imageio::PixelType::UInt16, sizeof(Integer), bytes);
    for (std::size_t i = image.texels.size(); i-- > 0;) {
      Integer k;
      std::memcpy(&k, bytes + i * sizeof(Integer), sizeof(Integer));
      image.texels[i] = float(k) / max;
    }
  };
  const int bits = source_bits(spec);
  if (bits == 8) {
    convert(std::uint8_t{}, 255.0f);
    image.source_bits = 8;
  } else if (bits == 16) {
    convert(std::uint16_t{}, 65535.0f);
    image.source_bits = 16;
  }
  else
    read(imageio::PixelType::Float, sizeof(float), image.texels.data());
  return image;
}

}  // namespace qdmr
