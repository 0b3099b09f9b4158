#pragma once
// CRC-32 as in IEEE 802.3, zlib and PNG: reflected, polynomial 0xEDB88320,
// initial value and final xor 0xFFFFFFFF. The check value of the nine
// bytes "123456789" is 0xCBF43926. Used by the frame codec (net/frame.h);
// computed by zlib's crc32 (the same CRC).

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace sp::net {

/// An incremental CRC-32: feed the bytes in any number of pieces; value()
/// equals crc32() of their concatenation. A plain value; use from one thread
/// at a time.
class Crc32 {
 public:
  /// Adds `n` bytes at `data` (may be null when n is 0).
  void update(const void* data, size_t n);
  void update(std::string_view bytes) { update(bytes.data(), bytes.size()); }

  /// The CRC of every byte added since construction or reset().
  uint32_t value() const { return crc_; }

  void reset() { crc_ = 0; }

 private:
  uint32_t crc_ = 0;  // the finished CRC so far (zlib's running value)
};

/// The CRC-32 of `bytes` in one call.
uint32_t crc32(std::string_view bytes);

}  // namespace sp::net
