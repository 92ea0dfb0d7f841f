#include "texture/fetch_recorder.hpp"

#include <algorithm>

namespace qdmr {
namespace {

// A recorded texel: phase (3 bits) | slot (8) | level (5) | x (24) | y (24).
constexpr std::uint64_t pack(FetchPhase phase, int slot, int level, std::int32_t x, std::int32_t y) {
  return std::uint64_t(phase) << 61 | std::uint64_t(slot) << 53 | std::uint64_t(level) << 48 |
         (std::uint64_t(std::uint32_t(x)) & 0xFFFFFFu) << 24 | (std::uint64_t(std::uint32_t(y)) & 0xFFFFFFu);
}
constexpr int phase_of(std::uint64_t t) { return int(t >> 61); }
constexpr int slot_of(std::uint64_t t) { return int((t >> 53) & 0xFFu); }
constexpr int level_of(std::uint64_t t) { return int((t >> 48) & 0x1Fu); }
constexpr int x_of(std::uint64_t t) { return int((t >> 24) & 0xFFFFFFu); }
constexpr int y_of(std::uint64_t t) { return int(t & 0xFFFFFFu); }

}  // namespace

FetchRecorder::Listening::Listening(FetchRecorder& r) : saved_(t_fetch_recorder) {
  t_fetch_recorder = &r;
  g_fetch_recorders_listening.fetch_add(1, std::memory_order_relaxed);
}
FetchRecorder::Listening::~Listening() {
  g_fetch_recorders_listening.fetch_sub(1, std::memory_order_relaxed);
  t_fetch_recorder = saved_;
}

FetchRecorder::FetchRecorder(const TextureCacheDesc& desc, const TextureAddressMap& addresses, int x0, int y0, int x1,
                             int y1)
    : desc_(desc), addresses_(addresses), x0_(x0), y0_(y0) {
  const int r = desc.region;
  regions_x_ = (x1 - x0 + r) / r;
  const int regions_y = (y1 - y0 + r) / r;
  regions_.resize(std::size_t(regions_x_) * std::size_t(regions_y));
}

void FetchRecorder::begin_batch(int lanes, const int* px, const int* py, std::uint32_t issuing) {
  lanes_ = std::min(lanes, kMaxLanes);
  for (int l = 0; l < lanes_; ++l) {
    px_[l] = px[l];
    py_[l] = py[l];
    lane_phase_[l] = 0;
    lane_texels_[l].clear();
  }
  issuing_ = live_ = issuing;
  phase_ = FetchPhase::Setup;
  outer_live_.clear();
}

void FetchRecorder::end_batch() {
  for (int l = 0; l < lanes_; ++l) {
    if (!((issuing_ >> l) & 1u)) continue;
    // The region of the lane's quad (regions are whole quads: their side is a multiple of 8).
    const int rx = ((px_[l] & ~1) - x0_) / desc_.region, ry = ((py_[l] & ~1) - y0_) / desc_.region;
    Region& region = regions_[std::size_t(ry) * std::size_t(regions_x_) + std::size_t(rx)];
    const auto begin = std::uint32_t(region.texels.size());
    region.texels.insert(region.texels.end(), lane_texels_[l].begin(), lane_texels_[l].end());
    region.streams.push_back({px_[l], py_[l], begin, std::uint32_t(region.texels.size())});
  }
  issuing_ = live_ = 0;
}

FetchRecorder::State FetchRecorder::enter(FetchPhase phase) {
  const State saved{live_, phase_};
  outer_live_.push_back(live_);
  phase_ = phase;
  return saved;
}

FetchPhase FetchRecorder::phase() const { return phase_; }

void FetchRecorder::narrow(std::uint32_t lanes) { live_ = outer_live_.back() & lanes; }

void FetchRecorder::leave(const State& saved) {
  outer_live_.pop_back();
  live_ = saved.live;
  phase_ = saved.phase;
}

void FetchRecorder::record(const Texture& texture, const std::int32_t* level_offset, const std::int32_t* x,
                           const std::int32_t* y) {
  if (live_ == 0) return;
  if (&texture != last_texture_) {
    last_slot_ = addresses_.slot(&texture);
    last_texture_ = &texture;
  }
  // A texture the frame did not register (none should exist) is left out rather than guessed at.
  if (last_slot_ < 0) return;
  for (int l = 0; l < lanes_; ++l) {
    if (!((live_ >> l) & 1u)) continue;
    int level = 0;
    while (level + 1 < texture.level_count() && texture.levels[std::size_t(level)].offset != std::size_t(level_offset[l]))
      ++level;
    lane_phase_[l] = std::max(lane_phase_[l], std::uint8_t(phase_));
    lane_texels_[l].push_back(pack(FetchPhase(lane_phase_[l]), last_slot_, level, x[l], y[l]));
  }
}

void FetchRecorder::replay(TextureCache& cache, CacheCounters& counters, int frame_width, int frame_height,
                           const float* depth, float* misses) const {
  std::vector<std::uint32_t> cursor;
  for (const Region& region : regions_) {
    if (region.streams.empty()) continue;
    cache.clear();
    for (std::size_t w = 0; w < region.streams.size(); w += std::size_t(desc_.warp)) {
      const std::size_t warp_end = std::min(region.streams.size(), w + std::size_t(desc_.warp));
      cursor.assign(warp_end - w, 0);
      for (std::size_t s = w; s < warp_end; ++s) cursor[s - w] = region.streams[s].begin;
      for (int phase = 0; phase < kFetchPhases; ++phase) {
        // Lock step: the k-th texel of this phase of every lane, then the next; lanes done with the phase wait.
        for (bool progressed = true; progressed;) {
          progressed = false;
          for (std::size_t s = w; s < warp_end; ++s) {
            const Stream& stream = region.streams[s];
            std::uint32_t& at = cursor[s - w];
            if (at == stream.end || phase_of(region.texels[at]) != phase) continue;
            const std::uint64_t t = region.texels[at++];
            progressed = true;
            const bool hit = cache.access(addresses_.address(slot_of(t), level_of(t), x_of(t), y_of(t)));
            ++counters.accesses;
            counters.hits += hit;
            if (hit || misses == nullptr || stream.x >= frame_width || stream.y >= frame_height) continue;
            const std::size_t pixel = std::size_t(stream.y) * std::size_t(frame_width) + std::size_t(stream.x);
            if (depth[pixel] < 1.0f) misses[pixel] += 1.0f;
          }
        }
      }
    }
  }
}

}  // namespace qdmr
