// Tests of the frame codec (net/frame.h): layout, decoding in pieces of any
// size, every error kind with its exact message, and bounded memory.

#include <QTest>

#include <random>
#include <string>
#include <vector>

#include "net/frame.h"

using namespace sp::net;

Q_DECLARE_METATYPE(sp::net::FrameError)

namespace {

std::string s(const QByteArray& b) { return std::string(b.constData(), static_cast<size_t>(b.size())); }
QByteArray b(const std::string& str) { return QByteArray(str.data(), static_cast<qsizetype>(str.size())); }

std::string frame(uint8_t type, const std::string& payload, uint8_t version = kProtocolVersion) {
  std::optional<std::string> f = encodeFrame(type, payload, version);
  if (!f) qFatal("payload too long");
  return *f;
}

// A header with any length field, without payload or CRC.
std::string header(uint8_t type, uint32_t length, uint8_t version = kProtocolVersion) {
  std::string h = {'S', 'P', static_cast<char>(version), static_cast<char>(type)};
  for (int i = 0; i < 4; ++i) h.push_back(static_cast<char>((length >> (8 * i)) & 0xFFu));
  return h;
}

const std::string kHeartbeat = frame(11, "seq=1\ntime=0.5\n");  // 27 bytes
const std::string kCommand = frame(7, "seq=1\nexpires_ms=500\ncommand=stop\n");

// What a decoder made of a stream.
struct Result {
  std::vector<Frame> frames;
  FrameError error = FrameError::None;
  std::string message;
  uint64_t consumed = 0;
  size_t buffered = 0;
};

// Feeds `stream` in pieces of `chunk()` bytes, draining next() after each.
template <class Chunk>
Result decode(const std::string& stream, Chunk chunk) {
  FrameDecoder decoder;
  Result r;
  for (size_t pos = 0; pos < stream.size();) {
    const size_t n = std::min(chunk(), stream.size() - pos);
    decoder.feed(stream.data() + pos, n);
    pos += n;
    while (std::optional<Frame> f = decoder.next()) r.frames.push_back(*f);
  }
  r.error = decoder.error();
  r.message = decoder.errorMessage();
  r.consumed = decoder.bytesConsumed();
  r.buffered = decoder.buffered();
  if (decoder.framesDecoded() != r.frames.size()) qFatal("framesDecoded is off");
  return r;
}
Result decodeWhole(const std::string& stream) {
  return decode(stream, [&] { return stream.size(); });
}
Result decodeBytewise(const std::string& stream) {
  return decode(stream, [] { return size_t{1}; });
}

// `count` frames of random types (1..20) and payload sizes (0..2000, now
// and then a maximal one), from a fixed seed.
std::string mixedStream(int count, std::vector<Frame>& frames) {
  std::mt19937 rng(20240611);
  std::string stream;
  for (int i = 0; i < count; ++i) {
    Frame f;
    f.type = static_cast<uint8_t>(1 + rng() % 20);
    const size_t size = i % 50 == 7 ? kMaxPayloadSize : rng() % 2001;
    for (size_t k = 0; k < size; ++k) f.payload.push_back(static_cast<char>(rng() & 0xFF));
    stream += frame(f.type, f.payload);
    frames.push_back(f);
  }
  return stream;
}

}  // namespace

class TestFrame : public QObject {
  Q_OBJECT

 private slots:
  void encodeLayout();
  void encodeSizeLimit();
  void roundTrip_data();
  void roundTrip();
  void byteAtATimeEqualsWhole();
  void randomChunksEqualWhole();
  void errors_data();
  void errors();
  void oversizeRejectedAfterHeader();
  void maximalHeaderAllocatesNothing();
  void garbage();
  void truncatedFrameWaits();
  void counters();
  void failedDecoderDropsBytes();
  void memoryBoundedAcrossFeeds();
};

// A frame is magic, version, type, little-endian length, payload and the
// little-endian CRC-32 of all before it (bytes checked against Python's
// zlib.crc32).
void TestFrame::encodeLayout() {
  const QByteArray expected = QByteArray::fromHex(
      "5350010b0f000000"                  // 'S' 'P', version 1, type 11, length 15
      "7365713d310a74696d653d302e350a"    // "seq=1\ntime=0.5\n"
      "95fc1088");                        // CRC-32 0x8810fc95
  QCOMPARE(b(kHeartbeat), expected);
}

