# Bare-metal Cortex-M7 (STM32H7, QEMU mps2-an500) with the FPv5 double-precision FPU.
set(CMAKE_SYSTEM_PROCESSOR cortex-m7)
set(HMPC_MCU_FLAGS "-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard")
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
