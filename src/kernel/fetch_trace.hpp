#pragma once
// The kernels' side of the texture-cache recorder (texture/fetch_recorder.hpp): one test of a process-wide count
// per texel fetch and per loop iteration when the cache is off.
#include <cstdint>

#include "core/simd.hpp"
#include "texture/fetch_recorder.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// Whether a texture-cache recorder listens on this thread (a program may then pick loops that never ask).
inline bool fetch_recorder_listens() { return listening_fetch_recorder() != nullptr; }

// Reports texel (x, y) of the level starting at byte `level_offset` of `texture`, per lane, to the recorder.
inline void trace_fetch(const Texture& texture, const simd::Int& level_offset, const simd::Int& x, const simd::Int& y) {
  FetchRecorder* recorder = listening_fetch_recorder();
  if (recorder == nullptr) [[likely]]
    return;
  alignas(64) std::int32_t o[simd::kLanes], xs[simd::kLanes], ys[simd::kLanes];
  level_offset.store_aligned(o);
  x.store_aligned(xs);
  y.store_aligned(ys);
  recorder->record(texture, o, xs, ys);
}

// A loop or branch of a shading program: while it lives, only the lanes last passed to narrow() fetch (on a GPU
// the retired lanes of a warp are masked off), and their fetches belong to `phase` (by default, the current one).
// Whatever a batch fetches for lanes that do not need it (work shared across the batch) must be narrowed away,
// or the statistics would depend on which pixels share a batch, i.e. on the SIMD width.
class FetchLanes {
public:
  FetchLanes() : recorder_(listening_fetch_recorder()) {
    if (recorder_ != nullptr) [[unlikely]]
      saved_ = recorder_->enter(recorder_->phase());
  }
  explicit FetchLanes(FetchPhase phase) : recorder_(listening_fetch_recorder()) {
    if (recorder_ != nullptr) [[unlikely]]
      saved_ = recorder_->enter(phase);
  }
  ~FetchLanes() {
    if (recorder_ != nullptr) [[unlikely]]
      recorder_->leave(saved_);
  }
  FetchLanes(const FetchLanes&) = delete;
  FetchLanes& operator=(const FetchLanes&) = delete;

  void narrow(const simd::Mask& active) {
    if (recorder_ != nullptr) [[unlikely]]
      recorder_->narrow(simd::to_bits(active));
  }

private:
  FetchRecorder* recorder_;
  FetchRecorder::State saved_{};
};

}  // namespace qdmr::QDMR_ISA_NAMESPACE