// Payloads up to 65524 bytes (a 65536-byte frame) encode; longer ones do not.
void TestFrame::encodeSizeLimit() {
  QCOMPARE(kMaxPayloadSize, size_t{65524});
  const std::optional<std::string> largest = encodeFrame(10, std::string(kMaxPayloadSize, 'x'));
  QVERIFY(largest);
  QCOMPARE(largest->size(), kMaxFrameSize);
  QVERIFY(!encodeFrame(10, std::string(kMaxPayloadSize + 1, 'x')));
}

void TestFrame::roundTrip_data() {
  QTest::addColumn<int>("type");
  QTest::addColumn<QByteArray>("payload");
  QTest::newRow("empty") << 3 << QByteArray();
  QTest::newRow("text") << 7 << QByteArray("seq=1\nexpires_ms=500\ncommand=stop\n");
  QTest::newRow("binary") << 255 << QByteArray("\0\xff\x53\x50\n", 5);
  QTest::newRow("type 0") << 0 << QByteArray("x");
  QTest::newRow("maximal") << 10 << QByteArray(static_cast<qsizetype>(kMaxPayloadSize), 'r');
}

// Any type byte and payload come back as sent, with the version.
void TestFrame::roundTrip() {
  QFETCH(int, type);
  QFETCH(QByteArray, payload);
  FrameDecoder decoder;
  decoder.feed(frame(static_cast<uint8_t>(type), s(payload)));
  const std::optional<Frame> f = decoder.next();
  QVERIFY(f);
  QCOMPARE(int(f->type), type);
  QCOMPARE(int(f->version), int(kProtocolVersion));
  QCOMPARE(b(f->payload), payload);
  QVERIFY(!decoder.next());
  QVERIFY(!decoder.failed());
  QCOMPARE(decoder.buffered(), size_t{0});
}

// 300 mixed frames (some maximal) then a bad one decode to exactly the same
// frames, error and counters fed one byte at a time as fed whole.
void TestFrame::byteAtATimeEqualsWhole() {
  std::vector<Frame> frames;
  std::string stream = mixedStream(300, frames);
  const size_t good = stream.size();
  std::string bad = kCommand;
  bad[10] ^= 0x20;
  stream += bad;

  const Result whole = decodeWhole(stream);
  const Result bytewise = decodeBytewise(stream);
  QCOMPARE(whole.frames.size(), frames.size());
  QVERIFY(whole.frames == frames);
  QVERIFY(bytewise.frames == frames);
  QCOMPARE(whole.error, FrameError::BadCrc);
  QCOMPARE(bytewise.error, FrameError::BadCrc);
  QCOMPARE(bytewise.message, whole.message);
  QCOMPARE(whole.message, "frame at stream byte " + std::to_string(good) +
                              " (type 7 COMMAND): bad CRC 0xdffd04d7, computed 0xe54fd905");
  QCOMPARE(whole.consumed, uint64_t{good});
  QCOMPARE(bytewise.consumed, uint64_t{good});
}

// Chunks of random sizes (fixed seeds; 1 byte to 100 KiB) decode as the
// whole stream.
void TestFrame::randomChunksEqualWhole() {
  std::vector<Frame> frames;
  const std::string stream = mixedStream(300, frames);
  for (unsigned seed : {1u, 2u, 3u, 4u}) {
    std::mt19937 rng(seed);
    const size_t maxChunk = seed % 2 ? 100 : 100000;
    const Result r = decode(stream, [&] { return size_t{1} + rng() % maxChunk; });
    QVERIFY(r.frames == frames);
    QCOMPARE(r.error, FrameError::None);
    QCOMPARE(r.consumed, uint64_t{stream.size()});
    QCOMPARE(r.buffered, size_t{0});
  }
}

