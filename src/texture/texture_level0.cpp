// Level-0 images of a layer's texture slots.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <utility>
#include <cmath>
#include <optional>
#include <vector>

#include "qdmr/core/error.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "texture/internal.hpp"

namespace qdmr {
namespace {

template <class F>
void for_rows(int height, F&& row) {
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& r) {
    for (int y = r.begin(); y != r.end(); ++y) row(y);
  });
}

const char* channel_name(Channel c) {
  switch (c) {
    case Channel::Default: return "default";
    case Channel::R: return "r";
    case Channel::G: return "g";
    case Channel::B: return "b";
    case Channel::A: return "a";
    case Channel::RGB: return "rgb";
    case Channel::RGBA: return "rgba";
  }
  return "?";
}

// Source channel of each output channel (`count` = 1 or 3) for a selection; single channels are replicated.
std::vector<int> select_channels(const Image& image, Channel channel, int count, const TextureDesc& desc,
                                 const std::string& where) {
  const auto fail = [&](const std::string& what) {
    return Error(where, "'" + desc.file.string() + "' has " + std::to_string(image.channels) + " channel(s): " + what);
  };
  int single = -1;
  switch (channel) {
    case Channel::Default:
      if (count == 3 && image.channels >= 3) return {0, 1, 2};
      single = 0;
      break;
    case Channel::R: single = 0; break;
    case Channel::G: single = 1; break;
    case Channel::B: single = 2; break;
    case Channel::A: single = 3; break;
    case Channel::RGB:
      if (count != 3) throw fail("channel 'rgb' selects 3 channels, this texture takes 1");
      if (image.channels < 3) throw fail("channel 'rgb' needs 3");
      return {0, 1, 2};
    case Channel::RGBA: throw fail("channel 'rgba' selects 4 channels, this texture takes " + std::to_string(count));
  }
  if (single >= image.channels) throw fail(std::string("channel '") + channel_name(channel) + "' does not exist");
  return std::vector<int>(std::size_t(count), single);
}

// `src` with the channels listed, in that order. Taken by value and freed on return, so the file image and the
// picked one are not both held after it; a selection of all channels in order returns `src` itself.
Image pick(Image src, const std::vector<int>& channels) {
  bool identity = int(channels.size()) == src.channels;
  for (std::size_t c = 0; c < channels.size(); ++c) identity = identity && channels[c] == int(c);
  if (identity) return src;
  Image out(src.width, src.height, int(channels.size()));
  out.source_bits = src.source_bits;
  for_rows(src.height, [&](int y) {
    for (int x = 0; x < src.width; ++x)
      for (int c = 0; c < out.channels; ++c) out.at(x, y, c) = src.at(x, y, channels[std::size_t(c)]);
  });
  return out;
}

Image constant(std::initializer_list<float> values) {
  Image out(1, 1, int(values.size()));
  std::copy(values.begin(), values.end(), out.texels.begin());
  return out;
}

// Unit vector of (x, y, z); a zero or non-finite vector becomes (0, 0, 1).
void normalise(float& x, float& y, float& z) {
  const double len2 = double(x) * x + double(y) * y + double(z) * z;
  if (!(len2 > 0.0) || !std::isfinite(len2)) {
    x = 0.0f, y = 0.0f, z = 1.0f;
    return;
  }
  const double inv = 1.0 / std::sqrt(len2);
  x = float(x * inv), y = float(y * inv), z = float(z * inv);
}

void apply_height_transform(Image& image, const LayerDesc& layer) {
  for_rows(image.height, [&](int y) {
    for (int x = 0; x < image.width; ++x) {
      float& h = image.at(x, y, 0);
      h = std::clamp(h * layer.height_scale + layer.height_offset, 0.0f, 1.0f);
    }
  });
}

