// Authenticated messages without a network: the trailer refuses any one bit flipped anywhere in
// a sealed state or command, another key, another channel, a replay and a message without a
// trailer, and never moves the receiver's counter when it refuses; the key file is refused when
// others may read it or it is not a key.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "gausstrack/control_command_t.hpp"
#include "gausstrack/nodes/auth.hpp"
#include "gausstrack/plant_state_t.hpp"

namespace gausstrack::nodes {
namespace {

MessageKey key_from(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::array<std::uint8_t, kKeyBytes> bytes{};
  for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
  return MessageKey(bytes);
}

template <typename Message>
std::vector<std::uint8_t> encoded(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()) + kTrailerBytes);
  m.encode(bytes.data(), 0, m.getEncodedSize());
  return bytes;
}

plant_state_t some_state() {
  plant_state_t s{};
  s.utime = 1'700'000'000'000'000;
  s.sequence = 41;
  s.run_id = 0x1234'5678'9abc;
  s.t = 0.041;
  s.dimension = 3;
  for (int i = 0; i < 3; ++i) s.q[i] = 0.1 * (i + 1), s.qd[i] = -0.2 * i;
  return s;
}

control_command_t some_command() {
  control_command_t c{};
  c.sequence = 42;
  c.run_id = 0x1234'5678'9abc;
  c.state_sequence = 41;
  c.dimension = 3;
  for (int i = 0; i < 3; ++i) c.force[i] = 1.5 * (i - 1);
  return c;
}

// Seals `bytes` (message then room for the trailer) on `channel`; returns the sealed size.
std::size_t seal(ChannelAuth& sender, std::vector<std::uint8_t>& bytes) {
  const int n = sender.seal(bytes.data(), bytes.size() - kTrailerBytes, bytes.size());
  EXPECT_EQ(n, static_cast<int>(bytes.size()));
  return static_cast<std::size_t>(n);
}

template <typename Message>
void every_bit_flip_is_refused(const Message& m, const char* channel) {
  ChannelAuth sender(key_from(1), channel), receiver(key_from(1), channel);
  std::vector<std::uint8_t> bytes = encoded(m);
  const std::size_t size = seal(sender, bytes);
  const std::size_t body = size - kTrailerBytes;
  for (std::size_t i = 0; i < size; ++i) {
    for (int bit = 0; bit < 8; ++bit) {
      std::vector<std::uint8_t> tampered = bytes;
      tampered[i] ^= static_cast<std::uint8_t>(1u << bit);
      std::size_t message_size = 0;
      const AuthRefusal r = receiver.open(tampered.data(), size, message_size);
      // A flip inside the magic makes it look unsigned; anywhere else the tag no longer matches.
      const AuthRefusal expected =
          i >= body && i < body + 4 ? AuthRefusal::kUnauthenticated : AuthRefusal::kBadTag;
      ASSERT_EQ(r, expected) << "byte " << i << " bit " << bit;
      ASSERT_EQ(receiver.last_accepted(), 0) << "a refused message moved the counter";
    }
  }
  // The untouched message opens, and gives back the message's own size and bytes.
  std::size_t message_size = 0;
  ASSERT_EQ(receiver.open(bytes.data(), size, message_size), AuthRefusal::kNone);
  EXPECT_EQ(message_size, body);
  Message decoded{};
  EXPECT_EQ(decoded.decode(bytes.data(), 0, static_cast<int>(message_size)), static_cast<int>(message_size));
}

TEST(MessageAuth, EveryBitFlippedInASealedStateIsRefused) { every_bit_flip_is_refused(some_state(), "STATE"); }

TEST(MessageAuth, EveryBitFlippedInASealedCommandIsRefused) {
  every_bit_flip_is_refused(some_command(), "COMMAND");
}

TEST(MessageAuth, AnotherKeyAnotherChannelOrNoTrailerIsRefused) {
  ChannelAuth sender(key_from(1), "COMMAND");
  std::vector<std::uint8_t> bytes = encoded(some_command());
  const std::size_t size = seal(sender, bytes);
  std::size_t message_size = 0;
  ChannelAuth other_key(key_from(2), "COMMAND"), other_channel(key_from(1), "STATE");
  EXPECT_EQ(other_key.open(bytes.data(), size, message_size), AuthRefusal::kBadTag);
  EXPECT_EQ(other_channel.open(bytes.data(), size, message_size), AuthRefusal::kBadTag);
  ChannelAuth receiver(key_from(1), "COMMAND");
  EXPECT_EQ(receiver.open(bytes.data(), size - kTrailerBytes, message_size), AuthRefusal::kUnauthenticated);
  EXPECT_EQ(receiver.open(bytes.data(), kTrailerBytes - 1, message_size), AuthRefusal::kUnauthenticated);
  EXPECT_EQ(receiver.open(bytes.data(), size - 1, message_size), AuthRefusal::kUnauthenticated);
  EXPECT_EQ(receiver.last_accepted(), 0);
  EXPECT_EQ(receiver.open(bytes.data(), size, message_size), AuthRefusal::kNone);
}

