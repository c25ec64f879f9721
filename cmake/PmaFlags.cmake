# SPDX-License-Identifier: Apache-2.0
# The project's warning and sanitizer flags as usage requirements of INTERFACE libraries, so
# that each target states what it gets (not directory options whose reach depends on the order
# of includes):
#
#   pma_warnings         -Wall -Wextra -Werror: every target of the project's own code
#   pma_warnings_strict  the above plus -Wshadow -Wdouble-promotion -Wconversion: the firmware
#                        libraries and programs (common, control, storage, app, the
#                        targets), which are clean with them on every core and compiler
#                        (not the codec cantools generates: clang finds float promotions)
#   pma_sanitize         host test builds: the sanitizers (cmake/PmaTest.cmake fills it in);
#                        empty elsewhere
#
#   pma_own_target(<target> [STRICT])  links a target with its warnings and pma_sanitize
include_guard(GLOBAL)

add_library(pma_warnings INTERFACE)
target_compile_options(pma_warnings INTERFACE -Wall -Wextra -Werror)
add_library(pma_warnings_strict INTERFACE)
target_link_libraries(pma_warnings_strict INTERFACE pma_warnings)
target_compile_options(pma_warnings_strict INTERFACE -Wshadow -Wdouble-promotion -Wconversion)
add_library(pma_sanitize INTERFACE)

function(pma_own_target target)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "STRICT" "" "")
  if(ARG_STRICT)
    target_link_libraries(${target} PRIVATE pma_warnings_strict pma_sanitize)
  else()
    target_link_libraries(${target} PRIVATE pma_warnings pma_sanitize)
  endif()
endfunction()
