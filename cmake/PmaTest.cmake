# SPDX-License-Identifier: Apache-2.0
# Test and benchmark helpers (included by the top-level CMakeLists.txt).
#
#   pma_add_test(<name> SOURCES <files...> [LIBRARIES <libs...>] [INCLUDES <dirs...>])
#       Executable <name> linked with Unity (ThrowTheSwitch, v2.6.1, fetched into .deps/unity by
#       tools/fetch-deps.sh) and the project's test support (`pma_test`: tests/support/pma_test.h,
#       the shared assertion helpers), registered with add_test(). Each test prints Unity's
#       summary ("N Tests M Failures K Ignored", then OK or FAIL) and exits with the number of
#       failures. host: ASan+UBSan (see below). ARM: the emulated board's startup code + linker
#       script (`pma_board`), run under QEMU through CMAKE_CROSSCOMPILING_EMULATOR (set by
#       cmake/arm-none-eabi.cmake). Timeout: PMA_TEST_TIMEOUT seconds (default 120).
#
#   pma_add_bench(<name> SOURCES <files...> [LIBRARIES <libs...>] [INCLUDES <dirs...>])
#       Executable <name>, NOT a test (benchmarks print figures and never assert), linked with
#       `pma_board` (timing API tests/qemu/include/pma_board.h) on every target, plus a target
#       `run-<name>` that runs it: natively on host, on ARM under the same QEMU command with
#       `-icount shift=0` (1 virtual ns == 1 instruction). The target `bench` runs all of them.
#
# Sanitizers: when PMA_TARGET is host, this file fills in the INTERFACE library pma_sanitize
# (cmake/PmaFlags.cmake) with
#   -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
# for compiling and linking; every target of the project's own code links it (pma_own_target),
# so the firmware libraries the tests link are instrumented too. Unity and the test support
# do not: uninstrumented (as a system library would be), they link into ASan programs and into
# the one test that runs without ASan alike.
# Host builds with PMA_BUILD_TESTS=OFF get no sanitizers. Set PMA_SANITIZE=OFF to turn them off.

include_guard(GLOBAL)

set(PMA_TEST_TIMEOUT 120 CACHE STRING "Timeout of each test in seconds")
set(PMA_QEMU_DIR "${CMAKE_SOURCE_DIR}/tests/qemu")
set(PMA_TEST_SUPPORT_DIR "${CMAKE_SOURCE_DIR}/tests/support")

# --------------------------------------------------------------------------------------------
# Unity: `pma_unity`, and `pma_test` (Unity + tests/support) is what tests link, whatever the
# target. Configuration, the same on every target:
#   UNITY_INCLUDE_DOUBLE    TEST_ASSERT_DOUBLE_* (golden vectors are doubles);
#   UNITY_SUPPORT_64        64-bit integer assertions on 32-bit cores too (UNITY_INT is 64 bits);
#   UNITY_USE_FLUSH_STDOUT  flush after each test, so a fault under QEMU loses no output.
include(PmaDeps)
pma_require_dep(unity src/unity.c)
add_library(pma_unity STATIC "${PMA_DEPS_DIR}/unity/src/unity.c")
target_include_directories(pma_unity SYSTEM PUBLIC "${PMA_DEPS_DIR}/unity/src")
target_compile_definitions(pma_unity PUBLIC UNITY_INCLUDE_DOUBLE UNITY_SUPPORT_64
                                            UNITY_USE_FLUSH_STDOUT)
# An object library, so that the weak default setUp()/tearDown() are in every test executable
# whatever the link order (a test's own definitions override them).
add_library(pma_test OBJECT "${PMA_TEST_SUPPORT_DIR}/pma_test.c")
target_include_directories(pma_test PUBLIC "${PMA_TEST_SUPPORT_DIR}")
target_link_libraries(pma_test PUBLIC pma_unity PRIVATE pma_warnings)

if(PMA_TARGET STREQUAL "host")
  # ON (default) = "address,undefined"; "undefined" for programs that run inside the
  # User-Mode Linux guest of hil/with-vcan, where ASan cannot map its shadow memory
  # (preset host-ubsan); OFF for none.
  set(PMA_SANITIZE "ON" CACHE STRING "Host sanitizers: ON (address,undefined), undefined, OFF")
  if(PMA_SANITIZE STREQUAL "ON")
    set(_pma_san "address,undefined")
  elseif(PMA_SANITIZE STREQUAL "OFF")
    set(_pma_san "")
  else()
    set(_pma_san "${PMA_SANITIZE}")
  endif()
  if(_pma_san)
    target_compile_options(pma_sanitize INTERFACE -fsanitize=${_pma_san} -fno-sanitize-recover=all
                           -fno-omit-frame-pointer)
    target_link_options(pma_sanitize INTERFACE -fsanitize=${_pma_san})
  endif()