Image albedo_texture(const TextureDesc& desc, const std::string& where) {
  switch (desc.source) {
    case TextureSource::None: return constant({1.0f, 1.0f, 1.0f});
    case TextureSource::Constant: return constant({desc.constant.r, desc.constant.g, desc.constant.b});
    case TextureSource::File: {
      Image file = read_image(desc.file, where);
      const std::vector<int> channels = select_channels(file, desc.channel, 3, desc, where);
      Image rgb = pick(std::move(file), channels);
      if (desc.srgb) {
        // 8-bit values (k / 255 exactly, as read_image gives them) from the samplers' table; the same results, faster.
        const std::array<float, 256>& table = texture_detail::kSrgbByteToLinear;
        for_rows(rgb.height, [&](int y) {
          float* row = &rgb.at(0, y, 0);
          for (int i = 0; i < rgb.width * 3; ++i) {
            const float k = std::floor(row[i] * 255.0f + 0.5f);
            const bool in_table = k >= 0.0f && k <= 255.0f && k / 255.0f == row[i];
            row[i] = in_table ? table[std::size_t(k)] : texture_detail::srgb_to_linear(row[i]);
          }
        });
      }
      if (desc.factor != glm::vec3(1.0f))
        for_rows(rgb.height, [&](int y) {
          float* row = &rgb.at(0, y, 0);
          for (int i = 0; i < rgb.width * 3; ++i) row[i] *= desc.factor[i % 3];
        });
      return rgb;
    }
    case TextureSource::Procedural: {
      // lerp(color_low, color_high, h) times a brightness jitter per pattern cell.
      const Image pattern = texture_detail::generate_pattern(desc.procedural, true);
      Image rgb(pattern.width, pattern.height, 3);
      for_rows(rgb.height, [&](int y) {
        for (int x = 0; x < rgb.width; ++x) {
          const float h = pattern.at(x, y, 0);
          const float jitter = 1.0f + desc.variation * (pattern.at(x, y, 1) - 0.5f);
          for (int c = 0; c < 3; ++c) {
            const float colour = desc.color_low[c] + (desc.color_high[c] - desc.color_low[c]) * h;
            rgb.at(x, y, c) = std::max(0.0f, colour * jitter);
          }
        }
      });
      return rgb;
    }
    case TextureSource::FromHeight:
    case TextureSource::Pixels: break;
  }
  throw Error(where, "an albedo texture cannot be 'from_height' or handed-over heights");
}

// Normals of the surface z = h * kFromHeightDepth * strength (UV units), by central differences with wrap.
Image normals_from_height(const Image& height, float strength) {
  const int w = height.width, h = height.height;
  Image out(w, h, 3);
  const double kx = strength * texture_detail::kFromHeightDepth * w * 0.5;
  const double ky = strength * texture_detail::kFromHeightDepth * h * 0.5;
  for_rows(h, [&](int y) {
    const int up = (y + h - 1) % h, down = (y + 1) % h;
    for (int x = 0; x < w; ++x) {
      const int left = (x + w - 1) % w, right = (x + 1) % w;
      float nx = float(-kx * (double(height.at(right, y, 0)) - height.at(left, y, 0)));
      float ny = float(-ky * (double(height.at(x, down, 0)) - height.at(x, up, 0)));
      float nz = 1.0f;
      normalise(nx, ny, nz);
      out.at(x, y, 0) = nx, out.at(x, y, 1) = ny, out.at(x, y, 2) = nz;
    }
  });
  return out;
}

Image normal_texture(const TextureDesc& desc, const LayerDesc& layer, const Image* height, const std::string& where) {
  const float flip = layer.normal_convention == NormalConvention::DX ? -1.0f : 1.0f;
  const float strength = layer.normal_strength;
  switch (desc.source) {
    case TextureSource::None: return constant({0.0f, 0.0f, 1.0f});
    case TextureSource::Constant: {
      float x = desc.constant.x * strength, y = desc.constant.y * strength, z = desc.constant.z;
      normalise(x, y, z);
      return constant({x, y, z});
    }
    case TextureSource::File: {
      Image file = read_image(desc.file, where);
      if (desc.channel != Channel::Default && desc.channel != Channel::RGB)
        throw Error(where, std::string("a normal map takes channels 'rgb', not '") + channel_name(desc.channel) + "'");
      if (file.channels < 3)
        throw Error(where, "'" + desc.file.string() + "' has " + std::to_string(file.channels) +
                               " channel(s); a normal map needs 3");
      // Decoded in place: the file's RGB texels become the normals.
      Image out = pick(std::move(file), {0, 1, 2});
      for_rows(out.height, [&](int y) {
        for (int x = 0; x < out.width; ++x) {
          float nx = (2.0f * out.at(x, y, 0) - 1.0f) * strength;
          float ny = (2.0f * out.at(x, y, 1) - 1.0f) * strength * flip;
          float nz = 2.0f * out.at(x, y, 2) - 1.0f;
          normalise(nx, ny, nz);
          out.at(x, y, 0) = nx, out.at(x, y, 1) = ny, out.at(x, y, 2) = nz;
        }
      });
      return out;
    }
    case TextureSource::FromHeight:
      if (!height) throw Error(where, "a 'from_height' normal map needs the layer's height");
      return normals_from_height(*height, strength);
    case TextureSource::Procedural:
    case TextureSource::Pixels: break;
  }
  throw Error(where, "a normal map cannot be procedural; use 'from_height' with a procedural height");
}

