// Writes keep to the threads asked for (WriteOptions::threads, qdmr/write/write.hpp): with 1, the calling thread
// alone encodes and compresses a PNG (its bands of rows, which otherwise run on oneTBB's workers) and a float EXR
// (OpenEXR's chunks, which otherwise go to a thread pool, codec/exr_writer.cpp), and the files hold the bytes of a
// write on every core. Measured by CPU time: the calling thread's (RUSAGE_THREAD) against the whole process's.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "qdmr/write/write.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

double cpu_seconds(int who) {
  rusage usage{};
  getrusage(who, &usage);
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + double(t.tv_usec) * 1e-6; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

struct CpuSplit {
  double caller = 0, others = 0;  // seconds of CPU on the calling thread, and on every other thread of the process
};

template <typename F>
CpuSplit cpu_of(F&& body) {
  const double thread0 = cpu_seconds(RUSAGE_THREAD), process0 = cpu_seconds(RUSAGE_SELF);
  body();
  const double thread1 = cpu_seconds(RUSAGE_THREAD), process1 = cpu_seconds(RUSAGE_SELF);
  return {thread1 - thread0, (process1 - process0) - (thread1 - thread0)};
}

// A smooth RGB image with some noise: real work for the compressors (tens of ms each at this size).
std::vector<float> test_image(int width, int height) {
  std::vector<float> pixels(std::size_t(width) * std::size_t(height) * 3);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const std::size_t p = i / 3;
    const float x = float(p % std::size_t(width)), y = float(p / std::size_t(width));
    pixels[i] = 0.5f + 0.4f * std::sin(0.01f * x + 0.02f * y + float(i % 3)) +
                0.05f * float(sample_hash(std::uint32_t(i)) % 1000) / 1000.0f;
  }
  return pixels;
}

TEST(WriteThreads, OneThreadWritesOnTheCallingThreadAloneWithTheSameBytes) {
  TempDir dir;
  constexpr int kWidth = 1536, kHeight = 1024;
  const std::vector<float> pixels = test_image(kWidth, kHeight);
  const auto write = [&](const std::string& name, int threads) {
    write_image(dir / name, kWidth, kHeight, 3, pixels, true, WriteOptions{.threads = threads});
  };
  // First, while no other thread of this process has worked yet: oneTBB's workers and OpenEXR's pool threads
  // (if any exist) wait asleep, and take no CPU time unless a write hands them work. The allowance for them is
  // 1 ms (the kernel's accounting of a wake-up or two, a few microseconds each) plus 5 % of the caller's time;
  // a write spread over 2 cores gives the others about half of the compression, tens of ms.
  for (const char* name : {"one.png", "one.exr"}) {
    SCOPED_TRACE(name);
    const CpuSplit cpu = cpu_of([&] { write(name, 1); });
    EXPECT_GT(cpu.caller, 0.005) << "too little work to tell";
    EXPECT_LE(cpu.others, 0.001 + 0.05 * cpu.caller) << "the calling thread " << cpu.caller << " s";
  }
  // Every core (0), and 2 threads: the same bytes.
  for (const char* extension : {".png", ".exr"}) {
    SCOPED_TRACE(extension);
    const std::string one = read_file(dir / (std::string("one") + extension));
    write(std::string("all") + extension, 0);
    write(std::string("two") + extension, 2);
    EXPECT_EQ(read_file(dir / (std::string("all") + extension)), one);
    EXPECT_EQ(read_file(dir / (std::string("two") + extension)), one);
  }
  // And the measure sees other threads' work when a write has them: on 2 threads, OpenEXR's chunks are compressed
  // by two threads of a pool while the calling thread writes the compressed chunks into the file in order.
  if (std::thread::hardware_concurrency() >= 2) {
    const CpuSplit cpu = cpu_of([&] { write("two-again.exr", 2); });
    EXPECT_GT(cpu.others, cpu.caller) << "the others " << cpu.others << " s";
  }
}

}  // namespace
}  // namespace qdmr::test
