#include "bake/float_cache.hpp"

#include <cstring>
#include <fstream>
#include <string>

#include "bake/content_hash.hpp"
#include "file/atomic_file.hpp"
#include "file/input_file.hpp"
#include "qdmr/bake/bake_cache.hpp"
#include "qdmr/core/error.hpp"
#include "qdmr/core/warning.hpp"

namespace qdmr {
namespace {

struct Header {
  char magic[8];
  std::uint32_t version;
  std::uint32_t tag;
  std::int32_t width, height;
  std::uint64_t key;
  std::uint64_t payload_hash;  // XXH3-64 of the values' bytes
};
static_assert(sizeof(Header) == 40);

std::uint64_t payload_hash(std::span<const float> values) {
  ContentHash h;
  h.bytes(values.data(), values.size() * sizeof(float));
  return h.digest();
}

}  // namespace

bool read_float_cache(const std::filesystem::path& file, const FloatCacheId& id, float lo, float hi,
                      std::span<float> values) {
  // Only a regular file of exactly the expected size is opened: a FIFO or device in its place is a miss, not a
  // hang (the cache is then rewritten over it by rename).
  if (!non_regular_reason(file).empty()) return false;
  const std::size_t count = std::size_t(id.width) * std::size_t(id.height);
  if (values.size() != count) return false;
  std::error_code ec;
  if (std::filesystem::file_size(file, ec) != sizeof(Header) + count * sizeof(float) || ec) return false;
  std::ifstream in(file, std::ios::binary);
  if (!in) return false;
  note_input(file);
  Header header{};
  if (!in.read(reinterpret_cast<char*>(&header), sizeof header)) return false;
  if (std::memcmp(header.magic, id.magic.data(), sizeof header.magic) != 0 || header.version != id.version ||
      header.tag != id.tag || header.width != id.width || header.height != id.height || header.key != id.key)
    return false;
  if (!in.read(reinterpret_cast<char*>(values.data()), std::streamsize(count * sizeof(float)))) return false;
  if (payload_hash(values) != header.payload_hash) return false;
  for (float v : values)
    if (!(v >= lo && v <= hi)) return false;
  touch_bake_cache_entry(file);  // recently used: evicted last
  return true;
}

void write_float_cache(const std::filesystem::path& file, const FloatCacheId& id, std::span<const float> values) {
  const std::uint64_t limit = bake_cache_limit_bytes();
  if (sizeof(Header) + values.size_bytes() > limit) return;  // larger than the whole cache may be
  // "FILE: cannot write bake cache: REASON", as an output's error would say, but a warning: the map was baked.
  const auto not_written = [](const std::string& message) { warn(message + " (the map is baked again next time)"); };
  std::error_code ec;
  std::filesystem::create_directories(file.parent_path(), ec);
  if (ec) return not_written(file.string() + ": cannot write bake cache: cannot create its folder: " + ec.message());
  Header header{};
  std::memcpy(header.magic, id.magic.data(), sizeof header.magic);
  header.version = id.version;
  header.tag = id.tag;
  header.width = id.width;
  header.height = id.height;
  header.key = id.key;
  header.payload_hash = payload_hash(values);
  try {
    write_atomically(file, "bake cache", [&](const std::filesystem::path& temporary) -> std::string {
      std::ofstream out(temporary, std::ios::binary);
      out.write(reinterpret_cast<const char*>(&header), sizeof header);
      out.write(reinterpret_cast<const char*>(values.data()), std::streamsize(values.size() * sizeof(float)));
      return out.flush() ? "" : "write failed";
    });
  } catch (const Error& e) {
    return not_written(e.what());
  }
  trim_bake_cache(file.parent_path(), limit, file);
}

}  // namespace qdmr
