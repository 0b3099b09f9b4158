#pragma once
// Frames of the robot link (docs/protocol.md). Every integer little-endian:
//
//   offset  size  field
//        0     2  magic 'S' 'P' (0x53 0x50)
//        2     1  protocol version (kProtocolVersion)
//        3     1  message type (net/message.h)
//        4     4  payload length N, uint32, at most kMaxPayloadSize
//        8     N  payload
//      8+N     4  CRC-32 (net/crc32.h) of bytes 0 .. 8+N-1
//
// A frame is at most kMaxFrameSize (64 KiB) bytes. Plain code: no sockets,
// no threads; the transport feeds bytes in and sends what encodeFrame makes.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sp::net {

inline constexpr uint8_t kProtocolVersion = 1;
inline constexpr size_t kFrameHeaderSize = 8;
inline constexpr size_t kFrameCrcSize = 4;
inline constexpr size_t kMaxFrameSize = 65536;
inline constexpr size_t kMaxPayloadSize = kMaxFrameSize - kFrameHeaderSize - kFrameCrcSize;  // 65524

/// One decoded frame. `payload` holds raw bytes (the message layer reads
/// them as UTF-8 text).
struct Frame {
  uint8_t type = 0;
  uint8_t version = kProtocolVersion;
  std::string payload;
  friend bool operator==(const Frame&, const Frame&) = default;
};

/// The frame of `payload` with message type `type`, ready to send; nullopt if
/// the payload is longer than kMaxPayloadSize. `version` other than
/// kProtocolVersion is for tests of the decoder.
std::optional<std::string> encodeFrame(uint8_t type, std::string_view payload,
                                       uint8_t version = kProtocolVersion);

/// Why a FrameDecoder stopped. Every error closes the connection: after one
/// the stream cannot be resynchronised (a payload may contain anything).
enum class FrameError {
  None,
  BadMagic,            ///< bytes 0-1 of a frame are not 'S' 'P'
  UnsupportedVersion,  ///< byte 2 is not kProtocolVersion
  Oversize,            ///< the payload length exceeds kMaxPayloadSize
  BadCrc,              ///< the CRC-32 does not match header and payload
};
const char* toString(FrameError error);

/// Splits a byte stream into frames. Feed the bytes as they arrive, in
/// pieces of any size, and call next() until it returns nullopt; the frames
/// and the error (if any) depend only on the bytes, never on how they were
/// split: feeding a stream one byte at a time decodes exactly what feeding it
/// whole does.
///
/// Checks, each as early as the stream allows: the magic once a frame's
/// first two bytes are in; the version and the payload length once its
/// 8-byte header is in (an oversize length is rejected then, without
/// allocating or waiting for the claimed size); the CRC once the whole frame
/// is in. The message type is not checked here (net/message.h does that).
///
/// On an error the decoder fails for good: next() returns nullopt, error()
/// and errorMessage() say what happened, its buffer is released and further
/// bytes fed are dropped. The owner must close the connection: nothing after
/// a bad frame can be trusted to be a frame boundary.
///
/// Memory: a claimed length is never allocated; bytes are held only as they
/// arrive. After next() has returned nullopt the decoder holds less than one
/// frame (kMaxFrameSize bytes) of the stream. Drain next() after each feed
/// and its buffer never exceeds kMaxFrameSize plus the largest single feed;
/// read the socket into a buffer of fixed size.
///
/// Not thread-safe: one decoder per connection, used by the thread that
/// reads that connection.
class FrameDecoder {
 public:
  /// Appends `n` bytes at `data` (may be null when n is 0) to the stream.
  /// Dropped once the decoder has failed.
  void feed(const char* data, size_t n);
  void feed(std::string_view bytes) { feed(bytes.data(), bytes.size()); }

  /// The next complete frame, or nullopt when more bytes are needed or the
  /// decoder has failed (check failed()).
  std::optional<Frame> next();

  bool failed() const { return error_ != FrameError::None; }
  FrameError error() const { return error_; }
  /// Names the stream offset of the bad frame, its type once known, and the
  /// problem, e.g. `frame at stream byte 24 (type 7 COMMAND): bad CRC
  /// 0x12345678, computed 0xcbf43926`. Empty while not failed.
  const std::string& errorMessage() const { return errorMessage_; }

  /// Frames returned by next() so far.
  uint64_t framesDecoded() const { return framesDecoded_; }
  /// Bytes of the stream taken up by those frames; the stream offset of the
  /// next frame (and of a bad one).
  uint64_t bytesConsumed() const { return bytesConsumed_; }
  /// Bytes fed but not yet decoded.
  size_t buffered() const { return buffer_.size() - start_; }
  /// Bytes of memory the decoder's buffer holds (its capacity).
  size_t memoryHeld() const { return buffer_.capacity(); }

 private:
  std::optional<Frame> fail(FrameError error, std::string message);

  std::vector<char> buffer_;
  size_t start_ = 0;  ///< first byte of the next frame in buffer_
  FrameError error_ = FrameError::None;
  std::string errorMessage_;
  uint64_t framesDecoded_ = 0;
  uint64_t bytesConsumed_ = 0;
};

}  // namespace sp::net
