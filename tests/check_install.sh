#!/bin/sh
# The installed library as a user sees it: installs the built tree
# into a fresh prefix, then builds tests/consumer/ outside the tree twice,
# with find_package(tsm) and with `pkg-config --static tsm`, and runs both.
# usage: check_install.sh CMAKE BUILD_DIR SOURCE_DIR WORK_DIR CXX [EXTRA_CXX_FLAGS]
set -eu
cmake=$1 build=$2 src=$3 work=$4 cxx=$5 flags=${6:-}
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix

"$cmake" --install "$build" --prefix "$prefix" >"$work/install.log" || { cat "$work/install.log"; exit 1; }
for f in include/tsm/tsm.hpp include/tsm/tsm.h include/tsm/io.hpp include/tsm/version.h \
         lib/cmake/tsm/tsmConfig.cmake lib/pkgconfig/tsm.pc; do
  [ -f "$prefix/$f" ] || { echo "check_install: $f not installed"; exit 1; }
done

# 1. CMake: find_package(tsm REQUIRED), tsm::tsm + tsm::tsm_io.
"$cmake" -S "$src/tests/consumer" -B "$work/cmake-build" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_BUILD_TYPE=Release >"$work/cmake.log" 2>&1 \
  || { cat "$work/cmake.log"; exit 1; }
"$cmake" --build "$work/cmake-build" >>"$work/cmake.log" 2>&1 || { cat "$work/cmake.log"; exit 1; }
"$work/cmake-build/consumer" "$work/cmake.ply"

# 2. pkg-config: the same program from `pkg-config --cflags --libs --static tsm`.
PKG_CONFIG_PATH=$prefix/lib/pkgconfig
export PKG_CONFIG_PATH
pc_flags=$("${PKG_CONFIG:-pkg-config}" --cflags --libs --static tsm)
echo "check_install: pkg-config --cflags --libs --static tsm: $pc_flags"
# shellcheck disable=SC2086  # the flags are words
"$cxx" -std=c++17 $flags "$src/tests/consumer/main.cpp" -o "$work/pc-consumer" $pc_flags
"$work/pc-consumer" "$work/pc.ply"
echo "check_install: ok"
