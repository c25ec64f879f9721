# SPDX-License-Identifier: Apache-2.0
# Third-party sources: where they are, and a clear error when one is missing.
#
# tools/fetch-deps.sh fetches them (pinned upstream commits, verified; PMA_DEPS_MIRROR for
# machines without GitHub) into PMA_DEPS_DIR: unity (tests), cmsis_device_g4 and cmsis_6 (the
# STM32G474 board port). CMake never downloads anything itself: one mechanism, one place.
#
#   pma_require_dep(<name> <file>)  fails the configure step unless PMA_DEPS_DIR/<name>/<file>
#                                   exists, naming the command that fetches it.
include_guard(GLOBAL)

set(PMA_DEPS_DIR "${CMAKE_SOURCE_DIR}/.deps" CACHE PATH
    "Third-party sources fetched by tools/fetch-deps.sh (Unity, ST cmsis_device_g4, Arm CMSIS_6)")

function(pma_require_dep name file)
  if(NOT EXISTS "${PMA_DEPS_DIR}/${name}/${file}")
    message(FATAL_ERROR "${name} not found: ${PMA_DEPS_DIR}/${name}/${file} is missing.\n"
                        "Run: bash tools/fetch-deps.sh   (fetches the pinned upstream commits into "
                        "${PMA_DEPS_DIR}; without access to GitHub set PMA_DEPS_MIRROR to a folder "
                        "of git bundles, see docs/testing.md)")
  endif()
endfunction()
