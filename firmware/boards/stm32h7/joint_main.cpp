// hmpc_joint_stm32h743: the hydraulic joint board application (firmware/app/joint_board.hpp)
// in the STM32H743 runtime (board_main.hpp), HMPC_STM32_JOINTS joints at the default 6 ms
// control period, encoders zeroed at boot on the host's command, each servo valve's coil on
// its own sign-magnitude bridge (servo_valves.hpp). The control loops run inside the tick, so
// there is no background work.
#include "board_main.hpp"
#include "joint_board.hpp"
#include "servo_valves.hpp"

namespace {

namespace board = hmpc::stm32h7;

struct JointSupport {
  using Board = hmpc::firmware::JointBoard<double>;
  using Description = hmpc::joint_protocol::Description;
  static_assert(Board::kMaxJoints == board::servo_valves::kValves);
  static void init_outputs() { board::servo_valves::init(); }
  static void apply_outputs(const Board& b) { board::servo_valves::apply(b.valve_commands()); }
  static void make_outputs_safe() { board::servo_valves::make_safe(); }
  static bool work_due(const Board&) { return false; }
  static void run_work(Board&) {}
};

constexpr hmpc::protocol::NodeId kNode = HMPC_STM32_NODE_ID;

}  // namespace

// Overrides startup.c's weak handler.
extern "C" [[noreturn]] void hmpc_fatal(const char* what) { board::fatal<JointSupport>(what); }

int main() {
  static board::Fdcan can;
  board::bring_up<JointSupport>(can, kNode);
  JointSupport::Board::Config config;
  config.node = kNode;
  config.joints = HMPC_STM32_JOINTS;
  config.tune_defaults();
  if (config.check() != nullptr) hmpc_fatal("invalid joint board configuration\n");
  static JointSupport::Board app(config);
  board::run<JointSupport>(app, can);
}
