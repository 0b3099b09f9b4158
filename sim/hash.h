#pragma once
// The one hash of the project: 64-bit FNV-1a. Simple and stable across
// builds and machines; it fingerprints states (World::stateHash), model
// layouts and file contents (the session log's meta). Not cryptographic.

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace sp {

/// Feeds bytes into a running FNV-1a 64 hash. A plain value; any thread.
class Fnv1a64 {
 public:
  void bytes(const void* data, size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) {
      h_ ^= p[i];
      h_ *= 0x100000001b3ULL;
    }
  }
  /// The object representation of a trivially copyable value (padding
  /// included: hash only types without padding, or zero-initialised ones).
  template <typename T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
  void text(std::string_view s) { bytes(s.data(), s.size()); }
  uint64_t digest() const { return h_; }

 private:
  uint64_t h_ = 0xcbf29ce484222325ULL;
};

/// FNV-1a 64 of `data` in one call.
inline uint64_t fnv1a64(std::string_view data) {
  Fnv1a64 h;
  h.text(data);
  return h.digest();
}

}  // namespace sp
