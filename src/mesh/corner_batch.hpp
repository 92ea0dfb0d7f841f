#pragma once
// MikkTSpace's arithmetic per corner (mesh/mikktspace.cpp), a batch of faces at a time, a face a SIMD lane: SSE2's
// four lanes (x86-64's baseline, compiled into mikktspace.cpp) or AVX2's eight (mesh/corner_batch_avx2.cpp,
// compiled with the AVX2 kernel's flags: -mavx2 -mno-fma, -ffp-contract=off; taken where the CPU has AVX2). For
// each face its +u direction and UV orientation (face_of), then for each corner k, one vector of the batch's lanes,
// the corner's direction (the face's +u in the plane of the corner's normal, normalised) times its angle (between
// its edges projected onto that plane). Every lane takes the scalar formulas' operations in their order (glm's
// dot is (x x + y y) + z z, its length the square root of that, a vector over a scalar three divisions;
// deterministic_acos's argument chosen per lane, its polynomial evaluated once), and both ISAs round as the scalar
// operations do (IEEE division and square root, no fused multiply-add): the same bits at either width. The three
// corners' vectors are independent: their divisions and square roots overlap.
#include <immintrin.h>

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <type_traits>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <xsimd/xsimd.hpp>

namespace qdmr::mesh_detail {

template <int Faces>
struct CornerBatch {
  static constexpr int kFaces = Faces;
  // Input per face (lane i): its corners' positions, UVs and normals.
  alignas(32) float px[3][kFaces]{}, py[3][kFaces]{}, pz[3][kFaces]{};
  alignas(32) float u[3][kFaces]{}, v[3][kFaces]{};
  alignas(32) float nx[3][kFaces]{}, ny[3][kFaces]{}, nz[3][kFaces]{};
  // Output: corner k of face i at [k][i]; per face whether it is degenerate or preserves the UV orientation.
  alignas(32) float wx[3][kFaces]{}, wy[3][kFaces]{}, wz[3][kFaces]{};
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
};

// What xsimd 8 lacks, by intrinsics: a float mask as bits, and float lanes to double lanes and back (xsimd
// converts only between batches of one lane count). Floats(Arch) to two Doubles(Arch), its low and high halves.
template <class Arch>
struct CornerLanes;

template <>
struct CornerLanes<xsimd::sse2> {
  using Floats = xsimd::batch<float, xsimd::sse2>;
  using Doubles = xsimd::batch<double, xsimd::sse2>;
  static std::uint32_t bits(const xsimd::batch_bool<float, xsimd::sse2>& m) { return std::uint32_t(_mm_movemask_ps(m)); }
  static Doubles low(const Floats& x) { return _mm_cvtps_pd(x); }
  static Doubles high(const Floats& x) { return _mm_cvtps_pd(_mm_movehl_ps(x, x)); }
  static Floats narrow(const Doubles& lo, const Doubles& hi) { return _mm_movelh_ps(_mm_cvtpd_ps(lo), _mm_cvtpd_ps(hi)); }
};

#ifdef __AVX2__
template <>
struct CornerLanes<xsimd::avx2> {
  using Floats = xsimd::batch<float, xsimd::avx2>;
  using Doubles = xsimd::batch<double, xsimd::avx2>;
  static std::uint32_t bits(const xsimd::batch_bool<float, xsimd::avx2>& m) { return std::uint32_t(_mm256_movemask_ps(m)); }
  static Doubles low(const Floats& x) { return _mm256_cvtps_pd(_mm256_castps256_ps128(x)); }
  static Doubles high(const Floats& x) { return _mm256_cvtps_pd(_mm256_extractf128_ps(x, 1)); }
  static Floats narrow(const Doubles& lo, const Doubles& hi) {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm256_cvtpd_ps(lo)), _mm256_cvtpd_ps(hi), 1);
  }
};
#endif

