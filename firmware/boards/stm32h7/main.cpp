// hmpc_forearm_stm32h743: the forearm board application (firmware/app/forearm_board.hpp) on
// an STM32H743 with FDCAN1 at 1 Mbit/s and the valve and motor on TIM4 PWM.
//
// One thread, as on the Linux board: SysTick counts milliseconds; the main loop runs one
// application tick per millisecond (received frames in, tick(), its frames out, outputs
// applied) and then the 4 ms MPC step when it is due. The MPC step runs for up to its
// budget (3.5 ms), and the ticks that fall due meanwhile are caught up at once right after
// it, so the tick count, the watchdogs and the telemetry rates stay exact while a tick's
// outputs may be applied up to one MPC step late. The application is not interrupt-safe (a
// received mode command can start an MPC initialisation), which rules out running tick()
// from the timer interrupt while the MPC step runs in the main loop.
//
// Sensors come from the bus (the Sensor frame of the protocol, sent by the HIL plant); a
// board with its own encoder and pressure sensor would feed them to on_measurement() here.
#include <cstdint>

#include "actuators.hpp"
#include "clock.hpp"
#include "fdcan.hpp"
#include "forearm_board.hpp"
#include "memory.hpp"

namespace {

using Board = hmpc::firmware::ForearmBoard<double>;
namespace board = hmpc::stm32h7;

constexpr hmpc::forearm_protocol::NodeId kNode = HMPC_STM32_NODE_ID;

}  // namespace

// For a debugger after a fatal error: what happened, and the bus's last state.
extern "C" {
const char* volatile hmpc_fatal_reason = nullptr;
}
board::FdcanStatus hmpc_can_status{};

// Overrides startup.c's weak handler: outputs safe first, off the bus, then stop here.
extern "C" [[noreturn]] void hmpc_fatal(const char* what) {
  __asm__ volatile("cpsid i" ::: "memory");  // nothing may re-apply outputs after this
  board::actuators::make_safe();
  board::Fdcan::stop();
  hmpc_fatal_reason = what;
  for (;;) {
  }
}

int main() {
  board::enable_caches();
  if (board::clock::configure_system_clock() != board::clock::Status::kOk)
    hmpc_fatal("clock configuration failed\n");
  board::clock::start_cycle_counter();
  board::actuators::init();

  static board::Fdcan can;
  board::FdcanConfig can_config;
  can_config.node = kNode;
  if (can.init(can_config) != board::Fdcan::InitResult::kOk) hmpc_fatal("FDCAN init failed\n");

  Board::Config config;
  config.node = kNode;
  // ~60 kB of MPC workspaces: AXI SRAM, built here, after the clocks are up.
  HMPC_AXI_SRAM static Board app(config, &board::clock::seconds);

  board::clock::start_millisecond_tick();
  std::uint32_t ticked_ms = board::clock::milliseconds();
  for (;;) {
    const std::uint32_t now_ms = board::clock::milliseconds();
    bool mpc_due = false;
    while (ticked_ms != now_ms) {
      ++ticked_ms;
      hmpc_can_status = can.poll(ticked_ms);

      board::Frame frame;
      for (std::uint32_t n = 0; n < board::MessageRam::kRxFifo0Elements && can.receive(frame); ++n)
        app.on_frame(frame);
      app.tick();
      mpc_due = mpc_due || app.mpc_due();
      // A frame the full TX FIFO refuses is dropped and counted (Fdcan::counters().tx_full):
      // the application sends state, and the next tick's frame supersedes it.
      while (app.pop_frame(frame)) (void)can.send(frame);
      board::actuators::apply(app.outputs().v_p, app.outputs().v_m);
    }
    if (mpc_due) app.run_mpc();
  }
}
