// Long steps' progress and stopping (qdmr/core/progress.hpp): what a sink hears from a bake, and a stop request
// ending a bake with qdmr::Interrupted.
#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>
#include <string>
#include <vector>

#include "qdmr/bake/cone_map.hpp"
#include "qdmr/core/progress.hpp"

namespace qdmr {
namespace {

struct Recorder final : ProgressSink {
  std::mutex mutex;
  std::vector<std::string> starts, ends;
  std::vector<double> fractions;
  void started(const void*, const std::string& name) override {
    const std::lock_guard<std::mutex> guard(mutex);
    starts.push_back(name);
  }
  void advanced(const void*, const std::string&, double fraction, double) override {
    const std::lock_guard<std::mutex> guard(mutex);
    fractions.push_back(fraction);
  }
  void finished(const void*, const std::string& name, double) override {
    const std::lock_guard<std::mutex> guard(mutex);
    ends.push_back(name);
  }
};

HeightField bumps(int size) {
  HeightField f;
  f.width = f.height = size;
  f.h = ZeroedBuffer<double>(std::size_t(size) * std::size_t(size));
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) f.h[std::size_t(j * size + i)] = ((i * 7 + j * 13) % 17) / 16.0;
  return f;
}

TEST(Progress, ABakeReportsItsRowsToTheSink) {
  Recorder recorder;
  set_progress_sink(&recorder);
  const ConeMap map = bake_cone_map(bumps(64), ConeKind::Relaxed);
  set_progress_sink(nullptr);
  EXPECT_EQ(map.width, 64);
  ASSERT_EQ(recorder.starts, std::vector<std::string>{"relaxed cone map 64x64"});
  EXPECT_EQ(recorder.ends, recorder.starts);
  ASSERT_FALSE(recorder.fractions.empty());
  double most = 0;
  for (double f : recorder.fractions) {
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
    most = std::max(most, f);
  }
  EXPECT_EQ(most, 1.0);  // every row counted once: 64 of 64
}

TEST(Progress, AStopRequestEndsABakeWithInterrupted) {
  request_stop();
  EXPECT_TRUE(stop_requested());
  EXPECT_THROW(bake_cone_map(bumps(64), ConeKind::Conservative), Interrupted);
  clear_stop_request();
  EXPECT_FALSE(stop_requested());
  EXPECT_EQ(bake_cone_map(bumps(64), ConeKind::Conservative).width, 64);  // the next job runs
}

}  // namespace
}  // namespace qdmr
