# SPDX-License-Identifier: Apache-2.0
# Toolchain file: bare-metal ARM Cortex-M with Debian's gcc-arm-none-eabi 12 + newlib.
#
# Select the core with the cache variable PMA_TARGET (the presets set it):
#   cortex-m4f  -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16   QEMU -M mps2-an386
#   cortex-m3   -mcpu=cortex-m3 -mthumb (soft float)                          QEMU -M mps2-an385
#   cortex-m0   -mcpu=cortex-m0 -mthumb (soft float)                          QEMU -M microbit
#   stm32g474   -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16   none: the board image
#               (firmware/targets/stm32g474; no QEMU machine emulates a G474, no tests; its
#               startup code and linker script come from hal/portable/st/stm32g474)
#
# What this file sets for every target of the build:
#   - the core/ABI flags above, -ffunction-sections -fdata-sections, -Wl,--gc-sections;
#   - the C library is the FULL newlib, not newlib-nano: nano's printf cannot print 64-bit
#     integers (%llx, PRIu64), which the tests' and benchmarks' own messages use. (Unity prints
#     its assertion values with its own routines, not printf.) Full newlib prints long long and
#     floats (no -u _printf_float needed), at the cost of ~1 KB more RAM and ~15-20 KB more flash.
#     Debian's newlib has no C99 printf formats either way (%zu %zd %jd %hhd print literally).
#     Nano vs full cannot be mixed per target: the two use different newlib.h configurations
#     (struct _reent layout), so the choice is made here, for the whole build;
#   - CMAKE_CROSSCOMPILING_EMULATOR: the qemu-system-arm command line (with semihosting) so that a
#     plain add_test(NAME x COMMAND x) runs x under QEMU, and its exit status is the test result;
#   - PMA_QEMU_COMMAND (the same command without the trailing -kernel), PMA_QEMU_MACHINE and
#     PMA_QEMU_BOARD (mps2 | microbit) for cmake/PmaTest.cmake.
# What it does NOT set: the startup code, linker script and semihosting C library (rdimon).
# Those belong to the emulated boards only, and cmake/PmaTest.cmake links them into test and
# benchmark executables through the `pma_board` library (tests/qemu/), so firmware images for a
# real board never pick up semihosting by accident.
#
# try_compile() builds static libraries only (CMAKE_TRY_COMPILE_TARGET_TYPE), so CMake's compiler
# checks never need a linker script.

set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
# ar, ranlib, objcopy, objdump, size: CMake finds the arm-none-eabi- ones from the compiler name.

set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
# try_compile() projects re-read this file: hand PMA_TARGET on to them.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES PMA_TARGET)

# Look for programs on the build machine, for libraries/headers only in the ARM tree.
set(CMAKE_FIND_ROOT_PATH /usr/lib/arm-none-eabi)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

if(NOT DEFINED PMA_TARGET OR PMA_TARGET STREQUAL "")
  message(FATAL_ERROR "arm-none-eabi.cmake: set PMA_TARGET to cortex-m4f, cortex-m3, cortex-m0 or stm32g474 "
                      "(e.g. cmake --preset cortex-m4f)")
endif()

if(PMA_TARGET STREQUAL "cortex-m4f")
  set(_pma_cpu_flags "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16")
  set(PMA_QEMU_MACHINE mps2-an386)
  set(PMA_QEMU_BOARD mps2)
elseif(PMA_TARGET STREQUAL "cortex-m3")
  set(_pma_cpu_flags "-mcpu=cortex-m3 -mthumb -mfloat-abi=soft")
  set(PMA_QEMU_MACHINE mps2-an385)
  set(PMA_QEMU_BOARD mps2)
elseif(PMA_TARGET STREQUAL "cortex-m0")
  set(_pma_cpu_flags "-mcpu=cortex-m0 -mthumb -mfloat-abi=soft")
  set(PMA_QEMU_MACHINE microbit)
  set(PMA_QEMU_BOARD microbit)
elseif(PMA_TARGET STREQUAL "stm32g474")
  set(_pma_cpu_flags "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16")
else()
  message(FATAL_ERROR "arm-none-eabi.cmake: PMA_TARGET='${PMA_TARGET}' is not an ARM target "
                      "(cortex-m4f, cortex-m3, cortex-m0 or stm32g474)")
endif()

if(PMA_TARGET STREQUAL "stm32g474")
  # The board image prints nothing: newlib-nano (smaller memcpy, math errno
  # state) for compiling and linking alike, so that the two never disagree.
  string(APPEND _pma_cpu_flags " --specs=nano.specs")
endif()
set(CMAKE_C_FLAGS_INIT "${_pma_cpu_flags} -ffunction-sections -fdata-sections")
set(CMAKE_ASM_FLAGS_INIT "${_pma_cpu_flags}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,--gc-sections")

if(NOT DEFINED PMA_QEMU_MACHINE)
  return() # a board image: nothing to emulate
endif()

# QEMU: no display, no monitor, no UART; semihosting console and exit go to the host process, so
# printf lands on QEMU's stdout and exit(n) / return n from main becomes QEMU's exit status
# (newlib's rdimon uses SYS_EXIT_EXTENDED). CTest appends the executable after -kernel.
find_program(PMA_QEMU_SYSTEM_ARM qemu-system-arm)
if(NOT PMA_QEMU_SYSTEM_ARM)
  message(WARNING "qemu-system-arm not found: target tests and benchmarks cannot run "
                  "(Debian: apt-get install qemu-system-arm)")
  set(PMA_QEMU_SYSTEM_ARM qemu-system-arm)
endif()
set(PMA_QEMU_COMMAND
    "${PMA_QEMU_SYSTEM_ARM}" -M ${PMA_QEMU_MACHINE} -nographic -monitor none -serial none
    -semihosting-config enable=on,target=native)
set(CMAKE_CROSSCOMPILING_EMULATOR ${PMA_QEMU_COMMAND} -kernel)
