#pragma once
// Long steps (a cone or AO bake, a texture build) report how far they are, and stop when asked to (Ctrl-C).
//
// A ProgressStep lives while its step runs and tells the process-wide ProgressSink (set by the command: a line
// on a terminal; none by default, so a library user and CI hear nothing) when it starts, how far it is and when it
// ends. advance() also polls the process-wide stop request (request_stop(), safe in a signal handler) and throws
// qdmr::Interrupted once one was made, from whichever thread calls it: a parallel loop then stops within one
// chunk of work, and the exception leaves through the caller like any error (nothing half-built is kept).
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>

namespace qdmr {

class Interrupted : public std::runtime_error {
public:
  Interrupted() : std::runtime_error("interrupted") {}
};

void request_stop() noexcept;  // async-signal-safe
void clear_stop_request() noexcept;  // for a program that goes on after a stopped job
bool stop_requested() noexcept;
void throw_if_stop_requested();  // throws Interrupted

// Receives every step's events, from any thread (a sink locks what it shares).
class ProgressSink {
public:
  virtual ~ProgressSink() = default;
  virtual void started(const void* step, const std::string& name) = 0;
  virtual void advanced(const void* step, const std::string& name, double fraction, double seconds) = 0;
  virtual void finished(const void* step, const std::string& name, double seconds) = 0;
};

// The sink every step reports to from now on (nullptr: none). Set it before any step starts and keep it alive
// until the last one ended.
void set_progress_sink(ProgressSink* sink);

class ProgressStep {
public:
  // `units`: how much work the step has (advance() adds to it); 0 when it reports no fraction.
  ProgressStep(std::string name, double units = 0);
  ~ProgressStep();
  ProgressStep(const ProgressStep&) = delete;
  ProgressStep& operator=(const ProgressStep&) = delete;

  // `done` more units finished (thread-safe; cheap enough for every row of a bake). Throws Interrupted when a stop
  // was requested.
  void advance(double done = 0);

private:
  std::string name_;
  double units_;
  std::atomic<double> done_{0};
  std::chrono::steady_clock::time_point start_;
  ProgressSink* sink_;
};

}  // namespace qdmr
