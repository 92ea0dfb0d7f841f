#pragma once
// A shading program as the rest of the frame sees it: made by a draw kernel (one per ISA) for one material,
// named by its variant, run by that kernel's rasterizer. What it runs on (lanes, SIMD types) is the kernel's
// business: see kernel/batch.hpp.
#include <string>

#include "program/varyings.hpp"

namespace qdmr {

class Program {
public:
  Program(std::string variant, int varying_count) : variant_(std::move(variant)), varying_count_(varying_count) {}
  virtual ~Program() = default;
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;

  // The variant that runs, from the instantiated program type (the plan names the same).
  const std::string& variant() const { return variant_; }
  // The rasterizer interpolates varyings [0, varying_count()) only; the others are left unset.
  int varying_count() const { return varying_count_; }

private:
  std::string variant_;
  int varying_count_;
};

}  // namespace qdmr
