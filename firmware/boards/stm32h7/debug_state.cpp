// What board_main.hpp leaves for a debugger: the fatal error's reason and the bus's last state.
#include "board_main.hpp"

const char* volatile hmpc_fatal_reason = nullptr;  // C linkage, from its declaration
hmpc::stm32h7::FdcanStatus hmpc_can_status{};
