// codec/jpeg_segments.hpp: a JPEG's metadata segments never reach OpenImageIO's metadata decoders (its IPTC
// decoder read past a damaged Photoshop segment: found by fuzz_image, tests/bad_inputs has the file), and the
// pixels do not depend on them; damaged segments before the first scan are refused with what is wrong.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "codec/jpeg_segments.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/texture/image.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;
using Bytes = std::string;

Bytes read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const fs::path& file, const Bytes& bytes) {
  std::ofstream out(file, std::ios::binary);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

// A segment: FF, the marker, the big-endian length (2 + payload), the payload.
Bytes segment(int marker, const Bytes& payload) {
  const std::size_t length = payload.size() + 2;
  return Bytes{char(0xFF), char(marker), char(length >> 8), char(length & 0xFF)} + payload;
}

// A 24x16 RGB JPEG with a gradient, as OpenImageIO writes it.
Bytes gradient_jpeg(const fs::path& file) {
  std::vector<unsigned char> pixels(24 * 16 * 3);
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<unsigned char>((i * 7) % 251);
  auto out = OIIO::ImageOutput::create(file.string());
  EXPECT_TRUE(out && out->open(file.string(), OIIO::ImageSpec(24, 16, 3, OIIO::TypeDesc::UINT8)) &&
              out->write_image(OIIO::TypeDesc::UINT8, pixels.data()) && out->close());
  return read_bytes(file);
}

// Photoshop's APP13 with an IPTC record (1C 02 ...) whose length runs far past the segment, as fuzz_image's.
Bytes damaged_iptc_segment() {
  const Bytes iptc = Bytes("\x1C\x02\x78\x7F\xF0", 5) + "caption";
  const Bytes resource = Bytes("8BIM\x04\x04\0\0", 8) + Bytes{0, 0, 0, char(iptc.size())} + iptc;
  return segment(0xED, Bytes("Photoshop 3.0", 14) + resource);
}

std::string jpeg_error_of(const fs::path& file) {
  std::vector<unsigned char> stripped;
  std::string error;
  EXPECT_FALSE(imageio::jpeg_without_metadata(file.string(), stripped, error));
  return error;
}

TEST(JpegSegments, MetadataSegmentsAreDroppedAndThePixelsStayTheSame) {
  TempDir dir;
  const Bytes plain = gradient_jpeg(dir / "plain.jpg");
  ASSERT_GT(plain.size(), 2u);
  // After SOI: a damaged IPTC segment, Exif and ICC-like APP1 / APP2 payloads, a comment, APP15.
  const Bytes metadata = damaged_iptc_segment() + segment(0xE1, Bytes("Exif\0\0MM\0*", 10) + Bytes(40, '\xFF')) +
                         segment(0xE2, "ICC_PROFILE") + segment(0xFE, "a comment") + segment(0xEF, "x");
  const Bytes with_metadata = plain.substr(0, 2) + metadata + plain.substr(2);
  write_bytes(dir / "with_metadata.jpg", with_metadata);

  std::vector<unsigned char> stripped_plain, stripped;
  std::string error;
  ASSERT_TRUE(imageio::jpeg_without_metadata((dir / "plain.jpg").string(), stripped_plain, error)) << error;
  ASSERT_TRUE(imageio::jpeg_without_metadata((dir / "with_metadata.jpg").string(), stripped, error)) << error;
  // OpenImageIO's own file may carry metadata of its own: either way both strip to the same bytes.
  const Bytes expected = stripped_plain.empty() ? plain : Bytes(stripped_plain.begin(), stripped_plain.end());
  EXPECT_EQ(Bytes(stripped.begin(), stripped.end()), expected);

  const Image a = read_image(dir / "plain.jpg", "test");
  const Image b = read_image(dir / "with_metadata.jpg", "test");
  ASSERT_EQ(a.width, 24);
  ASSERT_EQ(b.width, 24);
  EXPECT_EQ(a.texels, b.texels);
}

// A photo's Exif orientation (here 6: "rotate 90 degrees clockwise to display") is not applied: the texels are
// the stored ones, as OpenImageIO's read_image gives them (it reports the tag, and leaves the pixels as stored)
// and as GPU texture loaders take them.
TEST(JpegSegments, ExifOrientationIsNotApplied) {
  TempDir dir;
  const Bytes plain = gradient_jpeg(dir / "plain.jpg");
  // Exif: a big-endian TIFF header, IFD0 with one entry, Orientation (0x0112), SHORT, 1 value: 6.
  const Bytes exif = Bytes("Exif\0\0MM\0*\0\0\0\x08", 14) + Bytes("\0\x01", 2) +
                     Bytes("\x01\x12\0\x03\0\0\0\x01\0\x06\0\0", 12) + Bytes(4, '\0');
  write_bytes(dir / "rotated.jpg", plain.substr(0, 2) + segment(0xE1, exif) + plain.substr(2));
  auto in = OIIO::ImageInput::open((dir / "rotated.jpg").string());
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().get_int_attribute("Orientation"), 6);  // the file does carry the tag
  EXPECT_EQ(in->spec().width, 24);
  const Image a = read_image(dir / "plain.jpg", "test");
  const Image b = read_image(dir / "rotated.jpg", "test");
  EXPECT_EQ(b.width, 24);
  EXPECT_EQ(b.height, 16);
  EXPECT_EQ(a.texels, b.texels);
}

TEST(JpegSegments, DamagedSegmentsBeforeTheFirstScanAreRefusedWithWhatIsWrong) {
  TempDir dir;
  const Bytes plain = gradient_jpeg(dir / "plain.jpg");
  const auto refused = [&](const std::string& name, const Bytes& bytes) {
    write_bytes(dir / name, bytes);
    return jpeg_error_of(dir / name);
  };
  EXPECT_NE(refused("soi.jpg", plain.substr(0, 2)).find("truncated JPEG (it ends at byte 2"), std::string::npos);
  EXPECT_NE(refused("stuffed.jpg", plain.substr(0, 2) + Bytes("\xFF\x00", 2) + plain.substr(2)).find("byte 2 is not a marker"),
            std::string::npos);
  EXPECT_NE(refused("text.jpg", plain.substr(0, 2) + "text" + plain.substr(2)).find("byte 2 is not a marker"),
            std::string::npos);
  const Bytes past_end = plain.substr(0, 2) + Bytes("\xFF\xED\x7F\xFF", 4) + "Photoshop 3.0";
  EXPECT_NE(refused("past_end.jpg", past_end).find("the FFED segment at byte 2 claims 32767 bytes after its marker, the file has 15)"),
            std::string::npos)
      << jpeg_error_of(dir / "past_end.jpg");
  const Bytes short_length = plain.substr(0, 2) + Bytes("\xFF\xE1\x00\x01", 4) + plain.substr(2);
  EXPECT_NE(refused("short.jpg", short_length).find("declares 1 bytes"), std::string::npos);
  // A file that does not start with SOI is left to the decoder, which refuses it before reading any segment.
  write_bytes(dir / "png.jpg", "\x89PNG\r\n\x1A\n");
  std::vector<unsigned char> stripped;
  std::string error;
  EXPECT_TRUE(imageio::jpeg_without_metadata((dir / "png.jpg").string(), stripped, error)) << error;
  EXPECT_TRUE(stripped.empty());
  // Through read_image: one line naming the file and what is wrong.
  try {
    read_image(dir / "past_end.jpg", "test");
    ADD_FAILURE() << "read a damaged JPEG";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("past_end.jpg': truncated JPEG (the FFED segment"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace qdmr::test
