# SPDX-License-Identifier: Apache-2.0
# Prints an image's flash and RAM use against the STM32F405's 1 MB flash and 128 KB SRAM (the
# 64 KB CCM RAM is not used), from `arm-none-eabi-size -B` output in SIZE_FILE.
#   cmake -DSIZE_FILE=trigger_firmware.size -DIMAGE=trigger_firmware -P size_report.cmake
file(STRINGS ${SIZE_FILE} lines)
list(GET lines 1 numbers)
string(REGEX MATCHALL "[0-9]+" fields "${numbers}")
list(GET fields 0 text)
list(GET fields 1 data)
list(GET fields 2 bss)
math(EXPR flash "${text} + ${data}")
math(EXPR ram "${data} + ${bss}")
math(EXPR flash_permille "${flash} * 1000 / (1024 * 1024)")
math(EXPR ram_permille "${ram} * 1000 / (128 * 1024)")
message(STATUS "${IMAGE}: flash ${flash} B of 1048576 (${flash_permille} per mille), "
               "RAM ${ram} B of 131072 (${ram_permille} per mille; incl. the 4096 B stack "
               "reserve), CCM RAM 0 B of 65536")
