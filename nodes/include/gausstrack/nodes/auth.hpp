// Authenticated messages between a paired plant and controller. The pair shares a secret key
// (a file readable by its owner alone, written by gausstrack-keygen); the sender of a channel
// appends a trailer to every message it publishes on it, and the receiver verifies the trailer
// before it decodes anything:
//
//   [LCM-encoded message][ "GTA1" ][ counter: int64, big-endian ][ tag: 32 bytes ]
//   tag = BLAKE2b-256 keyed with the pair's key, over  channel name, '\0', message, "GTA1", counter
//
// - The tag covers every byte before it and the channel, so a message altered anywhere, or moved
//   to another channel, is refused (libsodium's keyed BLAKE2b; compared in constant time).
// - The counter strictly increases per sender: max(last + 1, the sender's wall clock in ns), so it
//   keeps increasing across restarts of the sender without stored state. A receiver accepts a
//   message only if its counter is above the last one it accepted on that channel: a message
//   captured and sent again later, in this run or from a recorded log, is refused as replayed.
//   (A sender whose clock is stepped back by s seconds is refused for s seconds by a receiver
//   that outlived it.)
// - Binding to the run: commands carry the plant run's random id and the sequence of the state
//   they answer; the plant applies only commands for states it published and has not yet had
//   answered (PlantNode). With the key, nobody else can make such a command.
// Checking costs bounded work per message: a size check, a counter comparison, one keyed hash of
// at most kMessageBufferBytes. Sealing and opening allocate nothing and throw nothing.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace gausstrack::nodes {

inline constexpr std::size_t kKeyBytes = 32;
inline constexpr std::size_t kTagBytes = 32;
inline constexpr std::size_t kTrailerBytes = 4 + 8 + kTagBytes;

/// Why a message failed authentication (each is counted by the nodes).
enum class AuthRefusal : std::uint8_t {
  kNone,
  kUnauthenticated,  ///< no trailer: sent without a key (or not a gausstrack message at all)
  kBadTag,           ///< the tag does not match: another key, or altered on the way
  kReplayed,         ///< a valid message whose counter is not above the last accepted one
};

const char* to_string(AuthRefusal r) noexcept;

/// The pair's secret key.
class MessageKey {
 public:
  /// Reads a key file: 64 hexadecimal digits. Throws std::runtime_error saying why it cannot (no
  /// such file, readable by group or others, not a key).
  static MessageKey load(const std::string& path);
  /// Writes a new random key to `path`, created with mode 0600; refuses to overwrite a file.
  /// Throws std::runtime_error when it cannot.
  static void generate(const std::string& path);
  /// A key from its bytes (tests).
  explicit MessageKey(const std::array<std::uint8_t, kKeyBytes>& bytes) noexcept : bytes_(bytes) {}

  const std::array<std::uint8_t, kKeyBytes>& bytes() const noexcept { return bytes_; }

 private:
  std::array<std::uint8_t, kKeyBytes> bytes_{};
};

/// One channel's authentication, for its sender (seal) or its receiver (open).
class ChannelAuth {
 public:
  /// Throws std::runtime_error if libsodium cannot start.
  ChannelAuth(const MessageKey& key, std::string channel);

  /// Appends the trailer to the `size` bytes of message in `buffer`. Returns the sealed size, or
  /// -1 when `capacity` cannot hold it.
  int seal(std::uint8_t* buffer, std::size_t size, std::size_t capacity) noexcept;

  /// Verifies a received message. On success returns kNone, sets `message_size` to the size of
  /// the message before its trailer and raises the channel's last accepted counter; on refusal
  /// changes nothing.
  AuthRefusal open(const void* data, std::size_t size, std::size_t& message_size) noexcept;

  const std::string& channel() const noexcept { return channel_; }
  std::int64_t last_accepted() const noexcept { return last_accepted_; }

 private:
  void tag(const std::uint8_t* data, std::size_t size, std::uint8_t* out) const noexcept;

  MessageKey key_;
  std::string channel_;
  std::int64_t last_sent_ = 0, last_accepted_ = 0;
};

/// Counts of messages refused by authentication, by reason.
struct AuthCounts {
  long unauthenticated = 0, bad_tag = 0, replayed = 0;
  long total() const noexcept { return unauthenticated + bad_tag + replayed; }
  void count(AuthRefusal r) noexcept {
    if (r == AuthRefusal::kUnauthenticated) ++unauthenticated;
    else if (r == AuthRefusal::kBadTag) ++bad_tag;
    else if (r == AuthRefusal::kReplayed) ++replayed;
  }
};

/// A receiver's first step: with no `auth` every message passes; with one, a message passes only
/// if it verifies, and `size` then becomes the size of the message before its trailer. A refused
/// message is counted by reason in `refused` and must not be read.
inline bool admit(ChannelAuth* auth, const void* data, std::size_t& size, AuthCounts& refused) noexcept {
  if (auth == nullptr) return true;
  std::size_t message_size = 0;
  const AuthRefusal r = auth->open(data, size, message_size);
  if (r != AuthRefusal::kNone) {
    refused.count(r);
    return false;
  }
  size = message_size;
  return true;
}

}  // namespace gausstrack::nodes
