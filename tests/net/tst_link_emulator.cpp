// Link emulation (net/link_emulator.h): delay and jitter bounds, loss
// fraction, bandwidth, order, determinism.

#include <QTest>

#include <cmath>
#include <vector>

#include "net/link_emulator.h"

using namespace sp::net;

class TestLinkEmulator : public QObject {
  Q_OBJECT

 private slots:
  // The default config is a perfect link: every frame due when sent.
  void perfectLink() {
    LinkEmulator link;
    QVERIFY(!link.config().active());
    for (int i = 0; i < 1000; ++i) {
      const double now = i * 0.001;
      const auto due = link.schedule(100, now);
      QVERIFY(due);
      QCOMPARE(*due, now);
    }
    QCOMPARE(link.framesDropped(), uint64_t{0});
    QCOMPARE(link.framesSent(), uint64_t{1000});
    QCOMPARE(link.bytesSent(), uint64_t{100000});
  }

  void delayAndJitter_data() {
    QTest::addColumn<double>("delay");
    QTest::addColumn<double>("jitter");
    QTest::newRow("planetary 2 s +- 0.1 s") << 2.0 << 0.1;
    QTest::newRow("field radio 30 ms +- 20 ms") << 0.03 << 0.02;
    QTest::newRow("delay only") << 0.5 << 0.0;
  }
  // Each frame's delay lies in [delay - jitter, delay + jitter]; over many
  // frames the delays fill that range and average to `delay`.
  void delayAndJitter() {
    QFETCH(double, delay);
    QFETCH(double, jitter);
    // Frames 1 s apart, so that keepOrder never holds one back.
    LinkEmulator link({.delay = delay, .jitter = jitter, .seed = 7});
    double lo = INFINITY, hi = -INFINITY, sum = 0;
    const int n = 10000;
    for (int i = 0; i < n; ++i) {
      const double now = 1.0 * i;
      const auto due = link.schedule(64, now);
      QVERIFY(due);
      const double d = *due - now;
      QVERIFY2(d >= delay - jitter - 1e-9 && d <= delay + jitter + 1e-9, qPrintable(QString::number(d)));
      lo = std::min(lo, d);
      hi = std::max(hi, d);
      sum += d;
    }
    // Uniform jitter: the extremes of 10000 draws come within 0.1 % of the
    // bounds, and the mean within 5 standard errors (sd = jitter / sqrt(3)).
    QVERIFY(lo <= delay - jitter + 0.002 * jitter + 1e-12);
    QVERIFY(hi >= delay + jitter - 0.002 * jitter - 1e-12);
    const double standardError = jitter / std::sqrt(3.0) / std::sqrt(double(n));
    QVERIFY(std::abs(sum / n - delay) <= 5 * standardError + 1e-12);
  }

  // A jitter larger than the delay never makes a frame due before it was sent.
  void delayNeverNegative() {
    LinkEmulator link({.delay = 0.01, .jitter = 0.05, .keepOrder = false});
    int atOnce = 0;
    for (int i = 0; i < 10000; ++i) {
      const double now = 0.1 * i;
      const double due = *link.schedule(10, now);
      QVERIFY(due >= now);
      if (due == now) ++atOnce;
    }
    QVERIFY(atOnce > 3000);  // 40 % of the draws fall below zero and are clipped to it
  }

  void lossFraction_data() {
    QTest::addColumn<double>("loss");
    QTest::newRow("1 %") << 0.01;
    QTest::newRow("10 %") << 0.1;
    QTest::newRow("50 %") << 0.5;
    QTest::newRow("90 %") << 0.9;
    QTest::newRow("none") << 0.0;
    QTest::newRow("all") << 1.0;
  }
  // The fraction of frames lost is the configured probability, within five
  // standard deviations of the binomial count (the seeds are fixed, so this
  // is a check of the mapping, not a flaky statistical test).
  void lossFraction() {
    QFETCH(double, loss);
    for (uint64_t seed : {1u, 2u, 3u}) {
      LinkEmulator link({.loss = loss, .seed = seed});
      const int n = 100000;
      for (int i = 0; i < n; ++i) link.schedule(32, i * 0.001);
      const double expected = n * loss, sd = std::sqrt(n * loss * (1 - loss));
      const double lost = double(link.framesDropped());
      QVERIFY2(std::abs(lost - expected) <= 5 * sd,
               qPrintable(QString("lost %1 of %2, expected %3 +- %4").arg(lost).arg(n).arg(expected).arg(5 * sd)));
    }
  }

