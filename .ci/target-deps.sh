#!/bin/sh
# Installs what tests/export/test_target.py needs on a fresh Debian machine:
# the Arm bare-metal cross compiler (Debian's gcc-arm-none-eabi: GCC 12.2, the
# Arm GNU toolchain 12.2.rel1) with newlib's libm (sinf, cosf, sqrtf for the
# header's float path), and clang for the -ffast-math check of
# tests/export/test_export_faults.py. The emulator (unicorn) comes from PyPI
# through the project's test extra. Nothing is downloaded from outside the
# Debian archive. Run as root.
set -eu
export DEBIAN_FRONTEND=noninteractive
apt-get update
apt-get install -y --no-install-recommends gcc-arm-none-eabi libnewlib-arm-none-eabi clang
arm-none-eabi-gcc --version | head -n 1
clang --version | head -n 1
