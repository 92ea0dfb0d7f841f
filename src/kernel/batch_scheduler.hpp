#pragma once
// The one way a program's group of batches (ShadingProgram::shade: 1 .. kMaxGroupBatches batches that write no
// pixel in common) is shaded: in stages, each a plain member function of the program's stage type, called by
// shade_in_stages() below. The scheduler owns the order, the pairing and the lane packing; the stages own what is
// computed. A new technique is a new trace (and, if interleaving two batches' loops pays, a trace_pair), a new
// shadow or AO mode a change to light: neither touches this file.
//
// The stages, in the order they run for each batch (S: the program's stage type, see BatchStages):
//   setup(in)                quad-wise: what needs whole quads (derivatives, LODs, the tangent frame, the ray);
//                            setup_pair(a, b, ...), where S has it, sets up two batches at once.
//   surface(in, setup)       what the trace walks and the surface is sampled on, for this batch.
//   trace(surface, setup)    the hit; trace_pair(...), where S has it, traces two batches at once (their loops
//                            interleaved); else a pair's batches are traced one after the other.
//   surface_at_hit(...)      the surface's samples at the hit (colour, normal, AO, ...).
//   light(in, setup, ...)    lighting: the lane-wise outputs (S::output_values).
//   finish(in, setup, out)   quad-wise again, on the batch's own lanes: what reads whole quads after the hit (the
//                            displaced depth reads the world position's derivatives) or the batch's own inputs.
// Everything from surface to light is lane by lane: each lane's result depends on its own inputs only. So the
// scheduler runs those stages of two batches side by side (a pair: each stage's chain of dependent operations
// overlaps the other batch's), and may run them on packed batches (S::kPackLanes): two sparse batches' covered
// lanes in one (simd::LanePacking), or a group's in as few batches as hold them (simd::LaneCompaction). Neither
// changes a bit of any lane's result.
#include <algorithm>
#include <bit>
#include <concepts>
#include <cstdint>
#include <new>
#include <type_traits>

#include "kernel/batch.hpp"
#include "kernel/lane_compaction.hpp"
#include "kernel/lane_packing.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

// Which packed batches a program's lane-wise stages may run on.
enum class PackLanes {
  Never,
  Pairs,   // a pair whose covered lanes fit in one batch runs as one (simd::LanePacking)
  Groups,  // a group whose covered lanes fit in fewer batches runs as those (simd::LaneCompaction)
};

// What shade_in_stages() calls (and, where S has them, setup_pair and trace_pair). For packed batches, visitors name the lane values each way, so that no packing code
// lists members by hand: S::Setup::values(f), s.lane_inputs(f) (what the lane-wise stages read of Fragments) and
// S::output_values(f) (what they write of ShadeOutput) call f(value) for each, `value(x)` being that Float in x.
// A Setup's `active`, where it has one, is the lanes the lane-wise stages work on: a packed batch's used lanes.
template <class S>
concept BatchStages = requires(const S& s, const Fragments& in, const typename S::Setup& setup,
                               const typename S::Hit& hit, typename S::Hit& hit_out,
                               const typename S::AtHit& at, ShadeOutput& out) {
  { s.setup(in) } -> std::same_as<typename S::Setup>;
  s.surface(in, setup);
  { s.trace(s.surface(in, setup), setup) } -> std::same_as<typename S::Hit>;
  { s.surface_at_hit(setup, s.surface(in, setup), hit) } -> std::same_as<typename S::AtHit>;
  s.light(in, setup, s.surface(in, setup), at, out);
  s.finish(in, setup, out);
  { S::kPackLanes } -> std::convertible_to<PackLanes>;
};

// GCC 12 says the per-batch arrays below "may be used uninitialized" where it passes them to a stage it does not
// inline: it cannot see that the callee reads only the entries filled (the group's batches, or its packed ones).
// Filling the rest would cost stores per group in the hot path.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace stages_detail {

