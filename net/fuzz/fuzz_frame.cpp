// libFuzzer target for the robot link's codec (net/frame.h, net/message.h).
// Build and run: docs/protocol-fuzzing.md. tests/net/tst_fuzz_corpus replays
// the seed corpus (net/fuzz/corpus/) through this same function with any
// compiler.
//
// Each input is used twice:
//  - as a byte stream: decoded whole, one byte at a time and in pseudo-random
//    chunks; the three must give the same frames, the same error and the
//    same counters, and a chunked decoder must never hold more than one
//    maximal frame plus one chunk;
//  - as a frame with type = the first byte and payload = the rest, so that
//    the message decoder is reached without a valid CRC.
// Every frame is decoded as a message; a message that decodes must encode
// again, and decoding and encoding that gives the same bytes. A COMMAND's
// text is parsed with sp::parseCommand, and the parsed command's text parses
// again to the same text. A broken property aborts.

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "net/crc32.h"
#include "net/frame.h"
#include "net/message.h"
#include "sim/command_file.h"

namespace {

using namespace sp::net;

constexpr size_t kMaxChunk = 4096;

void check(bool ok, const char* property) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_frame: property broken: %s\n", property);
  std::abort();
}

struct Decoded {
  std::vector<Frame> frames;
  FrameError error = FrameError::None;
  std::string message;
  uint64_t framesDecoded = 0;
  uint64_t bytesConsumed = 0;
  friend bool operator==(const Decoded&, const Decoded&) = default;
};

void drain(FrameDecoder& decoder, Decoded& out) {
  while (std::optional<Frame> frame = decoder.next()) out.frames.push_back(std::move(*frame));
}

Decoded finish(const FrameDecoder& decoder, Decoded out) {
  out.error = decoder.error();
  out.message = decoder.errorMessage();
  out.framesDecoded = decoder.framesDecoded();
  out.bytesConsumed = decoder.bytesConsumed();
  check(decoder.failed() == !out.message.empty(), "an error has a message, and only an error");
  check(out.framesDecoded == out.frames.size(), "framesDecoded counts the frames returned");
  return out;
}

// Feeds `stream` in chunks of the sizes `chunkSize()` returns, draining after
// each, and checks the memory bound.
template <class ChunkSize>
Decoded decodeChunked(std::string_view stream, ChunkSize chunkSize) {
  FrameDecoder decoder;
  Decoded out;
  for (size_t pos = 0; pos < stream.size();) {
    const size_t n = std::min(chunkSize(), stream.size() - pos);
    decoder.feed(stream.data() + pos, n);
    pos += n;
    drain(decoder, out);
    check(decoder.buffered() < kMaxFrameSize, "less than a frame held after draining");
    check(decoder.memoryHeld() <= kMaxFrameSize + kMaxChunk, "buffer bounded by a frame plus a chunk");
  }
  return finish(decoder, std::move(out));
}

// A COMMAND's text parses (without a robot) to a command whose text parses
// back to the same text.
void checkCommand(const CommandMsg& message) {
  std::string error;
  std::optional<sp::Command> command = parseCommandMsg(message, nullptr, error);
  if (!command) {
    check(!error.empty(), "a refused command text says why");
    return;
  }
  const std::string text = sp::toText(*command);
  std::optional<sp::Command> again = parseCommandMsg(CommandMsg{1, 1, text}, nullptr, error);
  check(again.has_value(), "toText of a parsed command parses");
  check(sp::toText(*again) == text, "toText, parse, toText is stable");
}

void checkMessage(const Frame& frame) {
  std::string error;
  std::optional<Message> message = decodeMessage(frame, error);
  if (!message) {
    check(!error.empty() && error.size() < 400, "a decoding error has a short message");
    check(error.find('\n') == std::string::npos, "a decoding error is one line");
    return;
  }
  check(static_cast<uint8_t>(typeOf(*message)) == frame.type, "a message has its frame's type");
  if (const auto* command = std::get_if<CommandMsg>(&*message)) checkCommand(*command);

  // Numbers may re-encode longer ("1e300" as "1e+300"): only then may
  // encoding fail, and only on size.
  std::optional<std::string> bytes = encodeMessage(*message, error);
  if (!bytes) {
    check(error.find("exceeds the maximum") != std::string::npos, "a decoded message encodes");
    return;
  }
  FrameDecoder decoder;
  decoder.feed(*bytes);
  std::optional<Frame> again = decoder.next();
  check(again.has_value() && decoder.buffered() == 0, "an encoded message is one frame");
  std::optional<Message> message2 = decodeMessage(*again, error);
  check(message2.has_value(), "an encoded message decodes");
  std::optional<std::string> bytes2 = encodeMessage(*message2, error);
  check(bytes2 == bytes, "decode and encode are stable");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);

  // The input as a stream.
  FrameDecoder whole;
  whole.feed(input);
  Decoded all;
  drain(whole, all);
  all = finish(whole, std::move(all));
  const Decoded bytewise = decodeChunked(input, [] { return size_t{1}; });
  check(bytewise == all, "one byte at a time decodes as the whole stream");
  uint32_t seed = crc32(input) | 1u;
  const Decoded chunked = decodeChunked(input, [&seed] {
    seed ^= seed << 13;
    seed ^= seed >> 17;
    seed ^= seed << 5;
    return size_t{1} + seed % (seed & 1u ? 16u : kMaxChunk);
  });
  check(chunked == all, "random chunks decode as the whole stream");
  check(all.bytesConsumed <= size, "no more bytes consumed than fed");
  for (const Frame& frame : all.frames) checkMessage(frame);

  // The input as one frame's type and payload.
  if (size > 0 && size - 1 <= kMaxPayloadSize) {
    Frame frame;
    frame.type = data[0];
    frame.payload.assign(input.substr(1));
    checkMessage(frame);
  }
  return 0;
}
