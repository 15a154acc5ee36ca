# Bare-metal Cortex-M4F (STM32G4/F4, QEMU mps2-an386) with the FPv4 single-precision FPU:
# firmware built here uses float, since double would be emulated in software.
set(CMAKE_SYSTEM_PROCESSOR cortex-m4)
set(HMPC_MCU_FLAGS "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi-common.cmake)
