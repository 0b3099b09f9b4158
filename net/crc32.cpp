#include "net/crc32.h"

#include <zlib.h>

namespace sp::net {

// zlib's crc32 is the same CRC (its own check value is ours) and is kept
// fast by its maintainers (slicing tables, and a folding kernel where the
// CPU has one); its state between calls is the finished CRC of the bytes
// so far.
void Crc32::update(const void* data, size_t n) {
  if (n == 0) return;
  crc_ = static_cast<uint32_t>(crc32_z(crc_, static_cast<const Bytef*>(data), n));
}

uint32_t crc32(std::string_view bytes) {
  Crc32 crc;
  crc.update(bytes);
  return crc.value();
}

}  // namespace sp::net
