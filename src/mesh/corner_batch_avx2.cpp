// MikkTSpace's corner arithmetic in AVX2's eight lanes (mesh/corner_batch.hpp): compiled with the AVX2 kernel's
// flags (CMakeLists.txt), linked after the baseline code, called only where the CPU has AVX2.
#include "mesh/corner_batch.hpp"

namespace qdmr::avx2 {

void compute_corners(mesh_detail::CornerBatch<8>& batch) { mesh_detail::compute_corners<xsimd::avx2>(batch); }

}  // namespace qdmr::avx2
