// Authenticated messages: the key file and the trailer, over libsodium (keyed BLAKE2b, constant-
// time comparison, the system's random source).
#include "gausstrack/nodes/auth.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <stdexcept>

namespace gausstrack::nodes {
namespace {

constexpr std::uint8_t kMagic[4] = {'G', 'T', 'A', '1'};
static_assert(kKeyBytes == crypto_generichash_KEYBYTES);
static_assert(kTagBytes >= crypto_generichash_BYTES_MIN && kTagBytes <= crypto_generichash_BYTES_MAX);

void start_sodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium cannot start (no random source?)");
}

std::int64_t wall_ns() noexcept {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

void put_be64(std::uint8_t* p, std::int64_t v) noexcept {
  const auto u = static_cast<std::uint64_t>(v);
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(u >> (56 - 8 * i));
}

std::int64_t get_be64(const std::uint8_t* p) noexcept {
  std::uint64_t u = 0;
  for (int i = 0; i < 8; ++i) u = u << 8 | p[i];
  return static_cast<std::int64_t>(u);
}

}  // namespace

const char* to_string(AuthRefusal r) noexcept {
  switch (r) {
    case AuthRefusal::kNone: return "none";
    case AuthRefusal::kUnauthenticated: return "unauthenticated";
    case AuthRefusal::kBadTag: return "bad tag";
    case AuthRefusal::kReplayed: return "replayed";
  }
  return "unknown";
}

MessageKey MessageKey::load(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0)
    throw std::runtime_error("key file " + path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw std::runtime_error("key file " + path + ": not a regular file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw std::runtime_error("key file " + path + ": permissions " + mode +
                             " let others read it; it must be readable by its owner alone (chmod 600)");
  }
  std::ifstream in(path);
  std::string hex;
  if (!(in >> hex)) throw std::runtime_error("key file " + path + ": cannot read it");
  std::string rest;
  std::array<std::uint8_t, kKeyBytes> bytes{};
  std::size_t written = 0;
  if (hex.size() != 2 * kKeyBytes || (in >> rest) ||
      sodium_hex2bin(bytes.data(), bytes.size(), hex.data(), hex.size(), nullptr, &written, nullptr) != 0 ||
      written != kKeyBytes)
    throw std::runtime_error("key file " + path + ": not a key (" + std::to_string(2 * kKeyBytes) +
                             " hexadecimal digits, as gausstrack-keygen writes)");
  return MessageKey(bytes);
}

void MessageKey::generate(const std::string& path) {
  start_sodium();
  std::array<std::uint8_t, kKeyBytes> key{};
  crypto_generichash_keygen(key.data());
  std::array<char, 2 * kKeyBytes + 1> hex{};
  sodium_bin2hex(hex.data(), hex.size(), key.data(), key.size());
  sodium_memzero(key.data(), key.size());
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) throw std::runtime_error("cannot create key file " + path + ": " + std::strerror(errno));
  std::string text(hex.data(), 2 * kKeyBytes);
  text += '\n';
  const bool ok = fchmod(fd, 0600) == 0 && write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const int saved = errno;
  sodium_memzero(text.data(), text.size());
  sodium_memzero(hex.data(), hex.size());
  if (close(fd) != 0 || !ok) {
    unlink(path.c_str());
    throw std::runtime_error("cannot write key file " + path + ": " + std::strerror(ok ? errno : saved));
  }
}

ChannelAuth::ChannelAuth(const MessageKey& key, std::string channel) : key_(key), channel_(std::move(channel)) {
  start_sodium();
}

void ChannelAuth::tag(const std::uint8_t* data, std::size_t size, std::uint8_t* out) const noexcept {
  crypto_generichash_state state;
  crypto_generichash_init(&state, key_.bytes().data(), kKeyBytes, kTagBytes);
  crypto_generichash_update(&state, reinterpret_cast<const unsigned char*>(channel_.c_str()), channel_.size() + 1);
  crypto_generichash_update(&state, data, size);
  crypto_generichash_final(&state, out, kTagBytes);
}

int ChannelAuth::seal(std::uint8_t* buffer, std::size_t size, std::size_t capacity) noexcept {
  if (capacity < kTrailerBytes || size > capacity - kTrailerBytes) return -1;
  last_sent_ = std::max(last_sent_ + 1, wall_ns());
  std::memcpy(buffer + size, kMagic, sizeof kMagic);
  put_be64(buffer + size + sizeof kMagic, last_sent_);
  tag(buffer, size + sizeof kMagic + 8, buffer + size + sizeof kMagic + 8);
  return static_cast<int>(size + kTrailerBytes);
}

AuthRefusal ChannelAuth::open(const void* data, std::size_t size, std::size_t& message_size) noexcept {
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  if (size < kTrailerBytes) return AuthRefusal::kUnauthenticated;
  const std::size_t body = size - kTrailerBytes;
  if (std::memcmp(bytes + body, kMagic, sizeof kMagic) != 0) return AuthRefusal::kUnauthenticated;
  // The tag first: an unauthenticated counter says nothing, not even that the message is old.
  std::uint8_t expected[kTagBytes];
  tag(bytes, body + sizeof kMagic + 8, expected);
  if (sodium_memcmp(expected, bytes + body + sizeof kMagic + 8, kTagBytes) != 0) return AuthRefusal::kBadTag;
  const std::int64_t counter = get_be64(bytes + body + sizeof kMagic);
  if (counter <= last_accepted_) return AuthRefusal::kReplayed;
  last_accepted_ = counter;
  message_size = body;
  return AuthRefusal::kNone;
}

}  // namespace gausstrack::nodes
