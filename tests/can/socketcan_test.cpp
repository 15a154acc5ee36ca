// The SocketCAN wrapper on vcan0. ctest runs this binary through hil/vcan/run-with-vcan.sh,
// which provides vcan0 natively or in a QEMU guest. Also prints the bus figures: throughput
// and round-trip latency through the kernel's CAN stack.
#include "hmpc/platform/linux/socketcan.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "hmpc/platform/linux/heap_monitor.hpp"

namespace {

using hmpc::platform::CanFilter;
using hmpc::platform::CanFrame;
using hmpc::platform::CanResult;
using hmpc::platform::CanStatus;
using hmpc::platform::kCanExtendedId;
using hmpc::platform::SocketCan;
using namespace std::chrono_literals;

constexpr const char* kBus = "vcan0";
// Generous: the guest under emulation runs about 15x slower than the host.
constexpr std::chrono::microseconds kArrival = 2s;

std::string describe(const CanResult& result) {
  std::string text = hmpc::platform::to_string(result.status);
  if (result.error_number != 0)
    text += std::string(" (") + std::strerror(result.error_number) + ")";
  return text;
}

CanFrame make_frame(std::uint32_t id, std::uint8_t dlc, std::uint8_t seed) {
  CanFrame frame{id, dlc, {}};
  for (std::uint8_t i = 0; i < dlc; ++i)
    frame.data[i] = static_cast<std::uint8_t>(seed * 31 + i * 7 + 1);
  return frame;
}

class SocketCanOnVcan : public ::testing::Test {
 protected:
  void SetUp() override {
    for (SocketCan* socket : {&sender_, &receiver_}) {
      const CanResult opened = socket->open(kBus);
      ASSERT_TRUE(opened.ok()) << "cannot open " << kBus << ": " << describe(opened)
                               << "; run this test through hil/vcan/run-with-vcan.sh";
    }
  }

