#include "cli/interrupt.hpp"

#include <signal.h>

#include "qdmr/core/progress.hpp"

namespace qdmr::cli {
namespace {

extern "C" void on_stop_signal(int) { request_stop(); }

}  // namespace

void stop_on_signals() {
  struct sigaction action{};
  action.sa_handler = on_stop_signal;
  action.sa_flags = SA_RESETHAND;  // the next one has the default effect: a second Ctrl-C ends the process
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

}  // namespace qdmr::cli
