#pragma once
// Frames of a scene's animation for `qdmr render --frames A:B[:STEP]` / `--frame N`, and output names with a frame
// number (`out_%04d.png`). Everything here is checked before anything is rendered: a bad range or pattern is one
// error, and no file is written.
#include <string>
#include <vector>

namespace qdmr::cli {

// The frames A, A + STEP, ... up to B (inclusive), each in 0 .. frame_count - 1. Throws qdmr::Error("--frames
// TEXT", ...) for text that is not A:B or A:B:STEP with integers A <= B, STEP >= 1, or frames outside the animation.
std::vector<int> parse_frame_range(const std::string& text, int frame_count);

// Whether a name holds a frame number: one %d or %0Nd (N 1 .. 9). `%%` is a literal %; any other % is an error
// (Error(option + " " + name, ...)), as is more than one frame number.
bool has_frame_number(const std::string& option, const std::string& name);

// The name with its frame number written in (a name without one is returned as it is, `%%` becoming `%`).
std::string frame_name(const std::string& name, int frame);

}  // namespace qdmr::cli
