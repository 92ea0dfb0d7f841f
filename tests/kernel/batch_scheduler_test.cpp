// The batch scheduler (kernel/batch_scheduler.hpp) on a toy program whose stages compute lane-wise values from
// whole-quad ones: whatever the group size, pairing or lane packing, every covered lane gets the bits its batch
// gets alone, every batch is set up before any lane-wise stage runs and finished after the last one, and packing
// runs fewer traces where the covered lanes fit in fewer batches.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "kernel/batch_scheduler.hpp"
#include "support/lane_values.hpp"

namespace qdmr {
namespace {

using simd::Float;
using simd::kLanes;
using test::bits_of;

// The stages record what ran, in order: 's' setup, 'u' surface, 't' trace, 'p' trace_pair, 'a' surface at hit,
// 'l' light, 'f' finish. Without Paired the stages have no trace_pair (the scheduler traces a pair's batches one
// after the other).
template <PackLanes Packing, bool Paired = true>
struct ToyStages {
  static constexpr PackLanes kPackLanes = Packing;
  struct Setup {
    Float slope;  // whole quads: the derivative of u along x
    simd::Mask active;
    template <class F>
    static constexpr void values(F&& f) {
      f([](auto& s) -> auto& { return s.slope; });
    }
  };
  struct Surface {
    Float u, v;
  };
  struct Hit {
    Float s;
  };
  struct AtHit {
    Float value;
    simd::Mask active;
  };

  std::string* log;

