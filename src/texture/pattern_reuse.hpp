#pragma once
// PatternReuse: while one lives, a procedural pattern asked for again (a layer's albedo beside its heights, the
// blend weights' terrain beside the mesh it displaces: one spec read twice) is copied from its first evaluation
// instead of evaluated again. A pattern is a function of its spec alone (procedural_key), so the same bits.
// Patterns up to 1024 x 1024 are kept, 32 MiB in all; the last scope to end frees them.
namespace qdmr {

class PatternReuse {
 public:
  PatternReuse();
  ~PatternReuse();
  PatternReuse(const PatternReuse&) = delete;
  PatternReuse& operator=(const PatternReuse&) = delete;
};

}  // namespace qdmr
