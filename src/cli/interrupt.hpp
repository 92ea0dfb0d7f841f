#pragma once
// Ctrl-C for every command: SIGINT and SIGTERM ask the run to stop (qdmr::request_stop, qdmr/core/progress.hpp)
// at its next configuration, check or bake rows, with nothing half-written; a second signal ends the process at
// once.
namespace qdmr::cli {

// The exit status of a run stopped by a signal (documented in docs/studies.md and docs/checks.md).
inline constexpr int kExitInterrupted = 130;

void stop_on_signals();

}  // namespace qdmr::cli
