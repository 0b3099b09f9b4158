// HELLO authentication (net/auth.h): the proof is HMAC-SHA256 as any other
// implementation computes it, it binds nonce, name, role and token, and
// nonces do not repeat.

#include <QTest>

#include <set>

#include "net/auth.h"

using namespace sp::net;

class TestAuth : public QObject {
  Q_OBJECT

 private slots:
  // The value Python's hmac module gives for the same inputs:
  //   hmac.new(token, b"simpartner-hello\n" + nonce + b"\nconsole\ncontrol", hashlib.sha256).hexdigest()
  void proofMatchesAnIndependentHmac() {
    QCOMPARE(helloProof("00112233445566778899aabbccddeeff", "0123456789abcdef0123456789abcdef", "console", Role::Control),
             std::string("a0c7492c3dbbaf2d413c18eab0825a575bc6ce0b38ff2e22fb56a3b162a8b1a9"));
  }

  // Change any input and the proof changes.
  void proofBindsEveryInput() {
    const std::string token = "00112233445566778899aabbccddeeff", nonce = "0123456789abcdef0123456789abcdef";
    const std::string proof = helloProof(token, nonce, "console", Role::Control);
    QCOMPARE(proof.size(), size_t{64});
    QVERIFY(helloProof("10112233445566778899aabbccddeeff", nonce, "console", Role::Control) != proof);
    QVERIFY(helloProof(token, "1123456789abcdef0123456789abcdef", "console", Role::Control) != proof);
    QVERIFY(helloProof(token, nonce, "consolf", Role::Control) != proof);
    QVERIFY(helloProof(token, nonce, "console", Role::Monitor) != proof);
  }

  // Nonces are fresh: 1000 draws of 128 bits, no repeat, all hex.
  void noncesDoNotRepeat() {
    std::set<std::string> seen;
    for (int i = 0; i < 1000; ++i) {
      const std::string n = randomHex(16);
      QCOMPARE(n.size(), size_t{32});
      QVERIFY(n.find_first_not_of("0123456789abcdef") == std::string::npos);
      seen.insert(n);
    }
    QCOMPARE(seen.size(), size_t{1000});
    QCOMPARE(randomToken().size(), size_t{32});
  }

  // Tokens compare equal only when equal, whatever their lengths.
  void constantTimeCompare() {
    const std::string token = "00112233445566778899aabbccddeeff";
    QVERIFY(equalConstantTime(token, token));
    QVERIFY(!equalConstantTime(token, token.substr(0, 31)));
    QVERIFY(!equalConstantTime(token, token + "0"));
    QVERIFY(!equalConstantTime(token, "10112233445566778899aabbccddeeff"));
  }
};

QTEST_GUILESS_MAIN(TestAuth)
#include "tst_auth.moc"
