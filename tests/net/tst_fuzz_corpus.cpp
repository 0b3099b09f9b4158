// Replays the fuzzer's seed corpus (net/fuzz/corpus/) through the libFuzzer
// entry point of net/fuzz/fuzz_frame.cpp, compiled here with the ordinary
// compiler, so that its properties are checked in every build; and checks
// that the corpus still seeds every message type and every frame error.

#include <QTest>

#include <QDir>
#include <QFile>

#include <set>

#include "net/frame.h"
#include "net/message.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

using namespace sp::net;

namespace {

const QString kCorpus = QStringLiteral(SP_SOURCE_DIR "/net/fuzz/corpus");

QByteArray readFile(const QString& path) {
  QFile file(path);
  if (!file.open(QIODevice::ReadOnly)) qFatal("cannot read %s", qPrintable(path));
  return file.readAll();
}

QStringList corpusFiles() { return QDir(kCorpus).entryList(QDir::Files, QDir::Name); }

}  // namespace

class TestFuzzCorpus : public QObject {
  Q_OBJECT

 private slots:
  void replay_data();
  void replay();
  void corpusCoversTypesAndErrors();
};

void TestFuzzCorpus::replay_data() {
  QTest::addColumn<QString>("file");
  for (const QString& name : corpusFiles()) QTest::newRow(qPrintable(name)) << kCorpus + "/" + name;
}

// Each seed runs through the fuzz function without breaking a property
// (a broken one aborts the test).
void TestFuzzCorpus::replay() {
  QFETCH(QString, file);
  const QByteArray bytes = readFile(file);
  QCOMPARE(LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.constData()),
                                  static_cast<size_t>(bytes.size())),
           0);
}

// The corpus holds a valid message of every type and a stream ending in each
// frame error, so that the fuzzer starts from every branch.
void TestFuzzCorpus::corpusCoversTypesAndErrors() {
  std::set<int> types;
  std::set<FrameError> errors;
  for (const QString& name : corpusFiles()) {
    const QByteArray bytes = readFile(kCorpus + "/" + name);
    FrameDecoder decoder;
    decoder.feed(bytes.constData(), static_cast<size_t>(bytes.size()));
    while (std::optional<Frame> frame = decoder.next()) {
      std::string error;
      if (decodeMessage(*frame, error)) types.insert(frame->type);
    }
    errors.insert(decoder.error());
  }
  for (int type = kFirstMessageType; type <= kLastMessageType; ++type)
    QVERIFY2(types.count(type), messageTypeName(static_cast<uint8_t>(type)));
  for (FrameError e : {FrameError::None, FrameError::BadMagic, FrameError::UnsupportedVersion, FrameError::Oversize,
                       FrameError::BadCrc})
    QVERIFY2(errors.count(e), toString(e));
}

QTEST_GUILESS_MAIN(TestFuzzCorpus)
#include "tst_fuzz_corpus.moc"