elseif(NOT CMAKE_CROSSCOMPILING OR NOT DEFINED PMA_QEMU_BOARD)
  message(FATAL_ERROR "PMA_TARGET=${PMA_TARGET} needs the ARM toolchain file: "
                      "use the preset (cmake --preset ${PMA_TARGET}) or "
                      "-DCMAKE_TOOLCHAIN_FILE=cmake/arm-none-eabi.cmake")
endif()

# --------------------------------------------------------------------------------------------
# Board support: `pma_board` (timing API + on ARM the startup code, fault handlers, heap and
# linker script of the emulated board).
if(PMA_TARGET STREQUAL "host")
  add_library(pma_board STATIC "${PMA_QEMU_DIR}/board_host.c")
  set(_pma_board_name "host")
else()
  set(_pma_board_name "${PMA_TARGET}/${PMA_QEMU_MACHINE}")
  add_library(pma_board STATIC
              "${PMA_QEMU_DIR}/startup.c"
              "${PMA_QEMU_DIR}/board_${PMA_QEMU_BOARD}.c")
  # -nostartfiles: startup.c brings the vector table and Reset_Handler (no crt0/crti/crtbegin).
  # rdimon.specs: newlib's semihosting syscalls (write/exit/...) over BKPT 0xAB.
  # The linker script INCLUDEs pma_sections.ld, found through -L.
  target_link_options(pma_board INTERFACE
    -nostartfiles --specs=rdimon.specs
    "-L${PMA_QEMU_DIR}" "-T${PMA_QEMU_DIR}/${PMA_QEMU_BOARD}.ld" -Wl,--print-memory-usage)
  set_property(TARGET pma_board APPEND PROPERTY INTERFACE_LINK_DEPENDS
               "${PMA_QEMU_DIR}/${PMA_QEMU_BOARD}.ld" "${PMA_QEMU_DIR}/pma_sections.ld")
endif()
target_include_directories(pma_board PUBLIC "${PMA_QEMU_DIR}/include")
pma_own_target(pma_board)
if(NOT PMA_TARGET STREQUAL "host")
  option(PMA_QEMU_MEMORY_REPORT
         "ARM: print stack and heap high-water marks when a test or benchmark exits" OFF)
  if(PMA_QEMU_MEMORY_REPORT)
    target_compile_definitions(pma_board PRIVATE PMA_BOARD_MEMORY_REPORT=1)
  endif()
endif()
target_compile_definitions(pma_board PRIVATE "PMA_BOARD_NAME=\"${_pma_board_name}\"")

# --------------------------------------------------------------------------------------------
add_custom_target(bench COMMENT "All benchmarks have run")

function(_pma_add_program name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "" "SOURCES;LIBRARIES;INCLUDES")
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "${name}: SOURCES is required")
  endif()
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "${name}: unexpected arguments: ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_include_directories(${name} PRIVATE ${ARG_INCLUDES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBRARIES} pma_board)
  pma_own_target(${name})
  if(NOT PMA_TARGET STREQUAL "host")
    set_target_properties(${name} PROPERTIES SUFFIX ".elf")
    target_link_options(${name} PRIVATE "-Wl,-Map=${CMAKE_CURRENT_BINARY_DIR}/${name}.map")
  endif()
endfunction()

function(pma_add_test name)
  _pma_add_program(${name} ${ARGN})
  target_link_libraries(${name} PRIVATE pma_test)
  add_test(NAME ${name} COMMAND ${name})
  set_tests_properties(${name} PROPERTIES TIMEOUT ${PMA_TEST_TIMEOUT})
endfunction()

function(pma_add_bench name)
  _pma_add_program(${name} ${ARGN})
  if(PMA_TARGET STREQUAL "host")
    set(_runner "")
  else()
    set(_runner ${PMA_QEMU_COMMAND} -icount shift=0 -kernel)
  endif()
  add_custom_target(run-${name}
    COMMAND ${_runner} $<TARGET_FILE:${name}>
    DEPENDS ${name}
    COMMENT "Benchmark ${name} (${PMA_TARGET})"
    USES_TERMINAL VERBATIM)
  add_dependencies(bench run-${name})
endfunction()
