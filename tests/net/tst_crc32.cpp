// Tests of the CRC-32 (net/crc32.h).

#include <QTest>

#include <string>

#include "net/crc32.h"

using namespace sp::net;

class TestCrc32 : public QObject {
  Q_OBJECT

 private slots:
  void knownValues_data();
  void knownValues();
  void incrementalEqualsOneShot();
  void matchesBitwiseReference();
};

namespace {
// The CRC one bit at a time, straight from the definition: the reference
// for the sliced tables.
uint32_t bitwise(const std::string& bytes) {
  uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}
}  // namespace

// Every length from 0 to 300 (all alignments and tails of the 8-byte
// slices) at every start offset 0..7, on pseudo-random bytes.
void TestCrc32::matchesBitwiseReference() {
  std::string data;
  uint32_t x = 2463534242u;
  for (int i = 0; i < 320; ++i) {
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    data += static_cast<char>(x & 0xFFu);
  }
  for (size_t offset = 0; offset < 8; ++offset)
    for (size_t n = 0; n <= 300; ++n) {
      const std::string piece = data.substr(offset, n);
      QCOMPARE(crc32(piece), bitwise(piece));
    }
}

void TestCrc32::knownValues_data() {
  QTest::addColumn<QByteArray>("bytes");
  QTest::addColumn<uint>("crc");
  QTest::newRow("check value") << QByteArray("123456789") << 0xCBF43926u;
  QTest::newRow("empty") << QByteArray() << 0u;
  QTest::newRow("a") << QByteArray("a") << 0xE8B7BE43u;
  QTest::newRow("fox") << QByteArray("The quick brown fox jumps over the lazy dog") << 0x414FA339u;
  QTest::newRow("zeros") << QByteArray(32, '\0') << 0x190A55ADu;
}

// The CRC is IEEE 802.3's (zlib's): the standard check value of "123456789"
// and other published values.
void TestCrc32::knownValues() {
  QFETCH(QByteArray, bytes);
  QFETCH(uint, crc);
  QCOMPARE(crc32(std::string_view(bytes.constData(), static_cast<size_t>(bytes.size()))), crc);
}

// Feeding the bytes in two pieces, split anywhere, gives the one-shot value;
// so does reset() and feeding again.
void TestCrc32::incrementalEqualsOneShot() {
  const std::string text = "The quick brown fox jumps over the lazy dog";
  for (size_t split = 0; split <= text.size(); ++split) {
    Crc32 crc;
    crc.update(text.data(), split);
    crc.update(std::string_view(text).substr(split));
    QCOMPARE(crc.value(), 0x414FA339u);
  }
  Crc32 crc;
  crc.update("junk", 4);
  crc.reset();
  crc.update(nullptr, 0);
  crc.update("123456789", 9);
  QCOMPARE(crc.value(), 0xCBF43926u);
}

QTEST_GUILESS_MAIN(TestCrc32)
#include "tst_crc32.moc"
