#pragma once
// What a run tells its user without failing: a bake cache entry that could not be written, say. One process-wide
// WarningSink receives them (set by the command: a "qdmr: warning: ..." line on stderr); none by default, so a
// library user hears nothing unless it sets one.
#include <string>

namespace qdmr {

class WarningSink {
public:
  virtual ~WarningSink() = default;
  virtual void warn(const std::string& message) = 0;  // from any thread
};

// The sink every warning goes to from now on (nullptr: none). Keep it alive while anything may warn.
void set_warning_sink(WarningSink* sink);

// Hands `message` (one line, no "warning:" prefix) to the sink, if there is one.
void warn(const std::string& message);

}  // namespace qdmr
