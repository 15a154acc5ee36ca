# cmake -DELF=<image.elf> -DBIN=<image.bin> -DNM=<arm-none-eabi-nm> -P check_image.cmake
# Checks a built STM32H743 image against the memory map of stm32h743.ld.
set(flash_start 0x08000000)
set(flash_end 0x08200000)   # 2 MB
set(dtcm_start 0x20000000)
set(dtcm_end 0x20020000)    # 128 KB

foreach(file ELF BIN)
  if(NOT EXISTS "${${file}}")
    message(FATAL_ERROR "${${file}} does not exist: build the image first")
  endif()
endforeach()

# objcopy -O binary starts at the lowest load address, which must be the vector table at the
# start of flash; a loadable section elsewhere (AXI SRAM, DTCM) would blow the file up.
file(SIZE "${BIN}" bin_size)
math(EXPR flash_size "${flash_end} - ${flash_start}")
if(bin_size GREATER flash_size OR bin_size LESS 8)
  message(FATAL_ERROR "${BIN} is ${bin_size} bytes; flash holds ${flash_size}")
endif()

# The first two words, little-endian: initial stack pointer, reset vector.
file(READ "${BIN}" head LIMIT 8 HEX)
function(word_at hex offset out)
  set(value "")
  foreach(i 3 2 1 0)
    math(EXPR at "2 * (${offset} + ${i})")
    string(SUBSTRING "${hex}" ${at} 2 byte)
    string(APPEND value "${byte}")
  endforeach()
  math(EXPR value "0x${value}" OUTPUT_FORMAT DECIMAL)
  set(${out} ${value} PARENT_SCOPE)
endfunction()
word_at("${head}" 0 sp)
word_at("${head}" 4 reset)

# The stack grows down from its top in DTCM, 8-byte aligned (AAPCS).
math(EXPR sp_misaligned "${sp} % 8")
if(sp LESS_EQUAL ${dtcm_start} OR sp GREATER ${dtcm_end} OR NOT sp_misaligned EQUAL 0)
  math(EXPR sp_hex "${sp}" OUTPUT_FORMAT HEXADECIMAL)
  message(FATAL_ERROR "initial SP ${sp_hex} is not an aligned top of stack in DTCM")
endif()

# Thumb code (bit 0 set) in flash, and exactly the Reset_Handler the linker placed.
math(EXPR reset_thumb "${reset} % 2")
math(EXPR reset_address "${reset} - ${reset_thumb}")
math(EXPR reset_hex "${reset}" OUTPUT_FORMAT HEXADECIMAL)
if(NOT reset_thumb EQUAL 1 OR reset_address LESS ${flash_start} OR
   reset_address GREATER_EQUAL ${flash_end})
  message(FATAL_ERROR "reset vector ${reset_hex} is not Thumb code in flash")
endif()

execute_process(COMMAND "${NM}" "${ELF}" OUTPUT_VARIABLE symbols RESULT_VARIABLE nm_result)
if(NOT nm_result EQUAL 0)
  message(FATAL_ERROR "${NM} ${ELF} failed")
endif()
if(NOT symbols MATCHES "([0-9a-f]+) T Reset_Handler\n")
  message(FATAL_ERROR "no Reset_Handler in ${ELF}")
endif()
math(EXPR handler "0x${CMAKE_MATCH_1}")
if(NOT handler EQUAL reset_address)
  message(FATAL_ERROR "reset vector ${reset_hex} is not Reset_Handler (0x${CMAKE_MATCH_1})")
endif()

# No allocator, defined or referenced: C, newlib's reentrant forms, sbrk, C++ new/delete.
set(heap_symbols malloc calloc realloc free _sbrk _malloc_r _calloc_r _realloc_r _free_r
    _sbrk_r _Znwj _Znaj _ZdlPv _ZdaPv _ZdlPvj _ZdaPvj)
foreach(symbol IN LISTS heap_symbols)
  if(symbols MATCHES "(^|\n)[0-9a-f ]* [A-Za-z] ${symbol}\n")
    message(FATAL_ERROR "${ELF} has the allocator symbol ${symbol}")
  endif()
endforeach()

math(EXPR sp_hex "${sp}" OUTPUT_FORMAT HEXADECIMAL)
message(STATUS "initial SP ${sp_hex} in DTCM, reset vector ${reset_hex} = Reset_Handler, "
               "${bin_size} bytes of flash, no allocator symbols")
