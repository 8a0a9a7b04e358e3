# Cross-compiling for arm64 (the Raspberry Pi 4/5) against a sysroot made
# from Debian's arm64 packages (scripts/cross-build-arm64 makes it).
# -DPROBELIGHT_ARM64_SYSROOT=PATH names it.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
if(NOT PROBELIGHT_ARM64_SYSROOT AND DEFINED ENV{PROBELIGHT_ARM64_SYSROOT})
  set(PROBELIGHT_ARM64_SYSROOT $ENV{PROBELIGHT_ARM64_SYSROOT})
endif()
if(NOT PROBELIGHT_ARM64_SYSROOT)
  message(FATAL_ERROR "cross-build: set PROBELIGHT_ARM64_SYSROOT (scripts/cross-build-arm64 makes it)")
endif()
# The compiler checks' own projects get it too.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES PROBELIGHT_ARM64_SYSROOT)
set(CMAKE_SYSROOT ${PROBELIGHT_ARM64_SYSROOT})
set(CMAKE_FIND_ROOT_PATH ${PROBELIGHT_ARM64_SYSROOT})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(ENV{PKG_CONFIG_SYSROOT_DIR} ${PROBELIGHT_ARM64_SYSROOT})
set(ENV{PKG_CONFIG_LIBDIR} "${PROBELIGHT_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${PROBELIGHT_ARM64_SYSROOT}/usr/share/pkgconfig:${PROBELIGHT_ARM64_SYSROOT}/usr/lib/pkgconfig")
# dpkg -x runs no maintainer scripts: libraries that link other libraries
# are found through these at link time.
set(CMAKE_EXE_LINKER_FLAGS_INIT
    "-Wl,-rpath-link,${PROBELIGHT_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu -Wl,-rpath-link,${PROBELIGHT_ARM64_SYSROOT}/lib/aarch64-linux-gnu")
# Tests run under qemu-user with the sysroot as the target's root.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L ${PROBELIGHT_ARM64_SYSROOT})
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE arm64)
