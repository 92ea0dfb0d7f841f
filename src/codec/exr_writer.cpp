#include "codec/exr_writer.hpp"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <IlmThreadPool.h>
#include <ImfThreading.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace qdmr {
namespace {

// OpenEXR's bytes straight into the file, every write checked (as the OpenImageIO backend's CheckedFileOutput):
// unbuffered pwrite() at the stream's position, the first OS error kept. OpenEXR writes the line offsets last, from
// ~OutputFile, which swallows exceptions: the caller asks failure() after the file object is gone.
class CheckedStream final : public Imf::OStream {
public:
  explicit CheckedStream(const std::string& path)
      : Imf::OStream(path.c_str()), fd_(::open(path.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC)) {
    if (fd_ < 0) failure_ = errno;
  }
  ~CheckedStream() override { close(); }
  CheckedStream(const CheckedStream&) = delete;
  CheckedStream& operator=(const CheckedStream&) = delete;

  void write(const char c[], int n) override {
    std::size_t done = 0;
    while (fd_ >= 0 && failure_ == 0 && done < std::size_t(n)) {
      const ssize_t w = ::pwrite(fd_, c + done, std::size_t(n) - done, off_t(position_ + done));
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) failure_ = w < 0 ? errno : ENOSPC;  // a write of 0 bytes: no room
      if (w > 0) done += std::size_t(w);
    }
    position_ += done;
    if (failure_ != 0) throw std::runtime_error(std::strerror(failure_));
  }
  std::uint64_t tellp() override { return position_; }
  void seekp(std::uint64_t position) override { position_ = position; }

  void close() {
    if (fd_ >= 0 && ::close(fd_) != 0 && failure_ == 0) failure_ = errno;
    fd_ = -1;
  }
  int failure() const { return failure_; }  // the first OS error (errno), 0 for none

private:
  int fd_;
  int failure_ = 0;
  std::uint64_t position_ = 0;
};

std::vector<std::string> channel_names(const imageio::WriteSpec& spec) {
  if (!spec.channel_names.empty()) return spec.channel_names;
  if (spec.channels == 1) return {"Y"};  // OpenImageIO's ImageSpec::default_channel_names
  static const char* const kNames[] = {"R", "G", "B", "A"};
  return {kNames, kNames + spec.channels};
}

// OpenEXR compresses a file's chunks as tasks on its global thread pool. The provider below, installed on that pool
// once, runs the tasks of a write or read that may use k threads (ExrThreads, set around it on the calling
// thread) on a pool of its own with k threads, and k = 1 in the calling thread itself (an OpenEXR pool of no
// threads); every other task (OpenImageIO's reads and writes outside such a scope) goes to a shared pool of the
// size the process set, or of one thread per core as the OpenImageIO backend sets it (pvt::set_exr_threads).
// OpenEXR forwards setGlobalThreadCount to the provider, which sizes the shared pool.
thread_local int t_exr_threads = 0;  // 0: no ExrThreads scope on this thread

class ExrPools final : public IlmThread::ThreadPoolProvider {
public:
  explicit ExrPools(int shared) : shared_(unsigned(shared)) {}
  int numThreads() const override { return shared_.numThreads(); }
  void setNumThreads(int count) override { shared_.setNumThreads(count); }
  void addTask(IlmThread::Task* task) override {
    const int k = t_exr_threads;
    if (k == 0) return shared_.addTask(task);
    IlmThread::ThreadPool* pool = nullptr;
    {
      const std::lock_guard lock(mutex_);
      std::unique_ptr<IlmThread::ThreadPool>& p = by_threads_[k];
      if (!p) p = std::make_unique<IlmThread::ThreadPool>(unsigned(k == 1 ? 0 : k));
      pool = p.get();
    }
    pool->addTask(task);
  }
  // Called as OpenEXR replaces or destroys the provider: each pool's destructor runs its queued tasks and joins.
  void finish() override {
    const std::lock_guard lock(mutex_);
    by_threads_.clear();
    shared_.setNumThreads(0);
  }

private:
  IlmThread::ThreadPool shared_;
  std::mutex mutex_;
  std::map<int, std::unique_ptr<IlmThread::ThreadPool>> by_threads_;
};

void install_exr_pools() {
  static std::once_flag once;
  std::call_once(once, [] {
    const int set = Imf::globalThreadCount();
    IlmThread::ThreadPool::globalThreadPool().setThreadProvider(
        new ExrPools(set > 0 ? set : int(std::max(1u, std::thread::hardware_concurrency()))));
  });
}

}  // namespace

ExrThreads::ExrThreads(int threads) : previous_(t_exr_threads) {
  install_exr_pools();
  t_exr_threads = std::max(1, threads > 0 ? threads : int(std::thread::hardware_concurrency()));
}

ExrThreads::~ExrThreads() { t_exr_threads = previous_; }

int ExrThreads::threads() const { return t_exr_threads; }

bool exr_writes(const imageio::WriteSpec& spec) {
  if (spec.type != imageio::PixelType::Float || spec.width < 1 || spec.height < 1 || spec.channels < 1 ||
      spec.channels > 4 || !spec.ints.empty())
    return false;
  if (!spec.channel_names.empty()) {
    if (spec.channel_names.size() != std::size_t(spec.channels)) return false;
    std::vector<std::string> names = spec.channel_names;
    std::sort(names.begin(), names.end());
    if (std::adjacent_find(names.begin(), names.end()) != names.end() ||
        std::any_of(names.begin(), names.end(), [](const std::string& n) { return n.empty(); }))
      return false;
  }
  // Without a DateTime, OpenImageIO stamps the file with the current time (write_image_file always sets one).
  return std::any_of(spec.strings.begin(), spec.strings.end(), [](const auto& s) { return s.first == "DateTime"; }) &&
         std::all_of(spec.strings.begin(), spec.strings.end(), [](const auto& s) {
           return s.first == "DateTime" || s.first == "Software" || s.first == "qdmr:bits_version";
         });
}

bool write_exr(const std::string& path, const imageio::WriteSpec& spec, const void* data, std::string& error) {
  const ExrThreads threads(spec.threads);
  CheckedStream stream(path);
  if (stream.failure() != 0) {
    error = std::strerror(stream.failure());
    return false;
  }
  const std::vector<std::string> names = channel_names(spec);
  try {
    Imf::Header header(spec.width, spec.height);
    for (const std::string& name : names) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    for (const auto& [name, value] : spec.strings)
      header.insert(name == "DateTime" ? "capDate" : name, Imf::StringAttribute(value));  // a later one replaces
    const std::size_t pixel = sizeof(float) * std::size_t(spec.channels);
    Imf::FrameBuffer frame;
    char* base = static_cast<char*>(const_cast<void*>(data));
    for (std::size_t c = 0; c < names.size(); ++c)
      frame.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), pixel, pixel * std::size_t(spec.width)));
    Imf::OutputFile file(stream, header, threads.threads());  // 2 x that many chunks in flight
    file.setFrameBuffer(frame);
    file.writePixels(spec.height);
  } catch (const std::exception& e) {
    error = stream.failure() != 0 ? std::strerror(stream.failure()) : e.what();
    return false;
  }
  stream.close();
  if (stream.failure() != 0) {  // the line offsets, written as the file object went
    error = std::strerror(stream.failure());
    return false;
  }
  return true;
}

}  // namespace qdmr
