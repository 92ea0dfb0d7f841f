#pragma once
// Which qdmr this is: the release version, and the bits version of its output.
//
// The bits version is a number for the output bits. Two builds with the same bits version render a scene to the
// same bits (any thread count, tile size, ISA, machine); a change that alters any rendered bit bumps it, with
// the reason in docs/bits-changelog.md. Images (metadata "qdmr:bits_version"), stats JSON and check manifests
// carry it, so a golden made by another bits version is named as such instead of failing as a wall of pixel
// differences. See docs/checks.md.
namespace qdmr {

inline constexpr int kBitsVersion = 7;

const char* version();  // "0.1.0", the project version of CMakeLists.txt

}  // namespace qdmr
