// Kernel::height_rows: the rows of a dynamic height's rebuild (texture/height_rows_code.hpp) compiled with this
// kernel's flags, so the compiler runs them on its vectors.
#include "kernel/kernel_calls.hpp"
#include "kernel/preparation.hpp"
#include "texture/height_rows_code.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

const HeightRows& height_rows() {
  kernel_calls.height_row_tables.fetch_add(1, std::memory_order_relaxed);
  return height_row_code::table();
}

}  // namespace qdmr::QDMR_ISA_NAMESPACE
