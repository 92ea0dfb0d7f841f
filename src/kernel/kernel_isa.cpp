// The kernel table of one ISA. This file, as all of src/kernel/, is compiled once per ISA with that ISA's flags;
// QDMR_ISA names its namespace and QDMR_ISA_ENUM its Isa value.
#include "kernel/displacement.hpp"
#include "kernel/kernel.hpp"
#include "kernel/kernel_calls.hpp"
#include "kernel/normal_mapping.hpp"
#include "kernel/preparation.hpp"
#include "kernel/tile_raster.hpp"
#include "kernel/ao_rows.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/program/program_key.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {
namespace {

class IsaKernel final : public Kernel {
public:
  Isa isa() const override { return Isa::QDMR_ISA_ENUM; }
  int lanes() const override { return simd::kLanes; }

  std::unique_ptr<Program> make_program(const ProgramKey& key, const ProgramParams& params,
                                        const DisplacementInputs& inputs, const LightRig& lights) const override {
    kernel_calls.programs.fetch_add(1, std::memory_order_relaxed);
    if (key.normal_mapping()) {
      if (inputs.layers.size() != 1 || params.specular.size() != 1)
        throw Error("normal mapping program", "needs one layer");
      const LayerInputs& l = inputs.layers[0];
      if (key.orm != (l.orm != nullptr)) throw Error("normal mapping program", "the key's orm and the inputs' differ");
      return std::make_unique<NormalMappingProgram>(variant_name(key), *l.albedo, *l.normal, l.twin_texels, l.orm,
                                                    params.orm, key.sampler, params.sampler, key.lighting,
                                                    params.lighting, params.specular[0], lights);
    }
    return std::make_unique<DisplacementProgram>(inputs, key, params, lights);
  }

  void raster_tile(const RasterContext& context, int tile_index, const PixelRect& tile, const TileBins& bins,
                   TileCounters& counters) const override {
    qdmr::QDMR_ISA::raster_tile(context, tile_index, tile, bins, counters);
  }

  void blend_box_values(const BlendBoxSource& source, float* out) const override {
    qdmr::QDMR_ISA::blend_box_values(source, out);
  }

  MipExtremum mip_extremum() const override { return &qdmr::QDMR_ISA::mip_extremum; }

  AoMapRow ao_map_row() const override {
    return {.f64 = &qdmr::QDMR_ISA::ao_map_row, .f32 = &qdmr::QDMR_ISA::ao_map_row};
  }

  const HeightRows& height_rows() const override { return qdmr::QDMR_ISA::height_rows(); }

  Bc3Encode bc3_encode() const override { return qdmr::QDMR_ISA::bc3_encoder(); }

  const KernelCalls& calls() const override { return kernel_calls; }
};

}  // namespace

const Kernel& kernel() {
  static const IsaKernel instance;
  return instance;
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
