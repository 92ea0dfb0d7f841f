#pragma once
// Remembered exact reference hits. A study draws the same rays through the same stored heights many times: the
// error AOVs and the reference image of a configuration, and every configuration that differs only in how the
// technique samples (filter, precision, height fetch). intersect_reference is a pure function of its arguments,
// so a hit remembered under all of them (the field by content) is the hit it would compute, bit for bit.
// Thread-safe; shared by the renderers that hold it (RenderOptions::reference_memo).
#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "qdmr/reference/reference.hpp"

namespace qdmr {

class ReferenceMemo {
public:
  // At most `max_bytes` of remembered hits (approximately): a full memo forgets them all and starts again.
  explicit ReferenceMemo(std::uint64_t max_bytes = std::uint64_t(256) << 20);

  // The id under which `field`'s hits are remembered: the same id for a field with the same content (size,
  // address mode, heights) as one registered before, unless it has been forgotten since (the memo holds the
  // last few fields). Ids are never reused.
  std::uint64_t field_id(const std::shared_ptr<const HeightField>& field);

  // intersect_reference(field, ...), remembered: `field` must be the field registered as `id`.
  ReferenceHit intersect(std::uint64_t id, const HeightField& field, double depth_scale, const SurfaceRay& ray,
                         ReferenceSurface surface, std::int64_t max_cells);

  std::uint64_t hits() const;
  std::uint64_t misses() const;

private:
  // Every argument, numbers by their bits (-0 is not 0 to the traversal; a NaN equals itself).
  using Key = std::array<std::uint64_t, 10>;
  struct KeyHash {
    std::size_t operator()(const Key& k) const;
  };
  struct Shard {
    mutable std::mutex mutex;
    std::unordered_map<Key, ReferenceHit, KeyHash> hits;
    std::uint64_t found = 0, computed = 0;
  };
  static constexpr int kShards = 16;  // threads look up at once without waiting for each other

  std::size_t max_entries_per_shard_;
  std::array<Shard, kShards> shards_;
  std::mutex fields_mutex_;
  std::vector<std::pair<std::shared_ptr<const HeightField>, std::uint64_t>> fields_;  // newest last
  std::uint64_t next_id_ = 1;
};

}  // namespace qdmr