Image height_texture(const TextureDesc& desc, const LayerDesc& layer, const std::string& where) {
  Image out;
  switch (desc.source) {
    case TextureSource::None: return constant({1.0f});  // flat at the top, whatever the scale and offset
    case TextureSource::Constant:
      out = constant({desc.constant.x});
      out.source_bits = 8;
      break;
    case TextureSource::File: {
      Image file = read_image(desc.file, where);
      const std::vector<int> channels = select_channels(file, desc.channel, 1, desc, where);
      out = pick(std::move(file), channels);
      break;
    }
    case TextureSource::Procedural:
      out = generate_procedural(desc.procedural);
      out.source_bits = 16;  // stored as R16 unless the scene asks otherwise
      break;
    case TextureSource::Pixels: {
      const Image& pixels = *desc.pixels;
      out = Image(pixels.width, pixels.height, 1);
      for (std::size_t i = 0; i < out.texels.size(); ++i) out.texels[i] = pixels.texels[i * std::size_t(pixels.channels)];
      out.source_bits = pixels.source_bits;
      break;
    }
    case TextureSource::FromHeight: throw Error(where, "a height texture cannot be 'from_height'");
  }
  apply_height_transform(out, layer);
  return out;
}

// The occlusion channel of a layer: 1 channel, its file's selected channel (default R) or its constant.
Image occlusion_texture(const TextureDesc& desc, const std::string& where) {
  if (desc.source == TextureSource::Constant) return constant({desc.constant.x});
  Image file = read_image(desc.file, where);
  const std::vector<int> channels = select_channels(file, desc.channel, 1, desc, where);
  return pick(std::move(file), channels);
}

std::string size_text(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

// The error of an occlusion file whose size is not the orm texture's (the plan reads the headers, prepare the pixels).
Error occlusion_size_error(const std::string& where, const LayerDesc& layer, int width, int height, int orm_width,
                           int orm_height) {
  return Error(where, "'" + layer.occlusion.file.string() + "' is " + size_text(width, height) + ", the layer's orm " +
                          size_text(orm_width, orm_height) + ": they must be the same size");
}

// RGB of the orm texture (none: 1, 1, 1) with R from the occlusion texture when the layer has one.
Image orm_texture(const LayerDesc& layer, const std::string& where) {
  const TextureDesc& desc = layer.orm;
  Image rgb;
  switch (desc.source) {
    case TextureSource::None: rgb = constant({1.0f, 1.0f, 1.0f}); break;
    case TextureSource::Constant: rgb = constant({desc.constant.r, desc.constant.g, desc.constant.b}); break;
    case TextureSource::File: {
      Image file = read_image(desc.file, where + "/orm");
      if (file.channels < 3)
        throw Error(where + "/orm", "'" + desc.file.string() + "' has " + std::to_string(file.channels) +
                                        " channel(s); an orm texture needs 3 (occlusion, roughness, metalness)");
      rgb = pick(std::move(file), {0, 1, 2});
      break;
    }
    default: throw Error(where + "/orm", "an orm texture is a file or a constant");
  }
  if (layer.occlusion.source == TextureSource::None) return rgb;
  const Image occlusion = occlusion_texture(layer.occlusion, where + "/occlusion");
  if (rgb.width == 1 && rgb.height == 1 && desc.source != TextureSource::File) {
    // A constant orm takes the occlusion's size.
    Image out(occlusion.width, occlusion.height, 3);
    for (std::size_t i = 0; i < out.texels.size(); ++i) out.texels[i] = rgb.texels[i % 3];
    rgb = std::move(out);
  }
  if (occlusion.width != 1 || occlusion.height != 1 || layer.occlusion.source == TextureSource::File) {
    if (occlusion.width != rgb.width || occlusion.height != rgb.height)
      throw occlusion_size_error(where + "/occlusion", layer, occlusion.width, occlusion.height, rgb.width,
                                 rgb.height);
    for_rows(rgb.height, [&](int y) {
      for (int x = 0; x < rgb.width; ++x) rgb.at(x, y, 0) = occlusion.at(x, y, 0);
    });
  } else {
    for (std::size_t i = 0; i < rgb.texels.size(); i += 3) rgb.texels[i] = occlusion.texels[0];
  }
  return rgb;
}

}  // namespace