  Setup setup(const Fragments& in) const {
    *log += 's';
    return {simd::quad_ddx(in.varyings[kU]), in.covered};
  }
  Surface surface(const Fragments& in, const Setup&) const {
    *log += 'u';
    return {in.varyings[kU], in.varyings[kV]};
  }
  Hit trace(const Surface& surface, const Setup& setup) const {
    *log += 't';
    return {surface.u * Float(3.0f) + setup.slope};
  }
  void trace_pair(const Surface& a, const Setup& setup_a, Hit& hit_a, const Surface& b, const Setup& setup_b,
                  Hit& hit_b) const
    requires Paired
  {
    *log += 'p';
    hit_a = trace(a, setup_a);
    hit_b = trace(b, setup_b);
  }
  AtHit surface_at_hit(const Setup& setup, const Surface& surface, const Hit& hit) const {
    *log += 'a';
    return {hit.s / (surface.v + Float(0.5f)), setup.active};
  }
  void light(const Fragments& in, const Setup&, const Surface&, const AtHit& at, ShadeOutput& out) const {
    *log += 'l';
    ShadeOutput::lane_values([&](auto value) { value(out) = Float(0.0f); });
    out.color[0] = at.value;
    out.color[1] = in.pixel_x;
    // The lanes the stages worked on must be the covered ones, packed or not.
    out.color[2] = xsimd::select(at.active, Float(1.0f), Float(0.0f));
    out.iterations = xsimd::floor(xsimd::abs(at.value)) + Float(1.0f);
  }
  void finish(const Fragments& in, const Setup&, ShadeOutput& out) const {
    *log += 'f';
    out.depth = simd::quad_ddy(in.varyings[kV]) + out.color[0];
  }
  template <class F>
  void lane_inputs(F&& f) const {
    f([](auto& in) -> auto& { return in.pixel_x; });
    f([](auto& in) -> auto& { return in.varyings[kU]; });
    f([](auto& in) -> auto& { return in.varyings[kV]; });
  }
  template <class F>
  static void output_values(F&& f) {
    ShadeOutput::lane_values(f);
  }
};

Fragments fragments(std::mt19937& random, std::uint32_t covered) {
  std::uniform_real_distribution<float> value(0.0f, 4.0f);
  alignas(64) float u[kLanes], v[kLanes], x[kLanes];
  for (int l = 0; l < kLanes; ++l) {
    u[l] = value(random);
    v[l] = value(random);
    x[l] = float(l) + value(random);
  }
  Fragments in;
  in.varyings[kU] = Float::load_aligned(u);
  in.varyings[kV] = Float::load_aligned(v);
  in.pixel_x = Float::load_aligned(x);
  in.covered = simd::from_bits(covered);
  return in;
}

template <PackLanes Packing, bool Paired>
void expect_group_as_alone(int n, bool sparse, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::string log;
  const ToyStages<Packing, Paired> stages{&log};
  Fragments in[kMaxGroupBatches];
  const Fragments* in_of[kMaxGroupBatches];
  ShadeOutput out[kMaxGroupBatches], alone[kMaxGroupBatches];
  ShadeOutput* out_of[kMaxGroupBatches];
  int covered_lanes = 0;
  for (int k = 0; k < n; ++k) {
    std::uint32_t covered = std::uint32_t(random()) & ((1u << kLanes) - 1u);
    if (sparse) covered &= 1u << (random() % kLanes);  // one lane at most
    in[k] = fragments(random, covered);
    in_of[k] = &in[k];
    out_of[k] = &out[k];
    covered_lanes += std::popcount(covered);
    ShadeOutput* const alone_of[1] = {&alone[k]};
    shade_in_stages(stages, &in_of[k], alone_of, 1);
  }
  log.clear();
  shade_in_stages(stages, in_of, out_of, n);

  for (int k = 0; k < n; ++k) {
    alignas(64) float got[4][kLanes], want[4][kLanes], iterations[kLanes];
    const Float* const got_values[4] = {&out[k].color[0], &out[k].color[1], &out[k].color[2], &out[k].depth};
    const Float* const want_values[4] = {&alone[k].color[0], &alone[k].color[1], &alone[k].color[2], &alone[k].depth};
    for (int c = 0; c < 4; ++c) {
      got_values[c]->store_aligned(got[c]);
      want_values[c]->store_aligned(want[c]);
    }
    out[k].iterations.store_aligned(iterations);
    const std::uint32_t covered = simd::to_bits(in[k].covered);
    for (int l = 0; l < kLanes; ++l) {
      if (!((covered >> l) & 1u)) continue;
      for (int c = 0; c < 4; ++c)
        ASSERT_EQ(bits_of(got[c][l]), bits_of(want[c][l])) << "batch " << k << " lane " << l << " value " << c;
      ASSERT_EQ(got[2][l], 1.0f) << "the lane worked as an active lane";
      ASSERT_GE(iterations[l], 1.0f);
    }
  }
  // Every setup first, every finish last, each batch once.
  ASSERT_EQ(log.find_first_not_of('s'), std::size_t(n)) << log;
  ASSERT_EQ(log.substr(log.size() - std::size_t(n)), std::string(std::size_t(n), 'f')) << log;
  const auto count = [&](char c) { return int(std::count(log.begin(), log.end(), c)); };
  const int batches_run = count('l');
  const bool packs = Packing == PackLanes::Groups ? n > 1 && (covered_lanes + kLanes - 1) / kLanes < n
                                                  : Packing == PackLanes::Pairs && n == 2 && covered_lanes <= kLanes;
  if (packs)
    EXPECT_EQ(batches_run, std::max(1, (covered_lanes + kLanes - 1) / kLanes)) << log;
  else
    EXPECT_EQ(batches_run, n) << log;
  // Batches run two at a time: a pair traces in one call, where the stages have trace_pair.
  EXPECT_EQ(count('p'), Paired ? batches_run / 2 : 0) << log;
  EXPECT_EQ(count('t'), batches_run) << log;
}

TEST(BatchScheduler, EveryGroupGivesEachLaneItsBitsAlone) {
  for (int n = 1; n <= kMaxGroupBatches; ++n) {
    for (std::uint32_t seed = 1; seed <= 20; ++seed) {
      for (bool sparse : {false, true}) {
        expect_group_as_alone<PackLanes::Never, true>(n, sparse, seed);
        expect_group_as_alone<PackLanes::Pairs, true>(n, sparse, seed);
        expect_group_as_alone<PackLanes::Groups, true>(n, sparse, seed);
        expect_group_as_alone<PackLanes::Never, false>(n, sparse, seed);
        expect_group_as_alone<PackLanes::Pairs, false>(n, sparse, seed);
        expect_group_as_alone<PackLanes::Groups, false>(n, sparse, seed);
      }
    }
  }
}

// A packed group's iterations: uncovered lanes report none, and the loops' executed lane-iterations are counted
// once per packed batch, with a batch of the group.
TEST(BatchScheduler, PackedGroupsCountTheirIterationsOnce) {
  std::mt19937 random(7);
  std::string log;
  const ToyStages<PackLanes::Groups> stages{&log};
  Fragments in[4];
  const Fragments* in_of[4];
  ShadeOutput out[4];
  ShadeOutput* out_of[4];
  for (int k = 0; k < 4; ++k) {
    in[k] = fragments(random, 0x3u);
    in_of[k] = &in[k];
    out_of[k] = &out[k];
  }
  shade_in_stages(stages, in_of, out_of, 4);
  int executed = 0;
  for (int k = 0; k < 4; ++k) {
    alignas(64) float iterations[kLanes];
    out[k].iterations.store_aligned(iterations);
    for (int l = 2; l < kLanes; ++l) EXPECT_EQ(iterations[l], 0.0f) << "batch " << k << " lane " << l;
    EXPECT_GE(out[k].executed_lane_iterations, 0);
    executed += out[k].executed_lane_iterations;
  }
  EXPECT_GT(executed, 0);
  EXPECT_EQ(executed % kLanes, 0);
}

}  // namespace
}  // namespace qdmr
