#pragma once
// What the command does with long steps' progress (qdmr/core/progress.hpp): on a terminal, a line for the newest
// step that has run for a second ("relaxed cone map 4096x4096  37% (12 s)", refreshed five times a second by a
// thread of its own, then the step's time when it ends). The steps' times in `render --stats` come from the
// renderer itself (RenderStats::prepare_steps). Warnings (qdmr/core/warning.hpp) go to stderr as
// "qdmr: warning: ..." lines, each message once per process, on a line of their own (terminal or not).
#include <chrono>
#include <condition_variable>
#include <map>
#include <set>
#include <mutex>
#include <string>
#include <thread>

#include "qdmr/core/progress.hpp"
#include "qdmr/core/warning.hpp"

namespace qdmr::cli {

class StepProgress final : public ProgressSink, public WarningSink {
public:
  explicit StepProgress(bool terminal) : terminal_(terminal) {}
  ~StepProgress() override;
  void started(const void* step, const std::string& name) override;
  void advanced(const void* step, const std::string& name, double fraction, double seconds) override;
  void finished(const void* step, const std::string& name, double seconds) override;
  void warn(const std::string& message) override;

private:
  using Clock = std::chrono::steady_clock;
  struct Running {
    std::string name;
    Clock::time_point start;
    double fraction = -1;  // unknown
  };
  void tick();  // the terminal line's thread

  bool terminal_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool ending_ = false;
  std::thread ticker_;
  std::map<const void*, Running> running_;
  const void* shown_ = nullptr;  // the step on the terminal line now
  std::set<std::string> warned_;
};

}  // namespace qdmr::cli
