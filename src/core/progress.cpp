#include "qdmr/core/progress.hpp"

#include <algorithm>
#include <csignal>

namespace qdmr {
namespace {

volatile std::sig_atomic_t stop_flag = 0;  // set from a signal handler: a sig_atomic_t, not a std::atomic
std::atomic<ProgressSink*> current_sink{nullptr};

}  // namespace

void request_stop() noexcept { stop_flag = 1; }
void clear_stop_request() noexcept { stop_flag = 0; }
bool stop_requested() noexcept { return stop_flag != 0; }
void throw_if_stop_requested() {
  if (stop_requested()) throw Interrupted();
}

void set_progress_sink(ProgressSink* sink) { current_sink = sink; }

ProgressStep::ProgressStep(std::string name, double units)
    : name_(std::move(name)), units_(units), start_(std::chrono::steady_clock::now()), sink_(current_sink.load()) {
  throw_if_stop_requested();
  if (sink_) sink_->started(this, name_);
}

ProgressStep::~ProgressStep() {
  if (sink_) sink_->finished(this, name_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
}

void ProgressStep::advance(double done) {
  throw_if_stop_requested();
  const double total = done_.fetch_add(done) + done;
  if (sink_)
    sink_->advanced(this, name_, units_ > 0 ? std::min(1.0, total / units_) : -1.0,
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
}

}  // namespace qdmr
