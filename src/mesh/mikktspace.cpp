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

// Four faces at once in SSE2's four lanes (x86-64's baseline), a face a lane: its +u direction and UV orientation
// (face_of), then for each corner k, one vector of four lanes each, the corner's direction (the face's +u in the
// plane of the corner's normal, normalised) times its angle (between its edges projected onto that plane). Every
// lane takes the scalar formulas' operations in their order (glm's dot is (x x + y y) + z z, its length the
// square root of that, a vector over a scalar three divisions; deterministic_acos's argument chosen per lane, its
// polynomial evaluated once), and SSE2 rounds as the scalar operations do: the same bits. The three corners' vectors are
// independent: their divisions and square roots overlap.
struct CornerBatch {
  static constexpr int kFaces = 4;
  // Input per face (lane i): its corners' positions, UVs and normals.
  alignas(16) float px[3][kFaces]{}, py[3][kFaces]{}, pz[3][kFaces]{};
  alignas(16) float u[3][kFaces]{}, v[3][kFaces]{};
  alignas(16) float nx[3][kFaces]{}, ny[3][kFaces]{}, nz[3][kFaces]{};
  // Output: corner k of face i at [k][i]; per face whether it is degenerate or preserves the UV orientation.
  alignas(16) float wx[3][kFaces]{}, wy[3][kFaces]{}, wz[3][kFaces]{};
  std::uint32_t degenerate = 0, preserving = 0;  // bit i: face i

