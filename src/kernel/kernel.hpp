#pragma once
// A kernel: the code of a frame that is compiled once per ISA (everything in src/kernel/, with that ISA's flags)
// and chosen at run time. Everything else is baseline x86-64 and reaches a kernel only through this table: the
// draw (programs, tiles) and preparation (the blend's box values, max/min mip chains, baked AO), both with the Renderer's
// kernel, so `--isa` holds for every stage of a frame.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "program/inputs.hpp"
#include "program/light_rig.hpp"
#include "program/program.hpp"
#include "qdmr/program/program_key.hpp"
#include "qdmr/program/program_params.hpp"
#include "bake/ao_map_row.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/texture/bc3.hpp"
#include "texture/blend_box_values.hpp"
#include "texture/height_rows.hpp"
#include "qdmr/texture/mip_texture.hpp"
#include "raster/raster_context.hpp"

namespace qdmr {

// How often a kernel's own code ran, per entry point: counted inside the per-ISA functions (not by the table),
// so a call that reaches a kernel some other way still counts under the ISA that ran. Once per material, tile,
// mip level, box-value table or AO row, and once per encoder or row table handed out (a BC3 texture, a dynamic
// height's rebuild: an atomic per 4x4 block or per row would cost more than it tells): relaxed atomics, no cost
// worth measuring.
struct KernelCalls {
  std::atomic<std::uint64_t> programs{0}, tiles{0}, mip_levels{0}, box_values{0}, ao_rows{0}, bc3_encoders{0},
      height_row_tables{0};
};

class Kernel {
public:
  virtual ~Kernel() = default;
  virtual Isa isa() const = 0;
  virtual int lanes() const = 0;  // pixels per batch: 4, 8 or 16 (one, two or four quads)
  // The shading program of one material (normal mapping, or a displacement technique) for this kernel, made from
  // the plan's key and parameters (MaterialPlan::key, ::params).
  virtual std::unique_ptr<Program> make_program(const ProgramKey& key, const ProgramParams& params,
                                                 const DisplacementInputs& inputs, const LightRig& lights) const = 0;
  // Clears and draws one tile (see kernel/tile_raster.hpp); the context's programs must come from this kernel.
  virtual void raster_tile(const RasterContext& context, int tile_index, const PixelRect& tile, const TileBins& bins,
                           TileCounters& counters) const = 0;
  // Preparation: a blend's level-0 box values (texture/blend_box_values.hpp) into `out`, which holds
  // blend_box_value_count(source) floats (not 0); every kernel gives the same bits.
  virtual void blend_box_values(const BlendBoxSource& source, float* out) const = 0;
  // Preparation: the max/min reduction of one mip level (MipReduce::Max / Min), for make_mip_texture.
  virtual MipExtremum mip_extremum() const = 0;
  // Preparation: one row of a baked AO map (bake/ao_map.hpp), for bake_ao_map.
  virtual AoMapRow ao_map_row() const = 0;
  // Preparation: the rows of a dynamic height's rebuild (texture/height_family.hpp).
  virtual const HeightRows& height_rows() const = 0;
  // Preparation: BC3 alpha blocks of compressed heights (the blocks of encode_bc3_alpha), for make_height_texture.
  virtual Bc3Encode bc3_encode() const = 0;
  virtual const KernelCalls& calls() const = 0;
};

// The kernel of a resolved ISA (not Auto); throws qdmr::Error when it is not built into this binary. Defined in
// draw/kernel.cpp: kernel/ holds only code compiled per ISA.
const Kernel& kernel_for(Isa isa);

}  // namespace qdmr
