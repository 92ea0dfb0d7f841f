#pragma once
// One image file read twice, by OpenImageIO as the backend opens files (oiio:UnassociatedAlpha) and by the native
// readers (codec/native_reader.hpp), and the two compared: size, channels, sample type, metadata and every
// sample's bits. The tests of the PNG, JPEG, TIFF and OpenEXR readers share it.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "codec/native_reader.hpp"

namespace qdmr::test {

struct Decoded {
  int width = 0, height = 0, channels = 0;
  imageio::PixelType type = imageio::PixelType::UInt8;  // of `bytes`
  std::vector<unsigned char> bytes;                      // top row first
  std::string software, bits_version;
};

inline std::size_t size_of(imageio::PixelType type) {
  return type == imageio::PixelType::UInt8 ? 1 : type == imageio::PixelType::UInt16 ? 2 : 4;
}

// OpenImageIO's reading: 8- and 16-bit unsigned samples as stored, any other as floats (as the backend reads
// them); false if it fails or reports an error.
inline bool read_with_oiio(const std::filesystem::path& file, Decoded& out) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(file.string(), &config);
  if (!in) return false;
  const OIIO::ImageSpec& spec = in->spec();
  out.width = spec.width;
  out.height = spec.height;
  out.channels = spec.nchannels;
  out.type = spec.channelformats.empty() && spec.format == OIIO::TypeDesc::UINT8    ? imageio::PixelType::UInt8
             : spec.channelformats.empty() && spec.format == OIIO::TypeDesc::UINT16 ? imageio::PixelType::UInt16
                                                                                    : imageio::PixelType::Float;
  const OIIO::TypeDesc as = out.type == imageio::PixelType::UInt8    ? OIIO::TypeDesc::UINT8
                            : out.type == imageio::PixelType::UInt16 ? OIIO::TypeDesc::UINT16
                                                                     : OIIO::TypeDesc::FLOAT;
  out.software = spec.get_string_attribute("Software");
  out.bits_version = spec.get_string_attribute("qdmr:bits_version");
  out.bytes.resize(spec.image_pixels() * std::size_t(spec.nchannels) * size_of(out.type));
  return in->read_image(0, 0, 0, spec.nchannels, as, out.bytes.data()) && !in->has_error();
}

// The native reader's, as `type` (the file's own by default); false if it does not claim the file, cannot open
// it or fails to read it (`error` then says why, when the reader said).
inline bool read_natively(const std::filesystem::path& file, Decoded& out, std::string& error,
                          const imageio::PixelType* type = nullptr) {
  imageio::ReadSpec spec;
  bool claimed = false;
  const auto reader = imageio::open_native(file.string(), spec, error, claimed);
  if (!claimed || !reader) return false;
  out.width = spec.width;
  out.height = spec.height;
  out.channels = spec.channels;
  out.type = type ? *type : spec.type;
  out.software = spec.software;
  out.bits_version = spec.bits_version;
  const std::size_t row = std::size_t(spec.width) * std::size_t(spec.channels) * size_of(out.type);
  out.bytes.resize(row * std::size_t(spec.height));
  return reader->read(out.type, out.bytes.data(), std::ptrdiff_t(row), error);
}

// Both readings of `file` succeed and agree in every field and every byte.
inline void expect_same_as_oiio(const std::filesystem::path& file) {
  SCOPED_TRACE(file.filename().string());
  Decoded oiio, native;
  std::string error;
  ASSERT_TRUE(read_with_oiio(file, oiio)) << OIIO::geterror();
  ASSERT_TRUE(read_natively(file, native, error)) << error;
  EXPECT_EQ(native.width, oiio.width);
  EXPECT_EQ(native.height, oiio.height);
  EXPECT_EQ(native.channels, oiio.channels);
  EXPECT_EQ(int(native.type), int(oiio.type));
  EXPECT_EQ(native.software, oiio.software);
  EXPECT_EQ(native.bits_version, oiio.bits_version);
  ASSERT_EQ(native.bytes.size(), oiio.bytes.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < native.bytes.size(); ++i) differ += native.bytes[i] != oiio.bytes[i];
  EXPECT_EQ(differ, 0u) << "bytes that differ of " << native.bytes.size();
}

}  // namespace qdmr::test