  void set(int face, std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
           std::span<const glm::vec2> uvs, const std::uint32_t* corner) {
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 &p = positions[corner[k]], &n = normals[corner[k]];
      const glm::vec2& t = uvs[corner[k]];
      px[k][face] = p.x, py[k][face] = p.y, pz[k][face] = p.z, u[k][face] = t.x, v[k][face] = t.y;
      nx[k][face] = n.x, ny[k][face] = n.y, nz[k][face] = n.z;
    }
  }

  using Floats = xsimd::batch<float, xsimd::sse2>;
  using Doubles = xsimd::batch<double, xsimd::sse2>;
  using V = std::array<Floats, 3>;              // one vector per corner
  using D = std::array<Doubles, 2 * 3>;         // a V's lanes 0-1 and 2-3 in double

  void compute() {
    const auto each = [](auto f, const auto&... in) {
      std::remove_cvref_t<decltype((in, ...))> out;
      for (std::size_t g = 0; g < out.size(); ++g) out[g] = f(in[g]...);
      return out;
    };
    const auto load = [](const float (&from)[3][kFaces]) {
      V r;
      for (std::size_t k = 0; k < 3; ++k) r[k] = Floats::load_aligned(from[k]);
      return r;
    };
    const auto add = [&](const V& a, const V& b) { return each([](const Floats& x, const Floats& y) { return x + y; }, a, b); };
    const auto sub = [&](const V& a, const V& b) { return each([](const Floats& x, const Floats& y) { return x - y; }, a, b); };
    const auto mul = [&](const V& a, const V& b) { return each([](const Floats& x, const Floats& y) { return x * y; }, a, b); };
    const auto dot = [&](const V& ax, const V& ay, const V& az, const V& bx, const V& by, const V& bz) {
      return add(add(mul(ax, bx), mul(ay, by)), mul(az, bz));
    };
    // not_zero(a) and a finite, for a = |x|.
    const auto usable = [](const Floats& x) {
      const Floats a = xsimd::abs(x);
      return (a > Floats(std::numeric_limits<float>::min())) & (a <= Floats(std::numeric_limits<float>::max()));
    };
    // unit_or_zero, in place. Where every lane's length is exactly 1 (axis-aligned normals, and many that are
    // already normalised) the divisions are skipped: x / 1 is x, every bit (-0, subnormals).
    const auto unit = [&](V& x, V& y, V& z) {
      const V len = each([](const Floats& d) { return xsimd::sqrt(d); }, dot(x, y, z, x, y, z));
      for (std::size_t g = 0; g < len.size(); ++g) {
        if (xsimd::all(len[g] == Floats(1.0f))) continue;
        const auto ok = usable(len[g]);
        x[g] = xsimd::select(ok, x[g] / len[g], Floats(0.0f));
        y[g] = xsimd::select(ok, y[g] / len[g], Floats(0.0f));
        z[g] = xsimd::select(ok, z[g] / len[g], Floats(0.0f));
      }
    };
    const V px_ = load(px), py_ = load(py), pz_ = load(pz);
    // face_of: the UV area's sign and the +u direction, os * (+-1 / |os|), where both are usable.
    const Floats d1x = px_[1] - px_[0], d1y = py_[1] - py_[0], d1z = pz_[1] - pz_[0];
    const Floats d2x = px_[2] - px_[0], d2y = py_[2] - py_[0], d2z = pz_[2] - pz_[0];
    const Floats u0 = Floats::load_aligned(u[0]), v0 = Floats::load_aligned(v[0]);
    const Floats t21x = Floats::load_aligned(u[1]) - u0, t21y = Floats::load_aligned(v[1]) - v0;
    const Floats t31x = Floats::load_aligned(u[2]) - u0, t31y = Floats::load_aligned(v[2]) - v0;
    const Floats area = t21x * t31y - t21y * t31x;
    const auto keeps = area > Floats(0.0f);
    const Floats osx = t31y * d1x - t21y * d2x, osy = t31y * d1y - t21y * d2y, osz = t31y * d1z - t21y * d2z;
    const Floats os_len = xsimd::sqrt((osx * osx + osy * osy) + osz * osz);
    const Floats scale = xsimd::select(keeps, Floats(1.0f), Floats(-1.0f)) / os_len;
    const auto ok = (xsimd::abs(area) > Floats(std::numeric_limits<float>::min())) & usable(os_len);
    preserving = std::uint32_t(_mm_movemask_ps(keeps));  // intrinsics: xsimd 8 has no mask-to-bits
    degenerate = ~std::uint32_t(_mm_movemask_ps(ok)) & 0xfu;
    const Floats ux = osx * scale, uy = osy * scale, uz = osz * scale;

    V nx_ = load(nx), ny_ = load(ny), nz_ = load(nz);
    unit(nx_, ny_, nz_);
    // in_plane: v - n dot(n, v), normalised; the edges' projections alike (not normalised).
    const auto project = [&](V& x, V& y, V& z) {
      const V d = dot(nx_, ny_, nz_, x, y, z);
      x = sub(x, mul(nx_, d));
      y = sub(y, mul(ny_, d));
      z = sub(z, mul(nz_, d));
    };
    V tx{ux, ux, ux}, ty{uy, uy, uy}, tz{uz, uz, uz};
    project(tx, ty, tz);
    unit(tx, ty, tz);
    // Corner k's edges: to corner k + 2 (a) and to corner k + 1 (b).
    const V ax_ = {px_[2], px_[0], px_[1]}, ay_ = {py_[2], py_[0], py_[1]}, az_ = {pz_[2], pz_[0], pz_[1]};
    const V bx_ = {px_[1], px_[2], px_[0]}, by_ = {py_[1], py_[2], py_[0]}, bz_ = {pz_[1], pz_[2], pz_[0]};
    V ex = sub(ax_, px_), ey = sub(ay_, py_), ez = sub(az_, pz_);
    V fx = sub(bx_, px_), fy = sub(by_, py_), fz = sub(bz_, pz_);
    project(ex, ey, ez);
    project(fx, fy, fz);
    // Float lanes to double lanes and back, two at a time, by intrinsics: xsimd converts only between batches of
    // one lane count.
    const auto wide = [](const V& x) {
      D d;
      for (std::size_t g = 0; g < x.size(); ++g) {
        d[2 * g] = _mm_cvtps_pd(x[g]);
        d[2 * g + 1] = _mm_cvtps_pd(_mm_movehl_ps(x[g], x[g]));
      }
      return d;
    };
    const D aa = wide(dot(ex, ey, ez, ex, ey, ez)), bb = wide(dot(fx, fy, fz, fx, fy, fz)),
            ab = wide(dot(ex, ey, ez, fx, fy, fz));
    // The corner's angle in double: cosine ab / sqrt(aa bb) (0 where aa bb is not positive and finite), then
    // deterministic_acos (std::clamp, through which NaN passes, then its branch).
    const D lengths2 = each([](const Doubles& a, const Doubles& b) { return a * b; }, aa, bb);
    const D root = each([](const Doubles& l) { return xsimd::sqrt(l); }, lengths2);
    const D x = each([](const Doubles& l, const Doubles& r, const Doubles& d) {
      const auto fine = (l > Doubles(0.0)) & (l <= Doubles(std::numeric_limits<double>::max()));
      const Doubles c = xsimd::select(fine, d / r, Doubles(0.0)), one(1.0), minus_one(-1.0);
      return xsimd::select(c < minus_one, minus_one, xsimd::select(one < c, one, c));
    }, lengths2, root, ab);
    const D abs_x = each([](const Doubles& a) { return xsimd::abs(a); }, x);
    // asin_small of a (|x| <= 0.5) or of sqrt((1 - a) / 2) (above): the branch's argument chosen first, the
    // polynomial evaluated once.
    const auto asin_small = [](const Doubles& a) {
      const Doubles z = a * a;
      Doubles p = Doubles(4.2163199048e-2) * z + Doubles(2.4181311049e-2);
      p = p * z + Doubles(4.5470025998e-2);
      p = p * z + Doubles(7.4953002686e-2);
      p = p * z + Doubles(1.6666752422e-1);
      return a + (a * z) * p;
    };
    const D angle = each([&](const Doubles& c, const Doubles& a) {
      const Doubles half_pi(1.57079632679489661923);
      const auto small = a <= Doubles(0.5);
      const Doubles s = asin_small(xsimd::select(small, a, xsimd::sqrt((Doubles(1.0) - a) * Doubles(0.5))));
      const Doubles asin_a = xsimd::select(small, s, half_pi - Doubles(2.0) * s);
      return xsimd::select(c < Doubles(0.0), half_pi + asin_a, half_pi - asin_a);
    }, x, abs_x);
    for (std::size_t k = 0; k < 3; ++k) {
      const Floats w = _mm_movelh_ps(_mm_cvtpd_ps(angle[2 * k]), _mm_cvtpd_ps(angle[2 * k + 1]));
      (w * tx[k]).store_aligned(wx[k]);
      (w * ty[k]).store_aligned(wy[k]);
      (w * tz[k]).store_aligned(wz[k]);
    }
  }
};

std::atomic<std::size_t> parts_seen{0};

}  // namespace

std::size_t take_mikktspace_parts_seen() { return parts_seen.exchange(0); }

MikkTSpaceCopies mikktspace_tangents(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                     std::span<const glm::vec2> uvs, std::span<std::uint32_t> indices,
                                     std::span<glm::vec4> tangents) {
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
  tbb::parallel_for(std::size_t(0), parts, [&](std::size_t part) {
    const std::uint32_t lo = std::uint32_t(n * part / parts), hi = std::uint32_t(n * (part + 1) / parts);
    const auto mine = [&](std::uint32_t v) { return same[v] >= lo && same[v] < hi; };
    // Faces wait in a batch of four for their directions and their corners' weights, then are summed in order.
    CornerBatch batch;
    struct Waiting {
      const std::uint32_t* corner;
      bool own[3];
    };
    std::array<Waiting, CornerBatch::kFaces> waiting{};
    int count = 0;
    const auto sum_batch = [&] {
      batch.compute();
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
      if (++count == CornerBatch::kFaces) sum_batch();
    }
    if (count > 0) sum_batch();
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