template <class Arch>
void compute_corners(CornerBatch<int(xsimd::batch<float, Arch>::size)>& b) {
  using Lanes = CornerLanes<Arch>;
  using Floats = typename Lanes::Floats;
  using Doubles = typename Lanes::Doubles;
  using V = std::array<Floats, 3>;       // one vector per corner
  using D = std::array<Doubles, 2 * 3>;  // a V's low and high lanes in double
  constexpr int kFaces = int(Floats::size);
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
  const auto add = [&](const V& a, const V& c) { return each([](const Floats& x, const Floats& y) { return x + y; }, a, c); };
  const auto sub = [&](const V& a, const V& c) { return each([](const Floats& x, const Floats& y) { return x - y; }, a, c); };
  const auto mul = [&](const V& a, const V& c) { return each([](const Floats& x, const Floats& y) { return x * y; }, a, c); };
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
  const V px_ = load(b.px), py_ = load(b.py), pz_ = load(b.pz);
  // face_of: the UV area's sign and the +u direction, os * (+-1 / |os|), where both are usable.
  const Floats d1x = px_[1] - px_[0], d1y = py_[1] - py_[0], d1z = pz_[1] - pz_[0];
  const Floats d2x = px_[2] - px_[0], d2y = py_[2] - py_[0], d2z = pz_[2] - pz_[0];
  const Floats u0 = Floats::load_aligned(b.u[0]), v0 = Floats::load_aligned(b.v[0]);
  const Floats t21x = Floats::load_aligned(b.u[1]) - u0, t21y = Floats::load_aligned(b.v[1]) - v0;
  const Floats t31x = Floats::load_aligned(b.u[2]) - u0, t31y = Floats::load_aligned(b.v[2]) - v0;
  const Floats area = t21x * t31y - t21y * t31x;
  const auto keeps = area > Floats(0.0f);
  const Floats osx = t31y * d1x - t21y * d2x, osy = t31y * d1y - t21y * d2y, osz = t31y * d1z - t21y * d2z;
  const Floats os_len = xsimd::sqrt((osx * osx + osy * osy) + osz * osz);
  const Floats scale = xsimd::select(keeps, Floats(1.0f), Floats(-1.0f)) / os_len;
  const auto ok = (xsimd::abs(area) > Floats(std::numeric_limits<float>::min())) & usable(os_len);
  b.preserving = Lanes::bits(keeps);
  b.degenerate = ~Lanes::bits(ok) & ((1u << kFaces) - 1u);
  const Floats ux = osx * scale, uy = osy * scale, uz = osz * scale;

  V nx_ = load(b.nx), ny_ = load(b.ny), nz_ = load(b.nz);
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
  const auto wide = [](const V& x) {
    D d;
    for (std::size_t g = 0; g < x.size(); ++g) {
      d[2 * g] = Lanes::low(x[g]);
      d[2 * g + 1] = Lanes::high(x[g]);
    }
    return d;
  };
  const D aa = wide(dot(ex, ey, ez, ex, ey, ez)), bb = wide(dot(fx, fy, fz, fx, fy, fz)),
          ab = wide(dot(ex, ey, ez, fx, fy, fz));
  // The corner's angle in double: cosine ab / sqrt(aa bb) (0 where aa bb is not positive and finite), then
  // deterministic_acos (std::clamp, through which NaN passes, then its branch).
  const D lengths2 = each([](const Doubles& a, const Doubles& c) { return a * c; }, aa, bb);
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
    const Floats w = Lanes::narrow(angle[2 * k], angle[2 * k + 1]);
    (w * tx[k]).store_aligned(b.wx[k]);
    (w * ty[k]).store_aligned(b.wy[k]);
    (w * tz[k]).store_aligned(b.wz[k]);
  }
}

}  // namespace qdmr::mesh_detail

namespace qdmr::avx2 {
// compute_corners<xsimd::avx2> (mesh/corner_batch_avx2.cpp); call it only where the CPU has AVX2.
void compute_corners(mesh_detail::CornerBatch<8>& batch);
}  // namespace qdmr::avx2
