#pragma once
// A read-only view of level-0 heights stored as T, row-major, with HeightField's addressing: a HeightField's
// doubles, or a blend's fp32 box values (texture/blend_box_values.hpp) read as the doubles they convert to
// exactly, so what is made from the view has the bits it would have from an fp64 copy, without the copy.
#include <cstddef>
#include <cstdint>

#include "qdmr/texture/heightfield.hpp"

namespace qdmr {

template <class T>
struct HeightView {
  int width = 0, height = 0;
  AddressMode address = AddressMode::Wrap;
  const T* h = nullptr;

  // HeightField::at's texel, as a double.
  double at(std::int64_t i, std::int64_t j) const {
    return double(h[std::size_t(HeightField::texel_index(j, height, address) * width +
                                HeightField::texel_index(i, width, address))]);
  }
};

// A field whose heights do not fill width x height gives a view without heights (h null), which the bakes refuse as
// an empty or inconsistent field.
inline HeightView<double> height_view(const HeightField& field) {
  const bool filled = field.h.size() == std::size_t(field.width) * std::size_t(field.height);
  return {field.width, field.height, field.address, filled ? field.h.data() : nullptr};
}

}  // namespace qdmr
