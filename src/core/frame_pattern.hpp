#pragma once
// Frame numbers: ranges FIRST:LAST[:STEP] and names holding a frame number (`out_%04d.png`, `h_%04d.exr`). The
// `qdmr render --frames/--frame` outputs and a height layer's file sequence share them. Every function throws
// qdmr::Error(where, what), `where` being what the caller names (an option, or a scene file and field).
#include <string>
#include <vector>

namespace qdmr {

// FIRST, FIRST + STEP, ... up to LAST (inclusive).
struct FrameRange {
  int first = 0;
  int last = 0;
  int step = 1;
  int size() const { return (last - first) / step + 1; }
  std::vector<int> frames() const;
};

// Text A:B or A:B:STEP with integers 0 <= A <= B and STEP >= 1.
FrameRange parse_frame_range(const std::string& where, const std::string& text);

// Whether a name holds a frame number: one %d or %0Nd (N 1 .. 9). `%%` is a literal %; any other % is an error,
// as is more than one frame number.
bool has_frame_number(const std::string& where, const std::string& name);

// The name with its frame number written in (a name without one is returned as it is, `%%` becoming `%`).
std::string frame_name(const std::string& name, int frame);

}  // namespace qdmr
