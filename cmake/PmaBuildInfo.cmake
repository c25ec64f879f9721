# SPDX-License-Identifier: Apache-2.0
# Firmware identity, stamped at build time: `pma_build_info` (a generated .c file in the build
# tree, behind firmware/app/build_info.h) holds the version of the VERSION file (the one source
# of the firmware's version), the git commit and whether the tree had uncommitted changes, and
# the build target. Regenerated on every build, rewritten only when something changed, so an
# unchanged tree relinks nothing.
#
# Two modes: included from CMakeLists.txt it defines the target; run as a script
# (cmake -P, with PMA_SOURCE_DIR, PMA_OUT, PMA_VERSION, PMA_TARGET_CHOICE) it writes the file.

if(CMAKE_SCRIPT_MODE_FILE)
  set(_commit 0)
  set(_flags 2) # bit 1: commit unknown
  find_package(Git QUIET)
  if(GIT_FOUND)
    execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${PMA_SOURCE_DIR}" rev-parse --short=8 HEAD
                    OUTPUT_VARIABLE _sha RESULT_VARIABLE _rc ERROR_QUIET
                    OUTPUT_STRIP_TRAILING_WHITESPACE)
    if(_rc EQUAL 0 AND _sha MATCHES "^[0-9a-f]+$")
      set(_commit "0x${_sha}")
      set(_flags 0)
      # bit 0: a tracked file differs from the commit (untracked files do not count)
      execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${PMA_SOURCE_DIR}" diff --quiet HEAD --
                      RESULT_VARIABLE _dirty ERROR_QUIET)
      if(NOT _dirty EQUAL 0)
        set(_flags 1)
      endif()
    endif()
  endif()
  string(REPLACE "." ";" _v "${PMA_VERSION}")
  list(GET _v 0 _major)
  list(GET _v 1 _minor)
  list(GET _v 2 _patch)
  set(_text "/* SPDX-License-Identifier: Apache-2.0 */
/* Generated at build time by cmake/PmaBuildInfo.cmake: do not edit. */
#include \"build_info.h\"

#include \"generated/pma_proto.h\"

const pma_build_info_t pma_build_info = {
    .fw_major = ${_major}u,
    .fw_minor = ${_minor}u,
    .fw_patch = ${_patch}u,
    .build_target = ${PMA_TARGET_CHOICE},
    .build_flags = ${_flags}u,
    .fw_commit = ${_commit}u,
};
")
  if(EXISTS "${PMA_OUT}")
    file(READ "${PMA_OUT}" _old)
  else()
    set(_old "")
  endif()
  if(NOT _old STREQUAL _text)
    file(WRITE "${PMA_OUT}" "${_text}")
  endif()
  return()
endif()

include_guard(GLOBAL)

# pma_build_info_library(<name>): the static library <name> (pma_build_info.c generated in the
# build tree), linked by the application. PMA_TARGET names the build target.
function(pma_build_info_library name)
  file(STRINGS "${PMA_REPO_DIR}/VERSION" _version LIMIT_COUNT 1)
  if(NOT _version MATCHES "^[0-9]+\\.[0-9]+\\.[0-9]+$")
    message(FATAL_ERROR "VERSION must hold MAJOR.MINOR.PATCH, got '${_version}'")
  endif()
  # PMA_TARGET -> the DBC's BuildTarget value (VAL_ 256 BuildTarget; the generated codec's
  # *_CHOICE macros, so the numbers live in the DBC only).
  set(_choices host HOST stm32g474 STM32_G474 cortex-m4f CORTEX_M4_F cortex-m3 CORTEX_M3
               cortex-m0 CORTEX_M0)
  list(FIND _choices "${PMA_TARGET}" _i)
  if(_i LESS 0)
    set(_choice UNKNOWN)
  else()
    math(EXPR _i "${_i} + 1")
    list(GET _choices ${_i} _choice)
  endif()
  set(_out "${CMAKE_CURRENT_BINARY_DIR}/pma_build_info.c")
  # Always out of date (the git state can change without any file CMake knows of); the
  # script rewrites the file only when its text changes.
  add_custom_target(${name}_stamp
    COMMAND "${CMAKE_COMMAND}" -DPMA_SOURCE_DIR=${PMA_REPO_DIR} -DPMA_OUT=${_out}
            -DPMA_VERSION=${_version}
            -DPMA_TARGET_CHOICE=PMA_PROTO_DEVICE_INFO_BUILD_TARGET_${_choice}_CHOICE
            -P "${PMA_REPO_DIR}/cmake/PmaBuildInfo.cmake"
    BYPRODUCTS "${_out}"
    COMMENT "Firmware identity (VERSION ${_version}, git commit, target ${PMA_TARGET})"
    VERBATIM)
  add_library(${name} STATIC "${_out}")
  add_dependencies(${name} ${name}_stamp)
  target_link_libraries(${name} PUBLIC pma_proto)
  target_include_directories(${name} PUBLIC "${CMAKE_CURRENT_SOURCE_DIR}")
  if(COMMAND pma_own_target)
    pma_own_target(${name} STRICT)
  endif()
endfunction()
