#pragma once
// SHA-1 through OpenSSL's libcrypto (SHA-NI where the CPU has it, about 4x OpenImageIO's portable SHA1 here): the
// canonical image hashes of checks and studies and the spec hash. libcrypto is loaded by every qdmr process anyway
// (OpenImageIO's dependencies pull it in).
#include <cstddef>
#include <memory>
#include <string>

namespace qdmr {

class Sha1 {
public:
  Sha1();
  ~Sha1();
  Sha1(const Sha1&) = delete;
  Sha1& operator=(const Sha1&) = delete;

  void append(const void* data, std::size_t size);
  // 40 lowercase hex digits; the object is finished after it.
  std::string hex_digest();

private:
  struct Context;
  std::unique_ptr<Context> context_;
};

// The hex digest of one buffer.
std::string sha1_hex(const void* data, std::size_t size);

}  // namespace qdmr
