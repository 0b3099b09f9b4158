#include "net/frame.h"

#include <algorithm>
#include <cstdio>

#include "net/crc32.h"
#include "net/message.h"

namespace sp::net {
namespace {

void putU32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}

uint32_t getU32(const char* p) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(p[i]);
  return v;
}

std::string hexByte(unsigned char b) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "0x%02x", b);
  return buf;
}

std::string hexWord(uint32_t w) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", w);
  return buf;
}

// "frame at stream byte 24 (type 7 COMMAND)"
std::string where(uint64_t offset, const unsigned char* type) {
  std::string s = "frame at stream byte " + std::to_string(offset);
  if (type) s += " (type " + std::to_string(*type) + " " + messageTypeName(*type) + ")";
  return s;
}

}  // namespace

std::optional<std::string> encodeFrame(uint8_t type, std::string_view payload, uint8_t version) {
  if (payload.size() > kMaxPayloadSize) return std::nullopt;
  std::string out;
  out.reserve(kFrameHeaderSize + payload.size() + kFrameCrcSize);
  out.push_back('S');
  out.push_back('P');
  out.push_back(static_cast<char>(version));
  out.push_back(static_cast<char>(type));
  putU32(out, static_cast<uint32_t>(payload.size()));
  out.append(payload);
  putU32(out, crc32(out));
  return out;
}

const char* toString(FrameError error) {
  switch (error) {
    case FrameError::None: return "none";
    case FrameError::BadMagic: return "bad magic";
    case FrameError::UnsupportedVersion: return "unsupported version";
    case FrameError::Oversize: return "oversize";
    case FrameError::BadCrc: return "bad CRC";
  }
  return "?";
}

void FrameDecoder::feed(const char* data, size_t n) {
  if (failed() || n == 0) return;
  // Drop the frames already returned, so that the buffer holds only the
  // stream from the next frame on.
  if (start_ > 0) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(start_));
    start_ = 0;
  }
  // Grow geometrically up to one maximal frame, and beyond it only as far as
  // this feed needs; give back what an earlier large feed took.
  const size_t need = buffer_.size() + n;
  if (buffer_.capacity() > kMaxFrameSize && need <= kMaxFrameSize) {
    std::vector<char> smaller;
    smaller.reserve(kMaxFrameSize);
    smaller.assign(buffer_.begin(), buffer_.end());
    buffer_.swap(smaller);
  }
  if (need > buffer_.capacity()) buffer_.reserve(std::max(need, std::min(2 * buffer_.capacity(), kMaxFrameSize)));
  buffer_.insert(buffer_.end(), data, data + n);
}

std::optional<Frame> FrameDecoder::next() {
  if (failed()) return std::nullopt;
  const size_t avail = buffered();
  const char* p = buffer_.data() + start_;
  const auto byte = [p](size_t i) { return static_cast<unsigned char>(p[i]); };

  if (avail < 2) return std::nullopt;
  if (byte(0) != 'S' || byte(1) != 'P')
    return fail(FrameError::BadMagic, where(bytesConsumed_, nullptr) + ": bad magic " + hexByte(byte(0)) + " " +
                                          hexByte(byte(1)) + ", expected 0x53 0x50 ('SP')");
  if (avail < kFrameHeaderSize) return std::nullopt;

  const unsigned char type = byte(3);
  if (byte(2) != kProtocolVersion)
    return fail(FrameError::UnsupportedVersion, where(bytesConsumed_, &type) + ": unsupported protocol version " +
                                                    std::to_string(byte(2)) + ", expected " +
                                                    std::to_string(kProtocolVersion));
  const uint32_t length = getU32(p + 4);
  if (length > kMaxPayloadSize)
    return fail(FrameError::Oversize, where(bytesConsumed_, &type) + ": payload length " + std::to_string(length) +
                                          " exceeds the maximum " + std::to_string(kMaxPayloadSize));

  const size_t frameSize = kFrameHeaderSize + length + kFrameCrcSize;
  if (avail < frameSize) return std::nullopt;

  const uint32_t sent = getU32(p + kFrameHeaderSize + length);
  const uint32_t computed = crc32(std::string_view(p, kFrameHeaderSize + length));
  if (sent != computed)
    return fail(FrameError::BadCrc,
                where(bytesConsumed_, &type) + ": bad CRC " + hexWord(sent) + ", computed " + hexWord(computed));

  Frame frame;
  frame.type = type;
  frame.version = byte(2);
  frame.payload.assign(p + kFrameHeaderSize, length);
  start_ += frameSize;
  ++framesDecoded_;
  bytesConsumed_ += frameSize;
  return frame;
}

std::optional<Frame> FrameDecoder::fail(FrameError error, std::string message) {
  error_ = error;
  errorMessage_ = std::move(message);
  std::vector<char>().swap(buffer_);
  start_ = 0;
  return std::nullopt;
}

}  // namespace sp::net
