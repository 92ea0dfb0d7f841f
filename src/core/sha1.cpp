#include "core/sha1.hpp"

#include <openssl/evp.h>

#include "qdmr/core/error.hpp"

namespace qdmr {

struct Sha1::Context {
  EVP_MD_CTX* md = nullptr;
  ~Context() { EVP_MD_CTX_free(md); }
};

Sha1::Sha1() : context_(std::make_unique<Context>()) {
  context_->md = EVP_MD_CTX_new();
  if (context_->md == nullptr || EVP_DigestInit_ex(context_->md, EVP_sha1(), nullptr) != 1)
    throw Error("sha1", "OpenSSL could not start a SHA-1 digest");
}

Sha1::~Sha1() = default;

void Sha1::append(const void* data, std::size_t size) {
  if (EVP_DigestUpdate(context_->md, data, size) != 1) throw Error("sha1", "OpenSSL could not hash the data");
}

std::string Sha1::hex_digest() {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_DigestFinal_ex(context_->md, digest, &length) != 1) throw Error("sha1", "OpenSSL could not finish the digest");
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (unsigned int i = 0; i < length; ++i) {
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 15];
  }
  return hex;
}

std::string sha1_hex(const void* data, std::size_t size) {
  Sha1 sha;
  sha.append(data, size);
  return sha.hex_digest();
}

}  // namespace qdmr
