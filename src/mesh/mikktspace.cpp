// MikkTSpace's essentials (mesh/mikktspace.hpp).
#include "mesh/mikktspace.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <type_traits>

#include <glm/geometric.hpp>
#include <xsimd/xsimd.hpp>

#include "mesh/builders.hpp"
#include "mesh/corner_batch.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/isa.hpp"

namespace qdmr::mesh_detail {

namespace {

bool not_zero(float x) { return std::abs(x) > std::numeric_limits<float>::min(); }

glm::vec3 unit_or_zero(const glm::vec3& v) {
  const float len = glm::length(v);
  return not_zero(len) && std::isfinite(len) ? v / len : glm::vec3(0.0f);
}

// A triangle's +u direction (unit, or zero) and UV orientation, as mikktspace.c's InitTriInfo computes them.
struct Face {
  glm::vec3 along_u{0.0f};
  bool preserving = false;  // UV area > 0
  bool degenerate = true;   // no usable UV derivative
};

inline Face face_of(std::span<const glm::vec3> positions, std::span<const glm::vec2> uvs, const std::uint32_t* corner) {
  Face f;
  const glm::vec3 d1 = positions[corner[1]] - positions[corner[0]];
  const glm::vec3 d2 = positions[corner[2]] - positions[corner[0]];
  const glm::vec2 t21 = uvs[corner[1]] - uvs[corner[0]], t31 = uvs[corner[2]] - uvs[corner[0]];
  const float area = t21.x * t31.y - t21.y * t31.x;
  f.preserving = area > 0.0f;
  const glm::vec3 os = t31.y * d1 - t21.y * d2;
  const float len = glm::length(os);
  if (not_zero(area) && not_zero(len) && std::isfinite(len)) {
    f.along_u = os * ((f.preserving ? 1.0f : -1.0f) / len);
    f.degenerate = false;
  }
  return f;
}

// Vertices with equal attributes are one vertex (mikktspace.c welds them): same[v] is the first vertex of v's kind.
// A hash table (+0 and -0 alike, as mikktspace.c's == sees them) filled by threads, each a range of vertices: a
// kind takes one slot (claimed by compare-and-swap) that ends up holding its smallest vertex (an atomic minimum),
// whatever the threads' timing; a second pass reads every vertex's kind from its slot. The table lives in
// `scratch` (the tangents, 16 bytes a vertex: 2 slots of 8 bytes, each the hash's low half above vertex + 1, so a
// probe compares a vertex's attributes only where the hashes agree).
using Slot = std::uint64_t __attribute__((may_alias));  // the scratch holds floats before and after

std::vector<std::uint32_t> weld(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                std::span<const glm::vec2> uvs, std::span<glm::vec4> scratch) {
  const std::size_t n = positions.size();
  const auto key = [&](std::uint32_t v) {
    return std::array<float, 8>{positions[v].x + 0.0f, positions[v].y + 0.0f, positions[v].z + 0.0f,
                                normals[v].x + 0.0f,   normals[v].y + 0.0f,   normals[v].z + 0.0f,
                                uvs[v].x + 0.0f,       uvs[v].y + 0.0f};
  };
  // Four independent products, then a mix (any hash gives the same kinds; this one is short).
  const auto hash = [](const std::array<float, 8>& k) {
    std::array<std::uint64_t, 4> w{};
    std::memcpy(w.data(), k.data(), sizeof w);
    std::uint64_t h = (w[0] * 0x9E3779B97F4A7C15ull) ^ (w[1] * 0xC2B2AE3D27D4EB4Full) ^
                      (w[2] * 0x165667B19E3779F9ull) ^ (w[3] * 0xD6E8FEB86659FD93ull);
    h ^= h >> 32;
    h *= 0x9FB21C651E98DF25ull;
    return h ^ (h >> 29);
  };
  // Linear probing at most 1/2 full; a hash's slot is the hash scaled to the capacity.
  const std::size_t capacity = 2 * n;
  Slot* table = reinterpret_cast<Slot*>(scratch.data());
  constexpr std::size_t kGrain = 16384;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, capacity, 2 * kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    std::memset(static_cast<void*>(table + r.begin()), 0, r.size() * sizeof(Slot));
  });
  std::vector<std::uint32_t> same(n);
  // The kinds' slots, into same[]; a batch's slots are asked for before they are probed.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    constexpr std::size_t kBatch = 32;
    std::array<std::size_t, kBatch> slot{};
    std::array<std::uint64_t, kBatch> tag{};
    for (std::size_t first = r.begin(); first < r.end(); first += kBatch) {
      const std::size_t count = std::min(kBatch, r.end() - first);
      for (std::size_t k = 0; k < count; ++k) {
        const std::uint64_t h = hash(key(std::uint32_t(first + k)));
        slot[k] = std::size_t(((h >> 32) * capacity) >> 32);  // capacity < 2^32: 3 x kMaxTriangles vertices at most
        tag[k] = h << 32;  // the low half
        __builtin_prefetch(&table[slot[k]]);
      }
      for (std::size_t k = 0; k < count; ++k) {
        const auto v = std::uint32_t(first + k);
        const std::uint64_t mine = tag[k] | (std::uint64_t(v) + 1);
        for (std::size_t at = slot[k];;) {
          std::uint64_t entry = __atomic_load_n(&table[at], __ATOMIC_RELAXED);
          if (entry == 0 && __atomic_compare_exchange_n(&table[at], &entry, mine, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
            same[v] = std::uint32_t(at);
            break;
          }
          // entry: the slot's (another thread may just have claimed it). Only its vertex can change, to a smaller
          // one of its kind.
          if ((entry & ~0xffffffffull) == tag[k] && key(std::uint32_t(entry) - 1) == key(v)) {
            while (entry > mine &&
                   !__atomic_compare_exchange_n(&table[at], &entry, mine, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
            }
            same[v] = std::uint32_t(at);
            break;
          }
          at = at + 1 == capacity ? 0 : at + 1;
        }
      }
    }
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v) same[v] = std::uint32_t(__atomic_load_n(&table[same[v]], __ATOMIC_RELAXED)) - 1;
  });
  return same;
}