void TestFrame::errors_data() {
  QTest::addColumn<QByteArray>("stream");
  QTest::addColumn<FrameError>("error");
  QTest::addColumn<int>("framesBefore");
  QTest::addColumn<QString>("message");

  QTest::newRow("bad magic") << QByteArray("GET / HTTP/1.1\r\n") << FrameError::BadMagic << 0
                             << "frame at stream byte 0: bad magic 0x47 0x45, expected 0x53 0x50 ('SP')";
  QTest::newRow("bad second magic byte") << b(kHeartbeat + "SX" + header(7, 0).substr(2)) << FrameError::BadMagic
                                         << 1
                                         << "frame at stream byte 27: bad magic 0x53 0x58, expected 0x53 0x50 ('SP')";
  QTest::newRow("bad magic, two bytes in") << QByteArray("PS") << FrameError::BadMagic << 0
                                           << "frame at stream byte 0: bad magic 0x50 0x53, expected 0x53 0x50 ('SP')";
  QTest::newRow("version 2") << b(kHeartbeat + frame(7, "seq=1", 2)) << FrameError::UnsupportedVersion << 1
                             << "frame at stream byte 27 (type 7 COMMAND): unsupported protocol version 2, expected 1";
  QTest::newRow("version 0, unknown type") << b(header(99, 0, 0)) << FrameError::UnsupportedVersion << 0
                                           << "frame at stream byte 0 (type 99 unknown): unsupported protocol "
                                              "version 0, expected 1";
  QTest::newRow("oversize by one") << b(header(10, 65525)) << FrameError::Oversize << 0
                                   << "frame at stream byte 0 (type 10 LASER): payload length 65525 exceeds the "
                                      "maximum 65524";
  QTest::newRow("oversize 4 GiB") << b(kHeartbeat + kHeartbeat + header(9, 0xFFFFFFFFu)) << FrameError::Oversize << 2
                                  << "frame at stream byte 54 (type 9 TELEMETRY): payload length 4294967295 exceeds "
                                     "the maximum 65524";
  std::string flipped = kCommand;
  flipped[10] ^= 0x20;  // "seq" -> "sEq"
  QTest::newRow("bad CRC, payload") << b(flipped) << FrameError::BadCrc << 0
                                    << "frame at stream byte 0 (type 7 COMMAND): bad CRC 0xdffd04d7, computed "
                                       "0xe54fd905";
  std::string badCrc = frame(200, "x");
  badCrc.back() = static_cast<char>(badCrc.back() ^ 0xFF);
  QTest::newRow("bad CRC, unknown type") << b(kHeartbeat + badCrc) << FrameError::BadCrc << 1
                                         << "frame at stream byte 27 (type 200 unknown): bad CRC 0x3f82dd08, "
                                            "computed 0xc082dd08";
}

// Each error kind stops the decoder with a message naming the bad frame's
// stream offset and type; the frames before it are returned, whether the
// stream is fed whole or byte by byte.
void TestFrame::errors() {
  QFETCH(QByteArray, stream);
  QFETCH(FrameError, error);
  QFETCH(int, framesBefore);
  QFETCH(QString, message);
  for (const Result& r : {decodeWhole(s(stream)), decodeBytewise(s(stream))}) {
    QCOMPARE(r.error, error);
    QCOMPARE(QString::fromStdString(r.message), message);
    QCOMPARE(int(r.frames.size()), framesBefore);
    QCOMPARE(r.buffered, size_t{0});
  }
}

// A header claiming 1 GiB fails as soon as its 8 bytes are in: nothing of
// the claimed size is allocated or waited for, and the buffer is released.
void TestFrame::oversizeRejectedAfterHeader() {
  FrameDecoder decoder;
  const std::string h = header(10, 1u << 30);
  decoder.feed(h.data(), 7);
  QVERIFY(!decoder.next());
  QVERIFY(!decoder.failed());
  decoder.feed(h.data() + 7, 1);
  QVERIFY(decoder.memoryHeld() < 64);
  QVERIFY(!decoder.next());
  QCOMPARE(decoder.error(), FrameError::Oversize);
  QCOMPARE(decoder.errorMessage(),
           "frame at stream byte 0 (type 10 LASER): payload length 1073741824 exceeds the maximum 65524");
  QCOMPARE(decoder.buffered(), size_t{0});
  QCOMPARE(decoder.memoryHeld(), size_t{0});
}

// A header claiming the largest valid payload is accepted, and the decoder
// holds only the bytes that came: it allocates as data arrives.
void TestFrame::maximalHeaderAllocatesNothing() {
  FrameDecoder decoder;
  decoder.feed(header(10, kMaxPayloadSize));
  QVERIFY(!decoder.next());
  QVERIFY(!decoder.failed());
  QCOMPARE(decoder.buffered(), size_t{8});
  QVERIFY(decoder.memoryHeld() < 64);
}