// The lane-wise stages of batches 0 .. n - 1, two at a time, each stage of a pair side by side. Inlined into the
// scheduler: a call between them sent every pair's setups through the stack and back (normal mapping's pairs cost
// more instructions than its own pair function had).
template <class S>
[[gnu::always_inline]] inline void shade_lanes(const S& s, const Fragments* const* in, const typename S::Setup* setups, ShadeOutput* const* out,
                 int n) {
  for (int k = 0; k < n; k += 2) {
    if (k + 1 == n) {
      decltype(auto) surface = s.surface(*in[k], setups[k]);
      const typename S::AtHit at = s.surface_at_hit(setups[k], surface, s.trace(surface, setups[k]));
      s.light(*in[k], setups[k], surface, at, *out[k]);
      return;
    }
    const typename S::Setup &setup_a = setups[k], &setup_b = setups[k + 1];
    decltype(auto) surface_a = s.surface(*in[k], setup_a);
    decltype(auto) surface_b = s.surface(*in[k + 1], setup_b);
    typename S::Hit hit_a, hit_b;
    if constexpr (requires { s.trace_pair(surface_a, setup_a, hit_a, surface_b, setup_b, hit_b); }) {
      s.trace_pair(surface_a, setup_a, hit_a, surface_b, setup_b, hit_b);
    } else {
      hit_a = s.trace(surface_a, setup_a);
      hit_b = s.trace(surface_b, setup_b);
    }
    const typename S::AtHit at_a = s.surface_at_hit(setup_a, surface_a, hit_a);
    const typename S::AtHit at_b = s.surface_at_hit(setup_b, surface_b, hit_b);
    s.light(*in[k], setup_a, surface_a, at_a, *out[k]);
    s.light(*in[k + 1], setup_b, surface_b, at_b, *out[k + 1]);
  }
}

template <class Setup>
void set_active(Setup& setup, const simd::Mask& lanes) {
  if constexpr (requires { setup.active; }) setup.active = lanes;
}

// The lane-wise stages of a pair whose covered lanes fit in one batch: run once, each batch's lanes back.
template <class S>
void shade_packed_pair(const S& s, const Fragments& a, const Fragments& b, const typename S::Setup& setup_a,
                       const typename S::Setup& setup_b, ShadeOutput& out_a, ShadeOutput& out_b,
                       std::uint32_t covered_a, std::uint32_t covered_b) {
  using Setup = typename S::Setup;
  const simd::LanePacking packing(covered_a, covered_b);
  Fragments packed_in;
  Setup packed_setup;
  s.lane_inputs([&](auto value) { value(packed_in) = packing.pack(value(a), value(b)); });
  Setup::values([&](auto value) { value(packed_setup) = packing.pack(value(setup_a), value(setup_b)); });
  const simd::Mask used = simd::from_bits((1u << (std::popcount(covered_a) + std::popcount(covered_b))) - 1u);
  packed_in.covered = used;
  set_active(packed_setup, used);
  const Fragments* const packed_in_of[1] = {&packed_in};
  ShadeOutput lit;
  ShadeOutput* const lit_of[1] = {&lit};
  shade_lanes(s, packed_in_of, &packed_setup, lit_of, 1);
  out_a = lit;
  S::output_values([&](auto value) { value(out_a) = packing.first(value(lit)); });
  out_b = lit;
  S::output_values([&](auto value) { value(out_b) = packing.second(value(lit)); });
}

