# Shared part of the bare-metal Cortex-M toolchains (Debian 12: gcc-arm-none-eabi 12.2 with
# newlib-nano). The including file sets HMPC_MCU_FLAGS and CMAKE_SYSTEM_PROCESSOR first.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)  # compiler checks without a linker script

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_OBJCOPY arm-none-eabi-objcopy CACHE FILEPATH "")
set(CMAKE_SIZE arm-none-eabi-size CACHE FILEPATH "")

# No exceptions, no RTTI, no guard variables or atexit registration: nothing that can pull
# in the heap or an unwinder. -ffp-contract=off and no vectorisation keep the arithmetic
# comparable with the host reference run, built the same way (only libm differs).
set(CMAKE_C_FLAGS_INIT "${HMPC_MCU_FLAGS} -ffunction-sections -fdata-sections -ffp-contract=off")
set(CMAKE_CXX_FLAGS_INIT "${HMPC_MCU_FLAGS} -ffunction-sections -fdata-sections -ffp-contract=off -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit -DEIGEN_DONT_VECTORIZE")
set(CMAKE_ASM_FLAGS_INIT "${HMPC_MCU_FLAGS} -x assembler-with-cpp")
# Build Release (-O3) for Eigen on Cortex-M: -Os is 4-8x slower (Eigen relies on inlining).
# newlib-nano; our own Reset_Handler replaces crt0.
set(CMAKE_EXE_LINKER_FLAGS_INIT "${HMPC_MCU_FLAGS} --specs=nano.specs -nostartfiles -Wl,--gc-sections -Wl,--print-memory-usage")
set(CMAKE_EXECUTABLE_SUFFIX_C .elf)
set(CMAKE_EXECUTABLE_SUFFIX_CXX .elf)

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
# Eigen's CMake package is architecture-independent (/usr/share/eigen3/cmake).
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
