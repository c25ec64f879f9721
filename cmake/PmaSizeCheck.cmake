# SPDX-License-Identifier: Apache-2.0
# Size report and budget of a firmware image (cmake -P, after the link).
#   -DSIZE=arm-none-eabi-size -DELF=<image.elf> -DFLASH_MAX=<bytes> -DRAM_MAX=<bytes>
# flash = text + data (the .data initialisers live in flash); RAM = data + bss
# (bss includes the linker script's .stack section). Fails above either budget.
cmake_policy(SET CMP0007 NEW)
execute_process(COMMAND "${SIZE}" -B "${ELF}" OUTPUT_VARIABLE _out RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "${SIZE} -B ${ELF} failed")
endif()
string(REPLACE "\n" ";" _lines "${_out}")
list(GET _lines 1 _vals)
string(REGEX MATCHALL "[0-9]+" _nums "${_vals}")
list(GET _nums 0 _text)
list(GET _nums 1 _data)
list(GET _nums 2 _bss)
math(EXPR _flash "${_text} + ${_data}")
math(EXPR _ram "${_data} + ${_bss}")
math(EXPR _flash_pct "100 * ${_flash} / ${FLASH_MAX}")
math(EXPR _ram_pct "100 * ${_ram} / ${RAM_MAX}")
message("${_out}")
message("size report: flash ${_flash} / ${FLASH_MAX} bytes (${_flash_pct} %), "
        "RAM ${_ram} / ${RAM_MAX} bytes (${_ram_pct} %, incl. the stack)")
if(_flash GREATER FLASH_MAX OR _ram GREATER RAM_MAX)
  message(FATAL_ERROR "image over budget: flash ${_flash} > ${FLASH_MAX} or RAM ${_ram} > ${RAM_MAX}")
endif()