std::atomic<std::size_t> parts_seen{0};

// Whether the corners go through AVX2's eight lanes: where this build has them, the CPU has AVX2 and `isa` (Auto:
// the ISA the draw would take, $QDMR_ISA where set) is AVX2 or better. Either width gives the same bits, so a
// $QDMR_ISA the draw will refuse is left for the draw to name: the load goes on with what the CPU has.
bool eight_lanes(Isa isa) {
#ifdef QDMR_KERNEL_AVX2
  if (!cpu_supports(Isa::Avx2)) return false;
  try {
    return resolve_isa(isa, "MikkTSpace") >= Isa::Avx2;
  } catch (const Error&) {
    if (isa != Isa::Auto) throw;
    return true;
  }
#else
  static_cast<void>(isa);
  return false;
#endif
}

}  // namespace

std::size_t take_mikktspace_parts_seen() { return parts_seen.exchange(0); }

MikkTSpaceCopies mikktspace_tangents(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                     std::span<const glm::vec2> uvs, std::span<std::uint32_t> indices,
                                     std::span<glm::vec4> tangents, Isa isa) {
  const std::size_t n = positions.size(), faces = indices.size() / 3;
  const auto normal = [&](std::uint32_t v) { return unit_or_zero(normals[v]); };
  const std::vector<std::uint32_t> same = weld(positions, normals, uvs, tangents);

  // Per vertex kind and orientation: the angle-weighted sum of its corners' directions, the preserving sums in
  // `tangents` (xyz), the mirrored ones beside them (made when the first mirrored triangle is met: only then do
  // vertices split). Each thread takes a range of kinds and sums their corners in triangle order. flags: bit 0 / 1
  // the kind has a preserving / mirrored sum; bits 2-3 the orientation of the vertex's own entry (1 preserving, 2
  // mirrored, 0 unset).
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384), [&](const tbb::blocked_range<std::size_t>& r) {
    std::fill(tangents.begin() + std::ptrdiff_t(r.begin()), tangents.begin() + std::ptrdiff_t(r.end()), glm::vec4(0.0f));
  });
  std::vector<glm::vec3> mirrored_sum;
  std::once_flag mirrored_made;
  std::vector<std::uint8_t> flags(n, 0);
  const std::size_t parts = std::size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
  for (std::size_t seen = parts_seen.load(); seen < parts && !parts_seen.compare_exchange_weak(seen, parts);) {
  }
  // Faces wait in a batch for their directions and their corners' weights, then are summed in order: the same
  // sums for either batch width.
  const auto sum_part = [&](std::size_t part, auto batch, auto compute) {
    constexpr int kFaces = decltype(batch)::kFaces;
    const std::uint32_t lo = std::uint32_t(n * part / parts), hi = std::uint32_t(n * (part + 1) / parts);
    const auto mine = [&](std::uint32_t v) { return same[v] >= lo && same[v] < hi; };
    struct Waiting {
      const std::uint32_t* corner;
      bool own[3];
    };
    std::array<Waiting, kFaces> waiting{};
    int count = 0;
    const auto sum_batch = [&] {
      compute(batch);
      for (int i = 0; i < count; ++i) {
        if (batch.degenerate >> i & 1) continue;
        const Waiting& face = waiting[std::size_t(i)];
        const bool preserving = batch.preserving >> i & 1;
        if (!preserving) std::call_once(mirrored_made, [&] { mirrored_sum.assign(n, glm::vec3(0.0f)); });
        for (int k = 0; k < 3; ++k) {
          if (!face.own[k]) continue;
          const std::uint32_t kind = same[face.corner[k]];
          const auto add = [&](auto& sum) {
            sum.x += batch.wx[k][i];
            sum.y += batch.wy[k][i];
            sum.z += batch.wz[k][i];
          };
          if (preserving) {
            add(tangents[kind]);
          } else {
            add(mirrored_sum[kind]);
          }
          flags[kind] |= preserving ? 1 : 2;
        }
      }
      count = 0;
    };
    for (std::size_t f = 0; f < faces; ++f) {
      const std::uint32_t* corner = &indices[3 * f];
      const bool own0 = mine(corner[0]), own1 = mine(corner[1]), own2 = mine(corner[2]);
      if (!(own0 || own1 || own2)) continue;
      batch.set(count, positions, normals, uvs, corner);
      Waiting& w = waiting[std::size_t(count)];  // field by field (a whole struct stored then copied stalls)
      w.corner = corner;
      w.own[0] = own0, w.own[1] = own1, w.own[2] = own2;
      if (++count == kFaces) sum_batch();
    }
    if (count > 0) sum_batch();
  };
  [[maybe_unused]] const bool wide = eight_lanes(isa);  // used where the AVX2 copy is built
  tbb::parallel_for(std::size_t(0), parts, [&](std::size_t part) {
#ifdef QDMR_KERNEL_AVX2  // else mesh/corner_batch_avx2.cpp is not built (the fuzz preset), and `wide` is false
    if (wide) {
      sum_part(part, CornerBatch<8>{}, [](CornerBatch<8>& b) { avx2::compute_corners(b); });
      return;
    }
#endif
    sum_part(part, CornerBatch<4>{}, [](CornerBatch<4>& b) { compute_corners<xsimd::sse2>(b); });
  });
  const bool any_mirrored = !mirrored_sum.empty();

  const auto tangent = [&](std::uint32_t v, int side) {
    const glm::vec3 t = unit_or_zero(side == 0 ? glm::vec3(tangents[same[v]]) : mirrored_sum[same[v]]);
    return glm::vec4(t == glm::vec3(0.0f) ? any_orthogonal(normal(v) == glm::vec3(0.0f) ? glm::vec3(0, 0, 1) : normal(v)) : t,
                     side == 0 ? 1.0f : -1.0f);
  };
  // Each corner takes its vertex kind's sum for its face's orientation (a degenerate face: the preserving sum if
  // its vertex has one, else the mirrored one). A vertex whose corners differ in orientation is copied. Without
  // mirrored triangles every corner takes the preserving sum.
  MikkTSpaceCopies copies;
  if (any_mirrored) {
    std::vector<std::uint32_t> copy(n, 0);  // per vertex, its copy for the other orientation (0: none yet)
    for (std::size_t f = 0; f < faces; ++f) {
      const Face face = face_of(positions, uvs, &indices[3 * f]);
      for (int k = 0; k < 3; ++k) {
        std::uint32_t& v = indices[3 * f + std::size_t(k)];
        const std::uint8_t kind = flags[same[v]];
        const int side = face.degenerate ? ((kind & 1) || !(kind & 2) ? 0 : 1) : face.preserving ? 0 : 1;
        const int own = (flags[v] >> 2) & 3;
        if (own == 0) {
          flags[v] = std::uint8_t(flags[v] | (side + 1) << 2);
        } else if (own != side + 1) {
          if (copy[v] == 0) {
            copy[v] = std::uint32_t(n + copies.of.size());
            copies.of.push_back(v);
            copies.tangents.push_back(tangent(v, side));
          }
          v = copy[v];
        }
      }
    }
  }
  // Each vertex's own tangent (a vertex no corner uses: any). The vertices that are not the first of their kind
  // first: they read the sums of their kind's first vertex, which is then overwritten by its own.
  const auto finish = [&](bool first_of_kind) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t v = range.begin(); v != range.end(); ++v)
        if ((same[v] == v) == first_of_kind) tangents[v] = tangent(std::uint32_t(v), ((flags[v] >> 2) & 3) == 2 ? 1 : 0);
    });
  };
  finish(false);
  finish(true);
  return copies;
}

}  // namespace qdmr::mesh_detail
