#pragma once
// Authentication of a HELLO by challenge and response: the robot sends a
// fresh random nonce (CHALLENGE) on every connection; the client answers
// with HMAC-SHA256 keyed by the shared token over that nonce, its name and
// its role (HELLO `proof`). The token never crosses the link, and a HELLO
// captured on one connection is useless on the next (another nonce).
// docs/protocol.md, "Connecting", says what this does and does not protect.
//
// Free functions on OpenSSL's libcrypto: usable from any thread.

#include <cstddef>
#include <string>
#include <string_view>

#include "net/message.h"

namespace sp::net {

/// `bytes` bytes from the operating system's secure random source, as
/// 2 * bytes lower-case hex digits. Throws std::runtime_error if the source
/// fails (never falls back to a weaker one).
std::string randomHex(size_t bytes);

/// A random token of 128 bits, as 32 hex digits.
std::string randomToken();

/// HELLO `proof`: 64 lower-case hex digits of HMAC-SHA256 with the token's
/// text as key over "simpartner-hello\n" nonce "\n" name "\n" role.
std::string helloProof(std::string_view token, std::string_view nonce, std::string_view name, Role role);

/// Constant-time comparison (no early exit), for tokens and proofs.
bool equalConstantTime(std::string_view a, std::string_view b);

}  // namespace sp::net