  SocketCan sender_;
  SocketCan receiver_;
};

TEST_F(SocketCanOnVcan, FramesRoundTripWithIdsLengthsAndPayloads) {
  const std::uint32_t ids[] = {0x000,
                               0x123,
                               0x7FF,
                               kCanExtendedId | 0x000,
                               kCanExtendedId | 0x123,
                               kCanExtendedId | 0x1ABCDEF,
                               kCanExtendedId | 0x1FFFFFFF};
  std::uint8_t seed = 0;
  for (const std::uint32_t id : ids) {
    for (std::uint8_t dlc = 0; dlc <= 8; ++dlc) {
      const CanFrame sent = make_frame(id, dlc, seed++);
      ASSERT_TRUE(sender_.send(sent).ok());
      CanFrame got{};
      std::fill(std::begin(got.data), std::end(got.data), std::uint8_t{0xEE});
      const CanResult received = receiver_.receive(got, kArrival);
      ASSERT_TRUE(received.ok()) << describe(received) << " for id " << std::hex << id;
      EXPECT_EQ(got.id, sent.id);
      ASSERT_EQ(got.dlc, sent.dlc);
      for (int i = 0; i < 8; ++i) {
        EXPECT_EQ(got.data[i], i < dlc ? sent.data[i] : 0) << "byte " << i << ", dlc " << int{dlc};
      }
    }
  }
}

TEST_F(SocketCanOnVcan, ReceiveTimeoutIsTimeoutNotError) {
  CanFrame frame{};
  const auto start = std::chrono::steady_clock::now();
  const CanResult result = receiver_.receive(frame, 50ms);
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_EQ(result.status, CanStatus::kTimeout);
  EXPECT_EQ(result.error_number, 0);
  EXPECT_GE(waited, 50ms);
  EXPECT_EQ(receiver_.receive(frame, 0us).status, CanStatus::kTimeout);
}

TEST_F(SocketCanOnVcan, FilterDropsOtherIds) {
  const CanFilter wanted[] = {CanFilter::exact(0x100), CanFilter::exact(kCanExtendedId | 0x2000)};
  ASSERT_TRUE(receiver_.set_filters(wanted, 2).ok());
  for (const std::uint32_t id : {0x101u, 0x200u, kCanExtendedId | 0x100u, 0x100u,
                                 kCanExtendedId | 0x2001u, kCanExtendedId | 0x2000u}) {
    ASSERT_TRUE(sender_.send(make_frame(id, 1, 0)).ok());
  }
  CanFrame frame{};
  ASSERT_TRUE(receiver_.receive(frame, kArrival).ok());
  EXPECT_EQ(frame.id, 0x100u);
  ASSERT_TRUE(receiver_.receive(frame, kArrival).ok());
  EXPECT_EQ(frame.id, kCanExtendedId | 0x2000u);
  EXPECT_EQ(receiver_.receive(frame, 100ms).status, CanStatus::kTimeout);

  // No filters: nothing at all; accept_all: everything again.
  ASSERT_TRUE(receiver_.set_filters(nullptr, 0).ok());
  ASSERT_TRUE(sender_.send(make_frame(0x100, 0, 0)).ok());
  EXPECT_EQ(receiver_.receive(frame, 100ms).status, CanStatus::kTimeout);
  ASSERT_TRUE(receiver_.accept_all().ok());
  ASSERT_TRUE(sender_.send(make_frame(0x555, 0, 0)).ok());
  ASSERT_TRUE(receiver_.receive(frame, kArrival).ok());
  EXPECT_EQ(frame.id, 0x555u);
}

TEST_F(SocketCanOnVcan, InvalidFramesAreRefusedAndNotSent) {
  EXPECT_EQ(sender_.send(make_frame(0x800, 0, 0)).status, CanStatus::kInvalidArgument);
  EXPECT_EQ(sender_.send(make_frame(kCanExtendedId | 0x20000000, 0, 0)).status,
            CanStatus::kInvalidArgument);
  CanFrame too_long = make_frame(0x10, 8, 0);
  too_long.dlc = 9;
  EXPECT_EQ(sender_.send(too_long).status, CanStatus::kInvalidArgument);
  EXPECT_EQ(sender_.send(make_frame(CAN_ERR_FLAG | 0x1, 0, 0)).status, CanStatus::kInvalidArgument);
  CanFrame frame{};
  EXPECT_EQ(receiver_.receive(frame, 100ms).status, CanStatus::kTimeout);
}

TEST_F(SocketCanOnVcan, NonBlockingSocketSendsAndPolls) {
  ASSERT_TRUE(sender_.set_non_blocking(true).ok());
  EXPECT_NE(::fcntl(sender_.native_handle(), F_GETFL) & O_NONBLOCK, 0);
  ASSERT_TRUE(sender_.send(make_frame(0x42, 2, 1)).ok());
  CanFrame frame{};
  ASSERT_TRUE(receiver_.receive(frame, kArrival).ok());
  EXPECT_EQ(frame.id, 0x42u);
  ASSERT_TRUE(sender_.set_non_blocking(false).ok());
  EXPECT_EQ(::fcntl(sender_.native_handle(), F_GETFL) & O_NONBLOCK, 0);
}

TEST_F(SocketCanOnVcan, MovedSocketKeepsWorkingAndSourceIsClosed) {
  SocketCan moved = std::move(sender_);
  EXPECT_FALSE(sender_.is_open());
  EXPECT_EQ(sender_.send(make_frame(0x1, 0, 0)).status, CanStatus::kNotOpen);
  ASSERT_TRUE(moved.send(make_frame(0x1, 0, 0)).ok());
  CanFrame frame{};
  EXPECT_TRUE(receiver_.receive(frame, kArrival).ok());
}

TEST_F(SocketCanOnVcan, SendAndReceiveDoNotAllocate) {
  namespace heap_monitor = hmpc::platform::heap_monitor;
  CanFrame frame{};
  const auto before = heap_monitor::allocations();
  heap_monitor::arm();
  for (int i = 0; i < 200; ++i) {
    if (!sender_.send(make_frame(0x300, 8, static_cast<std::uint8_t>(i))).ok()) break;
    if (!receiver_.receive(frame, kArrival).ok()) break;
  }
  receiver_.receive(frame, 1ms);  // the timeout path too
  heap_monitor::disarm();
  EXPECT_EQ(frame.data[0], make_frame(0x300, 8, 199).data[0]);
  EXPECT_EQ(heap_monitor::allocations(), before);

  // Positive control: the counter sees an allocation (operator new, and the malloc under it).
  heap_monitor::arm();
  int* volatile allocated = new int(1);  // volatile: the compiler may not elide the pair
  heap_monitor::disarm();
  delete allocated;
  EXPECT_GT(heap_monitor::allocations(), before);
}

TEST(SocketCanOpen, NamesTheProblem) {
  SocketCan socket;
  CanResult result = socket.open("hmpcnobus0");
  EXPECT_EQ(result.status, CanStatus::kNoSuchInterface) << describe(result);
  EXPECT_EQ(result.error_number, ENODEV);
  EXPECT_STREQ(hmpc::platform::to_string(result.status), "no such interface");
  EXPECT_FALSE(socket.is_open());

  EXPECT_EQ(socket.open("lo").status, CanStatus::kNotCanInterface);
  EXPECT_EQ(socket.open("a_name_longer_than_ifnamsiz").status, CanStatus::kInvalidArgument);
  EXPECT_EQ(socket.open("").status, CanStatus::kInvalidArgument);
  EXPECT_EQ(socket.open(nullptr).status, CanStatus::kInvalidArgument);
  EXPECT_FALSE(socket.is_open());

  CanFrame frame{};
  EXPECT_EQ(socket.receive(frame, 0us).status, CanStatus::kNotOpen);
  EXPECT_EQ(socket.set_filters(nullptr, 0).status, CanStatus::kNotOpen);
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

double percentile(std::vector<double> values, double fraction) {
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(fraction * static_cast<double>(values.size() - 1))];
}

// Bursts of a window of frames, each burst read back before the next, so the receive queue
// never overflows: every frame must arrive, in order.
TEST_F(SocketCanOnVcan, PrintsThroughput) {
  constexpr int kFrames = 20000;
  constexpr int kWindow = 32;
  const auto start = std::chrono::steady_clock::now();
  for (int base = 0; base < kFrames; base += kWindow) {
    for (int i = base; i < base + kWindow; ++i) {
      CanFrame frame = make_frame(0x123, 8, 0);
      std::memcpy(frame.data, &i, sizeof i);
      ASSERT_TRUE(sender_.send(frame).ok());
    }
    for (int i = base; i < base + kWindow; ++i) {
      CanFrame frame{};
      ASSERT_TRUE(receiver_.receive(frame, kArrival).ok()) << "frame " << i;
      int sequence = 0;
      std::memcpy(&sequence, frame.data, sizeof sequence);
      ASSERT_EQ(sequence, i);
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double frames_per_second = kFrames / seconds;
  std::printf("[ figures  ] %s throughput: %.0f frames/s (%d 8-byte frames, bursts of %d)\n", kBus,
              frames_per_second, kFrames, kWindow);
  RecordProperty("frames_per_second", std::to_string(static_cast<long>(frames_per_second)));
}

// A second thread echoes each frame back under another id: the round trip is two sends, two
// wake-ups and two receives through the kernel.
TEST_F(SocketCanOnVcan, PrintsRoundTripLatency) {
  constexpr int kRoundTrips = 2000;
  constexpr std::uint32_t kPingId = 0x10;
  constexpr std::uint32_t kPongId = 0x11;
  SocketCan echo;
  ASSERT_TRUE(echo.open(kBus).ok());
  const CanFilter ping = CanFilter::exact(kPingId);
  const CanFilter pong = CanFilter::exact(kPongId);
  ASSERT_TRUE(echo.set_filters(&ping, 1).ok());
  ASSERT_TRUE(sender_.set_filters(&pong, 1).ok());

  std::atomic<int> echoed{0};
  std::thread echo_thread([&] {
    CanFrame frame{};
    for (int i = 0; i < kRoundTrips; ++i) {
      if (!echo.receive(frame, kArrival).ok()) return;
      frame.id = kPongId;
      if (!echo.send(frame).ok()) return;
      echoed.fetch_add(1);
    }
  });

  std::vector<double> round_trip_us;
  round_trip_us.reserve(kRoundTrips);
  for (int i = 0; i < kRoundTrips; ++i) {
    CanFrame frame = make_frame(kPingId, 8, 0);
    std::memcpy(frame.data, &i, sizeof i);
    const auto sent_at = std::chrono::steady_clock::now();
    if (!sender_.send(frame).ok()) break;
    CanFrame reply{};
    if (!sender_.receive(reply, kArrival).ok()) break;
    round_trip_us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - sent_at)
            .count());
    int sequence = -1;
    std::memcpy(&sequence, reply.data, sizeof sequence);
    if (reply.id != kPongId || sequence != i) break;
  }
  echo_thread.join();
  ASSERT_EQ(static_cast<int>(round_trip_us.size()), kRoundTrips);
  EXPECT_EQ(echoed.load(), kRoundTrips);

  std::printf(
      "[ figures  ] %s round trip (send, echo by another thread, receive): median %.1f us, "
      "p99 %.1f us, max %.1f us over %d frames\n",
      kBus, median(round_trip_us), percentile(round_trip_us, 0.99),
      *std::max_element(round_trip_us.begin(), round_trip_us.end()), kRoundTrips);
  RecordProperty("round_trip_median_us", std::to_string(median(round_trip_us)));
}

}  // namespace
