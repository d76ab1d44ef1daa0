// A process's own record of the messages it publishes, written to an LCM log file
// (lcm::LogFile) by a writer thread, so that a run's log is complete by construction.
//
// Why not lcm-logger: it is a third process listening on UDP multicast, and a burst it cannot
// drain in time (a lock-step run publishes as fast as the loop turns) is lost in the kernel's
// socket buffer with nothing counted. Here each process hands every message it publishes to its
// own log before it goes on the wire; gausstrack-run merges the processes' logs into one.
//
// Real-time side: `record` copies the encoded bytes into a preallocated slot of a single-producer
// single-consumer ring (no allocation, no lock, no I/O). The writer thread drains the ring to the
// file. When the ring is full (the disk stalled for longer than the ring holds), `record` either
// waits for a free slot (lock-step: nothing is ever lost) or counts the message as dropped
// (real time: the loop never waits on the disk); `dropped()` reports it and the processes print it.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "gausstrack/nodes/auth.hpp"
#include "gausstrack/nodes/codec.hpp"

namespace gausstrack::nodes {

class MessageLog {
 public:
  static constexpr std::size_t kSlotBytes = 2048;  // the largest message (a command) is 1.1 kB

  /// Opens `path` for writing (throws std::runtime_error if it cannot), with `slots` messages of
  /// buffering (about 2 kB each; 4096 slots hold 4 s of a 1 kHz loop's messages).
  explicit MessageLog(const std::string& path, std::size_t slots = 4096)
      : file_(path, "w"), slots_(slots) {
    if (!file_.good()) throw std::runtime_error("cannot write the message log " + path);
    writer_ = std::thread([this] { drain_loop(); });
  }
  MessageLog(const MessageLog&) = delete;
  MessageLog& operator=(const MessageLog&) = delete;
  ~MessageLog() { close(); }

  /// Registers a channel name (at setup) and returns its index for `record`.
  int add_channel(const std::string& name) {
    channels_.push_back(name);
    return static_cast<int>(channels_.size()) - 1;
  }

  /// Copies one encoded message. Returns false when it was not recorded (too large, or the ring
  /// was full and `wait_if_full` is false); such messages are counted in `dropped()`.
  bool record(int channel, const void* data, std::size_t size, std::int64_t utime, bool wait_if_full) noexcept {
    if (size > kSlotBytes || channel < 0 || channel >= static_cast<int>(channels_.size()) ||
        stop_.load(std::memory_order_acquire)) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    const std::size_t head = head_.load(std::memory_order_relaxed);
    while (head - tail_.load(std::memory_order_acquire) >= slots_.size()) {
      if (!wait_if_full) {
        dropped_.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
    Slot& s = slots_[head % slots_.size()];
    s.utime = utime;
    s.channel = channel;
    s.size = static_cast<std::uint32_t>(size);
    std::memcpy(s.data, data, size);
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Writes what is buffered and closes the file; later `record` calls count as dropped.
  void close() {
    if (!writer_.joinable()) return;
    stop_.store(true, std::memory_order_release);
    writer_.join();
  }

  long dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
  long written() const noexcept { return written_.load(std::memory_order_relaxed); }

 private:
  struct Slot {
    std::int64_t utime = 0;
    int channel = 0;
    std::uint32_t size = 0;
    std::uint8_t data[kSlotBytes];
  };

  void drain_loop() {
    for (;;) {
      const bool stopping = stop_.load(std::memory_order_acquire);
      std::size_t tail = tail_.load(std::memory_order_relaxed);
      const std::size_t head = head_.load(std::memory_order_acquire);
      for (; tail != head; ++tail) {
        Slot& s = slots_[tail % slots_.size()];
        lcm::LogEvent event{};
        event.timestamp = s.utime;
        event.channel = channels_[static_cast<std::size_t>(s.channel)];
        event.datalen = static_cast<std::int32_t>(s.size);
        event.data = s.data;
        if (file_.writeEvent(&event) == 0) written_.fetch_add(1, std::memory_order_relaxed);
        else dropped_.fetch_add(1, std::memory_order_relaxed);
        tail_.store(tail + 1, std::memory_order_release);
      }
      if (stopping && tail == head_.load(std::memory_order_acquire)) break;
      if (tail == head) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    std::fflush(file_.getFilePtr());
  }

  lcm::LogFile file_;
  std::vector<Slot> slots_;
  std::vector<std::string> channels_;
  std::atomic<std::size_t> head_{0}, tail_{0};
  std::atomic<long> dropped_{0}, written_{0};
  std::atomic<bool> stop_{false};
  std::thread writer_;
};

/// One outgoing channel: publishes encoded bytes and, when the process keeps a log, records them
/// first. The real-time path passes bytes it encoded into its own buffer; `publish_message`
/// (statistics, once per run) encodes into a temporary.
class Outbox {
 public:
  /// `seal`: the channel's authentication (the pair's key), or nullptr to publish messages as
  /// they are. The log records what is published.
  Outbox(lcm::LCM& lcm, std::string channel, MessageLog* log, bool wait_if_full, ChannelAuth* seal = nullptr)
      : lcm_(lcm), channel_(std::move(channel)), log_(log), wait_(wait_if_full),
        log_channel_(log ? log->add_channel(channel_) : -1), seal_(seal) {}

  void publish(const void* data, std::size_t size, std::int64_t utime) noexcept {
    if (seal_) {
      if (size > sealed_.size()) return;
      std::memcpy(sealed_.data(), data, size);
      const int n = seal_->seal(sealed_.data(), size, sealed_.size());
      if (n < 0) return;
      data = sealed_.data();
      size = static_cast<std::size_t>(n);
    }
    if (log_) log_->record(log_channel_, data, size, utime, wait_);
    lcm_.publish(channel_, data, static_cast<unsigned>(size));
  }
  template <typename Message>
  void publish_message(const Message& m) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    publish(bytes.data(), bytes.size(), m.utime);
  }
  const std::string& channel() const noexcept { return channel_; }

 private:
  lcm::LCM& lcm_;
  std::string channel_;
  MessageLog* log_;
  bool wait_;
  int log_channel_;
  ChannelAuth* seal_;
  std::array<std::uint8_t, kMessageBufferBytes + kTrailerBytes> sealed_{};
};

/// Closes the process's log (if it keeps one) and returns how many messages it could not record,
/// warning on stderr when there were any.
inline long close_message_log(MessageLog* log, const char* program, const std::string& path) {
  if (!log) return 0;
  log->close();
  const long dropped = log->dropped();
  if (dropped > 0)
    std::fprintf(stderr, "%s: warning: %ld messages could not be logged to %s\n", program, dropped, path.c_str());
  return dropped;
}

/// The process's log when `path` is not empty, else nullptr.
inline std::unique_ptr<MessageLog> open_message_log(const std::string& path) {
  return path.empty() ? nullptr : std::make_unique<MessageLog>(path);
}

}  // namespace gausstrack::nodes
