#include "core/frame_pattern.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>

#include "qdmr/core/error.hpp"

namespace qdmr {
namespace {

// Frame numbers fit an int with room for FIRST + STEP.
constexpr long long kMaxFrameNumber = 1000000000;

// One integer, the whole of `text`.
bool parse_int(const std::string& text, long long& out) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, out);
  return !text.empty() && ec == std::errc() && ptr == end;
}

// Calls on_text for literal text and on_number(width) for each frame number of a checked pattern.
template <class Text, class Number>
void scan(const std::string& where, const std::string& name, Text&& on_text, Number&& on_number) {
  for (std::size_t i = 0; i < name.size(); ++i) {
    if (name[i] != '%') {
      on_text(name[i]);
      continue;
    }
    if (i + 1 < name.size() && name[i + 1] == '%') {
      on_text('%');
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    int width = 0;
    if (j < name.size() && name[j] == '0') {
      ++j;
      if (j < name.size() && name[j] >= '1' && name[j] <= '9') width = name[j++] - '0';
    }
    if (j >= name.size() || name[j] != 'd')
      throw Error(where, "a '%' starts a frame number written %d or %0Nd (N from 1 to 9; %% for a literal %)");
    on_number(width);
    i = j;
  }
}

}  // namespace

std::vector<int> FrameRange::frames() const {
  std::vector<int> out;
  for (long long f = first; f <= last; f += step) out.push_back(int(f));
  return out;
}

FrameRange parse_frame_range(const std::string& where, const std::string& text) {
  const auto fail = [&](const std::string& what) { return Error(where, what); };
  std::vector<std::string> parts(1);
  for (char c : text) {
    if (c == ':')
      parts.emplace_back();
    else
      parts.back().push_back(c);
  }
  long long v[3] = {0, 0, 1};
  if (parts.size() < 2 || parts.size() > 3) throw fail("expected FIRST:LAST or FIRST:LAST:STEP (e.g. 0:119)");
  for (std::size_t i = 0; i < parts.size(); ++i)
    if (!parse_int(parts[i], v[i])) throw fail("'" + parts[i] + "' is not an integer");
  if (v[0] < 0) throw fail("frame numbers start at 0");
  if (v[1] > kMaxFrameNumber) throw fail("frame numbers end at " + std::to_string(kMaxFrameNumber));
  if (v[0] > v[1]) throw fail("the first frame is after the last");
  if (v[2] < 1) throw fail("the step must be at least 1");
  return {int(v[0]), int(v[1]), int(std::min<long long>(v[2], kMaxFrameNumber))};
}

bool has_frame_number(const std::string& where, const std::string& name) {
  int numbers = 0;
  scan(where, name, [](char) {}, [&](int) { ++numbers; });
  if (numbers > 1) throw Error(where, "holds more than one frame number");
  return numbers == 1;
}

std::string frame_name(const std::string& name, int frame) {
  std::string out;
  scan("", name, [&](char c) { out.push_back(c); },
       [&](int width) {
         char digits[32];
         std::snprintf(digits, sizeof digits, "%0*d", width, frame);
         out += digits;
       });
  return out;
}

}  // namespace qdmr
