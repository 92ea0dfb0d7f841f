#pragma once
// The warnings (qdmr/core/warning.hpp) given while one of these lives, for tests of what a run tells its user.
#include <mutex>
#include <string>
#include <vector>

#include "qdmr/core/warning.hpp"

namespace qdmr::test {

class CapturedWarnings final : public WarningSink {
public:
  CapturedWarnings() { set_warning_sink(this); }
  ~CapturedWarnings() override { set_warning_sink(nullptr); }
  CapturedWarnings(const CapturedWarnings&) = delete;
  CapturedWarnings& operator=(const CapturedWarnings&) = delete;

  void warn(const std::string& message) override {
    const std::lock_guard<std::mutex> guard(mutex_);
    lines_.push_back(message);
  }
  std::vector<std::string> lines() {
    const std::lock_guard<std::mutex> guard(mutex_);
    return lines_;
  }

private:
  std::mutex mutex_;
  std::vector<std::string> lines_;
};

}  // namespace qdmr::test
