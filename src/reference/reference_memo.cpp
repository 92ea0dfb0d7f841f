#include "qdmr/reference/reference_memo.hpp"

#include <algorithm>
#include <bit>

namespace qdmr {
namespace {

constexpr std::size_t kFieldsHeld = 8;  // a study's stored heights: plain and compressed, a few maps

// An entry's bytes in the map: key, hit, the node's link and hash, the bucket pointer.
constexpr std::size_t kEntryBytes = sizeof(std::array<std::uint64_t, 10>) + sizeof(ReferenceHit) + 3 * sizeof(void*);

bool same_content(const HeightField& a, const HeightField& b) {
  return a.width == b.width && a.height == b.height && a.address == b.address &&
         std::equal(a.h.begin(), a.h.end(), b.h.begin(), b.h.end(),
                    [](double x, double y) { return std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y); });
}

std::uint64_t mix(std::uint64_t x) {  // splitmix64's finaliser
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

std::size_t ReferenceMemo::KeyHash::operator()(const Key& k) const {
  std::uint64_t h = 0;
  for (std::uint64_t word : k) h = mix(h ^ word);
  return std::size_t(h);
}

ReferenceMemo::ReferenceMemo(std::uint64_t max_bytes)
    : max_entries_per_shard_(std::max<std::size_t>(1, std::size_t(max_bytes / kEntryBytes / kShards))) {}

std::uint64_t ReferenceMemo::field_id(const std::shared_ptr<const HeightField>& field) {
  std::lock_guard lock(fields_mutex_);
  auto found = std::find_if(fields_.begin(), fields_.end(), [&](const auto& f) { return f.first == field; });
  if (found == fields_.end())
    found = std::find_if(fields_.begin(), fields_.end(), [&](const auto& f) { return same_content(*f.first, *field); });
  std::uint64_t id = next_id_;
  if (found != fields_.end()) {
    id = found->second;
    fields_.erase(found);
  } else {
    ++next_id_;
    if (fields_.size() == kFieldsHeld) fields_.erase(fields_.begin());  // its hits stay until the memo is full
  }
  fields_.emplace_back(field, id);  // the newest pointer: the last one a renderer handed in is the likeliest next
  return id;
}

ReferenceHit ReferenceMemo::intersect(std::uint64_t id, const HeightField& field, double depth_scale,
                                      const SurfaceRay& ray, ReferenceSurface surface, std::int64_t max_cells) {
  const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  const Key key{id,
                std::uint64_t(max_cells),
                std::uint64_t(surface),
                bits(depth_scale),
                bits(ray.origin.x),
                bits(ray.origin.y),
                bits(ray.origin.z),
                bits(ray.direction.x),
                bits(ray.direction.y),
                bits(ray.direction.z)};
  const std::size_t hash = KeyHash{}(key);
  Shard& shard = shards_[(hash >> 32) % kShards];
  {
    std::lock_guard lock(shard.mutex);
    const auto found = shard.hits.find(key);
    if (found != shard.hits.end()) {
      ++shard.found;
      return found->second;
    }
  }
  const ReferenceHit hit = intersect_reference(field, depth_scale, ray, surface, max_cells);  // outside the lock
  std::lock_guard lock(shard.mutex);
  ++shard.computed;
  if (shard.hits.size() >= max_entries_per_shard_) shard.hits.clear();
  shard.hits.emplace(key, hit);
  return hit;
}

std::uint64_t ReferenceMemo::hits() const {
  std::uint64_t n = 0;
  for (const Shard& s : shards_) {
    std::lock_guard lock(s.mutex);
    n += s.found;
  }
  return n;
}

std::uint64_t ReferenceMemo::misses() const {
  std::uint64_t n = 0;
  for (const Shard& s : shards_) {
    std::lock_guard lock(s.mutex);
    n += s.computed;
  }
  return n;
}

}  // namespace qdmr
