#include "cli/step_progress.hpp"

#include <cstdio>

namespace qdmr::cli {

StepProgress::~StepProgress() {
  {
    const std::lock_guard<std::mutex> guard(mutex_);
    ending_ = true;
  }
  wake_.notify_all();
  if (ticker_.joinable()) ticker_.join();
}

void StepProgress::started(const void* step, const std::string& name) {
  const std::lock_guard<std::mutex> guard(mutex_);
  running_[step] = {name, Clock::now(), -1};
  if (terminal_ && !ticker_.joinable()) ticker_ = std::thread([this] { tick(); });
}

void StepProgress::advanced(const void* step, const std::string&, double fraction, double) {
  const std::lock_guard<std::mutex> guard(mutex_);
  if (const auto it = running_.find(step); it != running_.end()) it->second.fraction = fraction;
}

void StepProgress::finished(const void* step, const std::string& name, double seconds) {
  const std::lock_guard<std::mutex> guard(mutex_);
  running_.erase(step);
  if (step != shown_) return;
  shown_ = nullptr;
  std::fprintf(stderr, "\r%-.60s: %s in %.1f s%20s\n", name.c_str(), stop_requested() ? "stopped" : "done", seconds, "");
  std::fflush(stderr);
}

void StepProgress::warn(const std::string& message) {
  const std::lock_guard<std::mutex> guard(mutex_);
  if (!warned_.insert(message).second) return;
  // Over the progress line, if one is shown: the tick redraws it.
  std::fprintf(stderr, "%sqdmr: warning: %s\n", shown_ ? "\r\033[K" : "", message.c_str());
  std::fflush(stderr);
}

void StepProgress::tick() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!ending_) {
    wake_.wait_for(lock, std::chrono::milliseconds(200));
    // The newest step running for a second or more (a bake inside a texture build, say): short steps stay quiet.
    const auto now = Clock::now();
    const Running* newest = nullptr;
    const void* newest_step = nullptr;
    for (const auto& [step, r] : running_)
      if (now - r.start >= std::chrono::seconds(1) && (!newest || r.start > newest->start)) {
        newest = &r;
        newest_step = step;
      }
    if (!newest) continue;
    shown_ = newest_step;
    const double seconds = std::chrono::duration<double>(now - newest->start).count();
    if (newest->fraction >= 0)
      std::fprintf(stderr, "\r%-.60s %3d%% (%.0f s)   ", newest->name.c_str(), int(newest->fraction * 100.0), seconds);
    else
      std::fprintf(stderr, "\r%-.60s (%.0f s)   ", newest->name.c_str(), seconds);
    std::fflush(stderr);
  }
}

}  // namespace qdmr::cli
