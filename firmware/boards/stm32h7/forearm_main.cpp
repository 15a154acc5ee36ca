// hmpc_forearm_stm32h743: the forearm board application (firmware/app/forearm_board.hpp) in
// the STM32H743 runtime (board_main.hpp), the valve and motor on TIM4 PWM (actuators.hpp).
#include "actuators.hpp"
#include "board_main.hpp"
#include "forearm_board.hpp"

namespace {

namespace board = hmpc::stm32h7;

struct ForearmSupport {
  using Board = hmpc::firmware::ForearmBoard<double>;
  using Description = hmpc::forearm_protocol::Description;
  static void init_outputs() { board::actuators::init(); }
  static void apply_outputs(const Board& b) {
    board::actuators::apply(b.outputs().v_p, b.outputs().v_m);
  }
  static void make_outputs_safe() { board::actuators::make_safe(); }
  static bool work_due(const Board& b) { return b.mpc_due(); }
  static void run_work(Board& b) { b.run_mpc(); }
};

constexpr hmpc::protocol::NodeId kNode = HMPC_STM32_NODE_ID;

}  // namespace

// Overrides startup.c's weak handler.
extern "C" [[noreturn]] void hmpc_fatal(const char* what) { board::fatal<ForearmSupport>(what); }

int main() {
  static board::Fdcan can;
  board::bring_up<ForearmSupport>(can, kNode);
  ForearmSupport::Board::Config config;
  config.node = kNode;
  // ~60 kB of MPC workspaces: AXI SRAM, built here, after the clocks are up.
  HMPC_AXI_SRAM static ForearmSupport::Board app(config, &board::clock::seconds);
  board::run<ForearmSupport>(app, can);
}
