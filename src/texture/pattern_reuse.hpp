#pragma once
// PatternReuse: while one lives, the procedural patterns it names (procedural_key) are kept, with their cells, the
// first time they are made, and a second request copies them instead of evaluating the pattern again: a layer's
// albedo beside its heights, the blend weights' terrain beside the mesh it displaces (one spec read twice). A
// pattern is a function of its spec alone, so the same bits. The plan names the patterns the texture phase asks
// for twice (FramePlan::reused_patterns) and counts what they hold; a pattern larger than kMaxReusedPatternSide is
// never kept. The last scope naming a pattern frees it.
#include <cstdint>
#include <string>
#include <vector>

namespace qdmr {

inline constexpr int kMaxReusedPatternSide = 1024;

// What a kept pattern of size x size texels holds: heights and cells in floats.
constexpr std::uint64_t kept_pattern_bytes(int size) { return std::uint64_t(size) * std::uint64_t(size) * 2 * 4; }

class PatternReuse {
 public:
  explicit PatternReuse(std::vector<std::string> keys);
  ~PatternReuse();
  PatternReuse(const PatternReuse&) = delete;
  PatternReuse& operator=(const PatternReuse&) = delete;

 private:
  std::vector<std::string> keys_;
};

}  // namespace qdmr
