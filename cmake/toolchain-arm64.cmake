# SPDX-License-Identifier: Apache-2.0
# Cross build for arm64 (aarch64) Debian with Debian's cross compiler (crossbuild-essential-arm64)
# against an arm64 sysroot of Debian's own -dev packages (scripts/arm64-sysroot.sh). Used by
# scripts/cross-arm64.sh:
#   cmake -S . -B build-arm64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-arm64.cmake
# The sysroot: -DRIGCAL_ARM64_SYSROOT=DIR, else $RIGCAL_ARM64_SYSROOT, else
# /var/cache/rigcal/arm64-sysroot. Binaries run here under qemu-aarch64 -L <sysroot>
# (CMAKE_CROSSCOMPILING_EMULATOR).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

if(NOT RIGCAL_ARM64_SYSROOT)
  if(DEFINED ENV{RIGCAL_ARM64_SYSROOT})
    set(RIGCAL_ARM64_SYSROOT $ENV{RIGCAL_ARM64_SYSROOT})
  else()
    set(RIGCAL_ARM64_SYSROOT /var/cache/rigcal/arm64-sysroot)
  endif()
endif()
# try_compile projects see the same sysroot.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES RIGCAL_ARM64_SYSROOT)
set(CMAKE_SYSROOT ${RIGCAL_ARM64_SYSROOT})
set(CMAKE_FIND_ROOT_PATH ${RIGCAL_ARM64_SYSROOT})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)  # host tools: lcm-gen, pkg-config, javac
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config (LCM, glib, libsystemd) reads the sysroot's .pc files and prefixes their paths.
set(ENV{PKG_CONFIG_SYSROOT_DIR} ${RIGCAL_ARM64_SYSROOT})
set(ENV{PKG_CONFIG_LIBDIR}
    "${RIGCAL_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${RIGCAL_ARM64_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L ${RIGCAL_ARM64_SYSROOT})
