#pragma once
// The fetch recorder of the emulated texture cache (docs/texture_cache.md). While a tile is drawn with the
// cache on, the sampler reports every texel it reads for the lanes that are live (issuing quads, minus lanes a
// loop has retired); the recorder keeps each lane's texels in order, tagged with the program phase. When the
// tile is done, replay() feeds them to the cache region by region, warp by warp, in the order a GPU would issue
// them: per phase, the k-th texel of every lane of the warp, then the (k+1)-th. Lanes are pixels and warps are
// runs of whole quads in draw order, so the result does not depend on the SIMD width or the thread count.
// ISA-neutral and out of line (the kernels of every ISA call the same copy), reached through
// kernel/fetch_trace.hpp.
#include <atomic>
#include <cstdint>
#include <vector>

#include "qdmr/core/texture_cache.hpp"
#include "texture/cache_model.hpp"

namespace qdmr {

// Program phases in execution order; the warps reconverge at each (a lane never goes back to an earlier one).
enum class FetchPhase : std::uint8_t { Setup, Trace, Refine, Surface, Shadow, Occlusion };
inline constexpr int kFetchPhases = 6;

struct CacheCounters {
  std::uint64_t accesses = 0, hits = 0;
};

class FetchRecorder;
// The recorder of the tile this thread draws, or null (the cache is off). Read through listening_fetch_recorder().
inline thread_local FetchRecorder* t_fetch_recorder = nullptr;
// How many recorders listen in the process, on any thread (FetchRecorder::Listening counts them).
inline std::atomic<int> g_fetch_recorders_listening{0};

// This thread's recorder, or null: asked on every texel fetch and per batch. A plain load of the process-wide count
// first, the thread-local only when some thread records. In a shared object (the Python module) a thread-local
// read is a call (0.08 % of the module's draw with TLS descriptors), unless initial-exec, which would put the
// module's thread-locals in glibc's small static TLS reserve for modules loaded later (`import qdmr` could fail
// with "cannot allocate memory in static TLS block"). A thread sees its own Listening's count, so it never misses
// its own recorder; another thread's count only sends it to its own, null, thread-local.
inline FetchRecorder* listening_fetch_recorder() {
  if (g_fetch_recorders_listening.load(std::memory_order_relaxed) == 0) [[likely]]
    return nullptr;
  return t_fetch_recorder;
}

class FetchRecorder {
public:
  static constexpr int kMaxLanes = 16;

  // tile: inclusive pixel bounds (x0, y0, x1, y1), its origin a multiple of desc.region.
  FetchRecorder(const TextureCacheDesc& desc, const TextureAddressMap& addresses, int x0, int y0, int x1, int y1);
  FetchRecorder(const FetchRecorder&) = delete;
  FetchRecorder& operator=(const FetchRecorder&) = delete;

  // Makes this the thread's recorder until the returned scope ends.
  class Listening {
  public:
    explicit Listening(FetchRecorder& r);
    ~Listening();
    Listening(const Listening&) = delete;
    Listening& operator=(const Listening&) = delete;

  private:
    FetchRecorder* saved_;
  };

  // A batch of `lanes` lanes at pixels (px[l], py[l]); `issuing`: the lanes that fetch (the quads with a
  // pixel to write; a GPU runs whole quads).
  void begin_batch(int lanes, const int* px, const int* py, std::uint32_t issuing);
  void end_batch();

  // Texel (x[l], y[l]) of the level that starts at byte `level_offset[l]` of `texture`, for each live lane.
  void record(const Texture& texture, const std::int32_t* level_offset, const std::int32_t* x, const std::int32_t* y);

  // Loops narrow the live lanes and name their phase; leave() restores what enter() returned.
  struct State {
    std::uint32_t live;
    FetchPhase phase;
  };
  State enter(FetchPhase phase);
  FetchPhase phase() const;
  void narrow(std::uint32_t lanes);
  void leave(const State& saved);

  // Feeds every recorded texel to `cache` (cleared at each region) and adds up the accesses and hits. With
  // `misses` (a frame-sized plane), adds each lane's misses at its pixel where `depth` < 1 (covered).
  void replay(TextureCache& cache, CacheCounters& counters, int frame_width, int frame_height, const float* depth,
              float* misses) const;

private:
  struct Stream {  // one issuing lane of one batch: a pixel's texels in issue order
    int x, y;
    std::uint32_t begin, end;  // into Region::texels
  };
  struct Region {
    std::vector<Stream> streams;
    std::vector<std::uint64_t> texels;  // packed: phase, slot, level, x, y
  };

  TextureCacheDesc desc_;
  const TextureAddressMap& addresses_;
  int x0_, y0_, regions_x_;
  std::vector<Region> regions_;
  // The batch being drawn.
  int lanes_ = 0;
  int px_[kMaxLanes] = {}, py_[kMaxLanes] = {};
  std::uint32_t issuing_ = 0, live_ = 0;
  FetchPhase phase_ = FetchPhase::Setup;
  std::uint8_t lane_phase_[kMaxLanes] = {};  // the latest phase each lane fetched in
  std::vector<std::uint32_t> outer_live_;
  std::vector<std::uint64_t> lane_texels_[kMaxLanes];
  // The last texture looked up (fetches come in runs from one texture).
  const Texture* last_texture_ = nullptr;
  int last_slot_ = -1;
};

}  // namespace qdmr
