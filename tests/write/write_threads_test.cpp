// Writes keep to the threads asked for (WriteOptions::threads, qdmr/write/write.hpp): with 1, the calling thread
// alone encodes and compresses a PNG (its bands of rows, which otherwise run on oneTBB's workers) and a float EXR
// (OpenEXR's chunks, which otherwise go to a thread pool, codec/exr_writer.cpp), and the files hold the bytes of a
// write on every core. Reads of OpenEXR files keep to the threads of the caller's task arena the same way, and not
// on the pool OpenEXR's other users share. Measured by CPU time: the calling thread's (CLOCK_THREAD_CPUTIME_ID)
// against the whole process's.
#include <gtest/gtest.h>

#include <ImfThreading.h>
#include <time.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "qdmr/texture/image.hpp"
#include "qdmr/write/write.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

// The scheduler's exact run time (CLOCK_*_CPUTIME_ID, nanoseconds). getrusage's user and system times are
// sampled at timer ticks and scaled for the thread and for the process separately: their difference put 3.2-3.6 ms
// of the caller's own time on "others" in about 1 run of 20-40 on a loaded 2-core machine (none in 60 with these).
double cpu_seconds(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return double(t.tv_sec) + double(t.tv_nsec) * 1e-9;
}

struct CpuSplit {
  double caller = 0, others = 0;  // seconds of CPU on the calling thread, and on every other thread of the process
};

template <typename F>
CpuSplit cpu_of(F&& body) {
  const double thread0 = cpu_seconds(CLOCK_THREAD_CPUTIME_ID), process0 = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID);
  body();
  const double thread1 = cpu_seconds(CLOCK_THREAD_CPUTIME_ID), process1 = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID);
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

// A renderer or study asked for 1 thread reads its OpenEXR inputs on 1 thread, even when the process has sized
// OpenEXR's shared pool (as OpenImageIO does, its exr_threads attribute): before, the reader handed its chunks to
// that pool whatever the caller's arena.
TEST(ReadThreads, OneThreadReadsAnExrOnTheCallingThreadAloneWithTheSamePixels) {
  TempDir dir;
  constexpr int kWidth = 1536, kHeight = 1024;
  const std::vector<float> pixels = test_image(kWidth, kHeight);
  const std::filesystem::path file = dir / "in.exr";
  write_image(file, kWidth, kHeight, 3, pixels, true, WriteOptions{.threads = 1});  // float EXR: ZIP, 16-row chunks
  const int shared = Imf::globalThreadCount();
  Imf::setGlobalThreadCount(4);  // the process's shared pool: 4 threads waiting for chunks
  const auto same = [&](const Image& image) {  // float EXR: the values written, the rows bottom-up (v = 0 first)
    if (image.texels.size() != pixels.size()) return false;
    const std::size_t row = std::size_t(kWidth) * 3;
    for (std::size_t y = 0; y < std::size_t(kHeight); ++y)
      if (!std::equal(pixels.begin() + std::ptrdiff_t((kHeight - 1 - y) * row),
                      pixels.begin() + std::ptrdiff_t((kHeight - y) * row), image.texels.begin() + std::ptrdiff_t(y * row)))
        return false;
    return true;
  };
  const auto read_on = [&](int threads) {
    tbb::task_arena arena(threads);
    return arena.execute([&] { return read_image(file, "in.exr"); });
  };
  // The allowance for the other threads as in WriteThreads above: 1 ms plus 5 % of the caller's time; the shared
  // pool would decompress nearly every chunk, tens of ms, while the caller waits.
  Image one;
  const CpuSplit cpu = cpu_of([&] { one = read_on(1); });
  EXPECT_GT(cpu.caller, 0.005) << "too little work to tell";
  EXPECT_LE(cpu.others, 0.001 + 0.05 * cpu.caller) << "the calling thread " << cpu.caller << " s";
  EXPECT_TRUE(same(one));
  // On 2 threads the chunks go to a pool of 2 threads of the read's own, which the measure sees; the same pixels.
  Image two;
  if (std::thread::hardware_concurrency() >= 2) {
    const CpuSplit cpu2 = cpu_of([&] { two = read_on(2); });
    EXPECT_GT(cpu2.others, cpu2.caller) << "the others " << cpu2.others << " s";
  } else {
    two = read_on(2);
  }
  EXPECT_TRUE(same(two));
  EXPECT_TRUE(same(read_on(tbb::task_arena::automatic)));  // every core
  Imf::setGlobalThreadCount(shared);
}

}  // namespace
}  // namespace qdmr::test