  // Loss and jitter come from separate draws: the frames that get through
  // have the same delays whatever the loss.
  void lossDoesNotShiftJitter() {
    LinkEmulator lossless({.delay = 1, .jitter = 0.5, .seed = 11});
    LinkEmulator lossy({.delay = 1, .jitter = 0.5, .loss = 0.3, .seed = 11});
    for (int i = 0; i < 1000; ++i) {
      const auto a = lossless.schedule(10, i * 10.0), b = lossy.schedule(10, i * 10.0);
      if (b) QCOMPARE(*b, *a);
    }
  }

  // Without keepOrder, frames spaced more than 2 x jitter apart still arrive
  // in order; closer ones may overtake each other (as documented).
  void orderWithoutKeepOrder() {
    const double spacing = 0.01;
    LinkEmulator wide({.delay = 0.1, .jitter = 0.0049, .keepOrder = false, .seed = 3});
    LinkEmulator narrow({.delay = 0.1, .jitter = 0.02, .keepOrder = false, .seed = 3});
    double lastWide = -1, lastNarrow = -1;
    int overtakes = 0;
    for (int i = 0; i < 10000; ++i) {
      const double now = i * spacing;
      const double w = *wide.schedule(50, now), n = *narrow.schedule(50, now);
      QVERIFY(w > lastWide);
      if (n < lastNarrow) ++overtakes;
      lastWide = w;
      lastNarrow = n;
    }
    QVERIFY(overtakes > 100);
  }

  // With keepOrder (the default) due times never decrease, whatever the jitter.
  void keepOrderAlways() {
    LinkEmulator link({.delay = 2, .jitter = 0.1, .seed = 5});
    double last = -1;
    for (int i = 0; i < 10000; ++i) {
      const double now = i * 0.001;
      const double due = *link.schedule(50, now);
      QVERIFY(due >= last);
      QVERIFY(due >= now + 1.9 - 1e-9);
      last = due;
    }
  }

  // Bandwidth: frames leave one after another, each taking bytes/bandwidth.
  void bandwidth() {
    LinkEmulator link({.delay = 0.5, .bandwidth = 10000});
    // Ten 1000-byte frames sent at once: the k-th is due 0.1 k s later.
    for (int k = 1; k <= 10; ++k) QCOMPARE(*link.schedule(1000, 0.0), 0.5 + 0.1 * k);
    // An idle link sends a frame at once.
    QCOMPARE(*link.schedule(100, 10.0), 10.0 + 0.5 + 0.01);
  }

  // A fade holds what is sent in it until its end, then adds the delay; the
  // frames around it keep the times they would have had (no draw is spent).
  void fade() {
    const LinkEmulatorConfig config{.delay = 0.3, .jitter = 0.05, .seed = 8};
    LinkEmulator faded(config), plain(config);
    for (int i = 0; i < 300; ++i) {
      const double now = i * 0.01;  // the fade covers [1, 1.5)
      if (i == 100) faded.fade(1.5);
      const double f = *faded.schedule(20, now), p = *plain.schedule(20, now);
      if (now < 1.0) QCOMPARE(f, p);
      else if (now < 1.5) QVERIFY2(f >= 1.5 + 0.25 - 1e-9, qPrintable(QString("sent at %1, due %2").arg(now).arg(f)));
      else if (now > 1.6) QCOMPARE(f, p);  // past the fade and its backlog
    }
    // A shorter fade inside a longer one does not shorten it.
    LinkEmulator link({.delay = 0.1});
    link.fade(2.0);
    link.fade(1.0);
    QCOMPARE(*link.schedule(1, 0.5), 2.1);
  }

  // The same seed gives the same times; another seed other times.
  void deterministic() {
    const LinkEmulatorConfig config{.delay = 0.2, .jitter = 0.1, .loss = 0.2, .seed = 99};
    LinkEmulator a(config), b(config);
    LinkEmulatorConfig other = config;
    other.seed = 100;
    LinkEmulator c(other);
    int differ = 0;
    for (int i = 0; i < 1000; ++i) {
      const auto x = a.schedule(40, i * 0.02), y = b.schedule(40, i * 0.02), z = c.schedule(40, i * 0.02);
      QCOMPARE(x, y);
      if (x != z) ++differ;
    }
    QVERIFY(differ > 500);
    // setConfig re-seeds: the sequence starts over.
    LinkEmulator d(config);
    const auto first = d.schedule(40, 0);
    d.setConfig(config);
    QCOMPARE(d.schedule(40, 100), first ? std::optional<double>(*first + 100) : std::nullopt);
  }
};

QTEST_APPLESS_MAIN(TestLinkEmulator)
#include "tst_link_emulator.moc"
