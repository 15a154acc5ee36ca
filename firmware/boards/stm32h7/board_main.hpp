// The STM32H743 board runtime around any board application (firmware/app), written once:
// bring-up (caches, clocks, cycle counter, the application's outputs, FDCAN1 at 1 Mbit/s with
// the protocol's acceptance filter for the board's node), then one thread, as on the Linux
// board: SysTick counts milliseconds; the main loop runs one application tick per millisecond
// (received frames in, tick(), its frames out, outputs applied) and then the application's
// background work when it is due (the forearm's MPC step). Background work runs for up to its
// budget, and the ticks that fall due meanwhile are caught up at once right after it, so the
// tick count, the watchdogs and the telemetry rates stay exact while a tick's outputs may be
// applied up to one background step late. Applications are not interrupt-safe (a received
// mode command can start an MPC initialisation), which rules out running tick() from the timer
// interrupt while background work runs in the main loop.
//
// Sensors come from the bus (the HIL plant's frames); a board with its own encoders and
// pressure sensors would feed them to the application in the tick loop here.
//
// The application's Support struct (in its main) names:
//   using Board, Description;
//   static void init_outputs();  static void apply_outputs(const Board&);
//   static void make_outputs_safe();  // from any state, before init_outputs() too
//   static bool work_due(const Board&);  static void run_work(Board&);
#pragma once

#include <cstdint>

#include "clock.hpp"
#include "fdcan.hpp"
#include "hmpc/protocol/codec.hpp"
#include "memory.hpp"

// For a debugger after a fatal error: what happened, and the bus's last state.
extern "C" const char* volatile hmpc_fatal_reason;
extern hmpc::stm32h7::FdcanStatus hmpc_can_status;

namespace hmpc::stm32h7 {

// What startup.c's hmpc_fatal does on this board: outputs safe first, off the bus, then stop
// here. Each main's hmpc_fatal calls it with its Support.
template <class Support>
[[noreturn]] void fatal(const char* what) {
  __asm__ volatile("cpsid i" ::: "memory");  // nothing may re-apply outputs after this
  Support::make_outputs_safe();
  Fdcan::stop();
  hmpc_fatal_reason = what;
  for (;;) {
  }
}

// Clocks, outputs and the bus, before the application is built (its constructor may use the
// clock). A failure is fatal: outputs safe, off the bus.
template <class Support>
void bring_up(Fdcan& can, protocol::NodeId node) {
  using P = typename Support::Description;
  enable_caches();
  if (node > P::kIds.max_node) fatal<Support>("node id above the protocol's largest\n");
  if (clock::configure_system_clock() != clock::Status::kOk) {
    fatal<Support>("clock configuration failed\n");
  }
  clock::start_cycle_counter();
  Support::init_outputs();
  FdcanConfig can_config;
  can_config.accept = protocol::accepted_ids<P>(node);
  if (can.init(can_config) != Fdcan::InitResult::kOk) fatal<Support>("FDCAN init failed\n");
}

template <class Support>
[[noreturn]] void run(typename Support::Board& app, Fdcan& can) {
  clock::start_millisecond_tick();
  std::uint32_t ticked_ms = clock::milliseconds();
  for (;;) {
    const std::uint32_t now_ms = clock::milliseconds();
    bool work_due = false;
    while (ticked_ms != now_ms) {
      ++ticked_ms;
      hmpc_can_status = can.poll(ticked_ms);

      Frame frame;
      for (std::uint32_t n = 0; n < MessageRam::kRxFifo0Elements && can.receive(frame); ++n) {
        app.on_frame(frame);
      }
      app.tick();
      work_due = work_due || Support::work_due(app);
      // A frame the full TX FIFO refuses is dropped and counted (Fdcan::counters().tx_full):
      // the application sends state, and the next tick's frame supersedes it.
      while (app.pop_frame(frame)) (void)can.send(frame);
      Support::apply_outputs(app);
    }
    if (work_due) Support::run_work(app);
  }
}

}  // namespace hmpc::stm32h7
