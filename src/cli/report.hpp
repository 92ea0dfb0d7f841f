#pragma once
// qdmr report: the HTML page of a study's results, written by the Python report generator installed with qdmr
// (report/qdmr_report; docs/studies.md).
#include <string>
#include <vector>

namespace qdmr::cli {

struct ReportArgs {
  std::string results, output;  // output empty: RESULTS-report beside RESULTS
  int worst = 6, crop = 96;
  bool partial = false;
};

// Runs the generator and waits for it; its exit status (0, 1, or 2 for bad input).
int run_report(const ReportArgs& args);

}  // namespace qdmr::cli
