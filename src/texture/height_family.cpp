#include "texture/height_family.hpp"

#include <tbb/parallel_for_each.h>

#include <cstring>
#include <optional>

#include "qdmr/core/error.hpp"
#include "qdmr/texture/texture_level0.hpp"
#include "texture/height_rows_code.hpp"
#include "texture/internal.hpp"

namespace qdmr {
namespace {

// `t` shaped as a chain of this layout with its decoded copy and footprints where asked; its own buffers kept when
// they already have that layout (their bytes between levels are zero since they were made; the rest is overwritten).
void shape(Texture& t, int w, int h, TexelFormat format, bool footprints) {
  const bool same = !t.levels.empty() && t.format == format && !t.srgb && t.width() == w && t.height() == h &&
                    t.storage.size() == mip_chain_bytes(w, h, format);
  if (!same) t = allocate_texture(w, h, format, false);
  const std::size_t linear = linear_copy_bytes(w, h, format, false) / sizeof(float);
  if (t.linear.size() != linear) t.linear.assign(linear, 0.0f);
  const std::size_t prints = footprints ? wrap_footprint_bytes(w, h, format, false) / sizeof(float) : 0;
  if (t.wrap_footprints.size() != prints) t.wrap_footprints.assign(prints, 0.0f);
}

std::uint8_t* codes(Texture& t, int level, int y) {
  const TextureLevel& l = t.levels[std::size_t(level)];
  return t.storage.data() + l.offset + std::size_t(y) * std::size_t(l.width) * std::size_t(bytes_per_texel(t.format));
}

float* decoded(Texture& t, int level, int y) {
  const TextureLevel& l = t.levels[std::size_t(level)];
  return t.linear.data() + l.offset / std::size_t(bytes_per_texel(t.format)) + std::size_t(y) * std::size_t(l.width);
}

// Levels 1.. of one member from its level 0.
void build_levels(HeightFamilyMember& m, const HeightRows& rows, MipExtremum extremum) {
  Texture& t = m.texture;
  const TexelFormat format = t.format;
  for (int k = 0; k + 1 < t.level_count(); ++k) {
    const TextureLevel in = t.levels[std::size_t(k)], out = t.levels[std::size_t(k) + 1];
    if (!m.normals && m.reduce == MipReduce::Max)
      extremum(true, format, codes(t, k, 0), in.width, in.height, codes(t, k + 1, 0), out.width, out.height);
    mip::for_rows(out.height, std::size_t(out.width) * 16, [&](int y0, int y1) {
      for (int y = y0; y < y1; ++y) {
        const mip::Taps ty = mip::taps(y, in.height, out.height);
        if (m.normals) {
          const std::uint8_t* r[3] = {};
          for (int j = 0; j < ty.count; ++j) r[j] = codes(t, k, ty.first + j);
          rows.box_normals(r, ty.count, in.width, out.width, codes(t, k + 1, y));
        } else if (m.reduce == MipReduce::Max) {
          rows.decode(format, codes(t, k + 1, y), out.width, decoded(t, k + 1, y));
        } else {
          const float* r[3] = {};
          for (int j = 0; j < ty.count; ++j) r[j] = decoded(t, k, ty.first + j);
          rows.box(format, r, ty.count, in.width, out.width, codes(t, k + 1, y), decoded(t, k + 1, y));
        }
      }
    });
  }
}

}  // namespace

const HeightRows& baseline_height_rows() { return height_row_code::table(); }

bool height_family_stores(const TextureDesc& height, TexelFormat format, int width, int height_texels) {
  return height.compression == Compression::None && (format == TexelFormat::R8 || format == TexelFormat::R16) &&
         linear_copy_bytes(width, height_texels, format, false) > 0;
}

void build_height_family(const LayerDesc& layer, TexelFormat format, const std::string& where,
                         std::vector<HeightFamilyMember>& members, const HeightRows& rows, MipExtremum extremum) {
  if (extremum == nullptr) extremum = &mip::extremum<mip::NoVectors>;
  // Level 0 in floats: the waves row by row, anything else as the height slot makes it.
  const TextureDesc& desc = layer.height;
  const bool waves = desc.source == TextureSource::Procedural && desc.procedural.pattern == ProceduralPattern::Waves;
  std::optional<texture_detail::WaveRows> wave_rows;
  Image image;
  if (waves) {
    wave_rows = texture_detail::wave_rows(desc.procedural);
  } else {
    image = make_layer_height(layer, where);
  }
  const int w = waves ? wave_rows->size : image.width, h = waves ? wave_rows->size : image.height;
  if (!height_family_stores(desc, format, w, h)) throw Error(where, "a dynamic height's rebuild needs r8 or r16 heights");

  HeightFamilyMember* first = nullptr;
  for (HeightFamilyMember& m : members) {
    shape(m.texture, w, h, m.normals ? TexelFormat::RGBA8 : format, !m.normals && m.wrap_footprints);
    if (!m.normals && !first) first = &m;
  }
  if (!first) throw Error(where, "a dynamic height's rebuild needs a height texture");
  const std::size_t code_bytes = std::size_t(w) * std::size_t(bytes_per_texel(format));

  // Level 0's codes and decoded heights, into the first height texture and copied into the others.
  mip::for_rows(h, std::size_t(w) * 12, [&](int y0, int y1) {
    std::vector<float> row(waves ? std::size_t(w) : 0);
    for (int y = y0; y < y1; ++y) {
      const float* heights = row.data();
      if (waves) {
        wave_rows->row(y, row.data(), rows.add_wave);
        rows.finish_waves(row.data(), w, layer.height_scale, layer.height_offset);
      } else {
        heights = image.texels.data() + std::size_t(y) * std::size_t(w);
      }
      rows.quantise(format, heights, w, codes(first->texture, 0, y), decoded(first->texture, 0, y));
      for (HeightFamilyMember& m : members)
        if (!m.normals && &m != first) {
          std::memcpy(codes(m.texture, 0, y), codes(first->texture, 0, y), code_bytes);
          std::memcpy(decoded(m.texture, 0, y), decoded(first->texture, 0, y), std::size_t(w) * sizeof(float));
        }
    }
  });

  // Level 0's footprints and normals, from the decoded heights of each row and its neighbours (wrapped).
  mip::for_rows(h, std::size_t(w) * 24, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      const int up = (y + h - 1) % h, down = (y + 1) % h;
      const float *above = decoded(first->texture, 0, up), *row = decoded(first->texture, 0, y),
                  *below = decoded(first->texture, 0, down);
      for (HeightFamilyMember& m : members) {
        if (m.normals) {
          // normals_from_height's scales, in its order of operations.
          const float strength = m.normal_strength;
          const double kx = strength * texture_detail::kFromHeightDepth * w * 0.5;
          const double ky = strength * texture_detail::kFromHeightDepth * h * 0.5;
          rows.normals(above, row, below, w, kx, ky, codes(m.texture, 0, y));
        }
        else if (!m.texture.wrap_footprints.empty())
          rows.footprints(row, below, w, m.texture.wrap_footprints.data() + std::size_t(y) * std::size_t(w) * 4);
      }
    }
  });

  tbb::parallel_for_each(members.begin(), members.end(),
                         [&](HeightFamilyMember& m) { build_levels(m, rows, extremum); });
}

}  // namespace qdmr
