#pragma once
// A draw kernel: the code of a frame that runs per pixel, compiled once per ISA (kernel_isa.cpp with that
// ISA's flags) and chosen at run time. Everything else of the frame is baseline x86-64 and reaches the kernel
// only through this interface.
#include <memory>
#include <string>

#include "program/inputs.hpp"
#include "program/light_rig.hpp"
#include "program/program.hpp"
#include "qdmr/core/isa.hpp"
#include "qdmr/scene/scene.hpp"
#include "raster/raster_context.hpp"

namespace qdmr {

class Kernel {
public:
  virtual ~Kernel() = default;
  virtual Isa isa() const = 0;
  virtual int lanes() const = 0;  // pixels per batch: 4, 8 or 16 (one, two or four quads)
  // The shading program of one material (normal mapping, or a displacement technique), for this kernel.
  virtual std::unique_ptr<Program> make_program(const MaterialDesc& material, const DisplacementInputs& inputs,
                                                 const LightRig& lights) const = 0;
  // Clears and draws one tile (see raster/tile_raster.hpp); the context's programs must come from this kernel.
  virtual void raster_tile(const RasterContext& context, int tile_index, const PixelRect& tile, const TileBins& bins,
                           TileCounters& counters) const = 0;
};

// The kernel of a resolved ISA (not Auto); throws qdmr::Error when it is not built into this binary.
const Kernel& kernel_for(Isa isa);

}  // namespace qdmr