// The lane-wise stages of a group whose covered lanes fit in fewer batches (lanes): packed, run, and each batch's
// lanes unpacked into its output.
template <class S>
void shade_compacted(const S& s, const Fragments* const* in, const typename S::Setup* setups, ShadeOutput* const* out,
                     const simd::LaneCompaction& lanes) {
  using Setup = typename S::Setup;
  constexpr int kMax = simd::LaneCompaction::kMaxBatches;
  const int packed = lanes.packed_batches();
  Fragments packed_in[kMax];
  Setup packed_setup[kMax];
  const Fragments* packed_in_of[kMax];
  ShadeOutput lit[kMax];
  ShadeOutput* lit_of[kMax];
  for (int w = 0; w < packed; ++w) {
    s.lane_inputs([&](auto value) {
      value(packed_in[w]) = lanes.pack(w, [&](int k) -> const simd::Float& { return value(*in[k]); });
    });
    packed_in[w].covered = lanes.used(w);
    Setup::values([&](auto value) {
      value(packed_setup[w]) = lanes.pack(w, [&](int k) -> const simd::Float& { return value(setups[k]); });
    });
    set_active(packed_setup[w], lanes.used(w));
    packed_in_of[w] = &packed_in[w];
    lit_of[w] = &lit[w];
  }
  shade_lanes(s, packed_in_of, packed_setup, lit_of, packed);
  // What the packed batches' loops executed: each one's longest lane times the lanes, counted with the batch its
  // first lane came from.
  int executed[kMax] = {};
  for (int w = 0; w < packed; ++w) {
    alignas(64) float iterations[simd::kLanes];
    xsimd::select(lanes.used(w), lit[w].iterations, simd::Float(0.0f)).store_aligned(iterations);
    executed[lanes.first_source(w)] += int(*std::max_element(iterations, iterations + simd::kLanes)) * simd::kLanes;
  }
  for (int k = 0; k < lanes.batches(); ++k) {
    ShadeOutput& o = *out[k];
    o = lit[0];
    S::output_values([&](auto value) {
      value(o) = lanes.unpack(k, [&](int w) -> const simd::Float& { return value(lit[w]); });
    });
    // Uncovered lanes ran no iteration (unpack() leaves them undefined): the batch's useful iterations are its
    // covered lanes'.
    o.iterations = xsimd::select(in[k]->covered, o.iterations, simd::Float(0.0f));
    o.executed_lane_iterations = executed[k];
  }
}

// The lane-wise stages of batches 0 .. n - 1 on packed batches, where S packs lanes and theirs fit in fewer;
// false (nothing run) otherwise.
template <class S>
bool shade_packed(const S& s, const Fragments* const* in, const typename S::Setup* setups, ShadeOutput* const* out,
                  int n) {
  if constexpr (S::kPackLanes == PackLanes::Pairs) {
    if (n != 2) return false;
    const std::uint32_t covered_a = simd::to_bits(in[0]->covered), covered_b = simd::to_bits(in[1]->covered);
    if (!simd::LanePacking::fits(covered_a, covered_b)) return false;
    shade_packed_pair(s, *in[0], *in[1], setups[0], setups[1], *out[0], *out[1], covered_a, covered_b);
    return true;
  } else if constexpr (S::kPackLanes == PackLanes::Groups) {
    if (n < 2) return false;
    std::uint32_t covered[kMaxGroupBatches];
    for (int k = 0; k < n; ++k) covered[k] = simd::to_bits(in[k]->covered);
    const simd::LaneCompaction lanes(covered, n);
    if (lanes.packed_batches() == n) return false;
    shade_compacted(s, in, setups, out, lanes);
    return true;
  } else {
    return false;
  }
}

}  // namespace stages_detail

// Shades batches in[0 .. n - 1] into out[0 .. n - 1] (1 <= n <= kMaxGroupBatches) through the stages of s: every
// batch set up (two at once where S has setup_pair), then the lane-wise stages (on packed batches where S packs
// lanes and the group's fit in fewer, else two batches at a time), then each batch finished. Each batch gets the
// results it gets alone.
template <BatchStages S>
void shade_in_stages(const S& s, const Fragments* const* in, ShadeOutput* const* out, int n) {
  typename S::Setup setups[kMaxGroupBatches];
  int k = 0;
  if constexpr (requires { s.setup_pair(*in[0], *in[0], setups[0], setups[0]); })
    for (; k + 1 < n; k += 2) s.setup_pair(*in[k], *in[k + 1], setups[k], setups[k + 1]);
  // Each setup made in its slot: assigned (setups[k] = s.setup(...)), the returned Setup was made in a temporary
  // and copied (displacement's with rep movsq), once per batch.
  static_assert(std::is_trivially_destructible_v<typename S::Setup>, "a slot's old Setup is not destroyed");
  for (; k < n; ++k) ::new (&setups[k]) typename S::Setup(s.setup(*in[k]));
  if (!stages_detail::shade_packed(s, in, setups, out, n)) stages_detail::shade_lanes(s, in, setups, out, n);
  for (k = 0; k < n; ++k) s.finish(*in[k], setups[k], *out[k]);
}

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

}  // namespace qdmr::QDMR_ISA_NAMESPACE