const char* purpose_name(TexturePurpose purpose) {
  switch (purpose) {
    case TexturePurpose::Albedo: return "albedo";
    case TexturePurpose::Normal: return "normal";
    case TexturePurpose::Height: return "height";
    case TexturePurpose::Orm: return "orm";
  }
  return "?";
}

Image make_texture(const TextureDesc& desc, TexturePurpose purpose, const LayerDesc& layer, const Image* height,
                   const std::string& where) {
  switch (purpose) {
    case TexturePurpose::Albedo: return albedo_texture(desc, where);
    case TexturePurpose::Normal: return normal_texture(desc, layer, height, where);
    case TexturePurpose::Height: return height_texture(desc, layer, where);
    case TexturePurpose::Orm: return orm_texture(layer, where);
  }
  throw Error(where, "unknown texture purpose");
}

Image make_layer_height(const LayerDesc& layer, const std::string& where) {
  return make_texture(layer.height, TexturePurpose::Height, layer, nullptr, where);
}

OrmSource orm_source(const LayerDesc& layer, const std::string& where) {
  std::optional<ImageHeader> orm, occlusion;
  if (layer.orm.source == TextureSource::File) orm = read_image_header(layer.orm.file, where + "/orm/file");
  if (layer.occlusion.source == TextureSource::File)
    occlusion = read_image_header(layer.occlusion.file, where + "/occlusion/file");
  if (orm && occlusion && (orm->width != occlusion->width || orm->height != occlusion->height))
    throw occlusion_size_error(where + "/occlusion/file", layer, occlusion->width, occlusion->height, orm->width,
                               orm->height);
  OrmSource source;
  if (orm || occlusion) {
    source.width = orm ? orm->width : occlusion->width;
    source.height = orm ? orm->height : occlusion->height;
  }
  // orm_texture step by step: the orm file read (or the constant spread), then the occlusion read beside it.
  const std::uint64_t texels = std::uint64_t(source.width) * std::uint64_t(source.height);
  const std::uint64_t out = texels * 3 * sizeof(float);
  const std::uint64_t rgb = orm ? std::max(read_image_bytes(*orm), texels * std::uint64_t(orm->channels) * sizeof(float) +
                                                                       (orm->channels == 3 ? 0 : out))
                                : out;
  const std::uint64_t occ = occlusion ? std::max(read_image_bytes(*occlusion),
                                                 texels * std::uint64_t(occlusion->channels + 1) * sizeof(float))
                                      : sizeof(float);
  source.build_bytes = std::max(rgb, out + occ);
  return source;
}

// Mirrors the slot functions above step by step: each step's peak is what it allocates plus what is still held.
std::uint64_t make_texture_bytes(const TextureDesc& desc, TexturePurpose purpose, int width, int height,
                                 const ImageHeader* file) {
  const std::uint64_t texels = std::uint64_t(width) * std::uint64_t(height);
  const std::uint64_t out_channels = purpose == TexturePurpose::Height ? 1 : 3;
  const std::uint64_t out = texels * out_channels * sizeof(float);
  switch (desc.source) {
    case TextureSource::None:
    case TextureSource::Constant: return out_channels * sizeof(float);
    case TextureSource::FromHeight: return out;  // normals_from_height's result; the height is the caller's
    case TextureSource::Pixels: return out;      // a copy of the handed-over channel
    case TextureSource::Procedural:
      // The albedo's colours are made from a pattern with its cell ids (2 channels), held until they are done.
      return purpose == TexturePurpose::Albedo ? texels * 2 * sizeof(float) + out : out;
    case TextureSource::File: {
      if (!file) return out;
      const std::uint64_t decoded = texels * std::uint64_t(file->channels) * sizeof(float);
      // pick() hands the file's image on when the selection is all its channels in order, else holds both.
      const bool all_in_order = out_channels == 1 ? desc.channel == Channel::Default || desc.channel == Channel::R
                                                  : desc.channel == Channel::Default || desc.channel == Channel::RGB;
      const bool in_place = std::uint64_t(file->channels) == out_channels && all_in_order;
      return std::max(read_image_bytes(*file), in_place ? decoded : decoded + out);
    }
  }
  return out;
}

}  // namespace qdmr
