#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The installed runtime package as engines use it (ctest: cache_format.install_consumer). Installs
# the sharcbake_runtime component into a scratch prefix, checks what it holds and what the shared
# library exports, then builds the consumers of install_consumer/ against it; each one looks up
# the golden cache and checks the answers:
#   (a) CMake, a C-only project: the static sharcbake::runtime, the shared sharcbake::runtime_shared;
#   (b) CMake, a C++ project: the README's example, static and shared;
#   (c) plain cc with pkg-config: the shared library (rpath), and --static with -static;
#   (d) the README's lookup snippets are the consumers' marked lines, word for word;
#   (e) CMake, add_subdirectory of the repository with sharcbake's defaults: the runtime alone,
#       and the engine's (empty) build type left as it was.
# Usage: install_consumer_test.sh CMAKE BUILD_DIR WORK_DIR C_COMPILER
set -euo pipefail
CMAKE=$1
BUILD=$2
WORK=$3
CC=$4
HERE=$(cd "$(dirname "$0")" && pwd)
README=$HERE/../../README.md
CONSUMER=$HERE/install_consumer
GOLDEN=$HERE/golden/small.v1.0.sharc
PREFIX=$WORK/prefix

fail() {
    echo "FAIL: $*" >&2
    exit 1
}
# quiet LOG COMMAND...: runs COMMAND; its output is shown only when it fails.
quiet() {
    local log=$1
    shift
    "$@" >"$log" 2>&1 || { cat "$log"; fail "$*"; }
}
# lookup EXE: runs a consumer on the golden cache (it checks its answers itself), labelled.
lookup() {
    printf '%-20s ' "$(basename "$1"):"
    "$1" "$GOLDEN" || fail "$1 (exit $?)"
}
# Whether an executable loads libsharcbake_runtime.so at run time.
loads_shared_runtime() { readelf -d "$1" 2>/dev/null | grep -q 'NEEDED.*libsharcbake_runtime\.so'; }

rm -rf "$WORK" && mkdir -p "$WORK"
echo "== install into $PREFIX"
quiet "$WORK/install.log" "$CMAKE" --install "$BUILD" --prefix "$PREFIX" --component sharcbake_runtime
# Only the runtime's headers: no writer, checkpoint or merge headers.
for header in cache_file.h checkpoint_file.h cache_merge.h; do
    [ ! -e "$PREFIX/include/sharcbake/$header" ] || fail "$header is installed"
done
[ -e "$PREFIX/include/sharcbake/runtime.h" ] || fail "runtime.h is not installed"
LIBDIR=$(dirname "$(find "$PREFIX" -name libsharcbake_runtime.a)")
SHARED=$LIBDIR/libsharcbake_runtime.so
[ -e "$SHARED" ] || fail "no $SHARED"

# The shared library: a versioned SONAME, and only the public API in its dynamic symbols: the
# whole C API and names in namespace sharcbake (hidden visibility leaves the unmarked ones out).
soname=$(readelf -d "$SHARED" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')
[[ $soname =~ ^libsharcbake_runtime\.so\.[0-9]+$ && -e $LIBDIR/$soname ]] || fail "SONAME '$soname'"
nm -D --defined-only "$SHARED" | awk '{print $NF}' | c++filt >"$WORK/exports.txt"
if grep -v -e '^sharcbake_' -e '^sharcbake::' "$WORK/exports.txt"; then fail "exported beyond the public API (above)"; fi
for function in $(grep -o '\bsharcbake_[a-z_]*(' "$PREFIX/include/sharcbake/runtime_c.h" | tr -d '('); do
    grep -qx "$function" "$WORK/exports.txt" || fail "C API function $function is not exported"
done
grep -q '^sharcbake::CacheView::openFile(' "$WORK/exports.txt" || fail "the C++ API is not exported"
echo "$soname: $(wc -l <"$WORK/exports.txt") exported symbols, all public API"

echo "== (a) CMake, C only"
quiet "$WORK/c.log" "$CMAKE" -S "$CONSUMER" -B "$WORK/c" -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_BUILD_TYPE=Release
quiet "$WORK/c.log" "$CMAKE" --build "$WORK/c"
! loads_shared_runtime "$WORK/c/consumer_c" || fail "consumer_c should be linked statically"
loads_shared_runtime "$WORK/c/consumer_c_shared" || fail "consumer_c_shared does not load the shared library"
lookup "$WORK/c/consumer_c"
lookup "$WORK/c/consumer_c_shared"  # found through the build tree's rpath

echo "== (b) CMake, C++"
quiet "$WORK/cpp.log" "$CMAKE" -S "$CONSUMER/cpp" -B "$WORK/cpp" -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_BUILD_TYPE=Release
quiet "$WORK/cpp.log" "$CMAKE" --build "$WORK/cpp"
loads_shared_runtime "$WORK/cpp/consumer_cpp_shared" || fail "consumer_cpp_shared does not load the shared library"
lookup "$WORK/cpp/consumer_cpp"
lookup "$WORK/cpp/consumer_cpp_shared"

echo "== (c) $CC with pkg-config"
command -v pkg-config >/dev/null || fail "pkg-config not found (apt-get install pkg-config)"
export PKG_CONFIG_PATH=$LIBDIR/pkgconfig
pc=sharcbake-runtime
# Shared (the linker prefers it when both kinds are installed): the loader finds it by rpath.
# shellcheck disable=SC2046  # pkg-config's flags are meant to be split
quiet "$WORK/pc.log" "$CC" "$CONSUMER/consumer.c" -o "$WORK/pc_shared" $(pkg-config --cflags --libs $pc) \
    -Wl,-rpath,"$(pkg-config --variable=libdir $pc)"
loads_shared_runtime "$WORK/pc_shared" || fail "pc_shared does not load the shared library"
lookup "$WORK/pc_shared"
# Static: --static adds Libs.private (the C++ standard library); -static makes the linker take
# the archive, so the link fails if the .pc misses anything the archive needs.
# shellcheck disable=SC2046
quiet "$WORK/pc.log" "$CC" -static "$CONSUMER/consumer.c" -o "$WORK/pc_static" $(pkg-config --static --cflags --libs $pc)
! loads_shared_runtime "$WORK/pc_static" || fail "pc_static should be linked statically"
lookup "$WORK/pc_static"

echo "== (e) CMake, add_subdirectory of the repository"
quiet "$WORK/sub.log" "$CMAKE" -S "$CONSUMER/subdirectory" -B "$WORK/sub" -DSHARCBAKE_SOURCE_DIR="$HERE/../.."
grep -q '^CMAKE_BUILD_TYPE:STRING=$' "$WORK/sub/CMakeCache.txt" ||
    fail "the subproject changed the engine's build type: $(grep '^CMAKE_BUILD_TYPE' "$WORK/sub/CMakeCache.txt")"
quiet "$WORK/sub.log" "$CMAKE" --build "$WORK/sub" --target consumer_cpp
lookup "$WORK/sub/consumer_cpp"

echo "== (d) README snippets"
# marked FILE: the lines between the file's readme markers, without the function's indentation.
marked() { sed -n '/readme-begin/,/readme-end/{/readme-begin/d;/readme-end/d;s/^    //;p;}' "$1"; }
readme=$(<"$README")
for source in consumer.cpp consumer.c; do
    snippet=$(marked "$CONSUMER/$source")
    [ -n "$snippet" ] || fail "no readme markers in $source"
    [[ $readme == *"$snippet"* ]] || fail "README.md does not show install_consumer/$source's marked lines as they are"
done
echo "README.md shows the consumers' code"
