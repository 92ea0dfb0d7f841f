#include "qdmr/core/warning.hpp"

#include <atomic>

namespace qdmr {
namespace {

std::atomic<WarningSink*> current_sink{nullptr};

}  // namespace

void set_warning_sink(WarningSink* sink) { current_sink = sink; }

void warn(const std::string& message) {
  if (WarningSink* sink = current_sink.load()) sink->warn(message);
}

}  // namespace qdmr