TEST(MessageAuth, AReplayIsRefusedAndTheCounterOnlyGrows) {
  ChannelAuth sender(key_from(7), "STATE"), receiver(key_from(7), "STATE");
  std::vector<std::vector<std::uint8_t>> sealed;
  for (int k = 0; k < 100; ++k) {  // faster than the clock's resolution: the counter still grows
    sealed.push_back(encoded(some_state()));
    seal(sender, sealed.back());
  }
  std::size_t message_size = 0;
  std::int64_t last = 0;
  for (std::size_t k = 0; k < sealed.size(); k += 2) {  // every other one, in order: accepted
    ASSERT_EQ(receiver.open(sealed[k].data(), sealed[k].size(), message_size), AuthRefusal::kNone) << k;
    ASSERT_GT(receiver.last_accepted(), last);
    last = receiver.last_accepted();
  }
  // The same message again, or an older one that never arrived: replayed, counter unchanged.
  EXPECT_EQ(receiver.open(sealed[98].data(), sealed[98].size(), message_size), AuthRefusal::kReplayed);
  EXPECT_EQ(receiver.open(sealed[51].data(), sealed[51].size(), message_size), AuthRefusal::kReplayed);
  EXPECT_EQ(receiver.last_accepted(), last);
  EXPECT_EQ(receiver.open(sealed[99].data(), sealed[99].size(), message_size), AuthRefusal::kNone);
  // A restarted sender keeps counting up (its counter follows the wall clock), so a receiver that
  // outlived it accepts it; messages recorded from the first sender stay refused.
  ChannelAuth restarted(key_from(7), "STATE");
  std::vector<std::uint8_t> fresh = encoded(some_state());
  seal(restarted, fresh);
  EXPECT_EQ(receiver.open(fresh.data(), fresh.size(), message_size), AuthRefusal::kNone);
  EXPECT_EQ(receiver.open(sealed[99].data(), sealed[99].size(), message_size), AuthRefusal::kReplayed);
}

TEST(MessageAuth, SealRefusesABufferWithoutRoomForTheTrailer) {
  ChannelAuth sender(key_from(1), "STATE");
  std::vector<std::uint8_t> bytes(100);
  EXPECT_EQ(sender.seal(bytes.data(), 100 - kTrailerBytes + 1, bytes.size()), -1);
  EXPECT_EQ(sender.seal(bytes.data(), 0, kTrailerBytes - 1), -1);
  EXPECT_EQ(sender.seal(bytes.data(), 100 - kTrailerBytes, bytes.size()), 100);
}

struct KeyFile : ::testing::Test {
  std::filesystem::path dir;
  void SetUp() override {
    dir = std::filesystem::temp_directory_path() /
          ("gausstrack_key_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
  }
  void TearDown() override { std::filesystem::remove_all(dir); }
  std::string write(const std::string& name, const std::string& text, mode_t mode) {
    const std::string path = (dir / name).string();
    std::ofstream(path) << text;
    chmod(path.c_str(), mode);
    return path;
  }
  static std::string error_of(const std::string& path) {
    try {
      MessageKey::load(path);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(KeyFile, GeneratedKeysLoadAreOwnerOnlyAndDiffer) {
  const std::string a = (dir / "a.key").string(), b = (dir / "b.key").string();
  MessageKey::generate(a);
  MessageKey::generate(b);
  struct stat st {};
  ASSERT_EQ(stat(a.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  const MessageKey ka = MessageKey::load(a), kb = MessageKey::load(b);
  EXPECT_NE(ka.bytes(), kb.bytes());
  // What one side seals with the file, the other opens with the same file.
  ChannelAuth sender(ka, "C"), receiver(MessageKey::load(a), "C"), stranger(kb, "C");
  std::vector<std::uint8_t> bytes = encoded(some_command());
  const std::size_t size = seal(sender, bytes);
  std::size_t message_size = 0;
  EXPECT_EQ(stranger.open(bytes.data(), size, message_size), AuthRefusal::kBadTag);
  EXPECT_EQ(receiver.open(bytes.data(), size, message_size), AuthRefusal::kNone);
  EXPECT_THROW(MessageKey::generate(a), std::runtime_error);  // never overwrites a key
}

TEST_F(KeyFile, RefusesAFileOthersMayReadOrThatIsNotAKey) {
  const std::string hex(2 * kKeyBytes, 'a');
  EXPECT_EQ(error_of(write("ok.key", hex + "\n", 0600)), "");
  EXPECT_NE(error_of(write("open.key", hex, 0644)).find("readable by its owner alone"), std::string::npos);
  EXPECT_NE(error_of(write("group.key", hex, 0640)).find("0640"), std::string::npos);
  EXPECT_NE(error_of(write("short.key", hex.substr(1), 0600)).find("not a key"), std::string::npos);
  EXPECT_NE(error_of(write("nothex.key", std::string(2 * kKeyBytes, 'g'), 0600)).find("not a key"), std::string::npos);
  EXPECT_NE(error_of(write("extra.key", hex + " " + hex, 0600)).find("not a key"), std::string::npos);
  EXPECT_NE(error_of((dir / "missing.key").string()).find("No such file"), std::string::npos);
  EXPECT_NE(error_of(dir.string()).find("not a regular file"), std::string::npos);
}

}  // namespace
}  // namespace gausstrack::nodes