// Random garbage (fixed seed) never yields a frame: it fails at once on
// the magic, or, behind a forged "SP", on the version, the length or the
// CRC, or waits for more; fed whole or bytewise alike.
void TestFrame::garbage() {
  std::mt19937 rng(7);
  int failures[5] = {};
  for (int i = 0; i < 2000; ++i) {
    std::string junk(3 + rng() % 62, '\0');
    for (char& c : junk) c = static_cast<char>(rng() & 0xFF);
    if (i % 2) {  // not replace(0, 2, "SP"): GCC 12 at -O3 warns of a bound it imagines there
      junk[0] = 'S';
      junk[1] = 'P';
    }
    if (i % 4 == 1) junk[2] = 1;
    if (i % 8 == 1 && junk.size() >= 8) junk.replace(4, 4, std::string("\x10\0\0\0", 4));
    const Result whole = decodeWhole(junk);
    const Result bytewise = decodeBytewise(junk);
    QVERIFY(whole.frames.empty());
    QCOMPARE(bytewise.error, whole.error);
    QCOMPARE(bytewise.message, whole.message);
    ++failures[int(whole.error)];
  }
  QVERIFY(failures[int(FrameError::BadMagic)] > 900);
  QVERIFY(failures[int(FrameError::UnsupportedVersion)] > 100);
  QVERIFY(failures[int(FrameError::Oversize)] > 100);
  QVERIFY(failures[int(FrameError::BadCrc)] > 10);
  QVERIFY(failures[int(FrameError::None)] > 10);  // waiting for more
}

// A frame missing its last byte is held, not failed; the last byte
// completes it.
void TestFrame::truncatedFrameWaits() {
  FrameDecoder decoder;
  decoder.feed(kCommand.data(), kCommand.size() - 1);
  QVERIFY(!decoder.next());
  QVERIFY(!decoder.failed());
  QCOMPARE(decoder.buffered(), kCommand.size() - 1);
  QCOMPARE(decoder.bytesConsumed(), uint64_t{0});
  decoder.feed(kCommand.data() + kCommand.size() - 1, 1);
  const std::optional<Frame> f = decoder.next();
  QVERIFY(f);
  QCOMPARE(int(f->type), 7);
  QCOMPARE(decoder.buffered(), size_t{0});
}

// framesDecoded and bytesConsumed count whole frames only.
void TestFrame::counters() {
  FrameDecoder decoder;
  decoder.feed(kHeartbeat + kCommand + kHeartbeat.substr(0, 5));
  while (decoder.next()) {
  }
  QCOMPARE(decoder.framesDecoded(), uint64_t{2});
  QCOMPARE(decoder.bytesConsumed(), uint64_t{kHeartbeat.size() + kCommand.size()});
  QCOMPARE(decoder.buffered(), size_t{5});
}

// After an error, fed bytes are dropped and no frame is returned, even a
// good one.
void TestFrame::failedDecoderDropsBytes() {
  FrameDecoder decoder;
  decoder.feed("XX", 2);
  QVERIFY(!decoder.next());
  QVERIFY(decoder.failed());
  decoder.feed(kHeartbeat);
  QVERIFY(!decoder.next());
  QCOMPARE(decoder.buffered(), size_t{0});
  QCOMPARE(decoder.memoryHeld(), size_t{0});
  QCOMPARE(decoder.error(), FrameError::BadMagic);
}

// Maximal frames fed in 1000-byte reads never make the buffer hold more
// than one frame plus one read; a large feed's memory is given back once
// the decoder has drained it.
void TestFrame::memoryBoundedAcrossFeeds() {
  std::vector<Frame> frames;
  const std::string stream = mixedStream(120, frames);
  FrameDecoder decoder;
  size_t decoded = 0;
  for (size_t pos = 0; pos < stream.size(); pos += 1000) {
    decoder.feed(stream.data() + pos, std::min<size_t>(1000, stream.size() - pos));
    while (decoder.next()) ++decoded;
    QVERIFY(decoder.buffered() < kMaxFrameSize);
    QVERIFY2(decoder.memoryHeld() <= kMaxFrameSize + 1000, std::to_string(decoder.memoryHeld()).c_str());
  }
  QCOMPARE(decoded, frames.size());

  FrameDecoder big;
  big.feed(stream);
  while (big.next()) {
  }
  QVERIFY(big.memoryHeld() >= stream.size());
  big.feed(kHeartbeat);
  QVERIFY(big.memoryHeld() <= kMaxFrameSize);
  QVERIFY(big.next());
}

QTEST_GUILESS_MAIN(TestFrame)
#include "tst_frame.moc"
