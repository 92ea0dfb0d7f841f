#pragma once
// The canonical hash of a float image, what `qdmr check` stores for an exact check: SHA-1 over a header line
// "qdmr-canonical-1 <width> <height> <channels>\n" followed by every channel of every pixel as IEEE-754 binary32
// little-endian, rows from the top, channels interleaved in the image's order (colour: R, G, B), with every NaN
// written as 0x7fc00000 (so NaN payloads and signs do not matter; -0.0 and +0.0 stay different). Equal hashes mean
// bit-identical images on any machine. See docs/checks.md.
#include <span>
#include <string>

namespace qdmr {

// "sha1:" and 40 lowercase hex digits. `pixels` holds width * height * channels values, top row first.
std::string canonical_hash(int width, int height, int channels, std::span<const float> pixels);

}  // namespace qdmr
