#include "net/auth.h"

#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace sp::net {
namespace {

std::string toHex(const unsigned char* data, size_t size) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  out.reserve(size * 2);
  for (size_t i = 0; i < size; ++i) {
    out += digits[data[i] >> 4];
    out += digits[data[i] & 15u];
  }
  return out;
}

}  // namespace

std::string randomHex(size_t bytes) {
  std::vector<unsigned char> buffer(bytes);
  if (bytes > 0 && RAND_bytes(buffer.data(), static_cast<int>(bytes)) != 1)
    throw std::runtime_error("the system's secure random source failed");
  return toHex(buffer.data(), buffer.size());
}

std::string randomToken() { return randomHex(16); }

std::string helloProof(std::string_view token, std::string_view nonce, std::string_view name, Role role) {
  std::string text = "simpartner-hello\n";
  text.append(nonce).append("\n").append(name).append("\n").append(toString(role));
  unsigned char mac[EVP_MAX_MD_SIZE];
  unsigned int size = 0;
  if (!HMAC(EVP_sha256(), token.data(), static_cast<int>(token.size()),
            reinterpret_cast<const unsigned char*>(text.data()), text.size(), mac, &size))
    throw std::runtime_error("HMAC-SHA256 failed");
  return toHex(mac, size);
}

bool equalConstantTime(std::string_view a, std::string_view b) {
  // Runs over the longer string whatever the contents, so the time taken
  // tells nothing about where the first difference is.
  const size_t n = std::max(a.size(), b.size());
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < n; ++i) {
    const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
    const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    diff = static_cast<unsigned char>(diff | (x ^ y));
  }
  return diff == 0;
}

}  // namespace sp::net
